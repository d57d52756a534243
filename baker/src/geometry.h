// spherechain baker — internal geometry helpers for the fitting stage (not installed): closest point on
// a triangle, ray–triangle intersection (Möller–Trumbore 1997), and a uniform grid over a triangle
// subset for nearest-surface queries. Model space, source units, double precision.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "spherechain/baker/types.h"

namespace spherechain::baker::fit_detail {

/// Vertex `v` of `mesh` as a double vector (model space, source units).
inline Eigen::Vector3d Vertex(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

/// Unit vector of the mesh's up axis (Mesh::up_axis).
Eigen::Vector3d UpVector(UpAxis axis);

/// Closest point to `p` on triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Two-sided ray–triangle intersection (Möller–Trumbore). Returns the ray parameter t > `t_min`
/// (distance when `dir` is unit) or +infinity when the ray misses.
double RayTriangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b, const Eigen::Vector3d& c, double t_min = 1e-12);

/// A triangle subset of a mesh, copied out as corners, with a uniform grid of its bounding boxes for
/// nearest-surface queries. Build O(#T), about 8 triangles a cell; the object owns its copies and
/// does not reference the mesh after construction. Queries are const but not thread-safe (they use a
/// visit stamp).
class TriangleGrid {
 public:
  /// `triangles`: indices into mesh.indices / 3. An empty list gives a grid whose queries return
  /// +infinity.
  TriangleGrid(const Mesh& mesh, const std::vector<uint32_t>& triangles);

  /// Distance from `p` to the nearest triangle (exact, point–triangle), +infinity when empty.
  /// `closest` [opt] receives the nearest surface point.
  double NearestDistance(const Eigen::Vector3d& p, Eigen::Vector3d* closest = nullptr) const;

  size_t size() const { return a_.size(); }
  const Eigen::Vector3d& a(size_t i) const { return a_[i]; }
  const Eigen::Vector3d& b(size_t i) const { return b_[i]; }
  const Eigen::Vector3d& c(size_t i) const { return c_[i]; }

 private:
  int CellIndex(int x, int y, int z) const { return (z * dims_[1] + y) * dims_[0] + x; }
  std::vector<Eigen::Vector3d> a_, b_, c_;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  double cell_ = 1.0;
  int dims_[3] = {1, 1, 1};
  std::vector<uint32_t> cell_start_;  ///< CSR: cells → triangle slots
  std::vector<uint32_t> cell_items_;
  mutable std::vector<uint32_t> stamp_;
  mutable uint32_t epoch_ = 0;
};

}  // namespace spherechain::baker::fit_detail

namespace spherechain::baker {
struct FitParams;
}
namespace spherechain::baker::fit_detail {
/// Extent of the referenced vertices of `mesh` along `up` (source units); 0 for an empty mesh.
double BodyHeight(const Mesh& mesh, const Eigen::Vector3d& up);
/// δ: params.disk_step when > 0, else params.disk_step_rel × BodyHeight (source units).
double DiskStep(const Mesh& mesh, const FitParams& params);
}  // namespace spherechain::baker::fit_detail
