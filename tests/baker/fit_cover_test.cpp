// The cover fit (FitCover) on shapes with known answers, the bind-geometry exclusions, and the
// MakeHuman bake with its schema v2 asset through the runtime (contact margin).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "spherechain/baker/bake.h"
#include "spherechain/baker/chains.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/baker/fit.h"
#include "spherechain/runtime/runtime.h"
#include "test_data.h"

namespace sb = spherechain::baker;
namespace rt = spherechain::runtime;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Closed tube along +Y (end caps fanned from their centres), cross-section (a cos θ, b sin θ) in XZ.
sb::Mesh ClosedTube(double a, double b, double length, int n_around, int n_along) {
  sb::Mesh m;
  for (int j = 0; j <= n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const double th = 2.0 * kPi * i / n_around;
      m.positions.insert(m.positions.end(), {float(a * std::cos(th)), float(length * j / n_along), float(b * std::sin(th))});
    }
  for (int j = 0; j < n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const uint32_t v0 = j * n_around + i, v1 = j * n_around + (i + 1) % n_around;
      const uint32_t v2 = v1 + n_around, v3 = v0 + n_around;
      for (uint32_t v : {v0, v2, v1, v0, v3, v2}) m.indices.push_back(v);
    }
  const uint32_t bottom = m.vertex_count(), top = bottom + 1;
  m.positions.insert(m.positions.end(), {0.f, 0.f, 0.f, 0.f, float(length), 0.f});
  const uint32_t last = uint32_t(n_along) * n_around;
  for (int i = 0; i < n_around; ++i) {
    const uint32_t i1 = (i + 1) % n_around;
    for (uint32_t v : {bottom, uint32_t(i), i1}) m.indices.push_back(v);
    for (uint32_t v : {top, last + i1, last + uint32_t(i)}) m.indices.push_back(v);
  }
  m.up_axis = sb::UpAxis::kY;
  return m;
}

sb::Segmentation AllTorso(const sb::Mesh& m) {
  sb::Segmentation seg;
  seg.triangle_regions.assign(m.triangle_count(), uint8_t(sb::Region::kTorso));
  return seg;
}

double Coverage(const sb::Mesh& m, const std::vector<sb::FittedSphere>& spheres, double* protrusion = nullptr) {
  std::vector<sb::Ball> balls;
  for (const auto& s : spheres) balls.push_back({s.center, s.radius});
  auto c = sb::MeasureCoverage(m.positions, m.indices, balls);
  REQUIRE(c.ok());
  if (protrusion) *protrusion = c->protrusion;
  return c->coverage;
}

}  // namespace

TEST_CASE("heavy: fit cover: a cylinder is filled to >= 95 % with no sphere outside it") {
  // Long enough that the flat caps' rims (which no inscribed ball reaches) weigh little.
  const double R = 1.0, L = 24.0;
  const sb::Mesh m = ClosedTube(R, R, L, 96, 96);
  sb::FitParams p;
  p.dilation_rel = 0.0;
  p.max_spheres = 64;
  auto fit = sb::FitCover(m, AllTorso(m), p);
  REQUIRE_MESSAGE(fit.ok(), (fit.ok() ? "" : fit.error().message));
  const auto& sp = fit.value();
  REQUIRE(sp.size() >= 6);
  // Inscribed: every sphere inside the (polygonal) cylinder — the distance to the axis plus the radius
  // within R, the caps not crossed (the 96-gon's inradius is R cos(π/96)).
  const double inradius = R * std::cos(kPi / 96);
  for (const auto& s : sp) {
    double worst = -1.0;  // max over the prism's side faces of (c · n_k + r − inradius)
    for (int k = 0; k < 96; ++k) {
      const double th = 2.0 * kPi * (k + 0.5) / 96;
      worst = std::max(worst, s.center.x() * std::cos(th) + s.center.z() * std::sin(th) + s.radius - inradius);
    }
    CHECK(worst <= 1e-5);
    CHECK(s.center.y() - s.radius >= -1e-6);
    CHECK(s.center.y() + s.radius <= L + 1e-6);
    CHECK(s.region == sb::Region::kTorso);
  }
  double protrusion = 1.0;
  const double cov = Coverage(m, sp, &protrusion);
  MESSAGE("cylinder R=1 L=24: " << sp.size() << " spheres, coverage " << cov << ", protrusion " << protrusion);
  CHECK(cov >= 0.95);
  CHECK(protrusion <= 0.01);  // voxel sampling of the surface only
}

TEST_CASE("heavy: fit cover: a flat (elliptic) torso — two spheres a level miss the coverage target, the cover fit meets it") {
  const double a = 2.0, b = 1.0, H = 16.0;
  const sb::Mesh m = ClosedTube(a, b, H, 96, 96);
  const sb::Segmentation seg = AllTorso(m);
  std::vector<uint32_t> all(m.triangle_count());
  for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
  sb::FitParams paper;
  paper.disk_step = 0.25;
  auto disk = sb::FitTorso(m, all, seg, paper);
  REQUIRE(disk.ok());
  sb::FitParams cover;
  cover.dilation_rel = 0.0;
  cover.max_spheres = 128;
  auto filled = sb::FitCover(m, seg, cover);
  REQUIRE(filled.ok());
  const double c_paper = Coverage(m, disk.value()), c_cover = Coverage(m, filled.value());
  MESSAGE("elliptic torso a=2 b=1 H=16: paper " << disk->size() << " spheres " << c_paper << ", cover "
                                                 << filled->size() << " spheres " << c_cover);
  CHECK(c_paper < 0.90);
  CHECK(c_cover >= 0.90);
  for (const auto& s : filled.value()) {  // no sphere sticks out of the flat sides
    const double x = s.center.x(), z = s.center.z();
    CHECK(x * x / (a * a) + z * z / (b * b) < 1.0);
    CHECK(std::abs(z) + s.radius <= b + 1e-3);
  }
}

namespace {

/// Appends `part` moved by `offset` to `m`, its triangles in region `region` of `seg`.
void AppendPart(sb::Mesh* m, sb::Segmentation* seg, const sb::Mesh& part, const Vector3d& offset, sb::Region region) {
  const uint32_t base = m->vertex_count();
  for (uint32_t v = 0; v < part.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) m->positions.push_back(part.positions[3 * v + k] + float(offset[k]));
  for (uint32_t i : part.indices) m->indices.push_back(base + i);
  seg->triangle_regions.insert(seg->triangle_regions.end(), part.triangle_count(), uint8_t(region));
}

/// A torso (radius 1, 4 high, at the origin) and a left arm beside it (radius 0.3, 3 long, at x = 2.5), both
/// along +Y: the body the skin-pass tests hang their hands and fingers on.
void AppendTorsoAndArm(sb::Mesh* m, sb::Segmentation* seg) {
  AppendPart(m, seg, ClosedTube(1.0, 1.0, 4.0, 48, 32), Vector3d::Zero(), sb::Region::kTorso);
  AppendPart(m, seg, ClosedTube(0.3, 0.3, 3.0, 32, 24), Vector3d(2.5, 0.0, 0.0), sb::Region::kLeftArm);
}

/// Vertices of m[first, end) farther than `tol` outside every sphere of `region`.
size_t Uncovered(const sb::Mesh& m, uint32_t first, const std::vector<sb::FittedSphere>& spheres, sb::Region region, double tol) {
  size_t n = 0;
  for (uint32_t v = first; v < m.vertex_count(); ++v) {
    const Vector3d p(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
    double best = 1e300;
    for (const auto& s : spheres)
      if (s.region == region) best = std::min(best, (p - s.center).norm() - s.radius);
    n += best > tol;
  }
  return n;
}

}  // namespace

TEST_CASE("heavy: fit cover: the skin pass covers a thin hand the volume cover leaves bare") {
  // A torso (radius 1, 4 high), an arm beside it (radius 0.3, 3 long) and at its end a flat "hand"
  // (an elliptic plate 0.8 wide, 0.1 thick, 0.8 long): 0.4 % of the body's volume, so the volume
  // greedy gives it no sphere, while all its skin lies beyond the tolerance.
  sb::Mesh m;
  sb::Segmentation seg;
  AppendTorsoAndArm(&m, &seg);
  const uint32_t hand_first = m.vertex_count();
  AppendPart(&m, &seg, ClosedTube(0.4, 0.05, 0.8, 48, 16), Vector3d(2.5, 3.1, 0.0), sb::Region::kLeftArm);
  m.up_axis = sb::UpAxis::kY;
  const double height = 4.0, tol = 0.01 * height;

  sb::FitParams off;
  off.max_spheres = 160;
  off.skin_spheres = 0;
  off.cover_voxel_rel = 0.0075;  // voxels of 0.03, 3.3 across the plate (the default 1/200: 3.4x the voxels, 71 s)
  auto bare = sb::FitCover(m, seg, off);
  REQUIRE_MESSAGE(bare.ok(), (bare.ok() ? "" : bare.error().message));
  sb::FitParams on = off;
  on.skin_spheres = 140;
  on.skin_min_vertices = 1;
  auto skinned = sb::FitCover(m, seg, on);
  REQUIRE_MESSAGE(skinned.ok(), (skinned.ok() ? "" : skinned.error().message));
  const size_t hand_vertices = m.vertex_count() - hand_first;
  const size_t u_bare = Uncovered(m, hand_first, bare.value(), sb::Region::kLeftArm, tol),
               u_skin = Uncovered(m, hand_first, skinned.value(), sb::Region::kLeftArm, tol);
  MESSAGE("hand: " << hand_vertices << " vertices, beyond tolerance without the skin pass " << u_bare << " ("
                   << bare->size() << " spheres), with it " << u_skin << " (" << skinned->size() << " spheres)");
  // The volume cover leaves most of the hand bare (its greedy, refilling the places of redundant balls,
  // reaches part of the plate: 442 of 818 vertices stay bare).
  CHECK(u_bare * 2 >= hand_vertices);
  // With the skin pass all of it, the plate's knife edge too (thinner than a voxel: before the medial balls
  // no inner ball of at least one voxel brought the 148 vertices where the rim meets the end caps within
  // tolerance).
  CHECK(u_skin * 50 <= hand_vertices);
  CHECK(skinned->size() <= 160);
  // The spheres added sit in the hand and inside it (no sphere sticks out of a flat side by more than
  // the dilation).
  size_t in_hand = 0;
  for (const auto& s : skinned.value())
    if (s.center.x() > 2.0 && s.center.y() > 3.05) {
      ++in_hand;
      CHECK(s.region == sb::Region::kLeftArm);
      CHECK(std::abs(s.center.z()) + s.radius <= 0.05 + on.dilation_rel * height + 0.01);
    }
  CHECK(in_hand >= 2);
}

TEST_CASE("fit cover: the skin pass's medial balls follow fingers thinner than a voxel") {
  // A torso (radius 1, 4 high), an arm (radius 0.3, 3 long) and four fingers at its end: tubes of radius
  // 0.025, 0.6 long, their axes 0.12 apart. Voxels of 0.08 (cover_voxel_rel 0.02): a finger holds no
  // interior voxel, so no voxel ball can follow it; the medial ball behind each of its vertices is the
  // finger's own inscribed ball (radius 0.025, centre on its axis).
  sb::Mesh m;
  sb::Segmentation seg;
  AppendTorsoAndArm(&m, &seg);
  const uint32_t fingers_first = m.vertex_count();
  constexpr double kFingerR = 0.025, kSpacing = 0.12;
  const double finger_x0 = 2.5 - 1.5 * kSpacing;
  for (int f = 0; f < 4; ++f)
    AppendPart(&m, &seg, ClosedTube(kFingerR, kFingerR, 0.6, 16, 12), Vector3d(finger_x0 + f * kSpacing, 3.05, 0.0),
               sb::Region::kLeftArm);
  m.up_axis = sb::UpAxis::kY;
  const double height = 4.0, tol = 0.01 * height;
  sb::FitParams p;
  p.max_spheres = 96;
  p.skin_spheres = 48;
  p.skin_min_vertices = 1;
  p.cover_voxel_rel = 0.022;  // 0.08 voxels: 22,000 interior voxels, fast under ASan too

  sb::FitParams voxels_only = p;
  voxels_only.medial_min_rel = 1.0;  // no medial ball is that large: the voxel candidates alone
  auto bare = sb::FitCover(m, seg, voxels_only);
  REQUIRE_MESSAGE(bare.ok(), (bare.ok() ? "" : bare.error().message));
  auto fit = sb::FitCover(m, seg, p);
  REQUIRE_MESSAGE(fit.ok(), (fit.ok() ? "" : fit.error().message));

  const size_t finger_vertices = m.vertex_count() - fingers_first;
  const size_t u_bare = Uncovered(m, fingers_first, bare.value(), sb::Region::kLeftArm, tol),
               u_fit = Uncovered(m, fingers_first, fit.value(), sb::Region::kLeftArm, tol);
  MESSAGE("fingers: " << finger_vertices << " vertices beyond tolerance: voxel candidates only " << u_bare
                      << ", with medial balls " << u_fit);
  CHECK(u_bare * 2 >= finger_vertices);  // most of the fingers stay bare without them
  CHECK(u_fit == 0);                      // every finger vertex within tolerance with them
  size_t in_fingers = 0;
  for (const auto& s : fit.value()) {
    if (s.center.x() < 2.0 || s.center.y() < 3.05) continue;  // the torso, the arm
    ++in_fingers;
    CHECK(s.region == sb::Region::kLeftArm);
    // On a finger's axis (x = x0 + k spacing, z = 0), its radius the finger's plus the dilation.
    const double k = std::round((s.center.x() - finger_x0) / kSpacing);
    CHECK(k >= 0.0);
    CHECK(k <= 3.0);
    CHECK(std::abs(s.center.x() - (finger_x0 + k * kSpacing)) < 0.1 * kFingerR);
    CHECK(std::abs(s.center.z()) < 0.1 * kFingerR);
    CHECK(s.radius == doctest::Approx(kFingerR + p.dilation_rel * height).epsilon(0.08));
  }
  CHECK(in_fingers >= 8);  // at least two a finger
  CHECK(fit->size() <= 96);

  // Wound the other way (every triangle's corners swapped: the normals point in), the inward normals come
  // from the enclosed volume's sign: the same balls.
  sb::Mesh flipped = m;
  for (size_t t = 0; t + 2 < flipped.indices.size(); t += 3) std::swap(flipped.indices[t + 1], flipped.indices[t + 2]);
  auto fit_flipped = sb::FitCover(flipped, seg, p);
  REQUIRE(fit_flipped.ok());
  REQUIRE(fit_flipped->size() == fit->size());
  for (size_t i = 0; i < fit->size(); ++i) {
    CHECK((fit_flipped.value()[i].center - fit.value()[i].center).norm() < 1e-6 * height);  // rounding of the swapped corners
    CHECK(fit_flipped.value()[i].radius == doctest::Approx(fit.value()[i].radius));
  }
}

TEST_CASE("fit cover: the budget the skin pass leaves goes back to the volume cover") {
  // A torso and an arm, smooth tubes: with skin_min_vertices out of reach the skin pass adds nothing,
  // and the 16 spheres held back for it fill the volume instead: all 48 of the budget are spent (32
  // without the return).
  sb::Mesh m;
  sb::Segmentation seg;
  AppendTorsoAndArm(&m, &seg);
  m.up_axis = sb::UpAxis::kY;
  sb::FitParams p;
  p.max_spheres = 48;
  p.skin_spheres = 16;
  p.skin_min_vertices = 1000000;
  p.min_gain = 0.0;
  p.cover_voxel_rel = 0.02;  // 26,000 interior voxels: seconds, also under ASan
  auto full = sb::FitCover(m, seg, p);
  REQUIRE_MESSAGE(full.ok(), (full.ok() ? "" : full.error().message));
  CHECK(full->size() == 48);
}

TEST_CASE("fit cover: bad parameters and a mesh without volume are clear errors") {
  const sb::Mesh m = ClosedTube(1, 1, 4, 32, 16);
  sb::FitParams p;
  p.max_spheres = 2;
  auto r = sb::FitCover(m, AllTorso(m), p);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("max_spheres") != std::string::npos);
  for (auto bad : {+[](sb::FitParams* q) { q->skin_spheres = -2; }, +[](sb::FitParams* q) { q->skin_min_vertices = 0; },
                   +[](sb::FitParams* q) { q->skin_tolerance_rel = std::nan(""); }}) {
    sb::FitParams q;
    bad(&q);
    auto e = sb::FitCover(m, AllTorso(m), q);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message.find("skin_") != std::string::npos);
  }
  sb::Segmentation short_seg;
  short_seg.triangle_regions.assign(3, 4);
  CHECK_FALSE(sb::FitCover(m, short_seg, sb::FitParams{}).ok());
  // A flat square (two triangles) encloses nothing.
  sb::Mesh flat;
  flat.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  flat.indices = {0, 1, 2, 0, 2, 3};
  auto f = sb::FitCover(flat, AllTorso(flat), sb::FitParams{});
  REQUIRE_FALSE(f.ok());
  CHECK(f.error().code == sb::Error::Code::kFit);
}

TEST_CASE("exclusions from bind geometry on a bent limb: neighbours and near pairs, not a fixed window") {
  // An L-shaped arm of 8 spheres (r = 0.5, 0.8 apart: consecutive ones overlap, i and i+2 do not),
  // bent 90° at sphere 4, and a torso sphere by its root.
  std::vector<sb::FittedSphere> sp;
  for (int i = 0; i < 8; ++i) {
    sb::FittedSphere s;
    s.region = sb::Region::kLeftArm;
    s.sequence = i;
    s.radius = 0.5;
    s.center = i <= 4 ? Vector3d(1.2 + 1.1 * i, 0, 0) : Vector3d(1.2 + 1.1 * 4, -1.1 * (i - 4), 0);
    s.root_distance = 1.2 + 1.1 * i;  // along the limb from its root at the origin
    sp.push_back(s);
  }
  sb::FittedSphere torso;
  torso.region = sb::Region::kTorso;
  torso.radius = 0.6;
  torso.center = Vector3d(0, 0, 0);
  sp.push_back(torso);
  sb::ExclusionReasons why;
  const auto ex = sb::BindExcludedPairs(sp, 0.05, &why);
  auto has = [&](uint16_t a, uint16_t b) { return std::find(ex.begin(), ex.end(), sb::SpherePair{a, b}) != ex.end(); };
  for (uint16_t i = 0; i + 1 < 8; ++i) CHECK(has(i, i + 1));  // limb neighbours
  CHECK(why.limb_neighbour == 7);
  CHECK_FALSE(has(0, 2));  // 2.2 apart, radii sum 1: tested (a fixed ±2 window would hide it)
  CHECK_FALSE(has(2, 6));  // across the bend: 2.2·√2 apart
  CHECK(has(0, 8));        // the root and the torso: 1.2 apart < 1.1 (sum) + near? no: junction rule
  CHECK(why.bind_overlap + why.bind_near + why.junction == 1);
  // Near: two arm spheres 1.02 apart but not consecutive in sequence are excluded with near 0.05.
  sp[7].center = sp[5].center + Vector3d(1.02, 0, 0);
  sb::ExclusionReasons why2;
  const auto ex2 = sb::BindExcludedPairs(sp, 0.05, &why2);
  CHECK(std::find(ex2.begin(), ex2.end(), sb::SpherePair{5, 7}) != ex2.end());
  CHECK(why2.bind_near >= 1);
  CHECK(why2.limb_side_by_side == 0);
  // Side by side: a sphere beside sphere 2 in the same stretch of the limb (root distance 0.3 further,
  // 1.33 apart: neither overlapping nor near) is excluded as side by side; moved 2.5 further along the
  // limb (beyond rA + rB = 1) it is tested.
  sb::FittedSphere beside = sp[2];
  beside.sequence = 20;
  beside.center = sp[2].center + Vector3d(0.3, 0, 1.3);
  beside.root_distance = sp[2].root_distance + 0.3;
  sp.push_back(beside);
  const uint16_t k = static_cast<uint16_t>(sp.size() - 1);
  sb::ExclusionReasons why3;
  const auto ex3 = sb::BindExcludedPairs(sp, 0.05, &why3);
  CHECK(std::find(ex3.begin(), ex3.end(), sb::SpherePair{2, k}) != ex3.end());
  CHECK(why3.limb_side_by_side >= 1);
  sp[k].root_distance = sp[2].root_distance + 2.5;
  const auto ex4 = sb::BindExcludedPairs(sp, 0.05);
  CHECK(std::find(ex4.begin(), ex4.end(), sb::SpherePair{2, k}) == ex4.end());
}

TEST_CASE("exclusions from bind geometry: the crotch — two legs' root spheres, not their lower spheres") {
  // Up is y. Each leg: a root sphere (radius 0.5, 0.3 from the leg's root) and one further down (radius
  // 0.5, 2.0 from it). The two root spheres are 1.2 apart: beyond rA + rB + near = 1.05, within
  // 1.25 (rA + rB) + near = 1.3 — a sibling crease. The lower spheres, as close, are two legs standing
  // side by side (root distance 2.0 > rA + rB): tested. A torso sphere as close is a junction, not this.
  std::vector<sb::FittedSphere> sp(4);
  const double x[4] = {0.6, -0.6, 0.6, -0.6};
  for (int i = 0; i < 4; ++i) {
    sp[i].region = i % 2 == 0 ? sb::Region::kLeftLeg : sb::Region::kRightLeg;
    sp[i].radius = 0.5;
    sp[i].sequence = i / 2;
    sp[i].root_distance = i < 2 ? 0.3 : 2.0;
    sp[i].center = Vector3d(x[i], i < 2 ? 0.0 : -1.7, 0.0);
  }
  auto has = [](const std::vector<sb::SpherePair>& e, uint16_t a, uint16_t b) {
    return std::find(e.begin(), e.end(), sb::SpherePair{a, b}) != e.end();
  };
  sb::ExclusionReasons why;
  const auto ex = sb::BindExcludedPairs(sp, 0.05, &why, nullptr, sb::UpAxis::kY);
  CHECK(has(ex, 0, 1));
  CHECK(why.sibling_crease == 1);
  CHECK_FALSE(has(ex, 2, 3));  // the lower spheres: two legs, not a crease
  CHECK_FALSE(has(ex, 0, 3));  // a root sphere and the other leg's lower sphere (1.97 apart)
  // A leg's root sphere and an arm's (both hang off the torso) far apart stay tested; at the crotch's
  // distance they would be a crease too — the rule is by the tree, not by names.
  sp[1].region = sb::Region::kRightArm;
  sb::ExclusionReasons why_arm;
  const auto ex_arm = sb::BindExcludedPairs(sp, 0.05, &why_arm, nullptr, sb::UpAxis::kY);
  CHECK(has(ex_arm, 0, 1));
  sp[1].center.x() = -2.0;
  const auto ex_far = sb::BindExcludedPairs(sp, 0.05, &why_arm, nullptr, sb::UpAxis::kY);
  CHECK_FALSE(has(ex_far, 0, 1));
  CHECK(why_arm.sibling_crease == 0);
  // A leg sphere and a torso sphere as close: the junction rule, not a sibling crease.
  sp[1].region = sb::Region::kTorso;
  sp[1].center.x() = -0.6;
  sb::ExclusionReasons why_torso;
  const auto ex_torso = sb::BindExcludedPairs(sp, 0.05, &why_torso, nullptr, sb::UpAxis::kY);
  CHECK(has(ex_torso, 0, 1));
  CHECK(why_torso.junction >= 1);
  CHECK(why_torso.sibling_crease == 0);
}

TEST_CASE("exclusions from bind geometry: torso spheres side by side on one level, not across levels") {
  // Up is z. Two torso spheres of radius 1 and 0.6 whose heights differ by 0.9 (< the larger radius),
  // 2.5 apart sideways (beyond rA + rB + near = 1.65): one level, excluded as side by side. A third
  // 2.0 above the first (> its radius), 1.6 apart sideways: two levels, tested.
  std::vector<sb::FittedSphere> sp(3);
  for (auto& s : sp) s.region = sb::Region::kTorso;
  sp[0].center = Vector3d(0, 0, 0), sp[0].radius = 1.0;
  sp[1].center = Vector3d(2.5, 0, 0.9), sp[1].radius = 0.6;
  sp[2].center = Vector3d(0, 1.6, 2.0), sp[2].radius = 0.2;
  sb::ExclusionReasons why;
  const auto ex = sb::BindExcludedPairs(sp, 0.05, &why, nullptr, sb::UpAxis::kZ);
  auto has = [&](const std::vector<sb::SpherePair>& e, uint16_t a, uint16_t b) {
    return std::find(e.begin(), e.end(), sb::SpherePair{a, b}) != e.end();
  };
  CHECK(has(ex, 0, 1));
  CHECK(why.torso_side_by_side == 1);
  CHECK_FALSE(has(ex, 0, 2));  // 2.0 apart in height, larger radius 1: two levels
  CHECK_FALSE(has(ex, 1, 2));  // 1.1 apart in height, larger radius 0.6
  // Heights are taken along the given up axis: with y up the three lie at 0, 0 and 1.6.
  sb::ExclusionReasons why_y;
  const auto ex_y = sb::BindExcludedPairs(sp, 0.05, &why_y, nullptr, sb::UpAxis::kY);
  CHECK(has(ex_y, 0, 1));  // heights 0 and 0 along y
  CHECK_FALSE(has(ex_y, 0, 2));
  // Limb spheres at one height are not torso levels: two arms' spheres side by side stay tested.
  sp[0].region = sb::Region::kLeftArm, sp[1].region = sb::Region::kRightArm;
  sb::ExclusionReasons why_limbs;
  const auto ex_limbs = sb::BindExcludedPairs(sp, 0.05, &why_limbs, nullptr, sb::UpAxis::kZ);
  CHECK_FALSE(has(ex_limbs, 0, 1));
  CHECK(why_limbs.torso_side_by_side == 0);
}

TEST_CASE("exclusions from bind geometry: the trunk's fold, only where the head is a region of its own") {
  // Up is y. Two trunk spheres of radius 0.5 on two levels (1.0 apart in height, more than the larger
  // radius: not side by side), 1.2 apart: beyond rA + rB + near = 1.05, within 1.25 (rA + rB) + near = 1.3.
  // A third 2.4 above the first (1.55 from the second): beyond 1.3, tested in either layout.
  std::vector<sb::FittedSphere> sp(3);
  for (int i = 0; i < 3; ++i) sp[i].radius = 0.5;
  sp[0].center = Vector3d(0, 0, 0);
  sp[1].center = Vector3d(0, 1.0, std::sqrt(1.2 * 1.2 - 1.0));
  sp[2].center = Vector3d(0, 2.4, 0.0);
  auto has = [](const std::vector<sb::SpherePair>& e, uint16_t a, uint16_t b) {
    return std::find(e.begin(), e.end(), sb::SpherePair{a, b}) != e.end();
  };
  // The paper's five: the torso carries the head (a chin meets the chest through such a pair): tested.
  for (auto& s : sp) s.region = sb::Region::kTorso;
  sb::ExclusionReasons why_paper;
  const auto ex_paper = sb::BindExcludedPairs(sp, 0.05, &why_paper, nullptr, sb::UpAxis::kY);
  CHECK_FALSE(has(ex_paper, 0, 1));
  CHECK(why_paper.trunk_fold == 0);
  // The extended layout (head, hands, feet of their own; trunk R9): the fold of the belly, excluded.
  sb::RegionLayout ext;
  const char* names[10] = {"left_arm", "right_arm", "left_leg", "right_leg", "head",
                           "left_hand", "right_hand", "left_foot", "right_foot", "torso"};
  ext.regions.assign(10, sb::RegionInfo{});
  for (int k = 0; k < 10; ++k) ext.regions[size_t(k)].name = names[k];
  ext.regions[9].kind = sb::RegionKind::kTrunk;
  for (auto& s : sp) s.region = ext.trunk();
  sb::ExclusionReasons why_ext;
  const auto ex_ext = sb::BindExcludedPairs(sp, 0.05, &why_ext, nullptr, sb::UpAxis::kY, &ext);
  CHECK(has(ex_ext, 0, 1));
  CHECK(why_ext.trunk_fold == 1);
  CHECK_FALSE(has(ex_ext, 0, 2));  // 2.4 apart
  CHECK_FALSE(has(ex_ext, 1, 2));  // 1.55 apart
  // A limb's spheres as close are no trunk fold (the limb rules decide; here: tested).
  for (auto& s : sp) s.region = sb::Region::kLeftArm;
  sp[0].root_distance = 0.0, sp[1].root_distance = 2.0, sp[2].root_distance = 4.0;
  sp[0].sequence = 0, sp[1].sequence = 5, sp[2].sequence = 10;
  sb::ExclusionReasons why_limb;
  const auto ex_limb = sb::BindExcludedPairs(sp, 0.05, &why_limb, nullptr, sb::UpAxis::kY, &ext);
  CHECK_FALSE(has(ex_limb, 0, 1));
  CHECK(why_limb.trunk_fold == 0);
}

TEST_CASE("heavy: bake MakeHuman with the cover fit — coverage, protrusion, the default (extended) asset and its margins") {
  const std::string path = spherechain::test::SharedData("makehuman/base.obj");
  if (!spherechain::test::Require(path)) return;
  sb::Context ctx;
  auto r = sb::Bake(path, sb::BakeConfig{}, &ctx);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->fit.spheres.size() <= 128);
  REQUIRE(r->coverage.has_value());
  MESSAGE("MakeHuman cover fit: " << r->fit.spheres.size() << " spheres, coverage " << r->coverage->coverage
                                  << ", protrusion " << r->coverage->protrusion << ", p95 outside "
                                  << r->coverage->outside_p95_rel);
  // The extended layout's skin pass takes 24 of the 128 spheres (the paper's five: 16), for the hands', feet's
  // and face's skin: 0.5 points of MakeHuman's volume (89.6 %, paper layout 90.1 %) for 3 points of region recall.
  CHECK(r->coverage->coverage >= 0.89);
  CHECK(r->coverage->protrusion <= 0.05);
  CHECK(r->coverage->outside_p95_rel <= 0.005);
  {
    sb::BakeConfig paper;
    paper.regions = sb::RegionSet::kPaper;
    sb::Context pctx;
    auto rp = sb::Bake(path, paper, &pctx);
    REQUIRE_MESSAGE(rp.ok(), (rp.ok() ? "" : rp.error().message));
    REQUIRE(rp->coverage.has_value());
    CHECK(rp->segmentation.layout.IsPaperFive());
    CHECK(sb::SkinSpheres(sb::FitParams{}, rp->segmentation.layout) == 16);
    CHECK(sb::SkinSpheres(sb::FitParams{}, r->segmentation.layout) == 24);
    CHECK(rp->coverage->coverage >= 0.90);
    CHECK(rp->coverage->coverage > r->coverage->coverage);  // the bigger skin pass costs volume
  }
  // The default layout for a standing biped: the extended one — arms, legs, head, both hands, both feet, the
  // torso last — each region with spheres of its own.
  const sb::RegionLayout& layout = r->segmentation.layout;
  REQUIRE(layout.count() == 10);
  CHECK(std::string(layout.Name(layout.trunk())) == "torso");
  for (int k = 0; k < layout.count(); ++k) {
    size_t n = 0;
    for (const auto& s : r->fit.spheres) n += int(s.region) == k;
    CHECK_MESSAGE(n >= 2, "region " << layout.Name(sb::Region(k)) << " has " << n << " spheres");
  }

  // The asset: v4 (Asset.regions), the margins stored, bind pose quiet with them, pairs within a larger override.
  std::vector<uint64_t> storage((r->asset.size() + 7) / 8);
  std::memcpy(storage.data(), r->asset.data(), r->asset.size());
  rt::AssetView view;
  REQUIRE(rt::LoadAsset(storage.data(), r->asset.size(), &view) == rt::Status::kOk);
  CHECK(view.asset->schema_version() == rt::kSchemaVersion);
  REQUIRE(view.asset->coverage() != nullptr);
  CHECK(view.asset->coverage()->coverage() == doctest::Approx(r->coverage->coverage).epsilon(1e-6));
  CHECK(std::string(view.asset->fit_method()->c_str()) == "cover");
  rt::Model c;
  rt::Workspace ws;
  REQUIRE(c.Init(view) == rt::Status::kOk);
  REQUIRE(ws.Init(c) == rt::Status::kOk);
  const float margin = float(0.004 * r->fit.body_height);
  CHECK(c.contact_margin() == doctest::Approx(margin).epsilon(1e-5));
  CHECK(c.fold_margin() == doctest::Approx(0.0015 * r->fit.body_height).epsilon(1e-5));
  std::vector<rt::Collision> out(rt::DetectBound(view, rt::DetectMethod::kM2));
  uint32_t n = 0;
  rt::DetectJob job;
  job.model = &c;
  job.workspace = &ws;
  job.method = rt::DetectMethod::kM2;
  job.output = out.data();
  job.capacity = uint32_t(out.size());
  job.count = &n;
  REQUIRE(job.Run() == rt::Status::kOk);
  CHECK(n == 0);  // exclusions cover everything the margin reaches at bind pose
  job.margin = 0.05f * float(r->fit.body_height);
  REQUIRE(job.Run() == rt::Status::kOk);
  CHECK(n > 0);
  for (uint32_t i = 0; i < n; ++i) {
    CHECK(out[i].depth > -2.0f * job.margin * 1.0001f);
    CHECK(!c.IsExcluded(out[i].a, out[i].b));
  }
  job.margin = std::nanf("");
  CHECK(job.Run() == rt::Status::kErrorInvalidJob);
}
