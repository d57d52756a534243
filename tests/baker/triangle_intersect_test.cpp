// runtime::TrianglesIntersect / TriangleIsDegenerate / PrepareTriangle: hand-made cases with known
// answers, then agreement with CGAL's exact do_intersect / is_degenerate / orientation on random pairs
// built to be hard (coplanar, touching, shared vertices and edges, 1-ulp nudges, large offsets, wide
// exponent ranges, vertices a hair off the other's plane), for the float path, the prepared path and the
// prepared path's float filter alone (every sign it certifies must be CGAL's). Zero disagreements.
#include <doctest/doctest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "spherechain/runtime/triangle_intersect.h"

namespace rt = spherechain::runtime;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;  // predicates exact: the reference
using P3 = std::array<float, 3>;
using Tri = std::array<P3, 3>;

bool Ours(const Tri& a, const Tri& b) {
  return rt::TrianglesIntersect(a[0].data(), a[1].data(), a[2].data(), b[0].data(), b[1].data(), b[2].data());
}
bool OursDegenerate(const Tri& t) { return rt::TriangleIsDegenerate(t[0].data(), t[1].data(), t[2].data()); }

rt::PreparedTriangle Prepared(const Tri& t, bool* usable = nullptr) {
  rt::PreparedTriangle p;
  const bool ok = rt::PrepareTriangle(t[0].data(), t[1].data(), t[2].data(), &p);
  if (usable) *usable = ok;
  return p;
}

/// The prepared path: false when a triangle cannot intersect (PrepareTriangle false), else the prepared test.
bool OursPrepared(const Tri& a, const Tri& b) {
  bool usable_a = false, usable_b = false;
  const rt::PreparedTriangle pa = Prepared(a, &usable_a), pb = Prepared(b, &usable_b);
  return usable_a && usable_b && rt::TrianglesIntersect(pa, pb);
}

K::Triangle_3 ToCgal(const Tri& t) {
  auto p = [](const P3& v) { return K::Point_3(double(v[0]), double(v[1]), double(v[2])); };
  return {p(t[0]), p(t[1]), p(t[2])};
}

std::string Describe(const Tri& a, const Tri& b) {
  std::string s;
  char buf[96];
  for (const Tri* t : {&a, &b}) {
    s += t == &a ? "T1 =" : "  T2 =";
    for (const P3& v : *t) {
      std::snprintf(buf, sizeof buf, " (%.9g, %.9g, %.9g)", double(v[0]), double(v[1]), double(v[2]));
      s += buf;
    }
  }
  return s;
}

// ---- hand cases ----

Tri T(P3 a, P3 b, P3 c) { return {a, b, c}; }

/// Checks the expected answer for the pair in both argument orders and all 6 vertex orders of each.
void Expect(const Tri& a, const Tri& b, bool expected) {
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  for (const auto& pa : kPerm)
    for (const auto& pb : kPerm) {
      const Tri x = {a[pa[0]], a[pa[1]], a[pa[2]]};
      const Tri y = {b[pb[0]], b[pb[1]], b[pb[2]]};
      INFO(Describe(x, y));
      CHECK(Ours(x, y) == expected);
      CHECK(Ours(y, x) == expected);
      CHECK(OursPrepared(x, y) == expected);
      CHECK(OursPrepared(y, x) == expected);
    }
}

// ---- random pairs against CGAL ----

float Nudge(float x, int ulps) {
  for (; ulps > 0; --ulps) x = std::nextafter(x, std::numeric_limits<float>::infinity());
  for (; ulps < 0; ++ulps) x = std::nextafter(x, -std::numeric_limits<float>::infinity());
  return x;
}

struct Tally {
  uint64_t pairs = 0, intersecting = 0, disjoint = 0, degenerate = 0, needed_exact = 0, exact_evaluations = 0;
  uint64_t disagreements = 0;
  uint64_t filter_certified = 0, filter_deferred = 0;  // the prepared path's float filter, both directions
};

/// The exact side of t's vertices w.r.t. the plane of `plane_of` as the float filter reports it: +1 all
/// strictly positive, −1 all strictly negative, 0 otherwise (CGAL orientation, exact).
int ExactSide(const Tri& t, const Tri& plane_of) {
  auto p = [](const P3& v) { return K::Point_3(double(v[0]), double(v[1]), double(v[2])); };
  int pos = 0, neg = 0;
  for (const P3& v : t) {
    const CGAL::Orientation o = CGAL::orientation(p(plane_of[0]), p(plane_of[1]), p(plane_of[2]), p(v));
    pos += o == CGAL::POSITIVE;
    neg += o == CGAL::NEGATIVE;
  }
  return pos == 3 ? 1 : neg == 3 ? -1 : 0;
}

/// The float filter of prepared t against the plane of prepared `plane_of`: a certified side must be the
/// exact one (an uncertain 0 is always allowed). Tallies certified / deferred; false on a wrong sign.
bool FilterSound(const Tri& t, const rt::PreparedTriangle& pt, const Tri& plane_of, const rt::PreparedTriangle& pp,
                 Tally* tally) {
  const int side = rt::detail::FloatPlaneSide(pt, pp);
  (side != 0 ? tally->filter_certified : tally->filter_deferred) += 1;
  return side == 0 || side == ExactSide(t, plane_of);
}

/// Compares one pair with CGAL (both argument orders, and a vertex-permuted copy) and tallies it.
void Compare(const Tri& a, const Tri& b, std::mt19937& rng, Tally* tally) {
  ++tally->pairs;
  const K::Triangle_3 ca = ToCgal(a), cb = ToCgal(b);
  const bool deg_a = ca.is_degenerate(), deg_b = cb.is_degenerate();
  auto fail = [&](const char* what) {
    if (++tally->disagreements <= 20) {
      MESSAGE(what << ": " << Describe(a, b));
    }
  };
  if (OursDegenerate(a) != deg_a || OursDegenerate(b) != deg_b) fail("TriangleIsDegenerate != CGAL is_degenerate");
  bool usable_a = false, usable_b = false;
  const rt::PreparedTriangle pa = Prepared(a, &usable_a), pb = Prepared(b, &usable_b);
  if (usable_a == deg_a || usable_b == deg_b) fail("PrepareTriangle != !CGAL is_degenerate");
  if (deg_a || deg_b) {
    ++tally->degenerate;
    if (Ours(a, b) || Ours(b, a)) fail("degenerate triangle reported as intersecting");
    return;
  }
  const bool expected = CGAL::do_intersect(ca, cb);
  uint64_t exact = 0;
  const bool got = rt::detail::TrianglesIntersectCounted(a[0].data(), a[1].data(), a[2].data(), b[0].data(),
                                                         b[1].data(), b[2].data(), &exact);
  tally->needed_exact += exact != 0;
  tally->exact_evaluations += exact;
  (expected ? tally->intersecting : tally->disjoint) += 1;
  if (got != expected) fail(expected ? "missed intersection (CGAL: true)" : "false intersection (CGAL: false)");
  // The prepared path (float filter, then the same double filters and exact fallback), both orders.
  if (rt::TrianglesIntersect(pa, pb) != expected || rt::TrianglesIntersect(pb, pa) != expected)
    fail("prepared path != CGAL");
  uint64_t prepared_exact = 0;
  if (rt::detail::TrianglesIntersectCounted(pa, pb, &prepared_exact) != expected) fail("prepared path (counted) != CGAL");
  if (!FilterSound(a, pa, b, pb, tally) || !FilterSound(b, pb, a, pa, tally)) fail("float filter certified a wrong side");
  // Argument order and vertex order (rotation + reflection) must not matter.
  const int r = int(rng() % 3), m = int(rng() % 2);
  const Tri permuted_a = {a[r], a[(r + 1 + m) % 3], a[(r + 2 - m) % 3]};
  const Tri permuted_b = {b[(r + 2) % 3], b[(r + 1) % 3], b[r]};
  if (Ours(b, a) != expected || Ours(permuted_a, permuted_b) != expected || Ours(permuted_b, permuted_a) != expected ||
      OursPrepared(permuted_a, permuted_b) != expected)
    fail("answer depends on argument or vertex order");
}

void Report(const char* name, const Tally& t) {
  const uint64_t tested = t.pairs - t.degenerate;
  MESSAGE(std::string(name) << ": " << t.pairs << " pairs, " << t.intersecting << " intersecting, " << t.disjoint
                            << " disjoint, " << t.degenerate
                            << " with a degenerate triangle (false, skipped vs CGAL); exact fallback in "
                            << t.needed_exact << " of " << tested << " tests ("
                            << (tested ? 100.0 * double(t.needed_exact) / double(tested) : 0.0) << "%), "
                            << t.exact_evaluations << " exact orientations; prepared float filter: "
                            << t.filter_certified << " sides certified, " << t.filter_deferred << " deferred");
  CHECK_MESSAGE(t.disagreements == 0, std::string(name) << ": " << t.disagreements << " disagreements with CGAL");
}

/// The (x, y) of t's vertices embedded in the plane z = c (plane 0), y = x (1) or z = −2y (2): exactly
/// coplanar float triangles, where the 2D path and its orient2d run on the (possibly inexact) doubles.
Tri Embed(const Tri& t, int plane, float c) {
  Tri out;
  for (int v = 0; v < 3; ++v) {
    const float x = t[v][0], y = t[v][1];
    out[v] = plane == 0 ? P3{x, y, c} : plane == 1 ? P3{x, x, y} : P3{x, y, -2.0f * y};
  }
  return out;
}

constexpr int kPairsPerCategory = 40000;

/// ±m·2^e with m in [1, 2) of 1 to 24 mantissa bits.
float ScaledFloat(std::mt19937& rng, int e) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const int nb = std::uniform_int_distribution<int>(1, 24)(rng);
  const float m = std::ldexp(std::round(std::ldexp(1.0f + unit(rng), nb)), -nb);
  return (rng() % 2 ? -1.0f : 1.0f) * std::ldexp(m, e);
}

/// The pattern of a fuzzed bind pose: s·(1, 4, 16) with s = ScaledFloat at 2^−140..2^122 (on one ray through
/// the origin where the products are exact, denormals where they are not).
P3 RayPoint(std::mt19937& rng) {
  const float s = ScaledFloat(rng, std::uniform_int_distribution<int>(-140, 122)(rng));
  return P3{s, 4.0f * s, 16.0f * s};
}

/// A mesh-like point: coordinates k/10, k in −9..9.
P3 MeshPoint(std::mt19937& rng) {
  std::uniform_int_distribution<int> tenth(-9, 9);
  return P3{float(tenth(rng)) / 10, float(tenth(rng)) / 10, float(tenth(rng)) / 10};
}

/// Coordinates 1e-30..1e30 (and 1 + 1 ulp): differences of these are often inexact in double.
constexpr float kWidePalette[] = {0.0f,       1e-30f, -1e-30f, 3e-8f, 1.0f,  -1.0f,
                                  1.0000001f, 2.5f,   1e8f,    -1e8f, 1e30f, -1e30f};

}  // namespace

TEST_CASE("triangle_intersect: hand cases with known answers") {
  const Tri base = T({0, 0, 0}, {4, 0, 0}, {0, 4, 0});  // in z = 0

  SUBCASE("crossing: a vertical triangle pierces the base") {
    Expect(base, T({1, 1, -1}, {1, 1, 1}, {2, 0.5f, 1}), true);
  }
  SUBCASE("separated: above the base, not parallel") { Expect(base, T({1, 1, 1}, {2, 1, 3}, {1, 2, 2}), false); }
  SUBCASE("separated: the other's plane crosses the triangle but outside") {
    Expect(base, T({5, 5, -1}, {5, 5, 1}, {6, 5, 0}), false);
  }
  SUBCASE("parallel planes") { Expect(base, T({0, 0, 1}, {4, 0, 1}, {0, 4, 1}), false); }
  SUBCASE("touching at a vertex (vertex to vertex)") { Expect(base, T({4, 0, 0}, {5, 1, 1}, {5, 0, 2}), true); }
  SUBCASE("touching: a vertex on the other's interior") { Expect(base, T({1, 1, 0}, {1, 1, 2}, {2, 1, 2}), true); }
  SUBCASE("sharing an edge (hinge, not coplanar)") { Expect(base, T({0, 0, 0}, {4, 0, 0}, {2, 0, 3}), true); }
  SUBCASE("a vertex on the other's edge interior") { Expect(base, T({2, 0, 0}, {2, -1, 1}, {3, -1, 2}), true); }
  SUBCASE("edge crossing edge (skew edges meeting in one point)") {
    Expect(base, T({2, -1, -1}, {2, 1, 1}, {2, -3, 1}), true);
  }
  SUBCASE("just missing an edge by one float step") {
    Expect(base, T({2, Nudge(0, -1), 0}, {2, -1, 1}, {3, -1, 2}), false);
  }
  SUBCASE("coplanar overlapping") { Expect(base, T({1, 1, 0}, {5, 1, 0}, {1, 5, 0}), true); }
  SUBCASE("coplanar disjoint") { Expect(base, T({3, 3, 0}, {6, 3, 0}, {3, 6, 0}), false); }
  SUBCASE("coplanar disjoint, bounding boxes overlap") { Expect(base, T({4, 4, 0}, {1, 4, 0}, {4, 1, 0}), false); }
  SUBCASE("coplanar nested") { Expect(base, T({0.5f, 0.5f, 0}, {1.5f, 0.5f, 0}, {0.5f, 1.5f, 0}), true); }
  SUBCASE("coplanar touching along an edge") { Expect(base, T({4, 0, 0}, {0, 4, 0}, {4, 4, 0}), true); }
  SUBCASE("coplanar touching at a vertex") { Expect(base, T({4, 0, 0}, {6, 0, 0}, {5, -2, 0}), true); }
  SUBCASE("coplanar, a vertex on the other's edge") { Expect(base, T({2, 2, 0}, {4, 4, 0}, {3, 5, 0}), true); }
  SUBCASE("coplanar star of David (no vertex inside the other)") {
    Expect(T({0, 0, 0}, {6, 0, 0}, {3, 6, 0}), T({0, 4, 0}, {6, 4, 0}, {3, -2, 0}), true);
  }
  SUBCASE("coplanar in a tilted plane x + y + z = 3") {
    Expect(T({3, 0, 0}, {0, 3, 0}, {0, 0, 3}), T({1, 1, 1}, {2, 1, 0}, {1, 2, 0}), true);
    Expect(T({3, 0, 0}, {0, 3, 0}, {0, 0, 3}), T({4, 0, -1}, {5, -1, -1}, {4, -2, 1}), false);
  }
  SUBCASE("identical triangles") { Expect(base, base, true); }

  SUBCASE("degenerate triangles: false, and TriangleIsDegenerate") {
    const Tri segment = T({1, 1, -1}, {1, 1, 1}, {1, 1, 0});   // collinear, crosses the base
    const Tri point = T({1, 1, 0}, {1, 1, 0}, {1, 1, 0});      // a point inside the base
    const Tri repeated = T({1, 1, -1}, {1, 1, 1}, {1, 1, 1});  // two equal vertices
    CHECK(rt::TriangleIsDegenerate(segment[0].data(), segment[1].data(), segment[2].data()));
    CHECK(rt::TriangleIsDegenerate(point[0].data(), point[1].data(), point[2].data()));
    CHECK(rt::TriangleIsDegenerate(repeated[0].data(), repeated[1].data(), repeated[2].data()));
    CHECK_FALSE(rt::TriangleIsDegenerate(base[0].data(), base[1].data(), base[2].data()));
    Expect(base, segment, false);
    Expect(base, point, false);
    Expect(base, repeated, false);
    Expect(segment, segment, false);
    // A sliver one float step away from collinear is not degenerate, and is tested.
    const Tri sliver = T({1, 1, -1}, {1, 1, 1}, {1, Nudge(1, 1), 0});
    CHECK_FALSE(rt::TriangleIsDegenerate(sliver[0].data(), sliver[1].data(), sliver[2].data()));
    Expect(base, sliver, true);
  }

  SUBCASE("non-finite coordinates: false, no crash") {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (float bad : {nan, inf, -inf}) {
      for (int v = 0; v < 3; ++v)
        for (int c = 0; c < 3; ++c) {
          Tri t = base;
          t[v][c] = bad;
          CHECK_FALSE(Ours(t, base));
          CHECK_FALSE(Ours(base, t));
          CHECK_FALSE(rt::TriangleIsDegenerate(t[0].data(), t[1].data(), t[2].data()));
        }
    }
  }

  SUBCASE("extreme magnitudes stay exact") {
    const float big = std::numeric_limits<float>::max(), tiny = std::numeric_limits<float>::denorm_min();
    Expect(T({-big, -big, 0}, {big, -big, 0}, {0, big, 0}), T({0, 0, -big}, {0, 0, big}, {tiny, 0, 0}), true);
    Expect(T({0, 0, 0}, {tiny, 0, 0}, {0, tiny, 0}), T({tiny, tiny, -tiny}, {tiny, tiny, tiny}, {2 * tiny, 0, 0}),
           false);
    Expect(T({0, 0, 0}, {2 * tiny, 0, 0}, {0, 2 * tiny, 0}), T({tiny, tiny, -tiny}, {tiny, tiny, tiny}, {0, 0, tiny}),
           true);
  }
}

TEST_CASE("heavy: triangle_intersect: agrees with CGAL exact do_intersect on random hard pairs") {
  std::mt19937 rng(20240611u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> grid(0, 4), ulp(-2, 2), pick(0, 8);
  auto random_tri = [&](auto&& coord) {
    Tri t;
    for (auto& v : t)
      for (float& c : v) c = coord();
    return t;
  };
  auto nudged = [&](P3 v) {
    for (float& c : v) c = Nudge(c, ulp(rng));
    return v;
  };
  // A point of the plane of t (a + s(b − a) + u(c − a), rounded to float, so only near the plane).
  auto near_plane = [&](const Tri& t, float s, float u) {
    P3 out;
    for (int k = 0; k < 3; ++k) out[k] = t[0][k] + s * (t[1][k] - t[0][k]) + u * (t[2][k] - t[0][k]);
    return out;
  };
  std::uniform_real_distribution<float> coef(-1.0f, 2.0f);
  // 2·q − p in float (exact when representable: then p, q and the result are collinear) and q + 1e-10·u:
  // with mixed scales these make products of inexact differences cancel, where plain double signs fail.
  auto reflect = [](const P3& p, const P3& q) { return P3{2 * q[0] - p[0], 2 * q[1] - p[1], 2 * q[2] - p[2]}; };
  auto offset = [&](P3 q) {
    for (float& c : q) c += 1e-10f * (unit(rng) - 0.5f);
    return q;
  };
  // Mixed scales: a random sign, 1..24 mantissa bits, exponent spread over up to 2^±60.
  std::uniform_int_distribution<int> mantissa_bits(1, 24), exponent(-60, 60), spread(1, 4);
  auto mixed_coord = [&] {
    const int nb = mantissa_bits(rng);
    const float m = std::ldexp(std::round(std::ldexp(1.0f + unit(rng), nb)), -nb);
    return (rng() % 2 ? -1.0f : 1.0f) * std::ldexp(m, exponent(rng) / spread(rng));
  };
  // A second triangle made from the first: shared / nudged vertex or edge, near-coplanar, vertex on edge.
  auto hard_partner = [&](const Tri& a, auto&& coord) {
    Tri b;
    switch (pick(rng)) {
      case 0:  // the same triangle, every coordinate nudged by up to ±2 ulps
        b = {nudged(a[0]), nudged(a[1]), nudged(a[2])};
        break;
      case 1:  // sharing an edge (maybe nudged), third vertex near the plane or anywhere
        b = {rng() % 2 ? a[0] : nudged(a[0]), a[1],
             rng() % 2 ? near_plane(a, coef(rng), coef(rng)) : random_tri(coord)[0]};
        break;
      case 2:  // sharing a vertex, the others near the plane
        b = {a[0], nudged(near_plane(a, coef(rng), coef(rng))), near_plane(a, coef(rng), coef(rng))};
        break;
      case 3:  // a vertex on (near) an edge, crossing or touching
        b = {nudged(near_plane(a, unit(rng), 0.0f)), random_tri(coord)[0], random_tri(coord)[1]};
        break;
      case 4:  // near-coplanar, overlapping or not
        b = {near_plane(a, coef(rng), coef(rng)), nudged(near_plane(a, coef(rng), coef(rng))),
             near_plane(a, coef(rng), coef(rng))};
        break;
      case 5:  // a vertex exactly at a vertex, through the other's plane
        b = {a[2], random_tri(coord)[0], nudged(random_tri(coord)[1])};
        break;
      case 6:  // a sliver along an edge (near-collinear, often exactly degenerate), crossing or touching it
        b = {near_plane(a, coef(rng), 0.0f), nudged(near_plane(a, coef(rng), 0.0f)), near_plane(a, coef(rng), 0.0f)};
        break;
      case 7:  // reflections 2·q − p (nearly through a vertex, exactly when representable) and a near-copy of q
        b = {reflect(a[0], a[1]), offset(a[1]), rng() % 2 ? reflect(a[1], a[2]) : random_tri(coord)[0]};
        break;
      default:  // a sliver (p, q, 2·q − p) near the first triangle: degenerate or one rounding away from it
        b = {a[0], offset(a[1]), reflect(a[0], a[1])};
        break;
    }
    return b;
  };

  Tally uniform, snapped, near_degenerate, large, wide, coplanar, mixed;
  std::uniform_int_distribution<int> palette(0, int(std::size(kWidePalette)) - 1);
  auto wide_coord = [&] { return kWidePalette[palette(rng)]; };
  auto unit_coord = [&] { return unit(rng); };
  auto grid_coord = [&] { return float(grid(rng)); };
  for (int i = 0; i < kPairsPerCategory; ++i) {
    // (a) uniform floats in the unit cube
    Compare(random_tri(unit_coord), random_tri(unit_coord), rng, &uniform);
    // (b) the integer grid {0..4}^3: coplanar, touching, shared vertices, collinear (degenerate) abound
    Compare(random_tri(grid_coord), random_tri(grid_coord), rng, &snapped);
    // (c) near-degenerate partners of a unit-cube triangle (or of a grid triangle, every other pair)
    {
      const Tri a = i % 2 ? random_tri(unit_coord) : random_tri(grid_coord);
      Compare(a, i % 2 ? hard_partner(a, unit_coord) : hard_partner(a, grid_coord), rng, &near_degenerate);
    }
    // (d) large magnitude, tiny differences: 1000 + [0, 0.01) (≈160 floats per axis) or 1000 + k·ulp(1000),
    //     alone or with a hard partner
    {
      const float ulp1000 = Nudge(1000.0f, 1) - 1000.0f;
      auto big_coord = [&] { return 1000.0f + 0.01f * unit(rng); };
      auto big_grid = [&] { return 1000.0f + ulp1000 * float(grid(rng)); };
      const Tri a = i % 2 ? random_tri(big_coord) : random_tri(big_grid);
      Compare(a, i % 4 < 2 ? hard_partner(a, big_coord) : (i % 2 ? random_tri(big_coord) : random_tri(big_grid)), rng,
              &large);
    }
    // (e) wide exponent range: coordinates from a small palette spanning 1e-30..1e30 (so coincidences
    //     happen), where differences are not exact in double and the expansions carry two components
    {
      const Tri a = random_tri(wide_coord);
      Compare(a, i % 2 ? hard_partner(a, wide_coord) : random_tri(wide_coord), rng, &wide);
    }
    // (f) exactly coplanar: unit, grid, wide-palette or mixed-scale coordinates, a hard partner (in the plane)
    //     or random
    {
      const int kind = i % 4;
      auto coord = [&] {
        return kind == 0 ? unit(rng) : kind == 1 ? float(grid(rng)) : kind == 2 ? wide_coord() : mixed_coord();
      };
      Tri a = random_tri(coord), b = i % 4 < 3 ? hard_partner(a, coord) : random_tri(coord);
      for (Tri* t : {&a, &b})
        for (P3& v : *t) v[2] = 0.0f;  // hard_partner's near-plane points are in z = 0: flatten the rest
      const int plane = int(rng() % 3);
      const float c = unit(rng);
      Compare(Embed(a, plane, c), Embed(b, plane, c), rng, &coplanar);
    }
    // (g) mixed scales (2^±60, few or many mantissa bits) with a hard partner, every other pair
    {
      const Tri a = random_tri(mixed_coord);
      Compare(a, i % 2 ? hard_partner(a, mixed_coord) : random_tri(mixed_coord), rng, &mixed);
    }
  }
  Report("(a) uniform unit cube", uniform);
  Report("(b) integer grid {0..4}", snapped);
  Report("(c) near-degenerate partners (shared/nudged vertex or edge, near-coplanar)", near_degenerate);
  Report("(d) 1000 + tiny differences", large);
  Report("(e) wide exponent range 1e-30..1e30", wide);
  Report("(f) exactly coplanar (z = c, y = x, z = -2y)", coplanar);
  Report("(g) mixed scales 2^-60..2^60", mixed);
  // Every category must exercise both answers (otherwise it tests nothing).
  for (const Tally* t : {&uniform, &snapped, &near_degenerate, &large, &wide, &coplanar, &mixed}) {
    CHECK(t->intersecting > 100);
    CHECK(t->disjoint > 100);
  }
  CHECK(snapped.degenerate > 100);
}

TEST_CASE("heavy: triangle_intersect: agrees with CGAL where plain double orientations get the sign wrong") {
  // Mixed scales make coordinate differences inexact in double; then the naive orient2d can return 0 for
  // a non-zero determinant, a non-zero for zero, or even the opposite sign. These cases are selected so
  // that the answer hinges on exactly such a determinant.
  std::mt19937 rng(20240612u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> mantissa_bits(1, 24), exponent(-30, 30), gap(20, 59);
  auto scaled = [&](int e) {
    const int nb = mantissa_bits(rng);
    const float m = std::ldexp(std::round(std::ldexp(1.0f + unit(rng), nb)), -nb);
    return (rng() % 2 ? -1.0f : 1.0f) * std::ldexp(m, e);
  };

  SUBCASE("coplanar: a vertex at the float midpoint of an edge, decided by one orient2d") {
    // A big, B tiny, C = 2B − A (B is the midpoint of AC when C is exact). T1 = (A, C, P) lies left of
    // AC; T2 = (B, B − N, B − N + (C − A)/4) right of it: they meet iff B is on the closed left side of
    // AC. Kept only when the naive double orient2d(A, C, B) differs from the exact sign (CGAL).
    Tally tally;
    uint64_t opposite = 0;
    int kept = 0;
    for (int tries = 0; kept < 5000 && tries < 20000000; ++tries) {
      const int e = exponent(rng), g = gap(rng);
      float a[2], b[2], c[2];
      for (int k = 0; k < 2; ++k) {
        a[k] = scaled(e + int(rng() % 3));
        b[k] = scaled(e - g + int(rng() % 3));
        c[k] = 2 * b[k] - a[k];
      }
      const double det = (double(c[0]) - a[0]) * (double(b[1]) - a[1]) - (double(c[1]) - a[1]) * (double(b[0]) - a[0]);
      const int naive = (det > 0) - (det < 0);
      const int exact = int(CGAL::orientation(K::Point_2(a[0], a[1]), K::Point_2(c[0], c[1]), K::Point_2(b[0], b[1])));
      if (naive == exact) continue;
      ++kept;
      opposite += naive == -exact;
      const float nx = -(c[1] - a[1]), ny = c[0] - a[0];  // left normal of AC
      const Tri t1 = {P3{a[0], a[1], 0}, P3{c[0], c[1], 0}, P3{b[0] + nx, b[1] + ny, 0}};
      const Tri t2 = {P3{b[0], b[1], 0}, P3{b[0] - nx, b[1] - ny, 0},
                      P3{b[0] - nx + 0.25f * (c[0] - a[0]), b[1] - ny + 0.25f * (c[1] - a[1]), 0}};
      const int plane = int(rng() % 2);  // z = c or y = x: the projection keeps (x, y) or (y, z) = (x, y)
      const float z = unit(rng);
      Compare(Embed(t1, plane, z), Embed(t2, plane, z), rng, &tally);
    }
    Report("(h) coplanar, vertex at an edge midpoint, naive orient2d wrong", tally);
    MESSAGE("(h) of which the naive sign was the opposite one (not 0 vs non-zero): " << opposite);
    CHECK(kept == 5000);
    CHECK(tally.intersecting > 100);
    CHECK(tally.disjoint > 100);
  }

  SUBCASE("exactly collinear triples with inexact differences are degenerate") {
    // (a, b, a + k(b − a)) with k = 3 or −2 rounded to float at mixed scales, kept when exactly collinear
    // (CGAL): degenerate, so false against a triangle through two of its points.
    Tally tally;
    int kept = 0;
    for (int tries = 0; kept < 5000 && tries < 20000000; ++tries) {
      const int e = exponent(rng), g = gap(rng) / 2;
      const float k = rng() % 2 ? 3.0f : -2.0f;
      Tri t;
      for (int i = 0; i < 3; ++i) {
        t[0][i] = scaled(e + int(rng() % 3));
        t[1][i] = scaled(e - g + int(rng() % 3));
        t[2][i] = t[0][i] + k * (t[1][i] - t[0][i]);
      }
      if (!ToCgal(t).is_degenerate()) continue;
      ++kept;
      const Tri other = {P3{unit(rng), unit(rng), unit(rng)}, t[0], t[2]};
      Compare(t, other, rng, &tally);
    }
    Report("(i) exactly collinear triples at mixed scales (degenerate)", tally);
    CHECK(kept == 5000);
    CHECK(tally.degenerate == uint64_t(kept));
  }
}

TEST_CASE("heavy: triangle_intersect: agrees with CGAL on points along one ray over the whole float range") {
  // The pattern of a fuzzed bind pose: vertices s·(1, 4, 16) for s = ±m·2^e, e from −140 to 122 (collinear
  // with the origin where the products are exact, denormals where they are not), beside mesh-like points
  // k/10. Orientations mixing 1e-40 and 1e36 cancel far below double's rounding of the differences: the
  // adaptive stages of the exact orient3d (certified with ε² bounds) and the full expansions decide them.
  std::mt19937 rng(20261126u);
  auto vertex = [&] { return rng() % 2 ? RayPoint(rng) : MeshPoint(rng); };
  Tally tally;
  for (int i = 0; i < kPairsPerCategory; ++i) {
    const Tri a = {vertex(), vertex(), vertex()};
    Tri b = {vertex(), vertex(), vertex()};
    if (i % 2) b[0] = a[int(rng() % 3)];  // sharing a vertex: touching at least, when neither is degenerate
    Compare(a, b, rng, &tally);
  }
  Report("(j) points along one ray, 2^-140..2^122, beside mesh points", tally);
  CHECK(tally.intersecting > 100);
  CHECK(tally.disjoint > 100);
  CHECK(tally.needed_exact > 1000);
}

TEST_CASE("heavy: triangle_intersect: each stage of the exact orientation agrees with the full expansions and CGAL") {
  // Near-degenerate orientations at mixed magnitudes, where the error-free double stage fails and the
  // adaptive stages (rounded differences, then their tail correction) must decide or pass on: every sign
  // equals the full expansions' and CGAL's, and each stage decides a share of the cases.
  std::mt19937 rng(20261127u);
  std::uniform_real_distribution<float> coef(-1.0f, 2.0f);
  std::uniform_int_distribution<int> exponent(-60, 60), spread(1, 4);
  auto mixed_coord = [&] { return ScaledFloat(rng, exponent(rng) / spread(rng)); };
  uint64_t decided[4] = {0, 0, 0, 0};
  for (int i = 0; i < 4 * kPairsPerCategory; ++i) {
    std::array<P3, 4> p;
    if (i % 2) {  // the fuzzed bind pose's pattern: points along one ray beside mesh points
      for (P3& v : p) v = rng() % 2 ? RayPoint(rng) : MeshPoint(rng);
    } else {  // d near the plane of (a, b, c), rounded to float, at mixed scales
      for (int v = 0; v < 3; ++v) p[v] = {mixed_coord(), mixed_coord(), mixed_coord()};
      const float s = coef(rng), t = coef(rng);
      for (int k = 0; k < 3; ++k) p[3][k] = p[0][k] + s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[0][k]);
      if (!std::isfinite(p[3][0]) || !std::isfinite(p[3][1]) || !std::isfinite(p[3][2])) continue;
    }
    int stage = -1;
    const int ours = rt::detail::ExactOrientation(p[0].data(), p[1].data(), p[2].data(), p[3].data(), &stage);
    REQUIRE((stage >= 0 && stage <= 3));
    ++decided[stage];
    const int full = rt::detail::ExpansionOrientation(p[0].data(), p[1].data(), p[2].data(), p[3].data());
    auto point = [](const P3& v) { return K::Point_3(double(v[0]), double(v[1]), double(v[2])); };
    const int cgal = int(CGAL::orientation(point(p[0]), point(p[1]), point(p[2]), point(p[3])));
    if (ours != full || full != cgal) {
      CAPTURE(stage);
      CAPTURE(Describe({p[0], p[1], p[2]}, {p[3], p[3], p[3]}));
      CHECK(ours == cgal);
      CHECK(full == cgal);
    }
  }
  MESSAGE("exact orientation decided by stage: error-free " << decided[0] << ", rounded differences " << decided[1]
                                                          << ", tail correction " << decided[2] << ", expansions "
                                                          << decided[3]);
  for (uint64_t n : decided) CHECK(n > 100);
}

TEST_CASE("heavy: triangle_intersect: the prepared float filter certifies only exact sides, a hair off the plane too") {
  // The semi-static float filter of TrianglesIntersect(PreparedTriangle, PreparedTriangle) certifies a
  // side when n_f · x − δ_f is beyond its error bound. A bound too small would certify a wrong side for
  // vertices very close to the other plane: here the second triangle's vertices sit on the first one's
  // plane (rounded to float), or 1e-13..1e-1 triangle sizes off it, on one side or both, at character
  // scale (|x| ≤ 20, triangles 1e-3..1 across: the narrow phase's workload) and at large offsets up to
  // and beyond the filter's live range (2^40). Every side the filter certifies is compared with CGAL's
  // exact orientation of each vertex (Compare: FilterSound), every answer with CGAL's do_intersect (the
  // prepared path then also runs its float-filtered interval test); the interval test's float
  // orientation filter is checked alone the same way.
  std::mt19937 rng(20240613u);
  std::uniform_real_distribution<double> unit(0.0, 1.0), coef(-0.5, 1.5);
  constexpr double kCentres[] = {1.0, 20.0, 1000.0, 1e6, 1e11, 3e12};  // 3e12 > 2^40: filter off
  Tally body, offset;
  for (int i = 0; i < 60000; ++i) {
    const bool far = i % 4 == 3;
    const double centre_scale = far ? kCentres[2 + rng() % 4] : kCentres[rng() % 2];
    const double size = std::pow(10.0, -3.0 + 3.0 * unit(rng)) * (far ? centre_scale * 1e-3 : 1.0);
    double centre[3], corner[3][3];
    for (double& c : centre) c = centre_scale * (2.0 * unit(rng) - 1.0);
    Tri a;
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) a[v][k] = float(centre[k] + size * (2.0 * unit(rng) - 1.0));
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) corner[v][k] = double(a[v][k]);
    double u[3], w[3], n[3];
    for (int k = 0; k < 3; ++k) u[k] = corner[1][k] - corner[0][k], w[k] = corner[2][k] - corner[0][k];
    n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
    const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(norm > 0)) continue;
    // Off the plane by d (0: on it, up to float rounding), the same side for all three vertices half the
    // time (then the exact answer is "one side" and the filter may certify it), mixed otherwise.
    const int kind = int(rng() % 8);
    const double d = kind == 0 ? 0.0 : size * std::pow(10.0, -13.0 + 12.0 * unit(rng));
    const bool same_side = rng() % 2;
    const double side0 = rng() % 2 ? 1.0 : -1.0;
    Tri b;
    for (int v = 0; v < 3; ++v) {
      const double s = coef(rng), t = coef(rng);
      const double sign = same_side ? side0 : (rng() % 2 ? 1.0 : -1.0);
      for (int k = 0; k < 3; ++k) b[v][k] = float(corner[0][k] + s * u[k] + t * w[k] + sign * d * n[k] / norm);
      if (rng() % 4 == 0) b[v][rng() % 3] = Nudge(b[v][rng() % 3], int(rng() % 5) - 2);
    }
    Compare(a, b, rng, far ? &offset : &body);
  }
  // The interval test's float orientation filter alone: the fourth point on or a hair off the plane of
  // the first three, at the same scales; a certified sign must be CGAL's.
  uint64_t orient_certified = 0, orient_deferred = 0, orient_wrong = 0;
  for (int i = 0; i < 100000; ++i) {
    const double centre_scale = kCentres[rng() % 6], size = std::pow(10.0, -3.0 + 3.0 * unit(rng)) *
                                                            (centre_scale > 20.0 ? centre_scale * 1e-3 : 1.0);
    P3 q[4];
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) q[v][k] = float(centre_scale * 0.5 + size * (2.0 * unit(rng) - 1.0));
    const double d = i % 8 == 0 ? 0.0 : size * std::pow(10.0, -13.0 + 12.0 * unit(rng));
    double u[3], w[3], n[3];
    for (int k = 0; k < 3; ++k) u[k] = double(q[1][k]) - q[0][k], w[k] = double(q[2][k]) - q[0][k];
    n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
    const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(norm > 0)) continue;
    const double s = coef(rng), t = coef(rng), sign = rng() % 2 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) q[3][k] = float(double(q[0][k]) + s * u[k] + t * w[k] + sign * d * n[k] / norm);
    const int got = rt::detail::FloatOrientation(q[0].data(), q[1].data(), q[2].data(), q[3].data());
    auto p3 = [](const P3& v) { return K::Point_3(double(v[0]), double(v[1]), double(v[2])); };
    const int exact = int(CGAL::orientation(p3(q[0]), p3(q[1]), p3(q[2]), p3(q[3])));
    (got != 0 ? orient_certified : orient_deferred) += 1;
    if (got != 0 && got != exact && ++orient_wrong <= 10) MESSAGE("float orientation wrong: " << got << " vs " << exact);
  }
  MESSAGE("(l) float orientation filter: " << orient_certified << " certified, " << orient_deferred << " deferred, "
                                            << orient_wrong << " wrong");
  CHECK(orient_wrong == 0);
  CHECK(orient_certified > 1000);
  CHECK(orient_deferred > 1000);
  Report("(j) character scale, vertices on or a hair off the other plane", body);
  Report("(k) offsets 1e3..3e12 (beyond 2^40 the float filter is off), vertices a hair off the plane", offset);
  // The boundary is exercised: the filter both certifies and defers, and the answers go both ways.
  for (const Tally* t : {&body, &offset}) {
    CHECK(t->filter_certified > 1000);
    CHECK(t->filter_deferred > 1000);
    CHECK(t->intersecting > 100);
    CHECK(t->disjoint > 100);
  }
}
