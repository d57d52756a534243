// baker::ContactPoints: where two intersecting triangles meet, on hand-made pairs with known answers
// (crossing, touching at a corner, coplanar overlap), the fallback for a pair that does not meet, and the
// errors.
#include <doctest/doctest.h>

#include <limits>
#include <string>
#include <vector>

#include "spherechain/baker/contacts.h"

namespace sb = spherechain::baker;

namespace {

// Two triangles per case: vertices 0..2 and 3..5; indices 0..5.
struct TwoTriangles {
  std::vector<float> positions;
  std::vector<uint32_t> indices{0, 1, 2, 3, 4, 5};
};

Eigen::Vector3d PointOf(const TwoTriangles& m) {
  auto r = sb::ContactPoints(m.positions.data(), 6, m.indices, {{0, 1}});
  REQUIRE(r.ok());
  REQUIRE(r.value().size() == 1);
  return r.value()[0];
}

}  // namespace

TEST_CASE("ContactPoints: the midpoint of the intersection segment of two crossing triangles") {
  // A in the plane z = 0; B in the plane x = 0 with one corner on z = 0. B cuts the plane z = 0 along
  // x = 0, y in [0, 2]; A spans y in [-1, 2] along x = 0: the triangles meet on x = 0, z = 0, y in [0, 2].
  TwoTriangles m;
  m.positions = {-1, -1, 0, 3, -1, 0, -1, 3, 0,  // A
                 0, 0, -1, 0, 0, 1, 0, 2, 0};    // B
  const Eigen::Vector3d p = PointOf(m);
  CHECK(p.x() == doctest::Approx(0.0));
  CHECK(p.y() == doctest::Approx(1.0));
  CHECK(p.z() == doctest::Approx(0.0));

  // Shift B along y: the overlap becomes y in [0.5, 2] (A ends at y = 2 on x = 0), midpoint 1.25.
  for (int v = 3; v < 6; ++v) m.positions[3 * v + 1] += 0.5f;
  const Eigen::Vector3d q = PointOf(m);
  CHECK(q.y() == doctest::Approx(1.25));
  CHECK(q.x() == doctest::Approx(0.0));
}

TEST_CASE("ContactPoints: touching at one point, coplanar overlap, and apart") {
  SUBCASE("a corner of B on A's face") {
    TwoTriangles m;
    m.positions = {0, 0, 0, 4, 0, 0, 0, 4, 0,      // A in z = 0
                   1, 1, 0, 1, 1, 2, 2, 1, 3};     // B touches z = 0 at (1, 1, 0) only
    const Eigen::Vector3d p = PointOf(m);
    CHECK(p.x() == doctest::Approx(1.0));
    CHECK(p.y() == doctest::Approx(1.0));
    CHECK(p.z() == doctest::Approx(0.0));
  }
  SUBCASE("coplanar: the overlap's centroid") {
    // A = the right triangle (0,0) (2,0) (0,2); B = the same shape shifted by (1, 0): the overlap is the
    // triangle (1,0) (2,0) (1,1), centroid (4/3, 1/3).
    TwoTriangles m;
    m.positions = {0, 0, 5, 2, 0, 5, 0, 2, 5, 1, 0, 5, 3, 0, 5, 1, 2, 5};
    const Eigen::Vector3d p = PointOf(m);
    CHECK(p.x() == doctest::Approx(4.0 / 3.0));
    CHECK(p.y() == doctest::Approx(1.0 / 3.0));
    CHECK(p.z() == doctest::Approx(5.0));
  }
  SUBCASE("apart: the midpoint of the centroids") {
    TwoTriangles m;
    m.positions = {0, 0, 0, 3, 0, 0, 0, 3, 0, 0, 0, 6, 3, 0, 6, 0, 3, 6};
    const Eigen::Vector3d p = PointOf(m);
    CHECK(p.x() == doctest::Approx(1.0));
    CHECK(p.y() == doctest::Approx(1.0));
    CHECK(p.z() == doctest::Approx(3.0));
  }
}

TEST_CASE("ContactPoints: errors name what is wrong and where") {
  TwoTriangles m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  auto far = sb::ContactPoints(m.positions.data(), 6, m.indices, {{0, 7}});
  REQUIRE_FALSE(far.ok());
  CHECK(far.error().code == sb::Error::Code::kInvalidMesh);
  CHECK(far.error().message.find("out of range") != std::string::npos);

  m.indices[4] = 9;  // triangle 1 references vertex 9 of 6
  auto bad = sb::ContactPoints(m.positions.data(), 6, m.indices, {{0, 1}});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("vertex 9") != std::string::npos);

  m.indices[4] = 4;
  m.positions[3 * 5] = std::numeric_limits<float>::quiet_NaN();
  auto nan = sb::ContactPoints(m.positions.data(), 6, m.indices, {{0, 1}});
  REQUIRE_FALSE(nan.ok());
  CHECK(nan.error().message.find("non-finite") != std::string::npos);

  auto none = sb::ContactPoints(m.positions.data(), 6, m.indices, {});
  REQUIRE(none.ok());
  CHECK(none.value().empty());
}
