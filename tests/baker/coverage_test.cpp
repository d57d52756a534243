// baker/coverage: coverage and protrusion of spheres against shapes with known volumes (box, sphere,
// octahedron), the fill rule on lines through shared edges and vertices, triangle soups, open meshes,
// bad input; and the numbers for φ1, φ1', φ2 on the real characters.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <tuple>

#include "spherechain/baker/bake.h"
#include "spherechain/baker/coverage.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::baker;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct TestMesh {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
};

uint32_t AddVertex(TestMesh& m, double x, double y, double z) {
  m.positions.insert(m.positions.end(), {float(x), float(y), float(z)});
  return uint32_t(m.positions.size() / 3 - 1);
}

// Indexed box [-hx, hx]×[-hy, hy]×[-hz, hz], 12 triangles. Opposite faces are split along crossing
// diagonals (z=+h along x=y, z=−h along x=−y, and likewise for x and y), so a grid column on a diagonal
// meets a shared edge on one face only: counted twice or never, its parity would turn odd.
// Bit f of `skip_faces` (f = 0..5: +x, −x, +y, −y, +z, −z) leaves that face out (an open mesh).
TestMesh Box(double hx, double hy, double hz, unsigned skip_faces = 0) {
  TestMesh m;
  for (int k = 0; k < 8; ++k) AddVertex(m, (k & 1) ? hx : -hx, (k & 2) ? hy : -hy, (k & 4) ? hz : -hz);
  auto v = [](int sx, int sy, int sz) { return uint32_t((sx > 0) | ((sy > 0) << 1) | ((sz > 0) << 2)); };
  // Each quad (p0, p1, p2, p3) is split along p0–p2.
  const uint32_t quads[6][4] = {
      {v(1, -1, -1), v(1, 1, -1), v(1, 1, 1), v(1, -1, 1)},       // +x: y = z
      {v(-1, -1, 1), v(-1, 1, 1), v(-1, 1, -1), v(-1, -1, -1)},   // −x: y = −z
      {v(-1, 1, -1), v(-1, 1, 1), v(1, 1, 1), v(1, 1, -1)},       // +y: z = x
      {v(1, -1, -1), v(1, -1, 1), v(-1, -1, 1), v(-1, -1, -1)},   // −y: z = −x
      {v(-1, -1, 1), v(1, -1, 1), v(1, 1, 1), v(-1, 1, 1)},       // +z: x = y
      {v(1, -1, -1), v(-1, -1, -1), v(-1, 1, -1), v(1, 1, -1)},   // −z: x = −y
  };
  for (int f = 0; f < 6; ++f) {
    if (skip_faces & (1u << f)) continue;
    const uint32_t* q = quads[f];
    m.indices.insert(m.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  return m;
}

// Every triangle its own three vertices (a soup with duplicated seam vertices).
TestMesh Soup(const TestMesh& in) {
  TestMesh m;
  for (uint32_t i : in.indices)
    AddVertex(m, in.positions[3 * i], in.positions[3 * i + 1], in.positions[3 * i + 2]);
  for (uint32_t i = 0; i < in.indices.size(); ++i) m.indices.push_back(i);
  return m;
}

// UV sphere of radius r about the origin: poles on ±z (grid columns through the origin hit them).
TestMesh UvSphere(double r, int stacks, int slices) {
  TestMesh m;
  const uint32_t north = AddVertex(m, 0, 0, r);
  for (int i = 1; i < stacks; ++i) {
    const double th = kPi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double ph = 2 * kPi * j / slices;
      AddVertex(m, r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th));
    }
  }
  const uint32_t south = AddVertex(m, 0, 0, -r);
  auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * slices + (j % slices)); };
  for (int j = 0; j < slices; ++j) {
    m.indices.insert(m.indices.end(), {north, ring(1, j), ring(1, j + 1)});
    m.indices.insert(m.indices.end(), {south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
    for (int i = 1; i + 1 < stacks; ++i)
      m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j), ring(i + 1, j + 1),
                                         ring(i, j + 1)});
  }
  return m;
}

// Octahedron |x| + |y| + |z| ≤ 1: grid columns through 0 run along its edges and through its apexes.
TestMesh Octahedron() {
  TestMesh m;
  const uint32_t px = AddVertex(m, 1, 0, 0), nx = AddVertex(m, -1, 0, 0), py = AddVertex(m, 0, 1, 0),
                 ny = AddVertex(m, 0, -1, 0), pz = AddVertex(m, 0, 0, 1), nz = AddVertex(m, 0, 0, -1);
  for (uint32_t x : {px, nx})
    for (uint32_t y : {py, ny})
      for (uint32_t z : {pz, nz}) m.indices.insert(m.indices.end(), {x, y, z});
  return m;
}

Ball MakeBall(double x, double y, double z, double r) {
  Ball b;
  b.center = {x, y, z};
  b.radius = r;
  return b;
}

CoverageStats Measure(const TestMesh& m, const std::vector<Ball>& balls, float voxel_rel) {
  CoverageOptions o;
  o.voxel_rel = voxel_rel;
  auto r = MeasureCoverage(m.positions, m.indices, balls, o);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  return r.value();
}

void CheckSame(const CoverageStats& a, const CoverageStats& b) {
  CHECK(a.voxels_inside_body == b.voxels_inside_body);
  CHECK(a.voxels_in_spheres == b.voxels_in_spheres);
  CHECK(a.voxels_both == b.voxels_both);
  CHECK(a.voxels_undecided == b.voxels_undecided);
  CHECK(a.voxel_size == b.voxel_size);
  CHECK(a.coverage == b.coverage);
  CHECK(a.protrusion == b.protrusion);
  CHECK(a.outside_p95_rel == b.outside_p95_rel);
  CHECK(a.outside_max_rel == b.outside_max_rel);
}

}  // namespace

TEST_CASE("coverage: a sphere inside a closed box covers sphere/box volume and does not protrude") {
  const TestMesh box = Box(1.0, 0.5, 0.5);  // 2×1×1
  const double r = 0.4;
  const CoverageStats s = Measure(box, {MakeBall(0.3, -0.05, 0.02, r)}, 1.0f / 200);
  CHECK(s.body_height == doctest::Approx(2.0));
  CHECK(s.voxel_size == doctest::Approx(0.01));
  CHECK(s.grid_dims[0] == 200);
  CHECK(s.grid_dims[1] == 100);
  CHECK(s.grid_dims[2] == 100);
  CHECK(s.voxels_undecided == 0);
  CHECK(s.voxels_inside_body == 200u * 100u * 100u);  // faces on voxel boundaries: exact
  CHECK(s.body_volume == doctest::Approx(2.0).epsilon(1e-6));
  const double sphere_volume = 4.0 / 3.0 * kPi * r * r * r;
  CHECK(s.spheres_volume == doctest::Approx(sphere_volume).epsilon(0.01));
  CHECK(s.coverage == doctest::Approx(sphere_volume / 2.0).epsilon(0.01));
  CHECK(s.protrusion == 0.0);
  CHECK(s.outside_p95_rel == 0.0);
  CHECK(s.outside_max_rel == 0.0);
}

TEST_CASE("heavy: coverage: a unit-sphere mesh in a concentric r = 1.2 sphere: full coverage, 1 − 1/1.2³ protrudes") {
  const TestMesh body = UvSphere(1.0, 64, 128);
  const CoverageStats s = Measure(body, {MakeBall(0, 0, 0, 1.2)}, 1.0f / 80);  // h = 0.025
  CHECK(s.body_height == doctest::Approx(2.0).epsilon(1e-6));
  CHECK(s.voxels_undecided == 0);
  CHECK(s.body_volume == doctest::Approx(4.0 / 3.0 * kPi).epsilon(0.01));
  CHECK(s.coverage == 1.0);
  CHECK(s.protrusion == doctest::Approx(1.0 - 1.0 / (1.2 * 1.2 * 1.2)).epsilon(0.02));
  // The shell 1 < ρ ≤ 1.2 is uniform in ρ³: its 95th percentile of ρ − 1 is (1 + 0.95·0.728)^⅓ − 1.
  const double p95 = std::cbrt(1.0 + 0.95 * (1.2 * 1.2 * 1.2 - 1.0)) - 1.0;
  CHECK(s.outside_p95_rel == doctest::Approx(p95 / 2.0).epsilon(0.03));
  CHECK(s.outside_max_rel == doctest::Approx(0.2 / 2.0).epsilon(0.03));
  CHECK(s.outside_max_rel <= 0.1 + 0.01);  // never beyond the ball (plus the mesh's chord sag)
}

TEST_CASE("coverage: the skin outside the spheres — a sphere mesh around a concentric ball, and a box's corners") {
  // Unit sphere mesh (vertices on the sphere), body height 2: a concentric ball of radius 0.9 leaves every
  // vertex 0.1 outside (0.05 of the height; none within 0.5 %); of radius 1 none (all within).
  const TestMesh sphere = UvSphere(1.0, 16, 32);
  const CoverageStats in = Measure(sphere, {MakeBall(0, 0, 0, 0.9)}, 1.0f / 50);
  CHECK(in.skin_outside_p50_rel == doctest::Approx(0.05).epsilon(1e-6));
  CHECK(in.skin_outside_p95_rel == doctest::Approx(0.05).epsilon(1e-6));
  CHECK(in.skin_outside_max_rel == doctest::Approx(0.05).epsilon(1e-6));
  CHECK(in.skin_within_share == 0.0);
  const CoverageStats full = Measure(sphere, {MakeBall(0, 0, 0, 1.0)}, 1.0f / 50);
  CHECK(full.skin_outside_max_rel == doctest::Approx(0.0).epsilon(1e-6));
  CHECK(full.skin_within_share == doctest::Approx(1.0));
  // A 2×1×1 box and a ball of radius 0.5 at (0.7, 0, 0): the four corners at x = 1 lie √0.59 − 0.5 from
  // it, those at x = −1 √3.39 − 0.5, each side holding half the area (a third of each triangle's area to
  // each corner). p95 and max: the far corners (relative to the height 2); the near ones within nothing.
  const TestMesh box = Box(1.0, 0.5, 0.5);
  const CoverageStats corners = Measure(box, {MakeBall(0.7, 0, 0, 0.5)}, 1.0f / 50);
  const double near = (std::sqrt(0.59) - 0.5) / 2, far = (std::sqrt(3.39) - 0.5) / 2;
  CHECK(corners.skin_outside_p95_rel == doctest::Approx(far));
  CHECK(corners.skin_outside_max_rel == doctest::Approx(far));
  CHECK((corners.skin_outside_p50_rel == doctest::Approx(near) || corners.skin_outside_p50_rel == doctest::Approx(far)));
  CHECK(corners.skin_within_share == 0.0);
  // Grown to reach the near corners (radius √0.59 + 0.001), half the skin's area is within 0.5 %.
  const CoverageStats half = Measure(box, {MakeBall(0.7, 0, 0, std::sqrt(0.59) + 0.001)}, 1.0f / 50);
  CHECK(half.skin_within_share == doctest::Approx(0.5));
}

TEST_CASE("coverage: lines through shared edges and vertices are counted once (box diagonals, octahedron)") {
  // 51 voxels across [-1, 1]: the centre planes hold 0 exactly, diagonal columns have x = y exactly.
  const float rel = 1.0f / 51;
  SUBCASE("cube with crossing face diagonals") {
    const CoverageStats s = Measure(Box(1, 1, 1), {MakeBall(0, 0, 0, 0.5)}, rel);
    REQUIRE(s.grid_dims[0] == 51);
    CHECK(s.voxels_undecided == 0);
    CHECK(s.voxels_inside_body == 51u * 51u * 51u);
  }
  SUBCASE("octahedron: columns along its edges and through its apexes") {
    const CoverageStats s = Measure(Octahedron(), {MakeBall(0, 0, 0, 0.3)}, rel);
    REQUIRE(s.grid_dims[0] == 51);
    // Voxel centres are (2i + 1 − 51)/51: even numerators, never on the surface |x|+|y|+|z| = 1.
    uint32_t expected = 0;
    for (int a = -50; a <= 50; a += 2)
      for (int b = -50; b <= 50; b += 2)
        for (int c = -50; c <= 50; c += 2) expected += std::abs(a) + std::abs(b) + std::abs(c) < 51;
    CHECK(s.voxels_undecided == 0);
    CHECK(s.voxels_inside_body == expected);
    CHECK(s.body_volume == doctest::Approx(4.0 / 3.0).epsilon(0.03));
  }
}

TEST_CASE("coverage: a triangle soup (duplicated seam vertices) measures like the indexed mesh") {
  const std::vector<Ball> balls = {MakeBall(0.3, -0.05, 0.02, 0.4), MakeBall(-0.9, 0.3, 0.3, 0.35)};
  const TestMesh box = Box(1.0, 0.5, 0.5);
  const CoverageStats indexed = Measure(box, balls, 1.0f / 100);
  const CoverageStats soup = Measure(Soup(box), balls, 1.0f / 100);
  CHECK(indexed.protrusion > 0.05);  // the second ball sticks out of a corner
  CHECK(indexed.outside_max_rel > 0.0);
  CheckSame(indexed, soup);
  // And a soup of a curved surface, whose columns also run through the poles.
  const TestMesh sphere = UvSphere(1.0, 16, 32);
  CheckSame(Measure(sphere, {MakeBall(0.2, 0, 0, 0.9)}, 1.0f / 64),
            Measure(Soup(sphere), {MakeBall(0.2, 0, 0, 0.9)}, 1.0f / 64));
}

TEST_CASE("coverage: an open box (one face missing) still measures right by the axis vote") {
  const std::vector<Ball> balls = {MakeBall(0.3, -0.05, 0.02, 0.4), MakeBall(0.9, 0.3, 0.3, 0.35)};
  const CoverageStats closed = Measure(Box(1.0, 0.5, 0.5), balls, 1.0f / 100);
  for (int face : {0, 3, 4}) {
    CAPTURE(face);
    const CoverageStats open = Measure(Box(1.0, 0.5, 0.5, 1u << face), balls, 1.0f / 100);
    // The axis across the missing face is unknown inside its footprint; the other two decide.
    CHECK(open.voxels_undecided == 0);
    CHECK(open.voxels_inside_body == closed.voxels_inside_body);
    CHECK(open.coverage == doctest::Approx(closed.coverage).epsilon(0.01));
    CHECK(open.protrusion == doctest::Approx(closed.protrusion).epsilon(0.01));
  }
  // Two adjacent faces missing: one known axis is left over most of the box; still a majority.
  const CoverageStats two = Measure(Box(1.0, 0.5, 0.5, 1u | 4u), balls, 1.0f / 100);  // +x and +y
  CHECK(two.voxels_inside_body == closed.voxels_inside_body);
  CHECK(two.coverage == doctest::Approx(closed.coverage).epsilon(0.01));
}

TEST_CASE("coverage: max_voxels enlarges the voxels") {
  CoverageOptions o;
  o.voxel_rel = 1.0f / 1000;  // 10^9 voxels asked
  o.max_voxels = 20'000;
  const TestMesh box = Box(1.0, 0.5, 0.5);
  auto r = MeasureCoverage(box.positions, box.indices, {MakeBall(0, 0, 0, 0.4)}, o);
  REQUIRE(r.ok());
  CHECK(uint64_t{r->grid_dims[0]} * r->grid_dims[1] * r->grid_dims[2] <= 20'000u);
  CHECK(r->voxel_size > 0.04);  // 2/h³ ≤ 20,000: h ≥ 0.0464
  CHECK(r->body_volume == doctest::Approx(2.0).epsilon(0.15));
}

TEST_CASE("coverage: bad input is refused with kInvalidMesh / kConfig and a message saying what") {
  const TestMesh box = Box(1.0, 0.5, 0.5);
  const std::vector<Ball> one = {MakeBall(0, 0, 0, 0.4)};
  auto expect = [](const Result<CoverageStats>& r, Error::Code code, const char* fragment) {
    REQUIRE_FALSE(r.ok());
    CHECK_MESSAGE(r.error().code == code, r.error().message);
    CHECK_MESSAGE(r.error().message.find(fragment) != std::string::npos, r.error().message);
  };
  expect(MeasureCoverage({}, {}, one), Error::Code::kInvalidMesh, "no vertex");
  expect(MeasureCoverage(box.positions, {}, one), Error::Code::kInvalidMesh, "no triangle");
  TestMesh nan = box;
  nan.positions[3 * 5 + 1] = std::numeric_limits<float>::quiet_NaN();
  expect(MeasureCoverage(nan.positions, nan.indices, one), Error::Code::kInvalidMesh, "vertex 5");
  TestMesh bad_index = box;
  bad_index.indices[7] = 8;
  expect(MeasureCoverage(bad_index.positions, bad_index.indices, one), Error::Code::kInvalidMesh, "triangle 2");
  expect(MeasureCoverage(box.positions, box.indices, {}), Error::Code::kInvalidMesh, "no sphere");
  expect(MeasureCoverage(box.positions, box.indices, {MakeBall(0, std::nan(""), 0, 1)}), Error::Code::kInvalidMesh,
         "sphere 0");
  expect(MeasureCoverage(box.positions, box.indices, {one[0], MakeBall(0, 0, 0, -1)}), Error::Code::kInvalidMesh,
         "sphere 1");
  const std::vector<float> point = {1, 2, 3, 1, 2, 3, 1, 2, 3};
  expect(MeasureCoverage(point, {0, 1, 2}, one), Error::Code::kInvalidMesh, "zero extent");
  CoverageOptions o;
  o.voxel_rel = 0;
  expect(MeasureCoverage(box.positions, box.indices, one, o), Error::Code::kConfig, "voxel_rel");
  o = {};
  o.max_voxels = 0;
  expect(MeasureCoverage(box.positions, box.indices, one, o), Error::Code::kConfig, "max_voxels");
}

namespace {

struct Measured {
  CoverageStats phi1, phi1_adjusted, phi2, phi1_adjusted_holed;
};

// Bakes `path` and measures φ1, φ1' and φ2 against the imported body at 1/200 of its height.
Measured MeasureBake(const std::string& path, const std::string& name) {
  auto bake = Bake(path, BakeConfig{});
  REQUIRE_MESSAGE(bake.ok(), (bake.ok() ? "" : bake.error().message));
  std::vector<Ball> phi1, phi1a;
  for (const FittedSphere& s : bake->fit.spheres) {
    phi1.push_back({s.center_phi1, s.radius_phi1});
    phi1a.push_back({s.center, s.radius});
  }
  Measured m;
  for (auto [balls, out, label] : {std::tuple{&phi1, &m.phi1, std::string("phi1")},
                                   std::tuple{&phi1a, &m.phi1_adjusted, std::string("phi1'")},
                                   std::tuple{&bake->phi2, &m.phi2, std::string("phi2")}}) {
    const auto t0 = std::chrono::steady_clock::now();
    auto r = MeasureCoverage(bake->mesh.positions, bake->mesh.indices, *balls);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
    *out = r.value();
    const uint64_t voxels = uint64_t{out->grid_dims[0]} * out->grid_dims[1] * out->grid_dims[2];
    MESSAGE(name << " " << label << " (" << balls->size() << " spheres): coverage " << out->coverage
                 << ", protrusion " << out->protrusion << ", outside p95/max " << out->outside_p95_rel << " / "
                 << out->outside_max_rel << " of the height; body " << out->voxels_inside_body
                 << " voxels, spheres " << out->voxels_in_spheres << ", undecided " << out->voxels_undecided
                 << " of " << voxels << " (" << out->grid_dims[0] << "×" << out->grid_dims[1] << "×"
                 << out->grid_dims[2] << ", h = " << out->voxel_size << "); " << sec << " s");
    CHECK(out->voxels_undecided < 0.02 * double(voxels));
  }
  // The same body with holes: 1 triangle in 200 removed (fixed seed) — odd columns through each hole,
  // left to the other two axes.
  std::mt19937 rng(20240607u);
  std::vector<uint32_t> holed;
  for (size_t f = 0; f < bake->mesh.indices.size(); f += 3)
    if (rng() % 200 != 0) holed.insert(holed.end(), bake->mesh.indices.begin() + f, bake->mesh.indices.begin() + f + 3);
  auto r = MeasureCoverage(bake->mesh.positions, holed, phi1a);
  REQUIRE(r.ok());
  m.phi1_adjusted_holed = r.value();
  MESSAGE(name << " phi1' with " << (bake->mesh.indices.size() - holed.size()) / 3 << " triangles removed: coverage "
               << r->coverage << ", protrusion " << r->protrusion << ", body " << r->voxels_inside_body
               << " voxels, undecided " << r->voxels_undecided);
  return m;
}

}  // namespace

TEST_CASE("heavy: coverage: MakeHuman φ1, φ1', φ2 — φ1' fills most of the body and barely protrudes, φ2 fills it all") {
  const std::string path = test::SharedData("makehuman/base.obj");
  if (!test::Require(path)) return;
  const Measured m = MeasureBake(path, "MakeHuman");
  CHECK(m.phi1_adjusted.coverage > 0.3);
  CHECK(m.phi1_adjusted.coverage < 0.95);
  CHECK(m.phi1_adjusted.protrusion < 0.1);
  CHECK(m.phi2.coverage > m.phi1_adjusted.coverage);
  CHECK(m.phi2.coverage > 0.9);
  CHECK(m.phi2.protrusion > m.phi1_adjusted.protrusion);
  CHECK(m.phi1.coverage > 0.3);
  CHECK(m.phi1.protrusion < 0.1);
  CHECK(m.phi1_adjusted_holed.coverage == doctest::Approx(m.phi1_adjusted.coverage).epsilon(0.02));
  CHECK(m.phi1_adjusted_holed.body_volume == doctest::Approx(m.phi1_adjusted.body_volume).epsilon(0.02));
}

TEST_CASE("heavy: coverage: CesiumMan φ1, φ1', φ2") {
  const std::string path = test::SharedData("gltf/CesiumMan.gltf");
  if (!test::Require(path)) return;
  const Measured m = MeasureBake(path, "CesiumMan");
  CHECK(m.phi1_adjusted.coverage > 0.3);
  CHECK(m.phi2.coverage > m.phi1_adjusted.coverage);
  CHECK(m.phi2.protrusion > m.phi1_adjusted.protrusion);
  CHECK(m.phi1_adjusted_holed.coverage == doctest::Approx(m.phi1_adjusted.coverage).epsilon(0.02));
}
