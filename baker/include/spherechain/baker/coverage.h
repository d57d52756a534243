// spherechain baker — how well a set of spheres fills a body mesh at bind pose: coverage (share of the
// body's interior inside the spheres) and protrusion (share of the spheres' volume outside the body),
// by voxelisation with an axis-voted ray-parity inside test that tolerates real, non-watertight meshes.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "spherechain/baker/fit.h"  // Ball: the sphere type (φ1, φ1', φ2 all convert to it)
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// The skin distance CoverageStats::skin_within_share counts as reached: 0.5 % of the body height (about
/// what the default contact margin, 0.4 % a sphere, bridges when two skins press together).
constexpr double kSkinWithinRel = 0.005;

/// Options of MeasureCoverage.
struct CoverageOptions {
  /// Voxel edge as a fraction of the body height (the extent of the mesh's bounding box along its
  /// longest axis). [Limit: > 0, finite] [Units: relative to the body height]
  float voxel_rel = 1.0f / 200;
  /// Most voxels the grid may have; when voxel_rel would give more, the voxels are enlarged (uniformly,
  /// cube voxels kept) until the grid fits. Memory is ~1 byte a voxel. [Limit: >= 1]
  uint32_t max_voxels = 8'000'000;
  /// Also fill CoverageStats::sphere_outside_max_rel (one entry per sphere). Cost: one membership test
  /// per (protruding voxel, sphere whose box holds it).
  bool per_sphere = false;
};

/// What MeasureCoverage found. Volumes are voxel estimates in source units³ (count × voxel_size³);
/// the shares are ratios of voxel counts. Bind pose, model space.
struct CoverageStats {
  double body_volume = 0.0;     ///< volume of the mesh interior [Units: source³]
  double spheres_volume = 0.0;  ///< volume of the union of the spheres [Units: source³]
  /// Share of the body's interior inside at least one sphere: voxels_both / voxels_inside_body, in
  /// [0, 1]; 0 when the body has no interior voxel.
  double coverage = 0.0;
  /// Share of the spheres' union outside the body: (voxels_in_spheres − voxels_both) /
  /// voxels_in_spheres, in [0, 1]; 0 when no voxel centre lies in a sphere.
  double protrusion = 0.0;
  /// Distance from the mesh surface (nearest point on any triangle) of the union's voxel centres that
  /// lie outside the body: 95th percentile (nearest rank) and maximum, divided by the body height.
  /// 0 when no such voxel. [Units: relative to the body height]
  double outside_p95_rel = 0.0;
  double outside_max_rel = 0.0;  ///< see outside_p95_rel
  /// With CoverageOptions::per_sphere, \#spheres entries: the largest surface distance of the outside
  /// voxels inside that sphere (how far it sticks out of the skin), 0 when none; else empty.
  /// [Units: relative to the body height]
  std::vector<float> sphere_outside_max_rel;
  /// How far the skin lies outside the spheres — the one-sided surface distance of sphere-set fitting
  /// (MorphIt 2025's surface term; the skin a contact must reach through): per vertex used by a
  /// triangle, max(0, min over the spheres of ‖v − c‖ − r), weighted by a third of its triangles' area;
  /// the weighted median, 95th percentile and maximum, divided by the body height. The spheres count
  /// without a contact margin. [Units: relative to the body height]
  double skin_outside_p50_rel = 0.0;
  double skin_outside_p95_rel = 0.0;  ///< see skin_outside_p50_rel
  double skin_outside_max_rel = 0.0;  ///< see skin_outside_p50_rel
  /// Share of the skin's area within kSkinWithinRel (0.5 %) of the height of a sphere, in [0, 1].
  double skin_within_share = 0.0;
  uint32_t voxels_inside_body = 0;  ///< voxel centres classified inside the body
  uint32_t voxels_in_spheres = 0;   ///< voxel centres inside at least one sphere
  uint32_t voxels_both = 0;         ///< inside the body and inside at least one sphere
  /// Voxels whose inside/outside vote tied or had no known axis (counted as outside). A high share
  /// means the mesh is too open for the parity test to be trusted.
  uint32_t voxels_undecided = 0;
  double voxel_size = 0.0;           ///< voxel edge actually used [Units: source]
  uint32_t grid_dims[3] = {0, 0, 0};  ///< voxels along x, y, z (product ≤ CoverageOptions::max_voxels)
  double body_height = 0.0;          ///< longest extent of the mesh's bounding box [Units: source]
};

/// Measures how well `spheres` fill the body `positions`/`indices` (bind pose, model space, source
/// units): coverage, protrusion, how far the protruding volume reaches from the surface, and how far the
/// skin lies outside the spheres (CoverageStats::skin_outside_*: O(\#V × \#spheres), ~2 ms on MakeHuman).
///
/// `positions`: \#V×3 floats (x, y, z); `indices`: \#T×3 vertex indices (orientation and winding are not
/// used); `spheres`: centre and radius each [Units: source] — FittedSphere φ1 (center_phi1,
/// radius_phi1), φ1' (center, radius) and BakeResult::phi2 all fit; overlapping spheres count once.
///
/// Method:
/// 1. Grid: cube voxels of edge voxel_rel × body height (enlarged to keep ≤ max_voxels) over the union
///    of the mesh's and the spheres' bounding boxes, centred on it; every voxel is its centre sample.
/// 2. Inside the body — ray parity along axis-aligned lines, voted over the three axes: for each axis,
///    one line per grid column through the voxel centres. The triangles are rasterised onto the
///    columns of the plane perpendicular to the axis (each triangle visits only the columns in its
///    projected bounding box — a uniform 2-D grid in place of a tree), the crossing parameters of a
///    column are sorted and each of its voxels is inside when an odd number of crossings lie below
///    its centre. Lines through a shared edge or vertex: neither de-duplicated nor jittered by a real
///    offset, but by symbolic perturbation (Edelsbrunner & Mücke's Simulation of Simplicity): each
///    line is treated as moved by an infinitesimal (−ε, −ε²) in its plane, which is the rasteriser's
///    top-left fill rule decided with exact orientation predicates (CGAL Epick). A line through an
///    edge shared by two triangles therefore crosses exactly one of them (a fold/silhouette edge: both
///    or neither), through a vertex exactly one triangle of its fan, whether the mesh is indexed or a
///    soup with duplicated seam vertices (only coordinates are compared); triangles seen edge-on are
///    skipped. Real meshes are not watertight (eye holes, seams, internal faces): a column with an odd
///    number of crossings is "unknown" for that axis; each voxel takes the majority of the axes that
///    are known, ties and no known axis count as outside and in voxels_undecided.
/// 3. Spheres: a voxel is in a sphere when ‖centre − c‖² ≤ r² (double, exact up to rounding).
/// 4. Distances of the union's outside voxels to the surface: CGAL AABB_tree over the triangles
///    (degenerate ones left out) with accelerate_distance_queries, the previous voxel's closest point
///    as hint along a row.
/// Resolution: centre sampling can misclassify only the voxels a surface cuts (one voxel layer); the
/// errors largely cancel (a box and a ball come out within 1 % at 100–200 voxels across), but parts
/// only a few voxels thick (fingers: ~0.08 dm voxels on the 16.7 dm MakeHuman at 1/200) are coarse.
///
/// Errors (nothing else is returned then): kInvalidMesh — no vertex or no triangle, positions not a
/// multiple of 3 or indices not a multiple of 3, an index out of range, a non-finite coordinate, a
/// mesh with zero extent or only degenerate triangles, no sphere, a sphere with a non-finite centre or
/// radius or a negative radius (the message names which); kConfig — voxel_rel not > 0 and finite, or
/// max_voxels 0; kInternal — CGAL threw (its message).
///
/// Cost: O(\#T + \#voxels + Σ voxels in each sphere's box + \#outside-union voxels × AABB query);
/// allocates ~1 byte a voxel plus the crossings and the tree. Measured on the MakeHuman body (26,756
/// triangles, 96 spheres, 1/200: ~1.3 M voxels) on one core: 0.03 s for φ1' (few protruding voxels),
/// 0.3 s for φ2 (~84 k protruding voxels, the distance queries dominate). Single-threaded, reentrant,
/// does not print; adds a "coverage" timing to `ctx` [opt].
Result<CoverageStats> MeasureCoverage(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                                      const std::vector<Ball>& spheres, const CoverageOptions& options = {},
                                      Context* ctx = nullptr);

/// The interior of a body mesh as voxel centres (bind pose, model space, source units): the grid and
/// inside test of MeasureCoverage (steps 1–2: cube voxels of edge voxel_rel × body height over the
/// mesh's bounding box, axis-voted ray parity with the symbolically perturbed fill rule).
struct InteriorVoxels {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< corner of voxel (0, 0, 0) [Units: source]
  double voxel_size = 0.0;                           ///< voxel edge [Units: source]
  uint32_t dims[3] = {0, 0, 0};                      ///< voxels along x, y, z
  double body_height = 0.0;                          ///< longest extent of the mesh's bounding box
  /// Linear indices (i + nx·(j + ny·k)) of the voxels whose centre is inside, ascending.
  std::vector<uint32_t> inside;
  uint32_t undecided = 0;  ///< voxels whose vote tied (counted outside), as CoverageStats
  /// Centre of voxel `index` [Units: source].
  Eigen::Vector3d Centre(uint32_t index) const {
    const uint32_t i = index % dims[0], j = (index / dims[0]) % dims[1], k = index / (dims[0] * dims[1]);
    return origin + voxel_size * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
  }
};

/// Voxelises the interior of `positions`/`indices` (as MeasureCoverage: \#V×3 floats, \#T×3 indices).
/// Errors: those of MeasureCoverage that concern the mesh and the options. Cost: O(\#T + \#voxels),
/// ~1 byte a voxel while it runs. Adds a "voxelize" timing to `ctx` [opt].
Result<InteriorVoxels> VoxelizeInterior(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                                        const CoverageOptions& options = {}, Context* ctx = nullptr);

}  // namespace spherechain::baker
