// spherechain baker — sphere approximation of the regions (paper §3.1, §3.2), φ2 (Welzl 1991 via CGAL)
// and the accuracy measure F (§3.2).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// Torso labels (Figure 6), a bitmask: a sphere may be both L and T.
enum TorsoLabel : uint8_t { kLabelL = 1, kLabelR = 2, kLabelT = 4, kLabelD = 8 };

struct FitParams {
  int rays = 80;                    ///< N_r, rays of the torso disk [Limit: >= 8]
  int spheres_per_level = 2;        ///< N_s [Limit: 2]
  double disk_step = 0.0;           ///< δ [Units: source] ; 0 = disk_step_rel × height
  double disk_step_rel = 0.25 / 16.66;  ///< δ relative to the body height (0.25 on the 16.66-unit MakeHuman)
  double penetration_depth = 0.30;  ///< PD: neighbours overlap by PD·(r_a + r_b) [Limit: 0..0.9]
};

/// One fitted sphere ⊙ (bind pose, model space, source units).
struct FittedSphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< φ1' (adjusted; = φ1 for tubular regions)
  double radius = 0.0;
  Eigen::Vector3d center_phi1 = Eigen::Vector3d::Zero();  ///< φ1 before the adjustment
  double radius_phi1 = 0.0;
  Region region = Region::kTorso;
  uint8_t labels = 0;      ///< TorsoLabel bits (torso only)
  int sequence = 0;        ///< position along its region's sequence: limbs from the torso outwards,
                           ///< torso bottom-up by level (paper Figure 12)
  int level = -1;          ///< torso: disk level index; limbs: -1
  int column = -1;         ///< torso: 0 = character's left, 1 = right; limbs: -1
  /// Torso only: the disk's rays assigned to this sphere: ray index k (0..N_r-1), the disk centre and
  /// the surface hit distance along the ray (the paper's per-ray comparison, §6).
  Eigen::Vector3d disk_center = Eigen::Vector3d::Zero();
  std::vector<int> ray_ids;
  std::vector<Eigen::Vector3d> ray_dirs;
  std::vector<double> ray_hit;
};

struct FitResult {
  std::vector<FittedSphere> spheres;  ///< R0, R1, R2, R3 sequences, then the torso, in that order
  double body_height = 0.0;           ///< along the up axis, source units
  double disk_step = 0.0;             ///< δ actually used
};

/// Moving circumference (§3.1) for one tubular region: spheres centred in the limb's cross-section,
/// radius reaching the nearest surface of the region, neighbours overlapping by PD.
/// `region_triangles`: triangle indices of the region. Errors: kFit (region empty / degenerate).
Result<std::vector<FittedSphere>> FitTubular(const Mesh& mesh, const std::vector<uint32_t>& region_triangles,
                                             Region region, const FitParams& params, Context* ctx = nullptr);

/// Disk of N_r rays moving up in steps of δ, N_s = 2 spheres per level, then the adjustment φ1' (§3.2),
/// and the L/R/T/D labels (Figure 6). Errors: kFit.
Result<std::vector<FittedSphere>> FitTorso(const Mesh& mesh, const std::vector<uint32_t>& torso_triangles,
                                           const Segmentation& seg, const FitParams& params,
                                           Context* ctx = nullptr);

/// All five regions. Errors: kFit naming the region.
Result<FitResult> FitSpheres(const Mesh& mesh, const Segmentation& seg, const FitParams& params,
                             Context* ctx = nullptr);

/// φ2: the minimum enclosing ball of `points` (Welzl 1991, CGAL::Min_sphere_of_spheres_d). Exact up to
/// double rounding. Empty input gives radius 0 at the origin.
struct Ball {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;
};
Ball MinimumEnclosingBall(const std::vector<Eigen::Vector3d>& points);

/// F statistics (§3.2): F_i = r − ‖c − v_i‖ (positive: v_i inside the sphere).
struct AccuracyStats {
  double mean_abs_f = 0.0, rms_f = 0.0, min_f = 0.0, max_f = 0.0;
  size_t count = 0;
};
/// Adds the F values of `points` against sphere (c, r) to a running accumulation.
class AccuracyAccumulator {
 public:
  void Add(const Eigen::Vector3d& c, double r, const Eigen::Vector3d& v);
  AccuracyStats Stats() const;

 private:
  double sum_abs_ = 0, sum_sq_ = 0, min_ = 0, max_ = 0;
  size_t n_ = 0;
};

}  // namespace spherechain::baker
