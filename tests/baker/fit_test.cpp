// Tests of the sphere fitting stage (paper §3.1, §3.2): the moving circumference on a cylinder, the
// torso disk on an elliptic cylinder, φ2 against brute force, the sign of F, and a MakeHuman run.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "spherechain/baker/fit.h"
#include "test_data.h"

namespace sb = spherechain::baker;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Open tube along +Y: `n_around` × `n_along` quads, cross-section (a cos θ, b sin θ) in XZ.
sb::Mesh MakeTube(double a, double b, double length, int n_around, int n_along, double y0 = 0.0) {
  sb::Mesh m;
  for (int j = 0; j <= n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const double th = 2.0 * kPi * i / n_around;
      m.positions.push_back(static_cast<float>(a * std::cos(th)));
      m.positions.push_back(static_cast<float>(y0 + length * j / n_along));
      m.positions.push_back(static_cast<float>(b * std::sin(th)));
    }
  for (int j = 0; j < n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const uint32_t v0 = j * n_around + i, v1 = j * n_around + (i + 1) % n_around;
      const uint32_t v2 = v1 + n_around, v3 = v0 + n_around;
      for (uint32_t v : {v0, v1, v2, v0, v2, v3}) m.indices.push_back(v);
    }
  m.up_axis = sb::UpAxis::kY;
  return m;
}

std::vector<uint32_t> AllTriangles(const sb::Mesh& m) {
  std::vector<uint32_t> t(m.triangle_count());
  for (uint32_t i = 0; i < t.size(); ++i) t[i] = i;
  return t;
}

Vector3d V(const sb::Mesh& m, uint32_t v) { return {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]}; }

/// MakeHuman base.obj, group `body` (vertices 1..13380 in file order; quads split (0,1,2), (0,2,3)).
sb::Mesh LoadMakeHumanBody(const std::string& path) {
  sb::Mesh m;
  std::ifstream in(path);
  std::string line;
  bool body = false;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      if (m.vertex_count() < 13380) {
        std::istringstream ss(line.substr(2));
        float x, y, z;
        ss >> x >> y >> z;
        m.positions.insert(m.positions.end(), {x, y, z});
      }
    } else if (line.rfind("g ", 0) == 0) {
      if (body) break;
      body = line == "g body";
    } else if (body && line.rfind("f ", 0) == 0) {
      std::istringstream ss(line.substr(2));
      std::vector<uint32_t> f;
      std::string tok;
      while (ss >> tok) f.push_back(static_cast<uint32_t>(std::stoul(tok.substr(0, tok.find('/')))) - 1);
      for (size_t k = 1; k + 1 < f.size(); ++k) m.indices.insert(m.indices.end(), {f[0], f[k], f[k + 1]});
    }
  }
  m.up_axis = sb::UpAxis::kY;
  return m;
}

/// Stand-in segmentation (until segment*.cpp lands): each vertex goes with its heaviest bone in
/// default_weights.mhw; arm/hand bones → arms, leg/foot bones → legs, by .L/.R; triangles by majority.
sb::Segmentation StandInSegmentation(const sb::Mesh& m, const std::string& weights_path) {
  std::ifstream in(weights_path);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::vector<float> best_w(m.vertex_count(), 0.0f);
  std::vector<uint8_t> vr(m.vertex_count(), static_cast<uint8_t>(sb::Region::kTorso));
  for (const auto& [bone, list] : j["weights"].items()) {
    const bool left = bone.size() > 2 && bone.substr(bone.size() - 2) == ".L";
    auto starts = [&b = bone](const char* p) { return b.rfind(p, 0) == 0; };  // clang < 16: no capture of a binding
    uint8_t r = static_cast<uint8_t>(sb::Region::kTorso);
    if (starts("upperarm") || starts("lowerarm") || starts("wrist") || starts("finger") || starts("metacarpal"))
      r = static_cast<uint8_t>(left ? sb::Region::kLeftArm : sb::Region::kRightArm);
    else if (starts("upperleg") || starts("lowerleg") || starts("foot") || starts("toe"))
      r = static_cast<uint8_t>(left ? sb::Region::kLeftLeg : sb::Region::kRightLeg);
    for (const auto& vw : list) {
      const uint32_t v = vw[0].get<uint32_t>();
      const float w = vw[1].get<float>();
      if (v < m.vertex_count() && w > best_w[v]) best_w[v] = w, vr[v] = r;
    }
  }
  sb::Segmentation seg;
  seg.method = "stand-in";
  seg.vertex_regions = vr;
  for (uint32_t t = 0; t < m.triangle_count(); ++t) {
    const uint8_t a = vr[m.indices[3 * t]], b = vr[m.indices[3 * t + 1]], c = vr[m.indices[3 * t + 2]];
    seg.triangle_regions.push_back((a == b || a == c) ? a : (b == c ? b : static_cast<uint8_t>(sb::Region::kTorso)));
  }
  return seg;
}

sb::AccuracyStats Stats(const sb::Mesh& m, const std::vector<uint32_t>& verts, const Vector3d& c, double r) {
  sb::AccuracyAccumulator acc;
  for (uint32_t v : verts) acc.Add(c, r, V(m, v));
  return acc.Stats();
}

/// Front (x, y) and side (z, y) views of the mesh vertices and the spheres, as one SVG.
void WriteSvg(const std::string& path, const sb::Mesh& m, const std::vector<sb::FittedSphere>& spheres, bool phi1) {
  const char* colours[] = {"#d62728", "#ff7f0e", "#2ca02c", "#17becf", "#1f77b4"};
  const double s = 40.0, W = 2 * 14 * s, H = 18 * s;
  std::ofstream o(path);
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n";
  for (int view = 0; view < 2; ++view) {
    const double ox = (view == 0 ? 7.0 : 21.0) * s, oy = 8.8 * s;
    auto px = [&](const Vector3d& p) { return ox + s * (view == 0 ? p.x() : p.z()); };
    auto py = [&](const Vector3d& p) { return oy - s * p.y(); };
    for (uint32_t v = 0; v < m.vertex_count(); v += 3)
      o << "<circle cx='" << px(V(m, v)) << "' cy='" << py(V(m, v)) << "' r='0.8' fill='#999'/>\n";
    for (const auto& sp : spheres) {
      const Vector3d c = phi1 ? sp.center_phi1 : sp.center;
      const double r = phi1 ? sp.radius_phi1 : sp.radius;
      o << "<circle cx='" << px(c) << "' cy='" << py(c) << "' r='" << s * r << "' fill='none' stroke='"
        << colours[static_cast<int>(sp.region)] << "' stroke-width='1.5'/>\n";
      if (sp.labels & (sb::kLabelT | sb::kLabelD))
        o << "<text x='" << px(c) << "' y='" << py(c) << "' font-size='14'>" << ((sp.labels & sb::kLabelT) ? "T" : "")
          << ((sp.labels & sb::kLabelD) ? "D" : "") << "</text>\n";
    }
  }
  o << "</svg>\n";
}

}  // namespace

TEST_CASE("fit: F is positive for a point inside the sphere, negative outside") {
  sb::AccuracyAccumulator acc;
  acc.Add(Vector3d(1, 2, 3), 2.0, Vector3d(1.5, 2, 3));  // inside: F = 1.5
  CHECK(acc.Stats().max_f == doctest::Approx(1.5));
  CHECK(acc.Stats().min_f > 0.0);
  acc.Add(Vector3d(1, 2, 3), 2.0, Vector3d(1, 2, 6));  // outside: F = -1
  const sb::AccuracyStats s = acc.Stats();
  CHECK(s.count == 2);
  CHECK(s.min_f == doctest::Approx(-1.0));
  CHECK(s.mean_abs_f == doctest::Approx(1.25));
  CHECK(s.rms_f == doctest::Approx(std::sqrt((1.5 * 1.5 + 1.0) / 2.0)));
}

TEST_CASE("fit: phi2 minimum enclosing ball agrees with a brute-force check") {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  CHECK(sb::MinimumEnclosingBall({}).radius == 0.0);
  const sb::Ball two = sb::MinimumEnclosingBall({Vector3d(0, 0, 0), Vector3d(2, 0, 0)});
  CHECK(two.radius == doctest::Approx(1.0));
  CHECK((two.center - Vector3d(1, 0, 0)).norm() < 1e-12);
  for (int trial = 0; trial < 20; ++trial) {
    const double scale = std::pow(10.0, trial % 5 - 2);
    const Vector3d offset(u(rng) * 100 * scale, u(rng) * 100 * scale, u(rng) * 100 * scale);
    std::vector<Vector3d> pts(5 + trial * 37);
    for (auto& p : pts) p = offset + scale * Vector3d(3 * u(rng), u(rng), 0.5 * u(rng));
    const sb::Ball b = sb::MinimumEnclosingBall(pts);
    const double tol = 1e-9 * scale * 100;
    int on_boundary = 0;
    Vector3d lo = pts[0], hi = pts[0];
    for (const auto& p : pts) {
      const double d = (p - b.center).norm();
      CHECK(d <= b.radius + tol);
      if (std::abs(d - b.radius) <= tol) ++on_boundary;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    CHECK(on_boundary >= 2);
    double naive = 0.0;
    for (const auto& p : pts) naive = std::max(naive, (p - 0.5 * (lo + hi)).norm());
    CHECK(b.radius <= naive + tol);
  }
}

TEST_CASE("fit: tubular region on a cylinder gives spheres of its radius on its axis spaced per PD") {
  const double R = 1.0, L = 20.0;
  const sb::Mesh m = MakeTube(R, R, L, 64, 200);
  sb::FitParams params;
  auto res = sb::FitTubular(m, AllTriangles(m), sb::Region::kLeftArm, params);
  REQUIRE(res.ok());
  const auto& sp = res.value();
  REQUIRE(sp.size() >= 10);
  MESSAGE("cylinder R=1 L=20: " << sp.size() << " spheres");
  const double r_poly = R * std::cos(kPi / 64);  // inscribed radius of the 64-gon
  for (size_t i = 0; i < sp.size(); ++i) {
    CHECK(sp[i].radius == doctest::Approx(r_poly).epsilon(0.01));
    CHECK(std::hypot(sp[i].center.x(), sp[i].center.z()) < 0.02 * R);
    CHECK(sp[i].region == sb::Region::kLeftArm);
    CHECK(sp[i].sequence == static_cast<int>(i));
    CHECK(sp[i].center.y() >= R * 0.95);          // fits beyond the root end
    CHECK(sp[i].center.y() <= L - R * 0.95);      // and before the tip
  }
  const double spacing = 2.0 * r_poly * (1.0 - params.penetration_depth);
  for (size_t i = 0; i + 2 < sp.size(); ++i)  // the last pair may be the closer tip sphere
    CHECK((sp[i + 1].center - sp[i].center).norm() == doctest::Approx(spacing).epsilon(0.04));
  // Covered end to end: first sphere near the root, last near the tip.
  const double y0 = std::min(sp.front().center.y(), sp.back().center.y());
  const double y1 = std::max(sp.front().center.y(), sp.back().center.y());
  CHECK(y0 < R + spacing);
  CHECK(y1 > L - R - spacing);

  // PD changes the spacing.
  params.penetration_depth = 0.5;
  auto res2 = sb::FitTubular(m, AllTriangles(m), sb::Region::kLeftArm, params);
  REQUIRE(res2.ok());
  CHECK((res2.value()[1].center - res2.value()[0].center).norm() == doctest::Approx(2.0 * r_poly * 0.5).epsilon(0.04));
  CHECK(res2.value().size() > sp.size());
}

TEST_CASE("fit: invalid inputs give kFit") {
  const sb::Mesh m = MakeTube(1, 1, 4, 16, 8);
  auto empty = sb::FitTubular(m, {}, sb::Region::kLeftLeg, sb::FitParams{});
  REQUIRE(!empty.ok());
  CHECK(empty.error().code == sb::Error::Code::kFit);
  sb::FitParams bad;
  bad.penetration_depth = 1.5;
  CHECK(!sb::FitTubular(m, AllTriangles(m), sb::Region::kLeftLeg, bad).ok());
  sb::Segmentation seg;  // wrong size
  auto all = sb::FitSpheres(m, seg, sb::FitParams{});
  REQUIRE(!all.ok());
  CHECK(all.error().code == sb::Error::Code::kFit);
}

TEST_CASE("fit: torso disk on an elliptic cylinder gives two columns inside it, adjusted F no worse") {
  const double a = 2.0, b = 1.0, H = 12.0;
  const sb::Mesh m = MakeTube(a, b, H, 96, 120);
  sb::Segmentation seg;
  seg.triangle_regions.assign(m.triangle_count(), static_cast<uint8_t>(sb::Region::kTorso));
  sb::FitParams params;
  params.disk_step = 0.25;
  auto res = sb::FitTorso(m, AllTriangles(m), seg, params);
  REQUIRE(res.ok());
  const auto& sp = res.value();
  REQUIRE(sp.size() >= 6);
  CHECK(sp.size() % 2 == 0);
  MESSAGE("elliptic torso a=2 b=1 H=12: " << sp.size() << " spheres");
  double f1 = 0, f1a = 0, f2 = 0;
  for (size_t i = 0; i < sp.size(); ++i) {
    const auto& s = sp[i];
    CHECK(s.column == static_cast<int>(i % 2));
    CHECK(s.level == static_cast<int>(i / 2));
    // No limbs: the character's left falls back to +X for +Y up.
    if (s.column == 0) CHECK(s.center_phi1.x() > 0.3 * a);
    if (s.column == 1) CHECK(s.center_phi1.x() < -0.3 * a);
    CHECK((s.labels & (s.column == 0 ? sb::kLabelL : sb::kLabelR)) != 0);
    CHECK(((s.labels & sb::kLabelD) != 0) == (s.level == 0));
    // φ1 inscribed: centre inside the ellipse, radius within the surface distance.
    const double x = s.center_phi1.x(), z = s.center_phi1.z();
    CHECK(x * x / (a * a) + z * z / (b * b) < 1.0);
    CHECK(s.radius_phi1 <= b + 1e-6);
    CHECK(s.radius_phi1 > 0.7 * b);
    CHECK(std::abs(z) < 0.05 * b);
    REQUIRE(!s.support_vertices.empty());
    CHECK(s.ray_ids.size() == static_cast<size_t>(params.rays / 2));
    CHECK(s.ray_dirs.size() == s.ray_ids.size());
    CHECK(s.ray_hit.size() == s.ray_ids.size());
    const sb::AccuracyStats st1 = Stats(m, s.support_vertices, s.center_phi1, s.radius_phi1);
    const sb::AccuracyStats st1a = Stats(m, s.support_vertices, s.center, s.radius);
    const sb::AccuracyStats st2 = Stats(m, s.support_vertices, s.center_phi2, s.radius_phi2);
    CHECK(st1.max_f <= 1e-6);   // inscribed: no surface vertex inside φ1
    CHECK(st2.min_f >= -1e-9);  // enclosing: every vertex inside φ2
    CHECK(st1a.mean_abs_f <= st1.mean_abs_f + 1e-12);
    f1 += st1.mean_abs_f, f1a += st1a.mean_abs_f, f2 += st2.mean_abs_f;
    // the adjustment moves towards the disk centre, never away
    CHECK(std::abs(s.center.x()) <= std::abs(s.center_phi1.x()) + 1e-9);
  }
  MESSAGE("elliptic torso mean|F| phi1 " << f1 / sp.size() << ", phi1' " << f1a / sp.size() << ", phi2 "
                                          << f2 / sp.size());
  // Levels overlap by no more than PD: consecutive spheres of a column are >= (1-PD)(ra+rb) apart.
  for (size_t i = 0; i + 4 < sp.size(); ++i)  // the top level may be the closer last one
    CHECK((sp[i + 2].center_phi1 - sp[i].center_phi1).norm() >=
          (1 - params.penetration_depth) * (sp[i].radius_phi1 + sp[i + 2].radius_phi1) - 1e-9);
}

TEST_CASE("fit: MakeHuman body gives sphere counts per region") {
  const std::string obj = spherechain::test::SharedData("makehuman/base.obj");
  const std::string mhw = spherechain::test::SharedData("makehuman/default_weights.mhw");
  if (!spherechain::test::Require(obj) || !spherechain::test::Require(mhw)) return;
  const sb::Mesh m = LoadMakeHumanBody(obj);
  REQUIRE(m.vertex_count() == 13380);
  REQUIRE(m.triangle_count() == 26756);
  const sb::Segmentation seg = StandInSegmentation(m, mhw);
  sb::Context ctx;
  const auto t0 = std::chrono::steady_clock::now();
  sb::FitParams paper;
  paper.method = sb::FitMethod::kPaper;
  auto res = sb::FitSpheres(m, seg, paper, &ctx);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE(res.ok());
  const auto& fr = res.value();
  CHECK(fr.body_height == doctest::Approx(16.66).epsilon(0.01));
  CHECK(fr.disk_step == doctest::Approx(0.25).epsilon(0.01));
  int counts[sb::kRegionCount] = {};
  for (const auto& s : fr.spheres) ++counts[static_cast<int>(s.region)];
  double f1 = 0, f1a = 0, f2 = 0;
  int nt = 0, n_t = 0, n_d = 0;
  for (const auto& s : fr.spheres) {
    if (s.region != sb::Region::kTorso) continue;
    f1 += Stats(m, s.support_vertices, s.center_phi1, s.radius_phi1).mean_abs_f;
    f1a += Stats(m, s.support_vertices, s.center, s.radius).mean_abs_f;
    f2 += Stats(m, s.support_vertices, s.center_phi2, s.radius_phi2).mean_abs_f;
    ++nt;
    n_t += (s.labels & sb::kLabelT) != 0;
    n_d += (s.labels & sb::kLabelD) != 0;
    // column 0 is the character's left: +X on MakeHuman
    if (s.column == 0) CHECK(s.center_phi1.x() > 0.0);
    if (s.column == 1) CHECK(s.center_phi1.x() < 0.0);
  }
  MESSAGE("MakeHuman fit: R0 " << counts[0] << ", R1 " << counts[1] << ", R2 " << counts[2] << ", R3 " << counts[3]
                               << ", R4 " << counts[4] << ", total " << fr.spheres.size() << ", " << ms << " ms");
  MESSAGE("MakeHuman torso mean|F| phi1 " << f1 / nt << ", phi1' " << f1a / nt << ", phi2 " << f2 / nt
                                          << " (T " << n_t << ", D " << n_d << ")");
  for (int r = 0; r < 4; ++r) CHECK(counts[r] >= 6);
  CHECK(counts[4] >= 8);
  CHECK(fr.spheres.size() >= 50);
  CHECK(fr.spheres.size() <= 130);
  CHECK(n_t >= 2);
  CHECK(n_d == 2);
  CHECK(f1a <= f1);
  // Left limbs on the character's left (+X).
  for (const auto& s : fr.spheres)
    if (s.region == sb::Region::kLeftArm || s.region == sb::Region::kLeftLeg) CHECK(s.center.x() > 0.0);
  if (const char* dir = std::getenv("SPHERECHAIN_FIT_SVG_DIR")) {
    WriteSvg(std::string(dir) + "/fit_phi1a.svg", m, fr.spheres, false);
    WriteSvg(std::string(dir) + "/fit_phi1.svg", m, fr.spheres, true);
  }
}
