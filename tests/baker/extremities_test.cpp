// Head, hands and feet (segment.h SplitExtremities): the synthetic body with known answers (its head,
// feet and — when built with them — hands are capsules of their own), a body whose arms only taper (no
// hand to find), the real humans by rig and by geometry, and the documented error.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <string>

#include "spherechain/baker/chains.h"
#include "spherechain/import/import.h"
#include "spherechain/baker/segment.h"
#include "synthetic_body.h"
#include "test_data.h"

namespace sc = spherechain::baker;
using spherechain::test::AssimpModel;
using spherechain::test::MakeSyntheticBody;
using spherechain::test::Require;
using spherechain::test::SharedData;
using spherechain::test::SyntheticBody;

namespace {

/// Per Extremity value: triangles of that part in the construction (their nearest capsule is the part),
/// and how many of them the split labels so; and how many triangles it labels so that are far from the
/// part (on a capsule of no extremity, in the half of it nearer its root; the trunk below the neck).
struct PartScore {
  std::array<size_t, sc::kExtremityCount + 1> truth{}, found{}, stray{};
};

PartScore Score(const SyntheticBody& body, const sc::ExtremitySplit& split) {
  PartScore p;
  for (uint32_t t = 0; t < body.mesh.triangle_count(); ++t) {
    const auto& part = body.parts[size_t(body.part_of_triangle[t])];
    const uint8_t got = split.triangle_parts[t];
    if (part.extremity < 0) continue;  // wrist, ankle: the cut lies in them
    if (part.extremity > 0) {
      ++p.truth[size_t(part.extremity)];
      p.found[size_t(part.extremity)] += got == part.extremity;
    } else if (got != 0 && body.along_part[t] < 0.5 && part.region != sc::Region::kTorso) {
      ++p.stray[got];
    } else if (got != 0 && part.region == sc::Region::kTorso && part.a[1] < 1.3) {
      // The trunk is never head below the base of the neck (y 1.53, where the neck leaves the trunk's
      // dome): the neck is one width all along, so the cut may lie anywhere on it, down to its base ring.
      double y = 0.0;
      for (int k = 0; k < 3; ++k) y += body.mesh.positions[3 * body.mesh.indices[3 * t + k] + 1] / 3.0;
      p.stray[got] += y < 1.5;
    }
  }
  return p;
}

}  // namespace

TEST_CASE("extremities: synthetic body with wrists, palms and ankles, by geometry — head, both hands and both feet, known answer") {
  for (bool t_pose : {false, true}) {
    CAPTURE(t_pose);
    const SyntheticBody body = MakeSyntheticBody(t_pose, 0, /*extremities=*/true);
    auto seg = sc::SegmentByGeometry(body.mesh);
    REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
    auto split = sc::SplitExtremities(body.mesh, seg.value(), sc::ExtremityMethod::kGeometry);
    REQUIRE_MESSAGE(split.ok(), (split.ok() ? "" : split.error().message));
    MESSAGE(split->notes);
    const PartScore p = Score(body, split.value());
    for (int e = 1; e <= sc::kExtremityCount; ++e) {
      CAPTURE(sc::ExtremityName(sc::Extremity(e)));
      CHECK(split->method[size_t(e)] == "geometry");
      REQUIRE(p.truth[size_t(e)] > 50);
      // The cut lies at the narrowest section (wrist, ankle, neck): almost every triangle of the part's own
      // capsules is beyond it, and nothing of the limb's first two thirds or of the trunk is.
      CHECK(double(p.found[size_t(e)]) >= 0.9 * double(p.truth[size_t(e)]));
      CHECK(p.stray[size_t(e)] == 0);
    }
    // Never outside the parent region: a hand only in its arm, a foot only in its leg, the head in the torso.
    for (uint32_t t = 0; t < body.mesh.triangle_count(); ++t) {
      const uint8_t e = split->triangle_parts[t], r = seg->triangle_regions[t];
      if (e == uint8_t(sc::Extremity::kLeftHand)) CHECK(r == uint8_t(sc::Region::kLeftArm));
      if (e == uint8_t(sc::Extremity::kRightHand)) CHECK(r == uint8_t(sc::Region::kRightArm));
      if (e == uint8_t(sc::Extremity::kLeftFoot)) CHECK(r == uint8_t(sc::Region::kLeftLeg));
      if (e == uint8_t(sc::Extremity::kRightFoot)) CHECK(r == uint8_t(sc::Region::kRightLeg));
      if (e == uint8_t(sc::Extremity::kHead)) CHECK(r == uint8_t(sc::Region::kTorso));
    }
  }
}

TEST_CASE("extremities: arms that only taper have no hands (a mitten, a stump); the head is still found") {
  const SyntheticBody body = MakeSyntheticBody(false);  // arms end in their round cap
  auto seg = sc::SegmentByGeometry(body.mesh);
  REQUIRE(seg.ok());
  auto split = sc::SplitExtremities(body.mesh, seg.value());
  REQUIRE(split.ok());
  MESSAGE(split->notes);
  CHECK(split->method[size_t(sc::Extremity::kLeftHand)].empty());
  CHECK(split->method[size_t(sc::Extremity::kRightHand)].empty());
  CHECK(split->notes.find("hands: none") != std::string::npos);
  const PartScore p = Score(body, split.value());
  CHECK(p.found[size_t(sc::Extremity::kLeftHand)] + p.found[size_t(sc::Extremity::kRightHand)] == 0);
  CHECK(double(p.found[size_t(sc::Extremity::kHead)]) >= 0.9 * double(p.truth[size_t(sc::Extremity::kHead)]));
  CHECK(p.stray[size_t(sc::Extremity::kHead)] == 0);
}

TEST_CASE("extremities: a segmentation of another mesh is an error") {
  sc::Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  sc::Segmentation wrong;
  wrong.triangle_regions.assign(1, uint8_t(sc::Region::kTorso));
  auto split = sc::SplitExtremities(mesh, wrong);
  REQUIRE_FALSE(split.ok());
  CHECK(split.error().code == sc::Error::Code::kSegmentation);
  CHECK(split.error().message.find("triangle count") != std::string::npos);
}

TEST_CASE("extremities (heavy): MakeHuman — hands and feet by the rig's bones, the same by geometry") {
  const std::string path = SharedData("makehuman/base.obj");
  if (!Require(path)) return;
  auto mesh = sc::ImportMesh(path);
  REQUIRE(mesh.ok());
  auto seg = sc::SegmentByRig(mesh.value());
  REQUIRE(seg.ok());
  auto rig = sc::SplitExtremities(mesh.value(), seg.value(), sc::ExtremityMethod::kAuto);
  auto geo = sc::SplitExtremities(mesh.value(), seg.value(), sc::ExtremityMethod::kGeometry);
  REQUIRE(rig.ok());
  REQUIRE(geo.ok());
  MESSAGE("auto: " << rig->notes << "\ngeometry: " << geo->notes);
  for (int e = 2; e <= sc::kExtremityCount; ++e) CHECK(rig->method[size_t(e)] == "rig");
  CHECK(rig->method[size_t(sc::Extremity::kHead)] == "geometry");
  // Rig and geometry agree on each part (IoU over triangles): the wrist bone and the narrowest section of the
  // forearm, the foot bones and the ankle, are a few rings of quads apart.
  for (int e = 1; e <= sc::kExtremityCount; ++e) {
    CAPTURE(sc::ExtremityName(sc::Extremity(e)));
    size_t both = 0, either = 0;
    for (uint32_t t = 0; t < mesh->triangle_count(); ++t) {
      const bool a = rig->triangle_parts[t] == e, b = geo->triangle_parts[t] == e;
      both += a && b, either += a || b;
    }
    REQUIRE(either > 0);
    CHECK(double(both) / double(either) >= 0.85);
  }
  // Symmetric body, symmetric parts.
  auto count = [&](const sc::ExtremitySplit& s, sc::Extremity e) {
    size_t n = 0;
    for (uint8_t p : s.triangle_parts) n += p == uint8_t(e);
    return n;
  };
  CHECK(count(rig.value(), sc::Extremity::kLeftHand) == count(rig.value(), sc::Extremity::kRightHand));
  CHECK(count(geo.value(), sc::Extremity::kLeftFoot) == count(geo.value(), sc::Extremity::kRightFoot));
}

TEST_CASE("extremities (heavy): the humans of assimp-testmodels and CesiumMan — found where the mesh has them") {
  struct Case {
    std::string path;
    bool hands, feet;
  };
  // HUMAN.blend's arms and legs end in tapered stumps: no hands, no feet; every other body has both.
  spherechain::test::SomeInputs inputs;
  for (const Case& c : {Case{AssimpModel("X/BCN_Epileptic.X"), true, true}, Case{AssimpModel("Collada/human.zae"), true, true},
                        Case{AssimpModel("BLEND/HUMAN.blend"), false, false}, Case{SharedData("gltf/CesiumMan.gltf"), true, true}}) {
    CAPTURE(c.path);
    if (!inputs.Found(c.path)) continue;
    auto mesh = sc::ImportMesh(c.path);
    REQUIRE(mesh.ok());
    auto seg = sc::Segment(mesh.value(), sc::SegmentMethod::kAuto);
    REQUIRE(seg.ok());
    auto split = sc::SplitExtremities(mesh.value(), seg.value());
    REQUIRE(split.ok());
    MESSAGE(c.path << ": " << split->notes);
    CHECK(split->method[size_t(sc::Extremity::kHead)] == "geometry");
    CHECK(split->method[size_t(sc::Extremity::kLeftHand)].empty() != c.hands);
    CHECK(split->method[size_t(sc::Extremity::kRightHand)].empty() != c.hands);
    CHECK(split->method[size_t(sc::Extremity::kLeftFoot)].empty() != c.feet);
    CHECK(split->method[size_t(sc::Extremity::kRightFoot)].empty() != c.feet);
  }
}

// ---- the extended layout (regions: extended) -----------------------------------------------------------

TEST_CASE("extended layout: ApplyExtremities makes head, hands and feet regions — order, mirrors, parents, the torso last") {
  const SyntheticBody body = MakeSyntheticBody(false, 0, /*extremities=*/true);
  auto seg = sc::SegmentByGeometry(body.mesh);
  REQUIRE(seg.ok());
  const sc::Segmentation five = seg.value();
  auto split = sc::SplitExtremities(body.mesh, five, sc::ExtremityMethod::kGeometry);
  REQUIRE(split.ok());
  sc::Segmentation ext = five;
  REQUIRE(sc::ApplyExtremities(body.mesh, split.value(), &ext).ok());
  const sc::RegionLayout& L = ext.layout;
  REQUIRE(L.count() == 10);
  CHECK(L.paper);
  CHECK_FALSE(L.IsPaperFive());
  const char* names[10] = {"left_arm", "right_arm", "left_leg", "right_leg", "head",
                           "left_hand", "right_hand", "left_foot", "right_foot", "torso"};
  for (int k = 0; k < 10; ++k) CHECK(L.regions[size_t(k)].name == names[k]);
  CHECK(L.IsTrunk(sc::Region(9)));
  CHECK(L.regions[9].kind == sc::RegionKind::kTrunk);
  // Hands and feet mirror each other and hang off their limb; the head off the torso.
  CHECK(L.regions[5].mirror == 6);
  CHECK(L.regions[7].mirror == 8);
  CHECK(int(L.Parent(sc::Region(5))) == 0);
  CHECK(int(L.Parent(sc::Region(6))) == 1);
  CHECK(int(L.Parent(sc::Region(7))) == 2);
  CHECK(int(L.Parent(sc::Region(8))) == 3);
  CHECK(int(L.Parent(sc::Region(4))) == 9);
  CHECK(L.regions[5].volume_group == 0);
  CHECK(L.regions[4].volume_group == 9);
  // Every triangle moved by its part: a part's triangles to its region, the torso's to R9, the rest kept.
  for (uint32_t t = 0; t < body.mesh.triangle_count(); ++t) {
    const uint8_t p = split->triangle_parts[t], before = five.triangle_regions[t], after = ext.triangle_regions[t];
    if (p != 0) CHECK(after == uint8_t(L.Find(sc::ExtremityName(sc::Extremity(p)))));
    else if (before == uint8_t(sc::Region::kTorso)) CHECK(after == 9);
    else CHECK(after == before);
  }
  // Only the paper's five are split; a creature's layout is refused.
  sc::Segmentation again = ext;
  CHECK_FALSE(sc::ApplyExtremities(body.mesh, split.value(), &again).ok());
  CHECK_FALSE(sc::SplitExtremities(body.mesh, ext).ok());
}

TEST_CASE("extended layout: a body without hands keeps its arms whole — only the parts found become regions") {
  const SyntheticBody body = MakeSyntheticBody(false);  // arms end in round caps
  auto seg = sc::SegmentByGeometry(body.mesh);
  REQUIRE(seg.ok());
  auto split = sc::SplitExtremities(body.mesh, seg.value(), sc::ExtremityMethod::kGeometry);
  REQUIRE(split.ok());
  sc::Segmentation ext = seg.value();
  REQUIRE(sc::ApplyExtremities(body.mesh, split.value(), &ext).ok());
  CHECK(ext.layout.Find("left_hand") < 0);
  CHECK(ext.layout.Find("head") == 4);
  CHECK(ext.layout.regions.back().name == "torso");
  CHECK(ext.layout.count() == 5 + 1 + (split->method[size_t(sc::Extremity::kLeftFoot)].empty() ? 0 : 2));
}

TEST_CASE("extended layout: Table 1's chains extended — each limb with its hand or foot, the head with both sides and the arms") {
  sc::RegionLayout L;
  L.regions = sc::RegionLayout::PaperRegions();
  CHECK(sc::ExtendedChainDefs(L).size() == sc::DefaultChainDefs().size());
  for (size_t i = 0; i < sc::DefaultChainDefs().size(); ++i) CHECK(sc::ExtendedChainDefs(L)[i].members == sc::DefaultChainDefs()[i].members);
  // The layout ApplyExtremities builds when every part is found.
  sc::RegionInfo torso = L.regions.back();
  L.regions.pop_back();
  const char* parts[5] = {"head", "left_hand", "right_hand", "left_foot", "right_foot"};
  const int parents[5] = {-1, 0, 1, 2, 3};
  for (int k = 0; k < 5; ++k) {
    sc::RegionInfo r;
    r.name = parts[k];
    r.parent = parents[k];
    L.regions.push_back(r);
  }
  L.regions.push_back(torso);
  const auto defs = sc::ExtendedChainDefs(L);
  REQUIRE(defs.size() == 6);
  auto has = [](const sc::ChainDef& d, const char* m) { return std::find(d.members.begin(), d.members.end(), m) != d.members.end(); };
  // ζ0 = R0 ∪ left hand ∪ R9L ∪ R2 ∪ left foot ∪ head.
  for (const char* m : {"R0", "R5", "R9L", "R2", "R7", "R4"}) CHECK_MESSAGE(has(defs[0], m), "zeta0 " << m);
  CHECK_FALSE(has(defs[0], "R6"));
  // ζ2 both arms, both hands, the shoulders' band and the head: hand on face, fingers interlocked.
  for (const char* m : {"R0", "R5", "R9T", "R1", "R6", "R4"}) CHECK_MESSAGE(has(defs[2], m), "zeta2 " << m);
  // ζ3 both legs and feet: a foot on the other shin.
  for (const char* m : {"R2", "R7", "R9D", "R3", "R8"}) CHECK_MESSAGE(has(defs[3], m), "zeta3 " << m);
  CHECK_FALSE(has(defs[3], "R4"));
  // The torso's labels belong to R9 here: R4L (the paper's) is refused, and the message names R9's.
  auto refused = sc::BuildChains({}, {{"bad", {"R4L"}}}, L);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("(expected R0..R9, R9L, R9R, R9T or R9D)") != std::string::npos);
}

TEST_CASE("extended layout: the junction exclusion follows the parent — a hand with its forearm, not with the torso") {
  sc::RegionLayout L;
  sc::RegionInfo torso = L.regions.back();
  L.regions.pop_back();
  sc::RegionInfo hand;
  hand.name = "left_hand";
  hand.parent = 0;
  L.regions.push_back(hand);  // R4
  L.regions.push_back(torso);  // R5
  auto sphere = [](int region, double x, double r) {
    sc::FittedSphere s;
    s.region = sc::Region(region);
    s.center = {x, 0, 0};
    s.radius = r;
    return s;
  };
  // 0: forearm; 1: hand 1.1 (rA + rB) from it (the wrist's crease); 2: torso, as close to the hand again.
  const std::vector<sc::FittedSphere> spheres = {sphere(0, 0.0, 1.0), sphere(4, 2.2, 1.0), sphere(5, 4.4, 1.0)};
  sc::ExclusionReasons why;
  const auto pairs = sc::BindExcludedPairs(spheres, 0.0, &why, nullptr, sc::UpAxis::kY, &L);
  CHECK(std::find(pairs.begin(), pairs.end(), sc::SpherePair{0, 1}) != pairs.end());
  CHECK(std::find(pairs.begin(), pairs.end(), sc::SpherePair{1, 2}) == pairs.end());
  CHECK(why.junction == 1);
}
