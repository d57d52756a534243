// The any-skeleton path (issue 11): rigged creatures segmented by their bone tree into limbs and a trunk,
// their region layout through the fit, chains, exclusions and the asset (schema v4), and its bad inputs.
// Known answer: tests/data/creature/creature.gltf (make_creature.py: a four-legged animal of cubes with a
// tail, 1504 triangles — trunk 856, each leg 136, tail 104 — skinned rigidly, a clip crossing the fore
// legs). Real creature: Debian assimp-testmodels' X/Testwuson.X (skips visibly when absent).
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <vector>
#include <unistd.h>

#include "spherechain/baker/bake.h"
#include "spherechain/baker/chains.h"
#include "spherechain/import/import.h"
#include "spherechain/baker/plausibility.h"
#include "spherechain/baker/segment.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/play.h"
#include "spherechain/runtime/asset.h"
#include "test_data.h"

namespace sc = spherechain::baker;
namespace rt = spherechain::runtime;
namespace fs = std::filesystem;
using spherechain::test::Require;

namespace {

std::string Creature() { return spherechain::test::SourceFile("tests/data/creature/creature.gltf"); }
std::string Snake() { return spherechain::test::SourceFile("tests/data/creature/snake.gltf"); }

sc::Mesh Import(const std::string& path) {
  auto m = sc::ImportMesh(path);
  REQUIRE_MESSAGE(m.ok(), (m.ok() ? "" : m.error().message));
  return std::move(m).value();
}

size_t Count(const sc::Segmentation& seg, int region) {
  return size_t(std::count(seg.triangle_regions.begin(), seg.triangle_regions.end(), uint8_t(region)));
}

/// The bake configuration of the fast tests: coarse voxels (0.2 s a creature bake).
sc::BakeConfig Fast() {
  sc::BakeConfig c;
  c.fit.cover_voxel_rel = 0.01;
  return c;
}

std::string Write(const std::string& name, const nlohmann::json& j) {
  const fs::path p = fs::temp_directory_path() / ("spherechain_skeleton_" + name + "." + std::to_string(::getpid()) + ".json");
  std::ofstream(p) << j.dump();
  return p.string();
}

}  // namespace

TEST_CASE("segment (skeleton): the synthetic creature — trunk, four legs and a tail with exact triangle counts") {
  const sc::Mesh mesh = Import(Creature());
  REQUIRE(mesh.triangle_count() == 1504);
  auto seg = sc::SegmentBySkeleton(mesh);
  REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
  CHECK(seg->method == "skeleton");
  const sc::RegionLayout& L = seg->layout;
  CHECK_FALSE(L.paper);
  REQUIRE(L.count() == 6);
  const char* names[6] = {"Tail", "HindLeg_L", "HindLeg_R", "ForeLeg_L", "ForeLeg_R", "trunk"};
  const size_t triangles[6] = {104, 136, 136, 136, 136, 856};
  for (int r = 0; r < 6; ++r) {
    CAPTURE(r);
    CHECK(L.regions[size_t(r)].name == names[r]);
    CHECK(Count(seg.value(), r) == triangles[r]);
    CHECK((L.regions[size_t(r)].kind == sc::RegionKind::kTrunk) == (r == 5));
  }
  CHECK(L.IsTrunk(sc::Region(5)));
  CHECK(L.regions[1].mirror == 2);  // HindLeg_L ↔ HindLeg_R
  CHECK(L.regions[3].mirror == 4);  // ForeLeg_L ↔ ForeLeg_R
  CHECK(L.regions[0].mirror == -1);
  CHECK(L.regions[0].bone == "Tail01");
  CHECK(L.regions[5].bone == "Spine");
  CHECK(std::abs(L.trunk_axis[2]) > 0.99);  // the body lies along Z
  CHECK(seg->notes.find("trunk bones: Spine Pelvis Chest") != std::string::npos);
  // Every vertex takes its triangles' region; none is left out.
  CHECK(std::none_of(seg->vertex_regions.begin(), seg->vertex_regions.end(), [](uint8_t r) { return r >= 6; }));
  // The creature passes the checks that apply to it (balance by mirror pairs, limbs attached).
  CHECK(sc::CheckPlausibility(mesh, seg.value(), nullptr, nullptr).empty());
  // Auto: neither the rig rules (no arms) nor geometry (no standing body) take it; the skeleton does.
  auto autoseg = sc::Segment(mesh, sc::SegmentMethod::kAuto);
  REQUIRE(autoseg.ok());
  CHECK(autoseg->method == "skeleton");
}

TEST_CASE("segment (skeleton): bad input — no recognisable limbs, no skin, a single bone — says why") {
  SUBCASE("a chain of bones (snake.gltf): no junction") {
    auto r = sc::SegmentBySkeleton(Import(Snake()));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().code == sc::Error::Code::kSegmentation);
    CHECK(r.error().message.find("no recognisable limbs") != std::string::npos);
    CHECK(r.error().message.find("Seg0") != std::string::npos);  // the bones are named
  }
  SUBCASE("a mesh without a skin") {
    sc::Mesh mesh = Import(Creature());
    mesh.skin.reset();
    auto r = sc::SegmentBySkeleton(mesh);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("the mesh has no skin") != std::string::npos);
    // Auto says both: not a standing body, and no rig for a creature.
    auto a = sc::Segment(mesh, sc::SegmentMethod::kAuto);
    REQUIRE_FALSE(a.ok());
    CHECK(a.error().message.find("not a standing body") != std::string::npos);
    CHECK(a.error().message.find("needs a rig") != std::string::npos);
  }
  SUBCASE("every weight on one bone") {
    sc::Mesh mesh = Import(Creature());
    sc::Skin& skin = *mesh.skin;
    for (size_t k = 0; k < skin.weights.size(); ++k) skin.weight_joints[k] = 0;
    auto r = sc::SegmentBySkeleton(mesh);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("the skin uses 1 bone (Spine)") != std::string::npos);
  }
  SUBCASE("a limb share past the limit") {
    sc::SkeletonOptions o;
    o.limb_min_share = 0.5;
    auto r = sc::SegmentBySkeleton(Import(Creature()), o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("limb_min_share") != std::string::npos);
  }
  SUBCASE("legs too small to be limbs: the threshold decides") {
    sc::SkeletonOptions o;
    o.limb_min_share = 0.12;  // each leg moves 9 % of the surface, the tail 7 %
    auto r = sc::SegmentBySkeleton(Import(Creature()), o);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("no recognisable limbs") != std::string::npos);
  }
}

// A skin whose bones are two trees (found by fuzz_import_gltf: a glTF whose skin lists the mesh's own root
// node among its joints and leaves out the bone tree's root). The trunk's top bone is then a root and the
// weight outside its tree is a forest branch; its first bone used to be "top's parent" (none: an index past
// the bone list).
TEST_CASE("segment (skeleton): a skin of two bone trees — the other tree is a limb, or the error says why") {
  sc::Mesh mesh = Import(Creature());
  sc::Skin& skin = *mesh.skin;
  auto node_of = [&](const std::string& name) {
    for (size_t n = 0; n < skin.nodes.size(); ++n)
      if (skin.nodes[n].name == name) return int32_t(n);
    FAIL("no bone " << name);
    return int32_t(-1);
  };
  REQUIRE(skin.nodes[size_t(node_of("Spine"))].parent == -1);  // the trunk's top is the tree's root
  // A second root bone, "Extra", after the others (parents first still holds).
  sc::Node extra;
  extra.name = "Extra";
  skin.nodes.push_back(extra);
  const int32_t extra_node = int32_t(skin.nodes.size() - 1);
  SUBCASE("the tail's weight on the other tree: that tree is a limb with the tail's triangles") {
    for (sc::SkinJoint& j : skin.joints)
      if (j.node == node_of("Tail01") || j.node == node_of("Tail02")) j.node = extra_node;
    auto seg = sc::SegmentBySkeleton(mesh);
    REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
    const sc::RegionLayout& L = seg->layout;
    REQUIRE(L.count() == 6);
    int extra_region = -1;
    for (int r = 0; r < L.count(); ++r)
      if (L.regions[size_t(r)].bone == "Extra") extra_region = r;
    REQUIRE(extra_region >= 0);
    CHECK(Count(seg.value(), extra_region) == 104);  // the tail's triangles
    CHECK(L.IsTrunk(sc::Region(L.count() - 1)));
    CHECK(Count(seg.value(), L.count() - 1) == 856);
  }
  SUBCASE("the trunk's weight on the other tree (the fuzzer's input): refused, saying why") {
    for (sc::SkinJoint& j : skin.joints)
      if (j.node == node_of("Spine") || j.node == node_of("Pelvis") || j.node == node_of("Chest")) j.node = extra_node;
    auto seg = sc::SegmentBySkeleton(mesh);
    REQUIRE_FALSE(seg.ok());
    CHECK(seg.error().code == sc::Error::Code::kSegmentation);
    CHECK(seg.error().message.find("no recognisable limbs") != std::string::npos);
  }
}

TEST_CASE("segment: a region map naming its regions — a creature's layout, and an unknown name refused") {
  const sc::Mesh mesh = Import(Creature());
  auto truth = sc::SegmentBySkeleton(mesh);
  REQUIRE(truth.ok());
  std::vector<std::string> names;
  for (uint8_t r : truth->triangle_regions) names.push_back(truth->layout.regions[r].name);
  const nlohmann::json regions = {"Tail", "HindLeg_L", "HindLeg_R", "ForeLeg_L", "ForeLeg_R", "trunk"};
  auto map = sc::SegmentByMap(mesh, Write("creature", {{"regions", regions}, {"triangle_regions", names}}));
  REQUIRE_MESSAGE(map.ok(), (map.ok() ? "" : map.error().message));
  CHECK(map->triangle_regions == truth->triangle_regions);
  CHECK_FALSE(map->layout.paper);
  CHECK(map->layout.count() == 6);
  CHECK(map->layout.regions[1].mirror == 2);
  CHECK(std::abs(map->layout.trunk_axis[2]) > 0.99);

  // Symbols work too; an unknown name is a config error that lists the map's regions.
  names[3] = "R5";
  names[10] = "wing";
  auto bad = sc::SegmentByMap(mesh, Write("wing", {{"regions", regions}, {"triangle_regions", names}}));
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().code == sc::Error::Code::kConfig);
  CHECK(bad.error().message.find("triangle_regions[10] = \"wing\" names no region") != std::string::npos);
  CHECK(bad.error().message.find("HindLeg_L") != std::string::npos);
  // Without "regions" the names are the paper's: "Tail" is unknown there.
  auto paper = sc::SegmentByMap(mesh, Write("paper_names", {{"triangle_regions", std::vector<std::string>(
                                                                                    mesh.triangle_count(), "Tail")}}));
  REQUIRE_FALSE(paper.ok());
  CHECK(paper.error().message.find("left_arm, right_arm, left_leg, right_leg, torso") != std::string::npos);
  // The paper's names map onto the paper's values.
  auto torso = sc::SegmentByMap(mesh, Write("torso", {{"triangle_regions", std::vector<std::string>(
                                                                               mesh.triangle_count(), "torso")}}));
  REQUIRE(torso.ok());
  CHECK(torso->layout.paper);
  CHECK(Count(torso.value(), 4) == mesh.triangle_count());
  // A key the map does not know (a misspelt "regions") is refused, not read as the paper's five regions.
  auto typo = sc::SegmentByMap(mesh, Write("typo", {{"Regions", regions}, {"triangle_regions", names}}));
  REQUIRE_FALSE(typo.ok());
  CHECK(typo.error().message.find("unknown key 'Regions'") != std::string::npos);
  // A region named twice, too few regions.
  auto twice = sc::SegmentByMap(mesh, Write("twice", {{"regions", {"a", "a", "trunk"}}, {"triangle_regions", names}}));
  REQUIRE_FALSE(twice.ok());
  CHECK(twice.error().message.find("named twice") != std::string::npos);
  auto few = sc::SegmentByMap(mesh, Write("few", {{"regions", {"a", "trunk"}}, {"triangle_regions", names}}));
  REQUIRE_FALSE(few.ok());
  CHECK(few.error().message.find("3 to 32") != std::string::npos);
}

TEST_CASE("chains: a creature's chains pair every limb with the others and the trunk") {
  sc::RegionLayout L;
  L.paper = false;
  L.regions.clear();
  for (const char* n : {"Tail", "Leg_L", "Leg_R", "Neck"}) L.regions.push_back({n, sc::RegionKind::kLimb, -1, ""});
  L.regions.push_back({"trunk", sc::RegionKind::kTrunk, -1, ""});
  const std::vector<sc::ChainDef> defs = sc::CreatureChainDefs(L);
  REQUIRE(defs.size() == 4 * 5 / 2);  // L(L+1)/2
  CHECK(defs.front().name == "Tail+Leg_L");
  CHECK(defs.back().name == "Neck+trunk");
  // Two spheres a region; every pair of regions shares a chain.
  std::vector<sc::FittedSphere> spheres;
  for (int r = 0; r < 5; ++r)
    for (int k = 0; k < 2; ++k) {
      sc::FittedSphere s;
      s.region = sc::Region(r);
      s.radius = 1;
      spheres.push_back(s);
    }
  auto chains = sc::BuildChains(spheres, defs, L);
  REQUIRE(chains.ok());
  for (int a = 0; a < 5; ++a)
    for (int b = a; b < 5; ++b) {
      CAPTURE(a);
      CAPTURE(b);
      CHECK(std::any_of(chains->begin(), chains->end(), [&](const sc::Chain& c) {
        return std::count(c.spheres.begin(), c.spheres.end(), uint16_t(2 * a)) &&
               std::count(c.spheres.begin(), c.spheres.end(), uint16_t(2 * b + 1));
      }));
    }
  // Tokens: region names and R<k> of the layout; no torso labels, nothing past the layout.
  auto named = sc::BuildChains(spheres, {{"mine", {"Neck", "R0"}}}, L);
  REQUIRE(named.ok());
  CHECK(named->front().spheres == std::vector<uint16_t>{0, 1, 6, 7});
  auto past = sc::BuildChains(spheres, {{"bad", {"R5"}}}, L);
  REQUIRE_FALSE(past.ok());
  CHECK(past.error().message.find("R0..R4 or a region name") != std::string::npos);
  auto label = sc::BuildChains(spheres, {{"bad", {"R4L", "R0"}}}, L);
  REQUIRE_FALSE(label.ok());
  // Ten limbs (a spider's eight legs, its head and abdomen): 7 groups, 28 chains, every pair still shared.
  sc::RegionLayout spider;
  spider.paper = false;
  spider.regions.clear();
  for (int k = 0; k < 10; ++k) spider.regions.push_back({"Leg" + std::to_string(k), sc::RegionKind::kLimb, -1, ""});
  spider.regions.push_back({"body", sc::RegionKind::kTrunk, -1, ""});
  const std::vector<sc::ChainDef> many = sc::CreatureChainDefs(spider);
  CHECK(many.size() == 28);
  for (int a = 0; a < 11; ++a)
    for (int b = a; b < 11; ++b) {
      const std::string ta = "R" + std::to_string(a), tb = "R" + std::to_string(b);
      CHECK(std::any_of(many.begin(), many.end(), [&](const sc::ChainDef& d) {
        return std::count(d.members.begin(), d.members.end(), ta) && std::count(d.members.begin(), d.members.end(), tb);
      }));
    }
  // The paper's layout keeps Table 1's tokens and message.
  auto paper = sc::BuildChains(spheres, {{"bad", {"R7"}}});
  REQUIRE_FALSE(paper.ok());
  CHECK(paper.error().message.find("(expected R0..R4, R4L, R4R, R4T or R4D)") != std::string::npos);
}

TEST_CASE("plausibility: a creature's limbs are balanced by their mirror pairs, with no head or trunk-axis check") {
  const sc::Mesh mesh = Import(Creature());
  auto seg = sc::SegmentBySkeleton(mesh);
  REQUIRE(seg.ok());
  sc::Segmentation thin = seg.value();
  // The right fore leg keeps only its two lowest rows of cubes (the rest goes to the trunk): a leg with
  // 20 of the left's 68 faces.
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (thin.triangle_regions[t] != 4) continue;
    bool high = false;
    for (int k = 0; k < 3; ++k) high = high || mesh.positions[3 * mesh.indices[3 * t + k] + 1] > 0.25f;
    if (high) thin.triangle_regions[t] = 5;
  }
  const auto findings = sc::CheckPlausibility(mesh, thin, nullptr, nullptr);
  bool balance = false;
  for (const auto& f : findings) {
    balance = balance || (f.code == "PLAUS-LIMB-BALANCE" && f.message.find("ForeLeg_L, ForeLeg_R") != std::string::npos);
    CHECK(f.code != "PLAUS-TRUNK-AXIS");  // a lying trunk is no finding for a creature
    CHECK(f.code != "PLAUS-HEAD-IN-LIMB");
  }
  CHECK(balance);
  // A limb cut off the trunk: the tail's triangles next to the trunk go to the hind leg.
  sc::Segmentation cut = seg.value();
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (cut.triangle_regions[t] != 0) continue;
    bool root = false;
    for (int k = 0; k < 3; ++k) root = root || mesh.positions[3 * mesh.indices[3 * t + k] + 2] > -1.15f;
    if (root) cut.triangle_regions[t] = 1;
  }
  const auto cut_findings = sc::CheckPlausibility(mesh, cut, nullptr, nullptr);
  CHECK(std::any_of(cut_findings.begin(), cut_findings.end(), [](const sc::PlausibilityFinding& f) {
    return f.code == "PLAUS-LIMB-DETACHED" && f.message == "Tail shares no vertex with the trunk";
  }));
}

TEST_CASE("bake: the synthetic creature — a schema v4 asset naming its regions, its own chains") {
  sc::BakeConfig config = Fast();
  auto r = sc::Bake(Creature(), config);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->segmentation.method == "skeleton");
  CHECK(r->plausibility.empty());
  CHECK(r->chains.size() == 15);  // 5 limbs: 10 pairs of limbs, 5 limbs with the trunk
  CHECK(r->unassigned_triangles == 0);
  CHECK_FALSE(r->other_segmentation_error.empty());  // no rig/geometry comparison for a creature
  std::set<int> with_spheres;
  for (const sc::FittedSphere& s : r->fit.spheres) with_spheres.insert(int(s.region));
  CHECK(with_spheres.size() == 6);
  // The extended regions are a standing biped's (the default); a creature keeps its own, and its asset is the
  // same byte for byte whichever `regions` the configuration names (the config hash included).
  REQUIRE(config.regions == sc::RegionSet::kExtended);
  sc::BakeConfig paper_regions = config;
  paper_regions.regions = sc::RegionSet::kPaper;
  auto rp = sc::Bake(Creature(), paper_regions);
  REQUIRE(rp.ok());
  CHECK(rp->asset == r->asset);
  // Limb sequences run from the trunk outwards: a leg's first sphere is its highest.
  for (const sc::FittedSphere& a : r->fit.spheres)
    for (const sc::FittedSphere& b : r->fit.spheres)
      if (a.region == b.region && a.region == sc::Region(1) && a.sequence + 1 == b.sequence)
        CHECK(a.root_distance <= b.root_distance);

  rt::AssetView view;
  REQUIRE(rt::LoadAsset(r->asset.data(), r->asset.size(), &view) == rt::Status::kOk);
  CHECK(view.asset->schema_version() == 4);
  CHECK(rt::RegionCount(view) == 6);
  CHECK(std::string(rt::RegionName(view, 3)) == "ForeLeg_L");
  CHECK(rt::IsTrunkRegion(view, 5));
  CHECK(view.asset->regions()->Get(1)->mirror() == 2);
  CHECK(view.asset->regions()->Get(0)->bone()->str() == "Tail01");
  const nlohmann::json report = sc::MakeBakeReport(r.value(), config, sc::Context{});
  CHECK(report["regions"]["HindLeg_L"]["kind"] == "limb");
  CHECK(report["regions"]["HindLeg_L"]["mirror"] == "HindLeg_R");
  CHECK(report["regions"]["trunk"]["triangles"] == 856);
  CHECK(report["exclusions"].contains("limb_crease"));

  // Its clip "cross" swings the left fore leg (R3) across the right one (R4): the spheres report R3-R4
  // in the frames where the exact narrow phase finds their triangles crossing, and nothing at bind.
  {
    std::vector<uint64_t> storage((r->asset.size() + 7) / 8, 0);  // an 8-byte aligned copy for LoadAsset
    std::memcpy(storage.data(), r->asset.data(), r->asset.size());
    rt::AssetView v;
    REQUIRE(rt::LoadAsset(storage.data(), r->asset.size(), &v) == rt::Status::kOk);
    spherechain::playback::AnimationRequest req;
    req.clip = "cross";
    req.frames = 10;
    auto anim = spherechain::playback::OpenAnimation(r->mesh, req);
    REQUIRE_MESSAGE(anim.ok(), (anim.ok() ? "" : anim.error().message));
    spherechain::playback::PlayOptions o;
    o.repeat = 1;
    o.narrow_phase = true;
    auto played = spherechain::playback::Play(r->mesh, v, anim.value(), o);
    REQUIRE_MESSAGE(played.ok(), (played.ok() ? "" : played.error().message));
    CHECK(played->bind.regions.empty());
    CHECK(played->bind.contact_regions.empty());
    const std::pair<int, int> fore_legs{3, 4};
    int crossing = 0;
    for (const auto& f : played->frames) {
      const bool touching = std::count(f.contact_regions.begin(), f.contact_regions.end(), fore_legs) > 0;
      const bool reported = std::count(f.regions.begin(), f.regions.end(), fore_legs) > 0;
      CAPTURE(f.label);
      CHECK(touching == reported);  // every frame: the spheres see the legs cross exactly when they do
      crossing += touching;
    }
    CHECK(crossing >= 3);  // t = 0.3 … 0.7 s of the 1 s clip
  }

  // Forced paths: --segmentation skeleton gives the same; rig refuses it (no arms); the paper fit cannot
  // fill a creature's regions.
  auto forced = sc::Segment(r->mesh, sc::SegmentMethod::kSkeleton);
  REQUIRE(forced.ok());
  CHECK(forced->triangle_regions == r->segmentation.triangle_regions);  // auto took the same path
  config.segmentation = sc::SegmentMethod::kRig;
  auto rig = sc::Bake(Creature(), config);
  REQUIRE_FALSE(rig.ok());
  CHECK(rig.error().message.find("left_arm") != std::string::npos);
  config.segmentation = sc::SegmentMethod::kSkeleton;
  config.fit.method = sc::FitMethod::kPaper;
  auto paper = sc::Bake(Creature(), config);
  REQUIRE_FALSE(paper.ok());
  CHECK(paper.error().message.find("the paper fit") != std::string::npos);
}

TEST_CASE("bake: a creature with chains from the configuration takes them by region name") {
  auto config = sc::ParseBakeConfig(R"({"cover_voxel_rel": 0.02, "max_spheres": 64, "segmentation": "skeleton",
      "chains": [{"name": "front", "members": ["ForeLeg_L", "ForeLeg_R"]}, {"name": "all", "members": ["R0", "R1", "R2", "R5"]}]})",
                                    "test");
  REQUIRE_MESSAGE(config.ok(), (config.ok() ? "" : config.error().message));
  auto r = sc::Bake(Creature(), config.value());
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  REQUIRE(r->chains.size() == 2);
  CHECK(r->chains[0].name == "front");
  auto bad = sc::ParseBakeConfig(R"({"segmentation": "bones"})", "test");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("auto, rig, geometry, skeleton or map") != std::string::npos);
}

TEST_CASE("bake (heavy): Testwuson.X, the four-legged Wuson of assimp-testmodels, bakes by its skeleton") {
  const std::string path = spherechain::test::AssimpModel("X/Testwuson.X");
  if (!Require(path)) return;
  auto r = sc::Bake(path, sc::BakeConfig{});
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->segmentation.method == "skeleton");
  const sc::RegionLayout& L = r->segmentation.layout;
  REQUIRE(L.count() == 7);
  const char* names[7] = {"Tail", "HindLeg_L", "HindLeg_R", "Neck", "ForeLeg_L", "ForeLeg_R", "trunk"};
  for (int k = 0; k < 7; ++k) CHECK(L.regions[size_t(k)].name == names[k]);
  CHECK(L.regions[1].mirror == 2);
  CHECK(L.regions[4].mirror == 5);
  CHECK(r->plausibility.empty());
  CHECK(r->fit.spheres.size() == 128);
  CHECK(r->chains.size() == 21);
  CHECK(r->unassigned_triangles == 0);
  REQUIRE(r->coverage.has_value());
  CHECK(r->coverage->coverage > 0.9);
  CHECK(r->coverage->protrusion < 0.05);
  CHECK(r->bind_contact_exclusions > 0);  // horns and the tail's tuft pass through the skin at rest
}

TEST_CASE("bake: a quadruped whose bones carry humanoid names is rerouted from the rig path (horizontal trunk) to the skeleton") {
  // The creature with its legs renamed as a biped's arms and legs: the bone-name rules find two arms (the
  // fore legs) and two legs, but the torso lies along Z — PLAUS-TRUNK-AXIS — so auto takes the skeleton.
  std::ifstream in(Creature());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"ForeLeg_L_0", "LeftArm_0"}, {"ForeLeg_R_0", "RightArm_0"},
                                 {"HindLeg_L_0", "LeftLeg_0"}, {"HindLeg_R_0", "RightLeg_0"}})
    for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) text.replace(at, from.size(), to);
  const fs::path path = fs::temp_directory_path() / ("spherechain_skeleton_humanoid_names." + std::to_string(::getpid()) + ".gltf");
  std::ofstream(path) << text;
  auto rig = sc::SegmentByRig(Import(path.string()));
  REQUIRE_MESSAGE(rig.ok(), (rig.ok() ? "" : rig.error().message));  // the rules take it for a biped
  sc::BakeConfig config;
  config.fit.cover_voxel_rel = 0.02;
  config.fit.max_spheres = 64;
  auto r = sc::Bake(path.string(), config);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->segmentation.method == "skeleton");
  CHECK(r->segmentation.notes.find("the rig segmentation had a horizontal trunk (PLAUS-TRUNK-AXIS)") != std::string::npos);
  REQUIRE(r->segmentation.layout.count() == 6);
  CHECK(r->segmentation.layout.regions[3].name == "LeftArm");
  CHECK(r->segmentation.layout.regions[3].mirror == 4);
  CHECK(r->plausibility.empty());
  // Forced to the rig, it is refused for its lying trunk.
  config.segmentation = sc::SegmentMethod::kRig;
  auto refused = sc::Bake(path.string(), config);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().code == sc::Error::Code::kImplausible);
  CHECK(refused.error().message.find("PLAUS-TRUNK-AXIS") != std::string::npos);
  fs::remove(path);
}

TEST_CASE("bake: a humanoid whose joints are named node0…node12 bakes by its bone tree under auto, not refused") {
  // tests/data/creature/figure.gltf (make_creature.py figure()): the rig's names say nothing, so auto falls
  // back to geometry, whose segmentation is implausible (the arms hang with a gap: the left arm ends up
  // detached and half as long as the right); auto must then take the bone tree, which passes every check.
  const std::string figure = spherechain::test::SourceFile("tests/data/creature/figure.gltf");
  sc::BakeConfig config;
  config.fit.cover_voxel_rel = 0.02;
  config.fit.max_spheres = 64;
  auto r = sc::Bake(figure, config);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->segmentation.method == "skeleton");
  CHECK_MESSAGE(r->segmentation.notes.find("the geometry segmentation looks wrong (") != std::string::npos,
                r->segmentation.notes);
  CHECK(r->plausibility.empty());
  // Four limbs and the head hang off the trunk (node0 node1 node2), each region from its first bone, with
  // every triangle of the figure's parts: legs 136 each, arms 152 each, head and neck 98, trunk 206.
  const sc::RegionLayout& layout = r->segmentation.layout;
  REQUIRE(layout.count() == 6);
  std::map<std::string, size_t> triangles;
  for (uint8_t reg : r->segmentation.triangle_regions) ++triangles[layout.Name(sc::Region(reg))];
  const std::map<std::string, size_t> expected{{"node9", 136}, {"node11", 136}, {"node3", 98},
                                               {"node5", 152}, {"node7", 152}, {"trunk", 206}};
  CHECK(triangles == expected);
  // Forced to geometry, the same figure is refused with the findings that made auto look further.
  config.segmentation = sc::SegmentMethod::kGeometry;
  auto refused = sc::Bake(figure, config);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().code == sc::Error::Code::kImplausible);
  CHECK(refused.error().message.find("PLAUS-LIMB-BALANCE") != std::string::npos);
}
