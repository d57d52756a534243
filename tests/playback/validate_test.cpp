// playback::ValidateAsset on synthetic assets (tests/runtime/asset_builder.h tubes) with known answers:
// each broken asset or mesh gives the documented finding code, severity and location.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "runtime/asset_builder.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/validate.h"

namespace sc = spherechain;
using sc::playback::Finding;
using sc::playback::Severity;

namespace {

sc::import::Mesh ToMesh(const sc::test::Mesh& m) {
  sc::import::Mesh mesh;
  mesh.positions = m.positions;
  mesh.indices = m.triangles;
  return mesh;
}

/// Two tubes (crossing or apart), fingerprint hashes of their mesh recorded, and that mesh.
sc::test::AssetData Tubes(bool crossing, sc::import::Mesh* mesh) {
  sc::test::Mesh m;
  sc::test::AssetData d = sc::test::TwoTubes(crossing, &m);
  *mesh = ToMesh(m);
  const sc::import::Fingerprint fp = sc::import::ComputeFingerprint(*mesh);
  d.positions_hash = fp.positions_hash;
  d.indices_hash = fp.indices_hash;
  return d;
}

std::vector<Finding> Validate(const sc::test::AssetData& d, const sc::import::Mesh* mesh) {
  const sc::test::AlignedBytes bytes = sc::test::Serialize(d);
  return sc::playback::ValidateAssetBytes(bytes.data(), bytes.size, mesh, {"tubes.sphc", "tubes.obj"});
}

std::vector<Finding> WithCode(const std::vector<Finding>& all, const std::string& code) {
  std::vector<Finding> out;
  for (const Finding& f : all)
    if (f.code == code) out.push_back(f);
  return out;
}

}  // namespace

TEST_CASE("validate: a correct asset against its own mesh has only the documented warnings") {
  sc::import::Mesh mesh;
  const auto d = Tubes(false, &mesh);
  const auto findings = Validate(d, &mesh);
  CHECK(sc::playback::CountErrors(findings) == 0);
  // The builder gives each tube's last sphere no surrounding triangles: spheres 7 and 15.
  REQUIRE(findings.size() == 2);
  for (size_t i = 0; i < 2; ++i) {
    CHECK(findings[i].code == "SPHERE-NO-REGION");
    CHECK(findings[i].severity == Severity::kWarning);
    CHECK(findings[i].location.file == "tubes.sphc");
    CHECK(findings[i].location.field == "surrounding_offsets");
  }
  CHECK(findings[0].location.sphere == 7);
  CHECK(findings[1].location.sphere == 15);
  CHECK(findings[0].location.ToString() == "tubes.sphc sphere 7 field surrounding_offsets");
}

TEST_CASE("validate: crossing tubes report every overlapping bind pair, located by sphere pair") {
  sc::import::Mesh mesh;
  const auto d = Tubes(true, &mesh);
  const auto found = WithCode(Validate(d, &mesh), "BIND-COLLISION");
  // Known answer: every (tube A sphere, tube B sphere) whose bind spheres overlap (margin 0); pairs
  // inside a tube are adjacent (excluded) or apart.
  std::set<std::pair<int, int>> expected;
  for (int a = 0; a < 8; ++a)
    for (int b = 8; b < 16; ++b) {
      const auto& sa = d.spheres[a];
      const auto& sb = d.spheres[b];
      const float dx = sa.center().x() - sb.center().x(), dy = sa.center().y() - sb.center().y(),
                  dz = sa.center().z() - sb.center().z();
      if (dx * dx + dy * dy + dz * dz < (sa.radius() + sb.radius()) * (sa.radius() + sb.radius())) expected.emplace(a, b);
    }
  REQUIRE(!expected.empty());
  CHECK(expected.count({3, 11}) == 1);
  std::set<std::pair<int, int>> got;
  for (const Finding& f : found) {
    CHECK(f.severity == Severity::kError);
    CHECK(f.location.sphere < f.location.other_sphere);
    got.emplace(f.location.sphere, f.location.other_sphere);
  }
  CHECK(got == expected);
  CHECK(found.size() == expected.size());
  CHECK(found.front().location.ToString().rfind("spheres ", 0) == 0);
}

TEST_CASE("validate: a negative radius is SPHC-LOAD located at that sphere's radius") {
  sc::import::Mesh mesh;
  auto d = Tubes(false, &mesh);
  d.spheres[5] = sc::schema::Sphere(d.spheres[5].center(), -1.0f);
  const auto findings = Validate(d, &mesh);
  REQUIRE(findings.size() == 1);
  CHECK(findings[0].code == "SPHC-LOAD");
  CHECK(findings[0].severity == Severity::kError);
  CHECK(findings[0].location.sphere == 5);
  CHECK(findings[0].location.field == "spheres.radius");
  CHECK(findings[0].message.find("kErrorRadius") != std::string::npos);
  CHECK(findings[0].message.find("'tubes.sphc' is not a loadable .sphc asset") == 0);
}

TEST_CASE("validate: a NaN centre is SPHC-LOAD located at that sphere's centre") {
  sc::import::Mesh mesh;
  auto d = Tubes(false, &mesh);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  d.spheres[2] = sc::schema::Sphere(sc::schema::Vec3(nan, 0, 0), d.spheres[2].radius());
  const auto findings = Validate(d, nullptr);
  REQUIRE(findings.size() == 1);
  CHECK(findings[0].code == "SPHC-LOAD");
  CHECK(findings[0].message.find("kErrorNonFinite") != std::string::npos);
  CHECK(findings[0].location.sphere == 2);
  CHECK(findings[0].location.field == "spheres.center");
}

TEST_CASE("validate: an unsorted chain is SPHC-LOAD located at that chain") {
  sc::import::Mesh mesh;
  auto d = Tubes(false, &mesh);
  std::swap(d.chains[1][2], d.chains[1][3]);
  const auto findings = Validate(d, nullptr);
  REQUIRE(findings.size() == 1);
  CHECK(findings[0].code == "SPHC-LOAD");
  CHECK(findings[0].message.find("kErrorChainOrder") != std::string::npos);
  CHECK(findings[0].location.chain == 1);
  CHECK(findings[0].location.field == "chains.spheres");
}

TEST_CASE("validate: spheres in no chain are SPHERE-NO-CHAIN warnings, one per sphere") {
  sc::test::Mesh m;
  sc::test::Tube a, b;
  b.origin[2] = 10.0f;
  const auto d = sc::test::MakeTubes({a, b}, {{0}}, &m);  // one chain: tube A only
  const auto found = WithCode(Validate(d, nullptr), "SPHERE-NO-CHAIN");
  REQUIRE(found.size() == 8);
  for (size_t i = 0; i < found.size(); ++i) {
    CHECK(found[i].location.sphere == int(8 + i));
    CHECK(found[i].severity == Severity::kWarning);
  }
}

TEST_CASE("validate: mesh mismatches give FP-COUNTS, FP-INDICES, FP-POSITIONS") {
  sc::import::Mesh mesh;
  const auto d = Tubes(false, &mesh);
  {
    sc::import::Mesh more = mesh;
    more.indices.insert(more.indices.end(), {0, 1, 2});
    const auto f = WithCode(Validate(d, &more), "FP-COUNTS");
    REQUIRE(f.size() == 1);
    CHECK(f[0].severity == Severity::kError);
    CHECK(f[0].location.file == "tubes.obj");
    CHECK(f[0].message.find("triangles, the asset was baked from") != std::string::npos);
  }
  {
    sc::import::Mesh flipped = mesh;
    std::swap(flipped.indices[0], flipped.indices[1]);
    const auto all = Validate(d, &flipped);
    CHECK(WithCode(all, "FP-INDICES").size() == 1);
    CHECK(WithCode(all, "FP-POSITIONS").empty());
    CHECK(sc::playback::CountErrors(all) == 1);
  }
  {
    sc::import::Mesh moved = mesh;
    moved.positions[0] += 1e-3f;
    const auto all = Validate(d, &moved);
    const auto f = WithCode(all, "FP-POSITIONS");
    REQUIRE(f.size() == 1);
    CHECK(f[0].severity == Severity::kError);  // every other command refuses the pair (character.cpp)
    CHECK(sc::playback::CountErrors(all) == 1);
  }
}

TEST_CASE("validate: truncated bytes and a missing file are SPHC-LOAD errors") {
  sc::import::Mesh mesh;
  const auto d = Tubes(false, &mesh);
  const sc::test::AlignedBytes bytes = sc::test::Serialize(d);
  for (size_t n : {size_t(0), size_t(4), bytes.size / 2}) {
    const auto f = sc::playback::ValidateAssetBytes(bytes.data(), n, &mesh);
    REQUIRE(f.size() == 1);
    CHECK(f[0].code == "SPHC-LOAD");
    CHECK(f[0].location.sphere == -1);
  }
  const auto f = sc::playback::ValidateAssetFile("/nonexistent/x.sphc", "/nonexistent/x.obj");
  REQUIRE(f.size() == 1);
  CHECK(f[0].code == "SPHC-LOAD");
  CHECK(f[0].location.file == "/nonexistent/x.sphc");
  // An invalid view is one SPHC-LOAD, never a crash.
  const auto g = sc::playback::ValidateAsset(sc::runtime::AssetView{}, &mesh);
  REQUIRE(g.size() == 1);
  CHECK(g[0].code == "SPHC-LOAD");
}
