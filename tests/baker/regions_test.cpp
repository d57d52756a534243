// Surrounding regions and pivot polygons (§5.1) on a tessellated cylinder with known spheres.
#include <doctest/doctest.h>

#include <cmath>
#include <set>

#include "spherechain/baker/regions.h"
#include "spherechain/runtime/refit.h"

using namespace spherechain::baker;

namespace {

// Open cylinder along +Y, radius R, from y = 0 to y = H, `seg` around, `rings` along.
Mesh Cylinder(double R, double H, int seg, int rings) {
  Mesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < seg; ++j) {
      const double a = 2 * M_PI * j / seg;
      m.positions.insert(m.positions.end(), {float(R * std::cos(a)), float(H * i / rings), float(R * std::sin(a))});
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < seg; ++j) {
      const uint32_t a = i * seg + j, b = i * seg + (j + 1) % seg, c = a + seg, d = b + seg;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  m.parts.push_back({"cylinder", 0, m.vertex_count(), 0, m.triangle_count()});
  return m;
}

}  // namespace

TEST_CASE("regions: every triangle goes to the nearest sphere of its region and pivots surround each sphere") {
  const double R = 1.0, H = 9.0;
  Mesh mesh = Cylinder(R, H, 32, 36);
  Segmentation seg;
  seg.triangle_regions.assign(mesh.triangle_count(), uint8_t(Region::kLeftArm));
  std::vector<FittedSphere> spheres(3);
  for (int k = 0; k < 3; ++k) {
    spheres[k].region = Region::kLeftArm;
    spheres[k].sequence = k;
    spheres[k].center = {0, 1.5 + 3.0 * k, 0};
    spheres[k].radius = R;
  }
  auto surr = BuildSurroundingRegions(mesh, seg, spheres);
  REQUIRE(surr.ok());
  REQUIRE(surr->offsets.size() == 4);
  CHECK(surr->offsets.back() == mesh.triangle_count());
  std::set<uint32_t> seen;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    // Nearest centre by the triangle centroid's height: boundaries at y = 3 and y = 6.
    double y = 0;
    for (int k = 0; k < 3; ++k) y += mesh.positions[3 * mesh.indices[3 * t + k] + 1] / 3.0;
    const int expect = y < 3.0 ? 0 : y < 6.0 ? 1 : 2;
    if (std::abs(y - 3.0) > 1e-3 && std::abs(y - 6.0) > 1e-3) CHECK(surr->triangle_spheres[t] == expect);
  }
  for (uint32_t t : surr->triangles) seen.insert(t);
  CHECK(seen.size() == mesh.triangle_count());

  auto piv = ChoosePivots(mesh, spheres, surr.value());
  REQUIRE(piv.ok());
  REQUIRE(piv->triangles.size() == 12);
  REQUIRE(piv->vertices.size() == 36);
  for (int s = 0; s < 3; ++s) {
    std::set<uint32_t> distinct(piv->triangles.begin() + 4 * s, piv->triangles.begin() + 4 * s + 4);
    CHECK(distinct.size() == 4);
    // Pivots belong to the sphere's surrounding region and lie near its level.
    float p[4][3];
    for (int k = 0; k < 4; ++k) {
      const uint32_t t = piv->triangles[4 * s + k];
      CHECK(surr->triangle_spheres[t] == s);
      for (int j = 0; j < 3; ++j) {
        float sum = 0;
        for (int q = 0; q < 3; ++q) sum += mesh.positions[3 * mesh.indices[3 * t + q] + j];
        p[k][j] = sum / 3.0f;
      }
      CHECK(std::abs(p[k][1] - spheres[s].center.y()) < 0.5);
    }
    // Spread around: the pivots' mean is near the axis, and the frame is well defined.
    const double mx = 0.25 * (p[0][0] + p[1][0] + p[2][0] + p[3][0]);
    const double mz = 0.25 * (p[0][2] + p[1][2] + p[2][2] + p[3][2]);
    CHECK(std::hypot(mx, mz) < 0.2 * R);
    spherechain::runtime::PivotFrameBasis basis;
    CHECK(spherechain::runtime::BuildPivotFrame(p, &basis));
    // The stored frame data puts the centre back where it was.
    float c[3];
    spherechain::runtime::PivotFrameToModel(basis, piv->frames[s].local_center.data(), c);
    CHECK(c[0] == doctest::Approx(spheres[s].center.x()).epsilon(1e-5));
    CHECK(c[1] == doctest::Approx(spheres[s].center.y()).epsilon(1e-5));
    CHECK(c[2] == doctest::Approx(spheres[s].center.z()).epsilon(1e-5));
    CHECK(piv->frames[s].mean_distance == doctest::Approx(R).epsilon(0.2));
  }
}

TEST_CASE("regions: no sphere at all is an error") {
  Mesh mesh = Cylinder(1, 2, 8, 2);
  Segmentation seg;
  seg.triangle_regions.assign(mesh.triangle_count(), 0);
  auto surr = BuildSurroundingRegions(mesh, seg, {});
  REQUIRE_FALSE(surr.ok());
  CHECK(surr.error().code == Error::Code::kFit);
}
