// spherechain baker — internal (not installed): the mesh's non-degenerate triangles for a CGAL
// AABB_tree (nearest-surface queries), shared by the coverage measure and the cover fit.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace spherechain::baker::surface_detail {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = K::Point_3;
using Triangle3 = K::Triangle_3;
using TriangleList = std::vector<Triangle3>;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleList::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

/// The triangles of `indices` (#T×3 into `positions`, #V×3 floats) that are not collinear, as CGAL
/// triangles, with the source triangle index of each (ids[i] for triangles[i]). A tree built over
/// `triangles` names its primitives by iterator: ids[it − triangles.begin()].
struct SurfaceTriangles {
  TriangleList triangles;
  std::vector<uint32_t> ids;
};
inline SurfaceTriangles NonDegenerateTriangles(const std::vector<float>& positions,
                                               const std::vector<uint32_t>& indices) {
  SurfaceTriangles out;
  out.triangles.reserve(indices.size() / 3);
  out.ids.reserve(indices.size() / 3);
  for (size_t f = 0; f + 2 < indices.size(); f += 3) {
    std::array<Point3, 3> p;
    for (int k = 0; k < 3; ++k) {
      const float* x = &positions[3 * size_t{indices[f + k]}];
      p[k] = Point3(x[0], x[1], x[2]);
    }
    if (CGAL::collinear(p[0], p[1], p[2])) continue;
    out.triangles.emplace_back(p[0], p[1], p[2]);
    out.ids.push_back(static_cast<uint32_t>(f / 3));
  }
  return out;
}

}  // namespace spherechain::baker::surface_detail
