#include "spherechain/baker/contacts.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>

#include <CGAL/Box_intersection_d/Box_with_handle_d.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

namespace spherechain::baker {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint32_t>;

struct Soup {
  const float* positions;
  const std::vector<uint32_t>& indices;
  const std::vector<uint32_t>& weld;
  K::Point_3 P(uint32_t v) const {
    return {double(positions[3 * size_t{v}]), double(positions[3 * size_t{v} + 1]), double(positions[3 * size_t{v} + 2])};
  }
  K::Triangle_3 Tri(uint32_t t) const { return {P(indices[3 * t]), P(indices[3 * t + 1]), P(indices[3 * t + 2])}; }
  bool Adjacent(uint32_t s, uint32_t t) const {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (weld[indices[3 * s + i]] == weld[indices[3 * t + j]]) return true;
    return false;
  }
  bool IndexDegenerate(uint32_t t) const {
    const uint32_t a = weld[indices[3 * t]], b = weld[indices[3 * t + 1]], c = weld[indices[3 * t + 2]];
    return a == b || b == c || a == c;
  }
  Box MakeBox(uint32_t t, double pad) const {
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = hi[k] = positions[3 * size_t{indices[3 * t]} + k];
      for (int j = 1; j < 3; ++j) {
        const double x = positions[3 * size_t{indices[3 * t + j]} + k];
        lo[k] = std::min(lo[k], x);
        hi[k] = std::max(hi[k], x);
      }
      lo[k] -= pad;
      hi[k] += pad;
    }
    return Box(CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]), t);
  }
};

Status CheckSoup(const float* positions, uint32_t vertex_count, const std::vector<uint32_t>& indices,
                 const std::vector<uint32_t>& weld_ids) {
  if (!positions && vertex_count) return MakeError(Error::Code::kInvalidMesh, "no positions");
  if (indices.size() % 3) return MakeError(Error::Code::kInvalidMesh, "index count is not a multiple of 3");
  if (weld_ids.size() != vertex_count)
    return MakeError(Error::Code::kInvalidMesh, std::to_string(weld_ids.size()) + " weld ids for " +
                                                    std::to_string(vertex_count) + " vertices");
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= vertex_count)
      return MakeError(Error::Code::kInvalidMesh, "triangle " + std::to_string(i / 3) + " references vertex " +
                                                      std::to_string(indices[i]) + " of " + std::to_string(vertex_count));
  for (size_t i = 0; i < size_t{3} * vertex_count; ++i)
    if (!std::isfinite(positions[i]))
      return MakeError(Error::Code::kInvalidMesh, "vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  return Ok{};
}

// Least distance² between two non-intersecting triangles: vertex–triangle and edge–edge.
double TriangleDistance2(const K::Triangle_3& x, const K::Triangle_3& y) {
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    d = std::min(d, CGAL::to_double(CGAL::squared_distance(x.vertex(i), y)));
    d = std::min(d, CGAL::to_double(CGAL::squared_distance(y.vertex(i), x)));
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      d = std::min(d, CGAL::to_double(CGAL::squared_distance(K::Segment_3(x.vertex(i), x.vertex((i + 1) % 3)),
                                                             K::Segment_3(y.vertex(j), y.vertex((j + 1) % 3)))));
  return d;
}

struct Found {};

}  // namespace

Result<std::vector<TrianglePair>> ExactSelfIntersections(const float* positions, uint32_t vertex_count,
                                                          const std::vector<uint32_t>& indices,
                                                          const std::vector<uint32_t>& weld_ids, uint32_t* degenerate) {
  if (Status s = CheckSoup(positions, vertex_count, indices, weld_ids); !s.ok()) return s.error();
  const Soup soup{positions, indices, weld_ids};
  const uint32_t T = static_cast<uint32_t>(indices.size() / 3);
  std::vector<TrianglePair> out;
  try {
    std::vector<Box> boxes;
    boxes.reserve(T);
    uint32_t degen = 0;
    for (uint32_t t = 0; t < T; ++t) {
      if (soup.IndexDegenerate(t) || soup.Tri(t).is_degenerate()) {
        ++degen;
        continue;
      }
      boxes.push_back(soup.MakeBox(t, 0.0));
    }
    if (degenerate) *degenerate = degen;
    CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
      const uint32_t s = x.info(), t = y.info();
      if (soup.Adjacent(s, t)) return;
      if (CGAL::do_intersect(soup.Tri(s), soup.Tri(t))) out.push_back({std::min(s, t), std::max(s, t)});
    });
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kInternal, std::string("CGAL: ") + e.what());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

Result<bool> AnyTrianglesWithin(const float* positions, uint32_t vertex_count, const std::vector<uint32_t>& indices,
                                const std::vector<uint32_t>& weld_ids, const std::vector<uint32_t>& set_a,
                                const std::vector<uint32_t>& set_b, double distance,
                                const std::function<bool(uint32_t, uint32_t)>& allow) {
  if (Status s = CheckSoup(positions, vertex_count, indices, weld_ids); !s.ok()) return s.error();
  const uint32_t T = static_cast<uint32_t>(indices.size() / 3);
  for (const auto* set : {&set_a, &set_b})
    for (uint32_t t : *set)
      if (t >= T) return MakeError(Error::Code::kInvalidMesh, "triangle " + std::to_string(t) + " out of range");
  const Soup soup{positions, indices, weld_ids};
  const double pad = 0.5 * distance, d2 = distance * distance;
  try {
    std::vector<Box> a, b;
    for (uint32_t t : set_a)
      if (!soup.IndexDegenerate(t)) a.push_back(soup.MakeBox(t, pad));
    for (uint32_t t : set_b)
      if (!soup.IndexDegenerate(t)) b.push_back(soup.MakeBox(t, pad));
    CGAL::box_intersection_d(a.begin(), a.end(), b.begin(), b.end(), [&](const Box& x, const Box& y) {
      const uint32_t s = x.info(), t = y.info();
      if (s == t || soup.Adjacent(s, t) || (allow && !allow(s, t))) return;
      const K::Triangle_3 ts = soup.Tri(s), tt = soup.Tri(t);
      if (ts.is_degenerate() || tt.is_degenerate()) return;
      if (CGAL::do_intersect(ts, tt) || TriangleDistance2(ts, tt) <= d2) throw Found{};
    });
  } catch (const Found&) {
    return true;
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kInternal, std::string("CGAL: ") + e.what());
  }
  return false;
}

Result<std::vector<Eigen::Vector3d>> ContactPoints(const float* positions, uint32_t vertex_count,
                                                   const std::vector<uint32_t>& indices,
                                                   const std::vector<TrianglePair>& pairs) {
  if (!positions && vertex_count) return MakeError(Error::Code::kInvalidMesh, "no positions");
  const size_t T = indices.size() / 3;
  auto corner = [&](uint32_t t, int k) -> Result<Eigen::Vector3d> {
    const uint32_t v = indices[3 * size_t{t} + size_t(k)];
    if (v >= vertex_count)
      return MakeError(Error::Code::kInvalidMesh, "triangle " + std::to_string(t) + " references vertex " +
                                                      std::to_string(v) + " of " + std::to_string(vertex_count));
    const Eigen::Vector3d p(positions[3 * size_t{v}], positions[3 * size_t{v} + 1], positions[3 * size_t{v} + 2]);
    if (!p.allFinite())
      return MakeError(Error::Code::kInvalidMesh, "vertex " + std::to_string(v) + " has a non-finite coordinate");
    return p;
  };
  std::vector<Eigen::Vector3d> out;
  out.reserve(pairs.size());
  try {
    for (const TrianglePair& pr : pairs) {
      if (pr.a >= T || pr.b >= T)
        return MakeError(Error::Code::kInvalidMesh, "triangle pair (" + std::to_string(pr.a) + ", " +
                                                        std::to_string(pr.b) + ") out of range of " + std::to_string(T));
      K::Point_3 c[2][3];
      Eigen::Vector3d centroid[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
      for (int side = 0; side < 2; ++side)
        for (int k = 0; k < 3; ++k) {
          auto p = corner(side ? pr.b : pr.a, k);
          if (!p.ok()) return p.error();
          c[side][k] = K::Point_3(p.value().x(), p.value().y(), p.value().z());
          centroid[side] += p.value() / 3.0;
        }
      const K::Triangle_3 ta(c[0][0], c[0][1], c[0][2]), tb(c[1][0], c[1][1], c[1][2]);
      Eigen::Vector3d at = 0.5 * (centroid[0] + centroid[1]);
      auto eig = [](const K::Point_3& p) { return Eigen::Vector3d(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())); };
      if (!ta.is_degenerate() && !tb.is_degenerate()) {
        if (const auto hit = CGAL::intersection(ta, tb)) {
          if (const K::Segment_3* s = boost::get<K::Segment_3>(&*hit)) {
            at = 0.5 * (eig(s->source()) + eig(s->target()));
          } else if (const K::Point_3* p = boost::get<K::Point_3>(&*hit)) {
            at = eig(*p);
          } else if (const K::Triangle_3* t = boost::get<K::Triangle_3>(&*hit)) {
            at = (eig(t->vertex(0)) + eig(t->vertex(1)) + eig(t->vertex(2))) / 3.0;
          } else if (const auto* poly = boost::get<std::vector<K::Point_3>>(&*hit); poly && !poly->empty()) {
            at = Eigen::Vector3d::Zero();
            for (const K::Point_3& p : *poly) at += eig(p);
            at /= double(poly->size());
          }
        }
      }
      out.push_back(at);
    }
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kInternal, std::string("CGAL: ") + e.what());
  }
  return out;
}

}  // namespace spherechain::baker
