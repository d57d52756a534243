// The float filter on 16 triangles by lane (PrepareFilter16, FilterRejects16: the crease rule's AVX-512
// sweep) against the scalar path it stands for: every lane it certifies holds, bit for bit, what
// PrepareTriangle writes for that triangle (and PrepareTriangle accepts it), and every pair it rejects is a
// pair the prepared float filter rejects (detail::FloatPlaneSide either way), and no other. Triangles at
// character scale, slivers, exactly degenerate ones, coordinates beyond the filter's range, NaN and
// infinities, and pairs with vertices on or a hair off the other's plane, so both answers occur.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>

#include "../runtime/src/internal.h"
#include "spherechain/runtime/triangle_intersect.h"
#include "test_data.h"

namespace rt = spherechain::runtime;

#if defined(__GNUC__) && defined(__x86_64__)
namespace {

// 16 rows of 16 floats (PrepareFilter16's layout): rows 0–8 the corners of the 16 lanes.
struct Block {
  float f[16 * 16] = {};
  void Set(uint32_t lane, const float tri[3][3]) {
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) f[16 * (3 * v + k) + lane] = tri[v][k];
  }
  void Corners(uint32_t lane, float tri[3][3]) const {
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) tri[v][k] = f[16 * (3 * v + k) + lane];
  }
  // Lane `i` in PreparedTriangle's order: x, y, z with G, A, M; the plane.
  rt::PreparedTriangle Lane(uint32_t i) const {
    static constexpr int kRows[16] = {0, 3, 6, 13, 1, 4, 7, 14, 2, 5, 8, 15, 9, 10, 11, 12};
    rt::PreparedTriangle p;
    float* out = p.x;  // x, y, z, plane: 16 consecutive floats (one cache line)
    for (int k = 0; k < 16; ++k) out[k] = f[16 * kRows[k] + i];
    return p;
  }
};

// A triangle of one of the kinds above, from `rng`.
void MakeTriangle(std::mt19937& rng, float tri[3][3]) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int kind = static_cast<int>(rng() % 16);
  const double centre = kind == 12 ? 3e12 : kind == 13 ? 1e6 : 20.0;  // 3e12 > 2^40: the filter is off
  const double size = std::pow(10.0, -3.0 + 3.0 * unit(rng)) * (kind == 13 ? 1e3 : 1.0);
  double c[3];
  for (double& x : c) x = centre * (2.0 * unit(rng) - 1.0);
  for (int v = 0; v < 3; ++v)
    for (int k = 0; k < 3; ++k) tri[v][k] = static_cast<float>(c[k] + size * (2.0 * unit(rng) - 1.0));
  if (kind == 8) {  // exactly collinear: r = p + 2 (q − p) on integer-valued floats
    for (int k = 0; k < 3; ++k) {
      tri[0][k] = std::round(tri[0][k]), tri[1][k] = std::round(tri[1][k]);
      tri[2][k] = tri[0][k] + 2.0f * (tri[1][k] - tri[0][k]);
    }
  } else if (kind == 9) {  // two corners coincide
    for (int k = 0; k < 3; ++k) tri[2][k] = tri[0][k];
  } else if (kind == 10) {  // a sliver: r a few ulps off the line pq
    for (int k = 0; k < 3; ++k) tri[2][k] = std::nextafter(0.5f * (tri[0][k] + tri[1][k]), tri[1][k]);
  } else if (kind == 11) {  // a non-finite corner
    const float bad[3] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()};
    tri[rng() % 3][rng() % 3] = bad[rng() % 3];
  } else if (kind == 14) {  // tiny: products underflow
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) tri[v][k] *= 1e-30f;
  }
}

}  // namespace

TEST_CASE("filter16: PrepareFilter16 and FilterRejects16 decide as PrepareTriangle and the prepared float filter") {
  if (!rt::kernels::Supported(rt::kernels::Isa::kAvx512)) {
    spherechain::test::Skip("no AVX-512 on this CPU: the 16-lane filter is never run here");
    return;
  }
  std::mt19937 rng(20261130u);
  std::uniform_real_distribution<double> unit(0.0, 1.0), coef(-0.5, 1.5);
  uint64_t lanes_certified = 0, lanes_left = 0, pairs_rejected = 0, pairs_kept = 0;
  uint64_t wrong_lanes = 0, wrong_pairs = 0;
  for (int round = 0; round < 3000; ++round) {
    Block t, u;
    for (uint32_t lane = 0; lane < 16; ++lane) {
      float a[3][3];
      MakeTriangle(rng, a);
      t.Set(lane, a);
    }
    // u: half its lanes near the plane of one of t's lanes (on it, or a hair to a metre off, one side or
    // mixed), the rest of the kinds above.
    for (uint32_t lane = 0; lane < 16; ++lane) {
      float b[3][3];
      MakeTriangle(rng, b);
      float a[3][3];
      t.Corners(rng() % 16, a);
      double e[3], w[3], n[3];
      for (int k = 0; k < 3; ++k) e[k] = double(a[1][k]) - a[0][k], w[k] = double(a[2][k]) - a[0][k];
      n[0] = e[1] * w[2] - e[2] * w[1], n[1] = e[2] * w[0] - e[0] * w[2], n[2] = e[0] * w[1] - e[1] * w[0];
      const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (lane % 2 == 0 && std::isfinite(norm) && norm > 0) {
        const double size = std::sqrt(norm);
        const double d = rng() % 8 == 0 ? 0.0 : size * std::pow(10.0, -12.0 + 13.0 * unit(rng));
        const bool same_side = rng() % 2;
        const double side0 = rng() % 2 ? 1.0 : -1.0;
        for (int v = 0; v < 3; ++v) {
          const double s = coef(rng), r = coef(rng), sign = same_side ? side0 : (rng() % 2 ? 1.0 : -1.0);
          for (int k = 0; k < 3; ++k) b[v][k] = float(a[0][k] + s * e[k] + r * w[k] + sign * d * n[k] / norm);
        }
      }
      u.Set(lane, b);
    }
    // Some rounds leave lanes out (a patch of fewer than 16 triangles): never certified.
    const uint32_t lanes = round % 5 == 0 ? (1u << (1 + rng() % 16)) - 1 : 0xffffu;
    const uint32_t ct = rt::PrepareFilter16(t.f, lanes), cu = rt::PrepareFilter16(u.f, 0xffffu);
    for (const auto& [block, certified, in] : {std::tuple{&t, ct, lanes}, std::tuple{&u, cu, 0xffffu}})
      for (uint32_t lane = 0; lane < 16; ++lane) {
        float c[3][3];
        block->Corners(lane, c);
        rt::PreparedTriangle ref;
        const bool ok = rt::PrepareTriangle(c[0], c[1], c[2], &ref);
        if (!(certified >> lane & 1)) {
          ++lanes_left;
          continue;
        }
        ++lanes_certified;
        const rt::PreparedTriangle got = block->Lane(lane);
        if (!(in >> lane & 1) || !ok || std::memcmp(&got, &ref, sizeof ref) != 0) ++wrong_lanes;
      }
    for (uint32_t i = 0; i < 16; ++i) {
      if (!(ct >> i & 1)) continue;
      const rt::PreparedTriangle a = t.Lane(i);
      const uint32_t rejected = rt::FilterRejects16(t.f, i, u.f);
      for (uint32_t j = 0; j < 16; ++j) {
        if (!(cu >> j & 1)) continue;
        const rt::PreparedTriangle b = u.Lane(j);
        const bool expected =
            rt::detail::FloatPlaneSide(a, b) != 0 || rt::detail::FloatPlaneSide(b, a) != 0;
        (expected ? pairs_rejected : pairs_kept) += 1;
        if (bool(rejected >> j & 1) != expected) ++wrong_pairs;
      }
    }
  }
  MESSAGE("lanes certified " << lanes_certified << ", left to PrepareTriangle " << lanes_left << "; pairs rejected "
                             << pairs_rejected << ", kept " << pairs_kept);
  CHECK(wrong_lanes == 0);
  CHECK(wrong_pairs == 0);
  // Both answers occur, for lanes and for pairs.
  CHECK(lanes_certified > 40000);
  CHECK(lanes_left > 10000);
  CHECK(pairs_rejected > 100000);
  CHECK(pairs_kept > 10000);
}
#endif
