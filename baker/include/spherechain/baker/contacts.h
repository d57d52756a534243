// spherechain baker — ground truth for self-collision: exact intersection of the deformed mesh's
// triangles (what `spherechain evaluate` measures the proxy and the runtime narrow phase against).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// Two intersecting triangles of one mesh, source triangle indices, a < b.
struct TrianglePair {
  uint32_t a = 0, b = 0;
  friend bool operator==(const TrianglePair&, const TrianglePair&) = default;
  friend auto operator<=>(const TrianglePair&, const TrianglePair&) = default;
};

/// Every pair of triangles of the mesh (`positions` \#V×3 floats, any space; `indices` \#T×3) that
/// share no welded corner (`weld_ids`, \#V: see ComputeWeldIds / Asset.weld_ids) and intersect as
/// closed triangles (touching counts): CGAL box_self_intersection_d over the triangles' boxes
/// (Zomorodian & Edelsbrunner 2000), then CGAL::do_intersect(Triangle_3, Triangle_3) with exact
/// predicates (Epick) on the float coordinates. Degenerate triangles (exactly zero area, or a repeated
/// weld id) never intersect; their number goes to `*degenerate` [opt]. Sorted by (a, b).
/// Errors: kInvalidMesh (sizes disagree, an index out of range, a non-finite coordinate),
/// kInternal (CGAL threw). Cost: O(\#T log² \#T + k) for k box overlaps; ~0.1 s for 27k triangles.
Result<std::vector<TrianglePair>> ExactSelfIntersections(const float* positions, uint32_t vertex_count,
                                                          const std::vector<uint32_t>& indices,
                                                          const std::vector<uint32_t>& weld_ids,
                                                          uint32_t* degenerate = nullptr);

/// True when some triangle of `set_a` comes within `distance` [source units, >= 0] of some triangle of
/// `set_b` (exact-predicate intersection test, then the least of the 6 vertex–triangle and 9
/// edge–edge distances, Epick), among the pairs that share no welded corner and pass `allow` [opt].
/// Triangle ids are source indices (< \#T). Stops at the first such pair. Errors: as above.
Result<bool> AnyTrianglesWithin(const float* positions, uint32_t vertex_count, const std::vector<uint32_t>& indices,
                                const std::vector<uint32_t>& weld_ids, const std::vector<uint32_t>& set_a,
                                const std::vector<uint32_t>& set_b, double distance,
                                const std::function<bool(uint32_t, uint32_t)>& allow = {});

/// Where each pair of `pairs` meets: the midpoint of the two triangles' intersection segment, the
/// point itself when they touch at one point, the centroid of the overlap's corners when they are
/// coplanar and overlap (CGAL::intersection(Triangle_3, Triangle_3), Epick: inexact constructions, a
/// location to within float noise); for a pair that does not intersect (not a contact of these
/// positions), the midpoint of the two centroids. `positions` \#V×3 floats (any space, the result in the
/// same), `indices` \#T×3, `pairs` source triangle indices. One point per pair, in `pairs` order.
/// Errors: kInvalidMesh (an index or a triangle out of range, a non-finite coordinate of a pair's
/// triangle), kInternal (CGAL threw). Cost: ~1 µs per pair, no spatial search.
Result<std::vector<Eigen::Vector3d>> ContactPoints(const float* positions, uint32_t vertex_count,
                                                   const std::vector<uint32_t>& indices,
                                                   const std::vector<TrianglePair>& pairs);

}  // namespace spherechain::baker
