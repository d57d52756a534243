// The synthetic standing body of the segmentation tests, with known answers: the zero set of the union
// of capsules (one per body part, each labelled with its region), meshed by marching tetrahedra. Shared by
// segment_test.cpp and extremities_test.cpp.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "spherechain/import/types.h"

namespace spherechain::test {

namespace sc = spherechain::baker;

using Vec3 = std::array<double, 3>;
inline Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }

// ---------------------------------------------------------------------------------------------------
// Synthetic body: the zero set of min(capsule distances), meshed by marching tetrahedra. Y up, facing
// +Z (feet point +Z), so the character's left is +X.
struct Capsule {
  Vec3 a, b;
  double r;
  sc::Region region;
  /// The extremity the part is (baker::Extremity value: 1 head, 2/3 left/right hand, 4/5 left/right
  /// foot), -1 for a joint between a limb and its extremity (wrist, ankle: the cut lies in it), 0 for the
  /// rest.
  int extremity = 0;
  double Distance(const Vec3& p, double* t_out = nullptr) const {
    const Vec3 ab = Sub(b, a);
    double t = std::clamp(Dot(Sub(p, a), ab) / std::max(Dot(ab, ab), 1e-12), 0.0, 1.0);
    if (t_out) *t_out = t;
    const Vec3 q{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
    return Norm(Sub(p, q)) - r;
  }
};

/// `extremities`: each arm ends in a wrist (radius 0.032, 0.05 long, past the arm's round cap) and a flat
/// palm (two capsules of radius 0.028, 0.10 long, side by side 0.09 apart), each leg in an ankle (radius
/// 0.04) above its foot: narrower than the limb, then wider — the parts SplitExtremities cuts off.
/// Without, the arms end in their round cap (no hand to find) and the legs run into the feet.
inline std::vector<Capsule> BodyParts(bool t_pose, bool extremities = false) {
  using R = sc::Region;
  std::vector<Capsule> c;
  for (int s : {1, -1}) {
    const R leg = s > 0 ? R::kLeftLeg : R::kRightLeg;
    const R arm = s > 0 ? R::kLeftArm : R::kRightArm;
    if (extremities) {
      c.push_back({{s * 0.10, 0.86, 0.0}, {s * 0.11, 0.24, 0.0}, 0.07, leg});   // leg, hip → calf
      c.push_back({{s * 0.11, 0.24, 0.0}, {s * 0.11, 0.08, 0.0}, 0.04, leg, -1});   // ankle (the cut: either side)
    } else {
      c.push_back({{s * 0.10, 0.86, 0.0}, {s * 0.11, 0.10, 0.0}, 0.07, leg});   // leg, hip → ankle
    }
    c.push_back({{s * 0.11, 0.05, -0.02}, {s * 0.12, 0.05, 0.16}, 0.045, leg, s > 0 ? 4 : 5});  // foot, +Z
    const Vec3 shoulder = t_pose ? Vec3{s * 0.18, 1.36, 0.0} : Vec3{s * 0.18, 1.38, 0.0};
    const Vec3 end = t_pose ? Vec3{s * 0.82, 1.36, 0.0} : Vec3{s * 0.52, 0.92, 0.0};
    c.push_back({shoulder, end, 0.05, arm});
    if (extremities) {
      const Vec3 d0 = Sub(end, shoulder);
      const double n = Norm(d0);
      const Vec3 d{d0[0] / n, d0[1] / n, d0[2] / n};
      auto at = [&](double u, double z) { return Vec3{end[0] + u * d[0], end[1] + u * d[1], end[2] + u * d[2] + z}; };
      const int hand = s > 0 ? 2 : 3;
      c.push_back({at(0.03, 0.0), at(0.08, 0.0), 0.032, arm, -1});  // wrist (the cut: either side)
      for (double z : {-0.045, 0.045}) c.push_back({at(0.09, z), at(0.19, z), 0.028, arm, hand});  // palm
    }
  }
  c.push_back({{0.0, 0.86, 0.0}, {0.0, 1.36, 0.0}, 0.17, R::kTorso});  // trunk
  c.push_back({{0.0, 1.36, 0.0}, {0.0, 1.55, 0.0}, 0.05, R::kTorso});  // neck
  c.push_back({{0.0, 1.63, 0.0}, {0.0, 1.63, 0.0}, 0.11, R::kTorso, 1});  // head
  return c;
}

inline int NearestPart(const std::vector<Capsule>& parts, const Vec3& p) {
  int best = 0;
  for (int i = 1; i < int(parts.size()); ++i)
    if (parts[i].Distance(p) < parts[best].Distance(p)) best = i;
  return best;
}

/// Marching tetrahedra (Freudenthal split of each cube, consistent across cubes) of f < 0.
inline sc::Mesh MarchingTetrahedra(const std::function<double(const Vec3&)>& f, const Vec3& lo, const Vec3& hi, double step) {
  const int nx = int(std::ceil((hi[0] - lo[0]) / step)) + 1, ny = int(std::ceil((hi[1] - lo[1]) / step)) + 1,
            nz = int(std::ceil((hi[2] - lo[2]) / step)) + 1;
  auto gid = [&](int i, int j, int k) { return (int64_t(k) * ny + j) * nx + i; };
  auto gpos = [&](int64_t id) {
    const int64_t i = id % nx, j = (id / nx) % ny, k = id / (int64_t(nx) * ny);
    return Vec3{lo[0] + i * step, lo[1] + j * step, lo[2] + k * step};
  };
  std::vector<double> val(size_t(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) val[gid(i, j, k)] = f(gpos(gid(i, j, k)));
  sc::Mesh mesh;
  std::unordered_map<uint64_t, uint32_t> edge_vertex;
  auto vertex_on = [&](int64_t a, int64_t b) {
    if (a > b) std::swap(a, b);
    const uint64_t key = uint64_t(a) * uint64_t(val.size()) + uint64_t(b);
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const double t = val[a] / (val[a] - val[b]);
    const Vec3 pa = gpos(a), pb = gpos(b);
    const uint32_t idx = mesh.vertex_count();
    for (int d = 0; d < 3; ++d) mesh.positions.push_back(float(pa[d] + t * (pb[d] - pa[d])));
    edge_vertex.emplace(key, idx);
    return idx;
  };
  static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  static const int tets[6][4] = {{0, 1, 2, 6}, {0, 3, 2, 6}, {0, 3, 7, 6}, {0, 4, 7, 6}, {0, 4, 5, 6}, {0, 1, 5, 6}};
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i)
        for (const auto& tet : tets) {
          int64_t id[4];
          std::vector<int> in, out;
          for (int c = 0; c < 4; ++c) {
            const int* o = corner[tet[c]];
            id[c] = gid(i + o[0], j + o[1], k + o[2]);
            (val[id[c]] < 0 ? in : out).push_back(c);
          }
          if (in.empty() || out.empty()) continue;
          auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
            mesh.indices.insert(mesh.indices.end(), {a, b, c});
          };
          if (in.size() == 1 || out.size() == 1) {
            const auto& one = in.size() == 1 ? in : out;
            const auto& three = in.size() == 1 ? out : in;
            tri(vertex_on(id[one[0]], id[three[0]]), vertex_on(id[one[0]], id[three[1]]),
                vertex_on(id[one[0]], id[three[2]]));
          } else {
            const uint32_t a = vertex_on(id[in[0]], id[out[0]]), b = vertex_on(id[in[0]], id[out[1]]),
                           c = vertex_on(id[in[1]], id[out[1]]), d = vertex_on(id[in[1]], id[out[0]]);
            tri(a, b, c);
            tri(a, c, d);
          }
        }
  return mesh;
}

struct SyntheticBody {
  sc::Mesh mesh;
  std::vector<Capsule> parts;
  std::vector<int> part_of_triangle;
  std::vector<double> along_part;  ///< per triangle: 0 at the part's root, 1 at its tip (before rotation)
};

/// `yaw_quarter_turns`: the body is rotated about +Y by that many quarter turns after meshing.
inline SyntheticBody MakeSyntheticBody(bool t_pose, int yaw_quarter_turns = 0, bool extremities = false) {
  SyntheticBody body;
  body.parts = BodyParts(t_pose, extremities);
  auto f = [&](const Vec3& p) {
    double d = 1e9;
    for (const Capsule& c : body.parts) d = std::min(d, c.Distance(p));
    return d;
  };
  const double x = extremities ? 1.05 : 0.95;  // a T-pose's hands reach past 0.95
  body.mesh = MarchingTetrahedra(f, {-x, -0.02, -0.25}, {x, 1.8, 0.25}, 0.016);
  for (uint32_t t = 0; t < body.mesh.triangle_count(); ++t) {
    Vec3 c{0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) c[d] += body.mesh.positions[3 * body.mesh.indices[3 * t + k] + d] / 3.0;
    body.part_of_triangle.push_back(NearestPart(body.parts, c));
    double along = 0;
    body.parts[size_t(body.part_of_triangle.back())].Distance(c, &along);
    body.along_part.push_back(along);
  }
  for (int q = 0; q < (yaw_quarter_turns % 4 + 4) % 4; ++q) {
    for (uint32_t v = 0; v < body.mesh.vertex_count(); ++v) {
      float& x = body.mesh.positions[3 * v];
      float& z = body.mesh.positions[3 * v + 2];
      const float nx = z, nz = -x;  // +90° about +Y: +Z → +X
      x = nx;
      z = nz;
    }
  }
  body.mesh.up_axis = sc::UpAxis::kY;
  return body;
}

}  // namespace spherechain::test
