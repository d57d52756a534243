// spherechain baker — φ2: the minimum enclosing ball of a point set (Welzl 1991) via CGAL's
// Min_sphere_of_spheres_d (points as zero-radius spheres). The only translation unit that includes CGAL
// for fitting.
#include <CGAL/Min_sphere_of_spheres_d.h>
#include <CGAL/Min_sphere_of_spheres_d_traits_3.h>
#include <CGAL/Simple_cartesian.h>

#include "spherechain/baker/fit.h"

namespace spherechain::baker {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Traits = CGAL::Min_sphere_of_spheres_d_traits_3<Kernel, double, CGAL::Tag_true>;
using MinSphere = CGAL::Min_sphere_of_spheres_d<Traits>;
}  // namespace

Ball MinimumEnclosingBall(const std::vector<Eigen::Vector3d>& points) {
  Ball ball;
  if (points.empty()) return ball;
  std::vector<Traits::Sphere> spheres;
  spheres.reserve(points.size());
  for (const Eigen::Vector3d& p : points) spheres.emplace_back(Kernel::Point_3(p.x(), p.y(), p.z()), 0.0);
  MinSphere ms(spheres.begin(), spheres.end());
  if (ms.is_empty()) return ball;
  auto it = ms.center_cartesian_begin();
  for (int k = 0; k < 3; ++k, ++it) ball.center[k] = *it;
  ball.radius = ms.radius();
  // Rounding: make sure every input point lies inside (the CGAL double path is exact up to a few ulps).
  double r2 = ball.radius * ball.radius;
  for (const Eigen::Vector3d& p : points) r2 = std::max(r2, (p - ball.center).squaredNorm());
  ball.radius = std::sqrt(r2);
  return ball;
}

}  // namespace spherechain::baker
