// End to end: real characters bake, the asset round-trips through the runtime loader, two bakes are
// byte-identical, and bad inputs give clear errors with nothing written.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "spherechain/baker/bake.h"
#include "spherechain/playback/validate.h"
#include "spherechain/runtime/asset.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::baker;
namespace fs = std::filesystem;

namespace {

fs::path TempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("spherechain_bake_test_" + name + "." + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void WriteText(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// Loads the baked bytes through the runtime (aligned copy) and checks them against the bake result.
void CheckRoundTrip(const BakeResult& r) {
  std::vector<uint64_t> storage((r.asset.size() + 7) / 8);
  std::memcpy(storage.data(), r.asset.data(), r.asset.size());
  runtime::AssetView view;
  const runtime::Status s = runtime::LoadAsset(storage.data(), r.asset.size(), &view);
  REQUIRE_MESSAGE(runtime::Succeeded(s), runtime::ToString(s));
  CHECK(view.vertex_count == r.mesh.vertex_count());
  CHECK(view.triangle_count == r.mesh.triangle_count());
  CHECK(view.sphere_count == r.fit.spheres.size());
  CHECK(view.chain_count == r.chains.size());
  const auto* spheres = view.asset->spheres();
  for (uint32_t i = 0; i < view.sphere_count; ++i) {
    CHECK(spheres->Get(i)->radius() == doctest::Approx(r.fit.spheres[i].radius).epsilon(1e-6));
    CHECK(spheres->Get(i)->center().y() == doctest::Approx(r.fit.spheres[i].center.y()).epsilon(1e-6));
  }
  CHECK(view.asset->excluded_pairs()->size() == r.excluded.size());
  CHECK(view.asset->fingerprint()->positions_hash() == ComputeFingerprint(r.mesh).positions_hash);
  for (uint32_t c = 0; c < view.chain_count; ++c)
    CHECK(view.asset->chains()->Get(c)->spheres()->size() == r.chains[c].spheres.size());
}

}  // namespace

BakeConfig PaperConfig() {
  BakeConfig c;
  c.fit.method = FitMethod::kPaper;
  return c;
}

TEST_CASE("bake: MakeHuman base.obj — five regions, ~80 spheres, six chains, every triangle assigned") {
  const std::string path = test::SharedData("makehuman/base.obj");
  if (!test::Require(path)) return;
  Context ctx;
  auto r = Bake(path, PaperConfig(), &ctx);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->mesh.vertex_count() == 13380);
  CHECK(r->mesh.triangle_count() == 26756);
  CHECK(r->unassigned_triangles == 0);
  CHECK(r->chains.size() == 6);
  for (int k = 0; k < kRegionCount; ++k) {
    size_t n = 0;
    for (const auto& s : r->fit.spheres) n += int(s.region) == k;
    CHECK_MESSAGE(n >= 2, "region " << k << " has " << n << " spheres");
  }
  // "On the order of the paper's 80 spheres".
  CHECK(r->fit.spheres.size() >= 40);
  CHECK(r->fit.spheres.size() <= 160);
  CHECK(r->fit.disk_step == doctest::Approx(0.25).epsilon(0.02));  // δ = 0.25 on MakeHuman
  // φ2 encloses its surrounding region: F ≥ 0 everywhere (rounding aside).
  CHECK(r->accuracy.phi2.min_f > -1e-4);
  // The adjustment does not make the torso worse than φ1.
  CHECK(r->accuracy.phi1_adjusted.mean_abs_f <= r->accuracy.phi1.mean_abs_f + 1e-9);
  // Rig and geometry segmentation agree.
  REQUIRE(r->agreement.has_value());
  MESSAGE("MakeHuman: " << r->fit.spheres.size() << " spheres, rig/geometry agreement "
                        << 100 * r->agreement->triangle_fraction << "% of triangles");
  CHECK(r->agreement->triangle_fraction > 0.85);
  CheckRoundTrip(r.value());
  const auto report = MakeBakeReport(r.value(), PaperConfig(), ctx);
  for (const char* key : {"vertices", "triangles", "spheres", "regions", "chains", "unassigned_triangles", "accuracy",
                          "timings_ms", "mesh_issues"})
    CHECK(report.contains(key));
  CHECK(report["accuracy"]["phi2"].contains("mean_abs_F"));
  CHECK(report["mesh_issues"]["degenerate_triangles"] == 0);  // the MakeHuman body has none
  CHECK(TorsoRayCsv(r.value()).size() > 100);
}

TEST_CASE("bake: two bakes of one input are byte-identical") {
  const std::string path = test::SharedData("gltf/CesiumMan.gltf");
  if (!test::Require(path)) return;
  auto a = Bake(path, BakeConfig{});
  auto b = Bake(path, BakeConfig{});
  REQUIRE_MESSAGE(a.ok(), (a.ok() ? "" : a.error().message));
  REQUIRE(b.ok());
  CHECK(a->asset == b->asset);
  // Plausible: no findings, and the asset leaves Asset.forced_findings out.
  CHECK(a->plausibility.empty());
  {
    std::vector<uint64_t> storage((a->asset.size() + 7) / 8);
    std::memcpy(storage.data(), a->asset.data(), a->asset.size());
    runtime::AssetView view;
    REQUIRE(runtime::Succeeded(runtime::LoadAsset(storage.data(), a->asset.size(), &view)));
    CHECK(view.asset->forced_findings() == nullptr);
  }
  CHECK(a->mesh.vertex_count() == 3273);
  CHECK(a->mesh.triangle_count() == 4672);
  CheckRoundTrip(a.value());
  // No two balls where one would do: before FitCover's step 6d two of CesiumMan's chest balls, from voxels
  // 1.4 apart, climbed to the same medial point (0.6 % of a radius apart).
  const auto& sp = a->fit.spheres;
  double closest = 1e300;
  for (size_t i = 0; i < sp.size(); ++i)
    for (size_t j = i + 1; j < sp.size(); ++j)
      closest = std::min(closest, (sp[i].center - sp[j].center).norm() / std::min(sp[i].radius, sp[j].radius));
  MESSAGE("closest two balls: " << closest << " of the smaller radius apart");
  CHECK(closest > 0.05);
  // A different parameter gives a different asset.
  BakeConfig other;
  other.fit.penetration_depth = 0.2;
  auto c = Bake(path, other);
  REQUIRE(c.ok());
  CHECK(c->asset != a->asset);
}

TEST_CASE("bake: BCN_Epileptic.X (three meshes joined) bakes") {
  const std::string path = test::AssimpModel("X/BCN_Epileptic.X");
  if (!test::Require(path)) return;
  auto r = Bake(path, BakeConfig{});
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->mesh.parts.size() == 3);
  CHECK(r->unassigned_triangles == 0);
  CHECK(r->chains.size() == 6);
  CheckRoundTrip(r.value());
}

TEST_CASE("bake: bad inputs give a clear error") {
  const fs::path dir = TempDir("bad");
  auto expect = [&](const std::string& path, Error::Code code, const std::string& fragment) {
    auto r = Bake(path, BakeConfig{});
    REQUIRE_FALSE(r.ok());
    CHECK_MESSAGE(r.error().code == code, r.error().message);
    CHECK_MESSAGE(r.error().message.find(fragment) != std::string::npos, r.error().message);
  };
  expect((dir / "missing.obj").string(), Error::Code::kIo, "missing.obj");
  WriteText(dir / "notes.txt", "hello");
  expect((dir / "notes.txt").string(), Error::Code::kFormat, "notes.txt");
  WriteText(dir / "empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  expect((dir / "empty.obj").string(), Error::Code::kInvalidMesh, "triangle");
  WriteText(dir / "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  expect((dir / "nan.obj").string(), Error::Code::kInvalidMesh, "");
  WriteText(dir / "garbage.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [");
  expect((dir / "garbage.gltf").string(), Error::Code::kFormat, "garbage.gltf");
  // A cube is not a standing body.
  WriteText(dir / "cube.obj",
            "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
            "f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n");
  expect((dir / "cube.obj").string(), Error::Code::kSegmentation, "");
}

TEST_CASE("bake: configuration errors name the key") {
  auto c = ParseBakeConfig("{\"penetration_depth\": 3}", "cfg.json");
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("penetration_depth") != std::string::npos);
  CHECK_FALSE(ParseBakeConfig("{\"raysss\": 80}", "cfg.json").ok());
  CHECK_FALSE(ParseBakeConfig("[1, 2]", "cfg.json").ok());
  CHECK_FALSE(ParseBakeConfig("{\"chains\": [{\"members\": \"R0\"}]}", "cfg.json").ok());
  // A chain's name of the wrong type is refused with the key named (it became "chain0" silently).
  auto badname = ParseBakeConfig(R"({"chains": [{"name": 5, "members": ["R0"]}]})", "cfg.json");
  REQUIRE_FALSE(badname.ok());
  CHECK(badname.error().message.find("chains[0]: name must be a string") != std::string::npos);
  auto unnamed = ParseBakeConfig(R"({"chains": [{"members": ["R0"]}]})", "cfg.json");
  REQUIRE(unnamed.ok());
  CHECK(unnamed->chains[0].name == "chain0");
  auto ok = ParseBakeConfig("{\"rays\": 40, \"chains\": [{\"name\": \"arms\", \"members\": [\"R0\", \"R1\"]}]}", "cfg.json");
  REQUIRE(ok.ok());
  CHECK(ok->fit.rays == 40);
  REQUIRE(ok->chains.size() == 1);
  CHECK(ok->chains[0].name == "arms");
  // Pivot training: off by default, bounded, named in the message.
  CHECK(ok->pivot_poses == 0);
  for (const char* bad : {R"({"pivot_poses": 300})", R"({"pivot_poses": -1})", R"({"pivot_pose_angle": 91})"}) {
    auto b = ParseBakeConfig(bad, "cfg.json");
    REQUIRE_FALSE(b.ok());
    CHECK(b.error().message.find("pivot_pose") != std::string::npos);
  }
  auto trained = ParseBakeConfig(R"({"pivot_poses": 24, "pivot_pose_angle": 20})", "cfg.json");
  REQUIRE(trained.ok());
  CHECK(trained->pivot_poses == 24);
  CHECK(trained->pivot_pose_angle == 20.0);
  // The fold margin: unset by default (the layout's default then), a fraction in [0, 0.05] or negative (none).
  CHECK_FALSE(ok->fold_margin_rel.has_value());
  for (const char* bad : {R"({"fold_margin_rel": 0.2})", R"({"fold_margin_rel": -3})", R"({"fold_margin_rel": "x"})"}) {
    auto b = ParseBakeConfig(bad, "cfg.json");
    REQUIRE_FALSE(b.ok());
    CHECK(b.error().message.find("fold_margin_rel") != std::string::npos);
  }
  auto folded = ParseBakeConfig(R"({"fold_margin_rel": 0.002})", "cfg.json");
  REQUIRE(folded.ok());
  CHECK(folded->fold_margin_rel == 0.002);
  auto none = ParseBakeConfig(R"({"fold_margin_rel": -0.5})", "cfg.json");
  REQUIRE(none.ok());
  CHECK(none->fold_margin_rel == -1.0);
  // A whole-number key given a fraction is refused, not truncated ("pivot_poses": 0.5 turned training off).
  for (const char* bad : {R"({"rays": 80.9})", R"({"pivot_poses": 0.5})"}) {
    auto b = ParseBakeConfig(bad, "cfg.json");
    REQUIRE_FALSE(b.ok());
    CHECK(b.error().message.find("must be a whole number") != std::string::npos);
  }
  CHECK(ParseBakeConfig(R"({"rays": 80.0})", "cfg.json").ok());
  // A segmentation method beside a region map is refused (the map would win silently); "map" with one is fine.
  auto both = ParseBakeConfig(R"({"segmentation": "geometry", "region_map": "m.json"})", "cfg.json");
  REQUIRE_FALSE(both.ok());
  CHECK(both.error().message.find("segmentation 'geometry' and a 'region_map' both given") != std::string::npos);
  auto map = ParseBakeConfig(R"({"segmentation": "map", "region_map": "m.json"})", "cfg.json");
  REQUIRE(map.ok());
  // The options: a method overrides the configuration's map; beside --region-map it is refused.
  spherechain::baker::BakeOptions method;
  method.segmentation = "rig";
  spherechain::baker::BakeConfig overridden = map.value();
  REQUIRE(spherechain::baker::ApplyBakeOptions(method, &overridden).ok());
  CHECK(overridden.region_map.empty());
  method.region_map = "other.json";
  CHECK_FALSE(spherechain::baker::ApplyBakeOptions(method, &overridden).ok());
}

TEST_CASE("bake: atomic write leaves the old file intact when the folder is missing, and replaces it otherwise") {
  const fs::path dir = TempDir("atomic");
  const fs::path target = dir / "a.sphc";
  REQUIRE(WriteFileAtomic(target.string(), std::string("old")).ok());
  auto bad = WriteFileAtomic((dir / "nope" / "a.sphc").string(), std::string("new"));
  CHECK_FALSE(bad.ok());
  REQUIRE(WriteFileAtomic(target.string(), std::string("new")).ok());
  std::ifstream in(target);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  CHECK(text == "new");
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  CHECK(files == 1);  // no temporary left behind
}

// "No silent wrong bake" (issue 11): six separate boxes whose region map gives each limb box its limb
// (tests/data/implausible) — no limb touches the torso, so PLAUS-LIMB-DETACHED four times.
TEST_CASE("bake: an implausible body is refused, and with force written with its findings") {
  auto loaded = LoadBakeConfig(test::SourceFile("tests/data/implausible/fast.json"));  // coarse voxels: 0.1 s
  REQUIRE_MESSAGE(loaded.ok(), (loaded.ok() ? "" : loaded.error().message));
  BakeConfig config = loaded.value();
  config.region_map = test::SourceFile("tests/data/implausible/limbs_detached.json");
  const std::string input = test::SourceFile("tests/data/implausible/boxes.obj");

  auto refused = Bake(input, config);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().code == Error::Code::kImplausible);
  const std::string& why = refused.error().message;
  for (const char* part : {"boxes.obj", "refused", "PLAUS-LIMB-DETACHED: left_arm shares no vertex with the torso",
                           "right_arm", "left_leg", "right_leg", "--force"})
    CHECK_MESSAGE(why.find(part) != std::string::npos, "missing '" << part << "' in: " << why);

  config.force = true;
  Context ctx;
  std::vector<std::string> warnings;
  ctx.sink = [&](Context::Level level, const std::string& m) {
    if (level == Context::Level::kWarn) warnings.push_back(m);
  };
  auto forced = Bake(input, config, &ctx);
  REQUIRE_MESSAGE(forced.ok(), (forced.ok() ? "" : forced.error().message));
  REQUIRE(forced->plausibility.size() == 4);
  for (const PlausibilityFinding& f : forced->plausibility) CHECK(f.code == "PLAUS-LIMB-DETACHED");
  CHECK(forced->plausibility[0].message.find("left_arm") != std::string::npos);
  size_t logged = 0;
  for (const std::string& w : warnings) logged += w.find("PLAUS-LIMB-DETACHED") != std::string::npos;
  CHECK(logged == 4);
  CheckRoundTrip(forced.value());

  // The asset carries the findings (Asset.forced_findings) ...
  std::vector<uint64_t> storage((forced->asset.size() + 7) / 8);
  std::memcpy(storage.data(), forced->asset.data(), forced->asset.size());
  runtime::AssetView view;
  REQUIRE(runtime::Succeeded(runtime::LoadAsset(storage.data(), forced->asset.size(), &view)));
  const auto* stored = view.asset->forced_findings();
  REQUIRE(stored != nullptr);
  REQUIRE(stored->size() == 4);
  for (uint32_t i = 0; i < stored->size(); ++i) {
    CHECK(stored->Get(i)->code()->str() == forced->plausibility[i].code);
    CHECK(stored->Get(i)->message()->str() == forced->plausibility[i].message);
  }
  // ... which validation reports as errors with their code,
  const auto findings = playback::ValidateAsset(view, &forced->mesh);
  size_t plaus = 0;
  for (const playback::Finding& f : findings)
    if (f.code == "PLAUS-LIMB-DETACHED") {
      ++plaus;
      CHECK(f.severity == playback::Severity::kError);
      CHECK(f.location.field == "forced_findings");
    }
  CHECK(plaus == 4);
  CHECK(playback::CountErrors(findings) >= 4);
  // ... and the report lists them as errors.
  const auto report = MakeBakeReport(forced.value(), config, ctx);
  CHECK(report["plausibility"]["passed"] == false);
  CHECK(report["plausibility"]["forced"] == true);
  REQUIRE(report["plausibility"]["errors"].size() == 4);
  CHECK(report["plausibility"]["errors"][0]["code"] == "PLAUS-LIMB-DETACHED");
  CHECK(report["plausibility"]["errors"][0]["severity"] == "error");
  CHECK(report["timings_ms"].contains("plausibility"));
}

TEST_CASE("bake: pivots trained on poses change the pivots only — same spheres and exclusions, reported, deterministic") {
  const std::string creature = test::SourceFile("tests/data/creature/creature.gltf");
  auto plain_config = ParseBakeConfig(R"({"cover_voxel_rel": 0.01, "max_spheres": 64})", "test");
  auto trained_config = ParseBakeConfig(R"({"cover_voxel_rel": 0.01, "max_spheres": 64, "pivot_poses": 12})", "test");
  REQUIRE(plain_config.ok());
  REQUIRE(trained_config.ok());
  auto plain = Bake(creature, plain_config.value());
  auto trained = Bake(creature, trained_config.value());
  auto again = Bake(creature, trained_config.value());
  REQUIRE_MESSAGE(plain.ok(), (plain.ok() ? "" : plain.error().message));
  REQUIRE_MESSAGE(trained.ok(), (trained.ok() ? "" : trained.error().message));
  REQUIRE(again.ok());
  CheckRoundTrip(trained.value());
  CHECK(trained->asset == again->asset);  // same poses, same refinement, on any number of cores

  REQUIRE(trained->fit.spheres.size() == plain->fit.spheres.size());
  for (size_t s = 0; s < plain->fit.spheres.size(); ++s) {
    CHECK(trained->fit.spheres[s].center == plain->fit.spheres[s].center);
    CHECK(trained->fit.spheres[s].radius == plain->fit.spheres[s].radius);
  }
  CHECK(trained->excluded == plain->excluded);
  CHECK(plain->pivots.training.poses == 0);
  const Pivots::Training& t = trained->pivots.training;
  CHECK(t.poses == 12);
  CHECK(t.spheres_changed > 0);
  CHECK(trained->pivots.triangles != plain->pivots.triangles);
  CHECK(t.error_after <= t.error_before);
  CHECK(t.error_after > 0.0);
  Context ctx;
  const nlohmann::json report = MakeBakeReport(trained.value(), trained_config.value(), ctx);
  CHECK(report["pivot_training"]["poses"] == 12);
  CHECK(report["params"]["pivot_poses"] == 12);
  CHECK_FALSE(MakeBakeReport(plain.value(), plain_config.value(), ctx).contains("pivot_training"));
}
