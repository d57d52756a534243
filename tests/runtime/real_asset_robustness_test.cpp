// Untrusted-input robustness on real baked assets (STYLE.md: "every truncated prefix of a valid
// buffer under AddressSanitizer"): the committed corpus assets fuzz/corpus/load_asset/{cesium_man,
// bcn_epileptic, creature}.sphc (baked from ../shared/data/gltf/CesiumMan.gltf, assimp's X/BCN_Epileptic.X and
// tests/data/creature/creature.gltf: a schema v4 asset with its Asset.regions).
// Every prefix is rejected; thousands of seeded bit flips are rejected or load and then run the
// whole per-frame sequence without breaking an invariant. Each buffer is an exact-size heap copy, so
// ASan (asan preset) sees any read past the end.
#include <doctest/doctest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "../fuzz/load_asset_sequence.h"
#include "test_data.h"

using namespace spherechain::runtime;

namespace {

std::vector<uint8_t> ReadCorpusAsset(const std::string& name) {
  std::ifstream in(spherechain::test::SourceFile("fuzz/corpus/load_asset/" + name), std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST_CASE("Real asset: every truncated prefix is an error, never a crash") {
  for (const std::string name : {std::string("cesium_man.sphc"), std::string("bcn_epileptic.sphc"), std::string("creature.sphc")}) {
    const std::vector<uint8_t> full = ReadCorpusAsset(name);
    CAPTURE(name);
    REQUIRE(full.size() > 1000);
    {
      std::unique_ptr<uint8_t[]> whole(new uint8_t[full.size()]);
      std::memcpy(whole.get(), full.data(), full.size());
      AssetView view;
      REQUIRE(LoadAsset(whole.get(), full.size(), &view) == Status::kOk);
    }
    size_t failures = 0;
    for (size_t n = 0; n < full.size(); ++n) {
      std::unique_ptr<uint8_t[]> prefix(new uint8_t[n ? n : 1]);  // exact size: ASan sees over-reads
      std::memcpy(prefix.get(), full.data(), n);
      AssetView view;
      const Status s = LoadAsset(prefix.get(), n, &view);
      if (Failed(s) && !view.valid()) ++failures;
      else FAIL_CHECK("prefix " << n << " of " << full.size() << " gave " << ToString(s));
    }
    CHECK(failures == full.size());
  }
}

TEST_CASE("Real asset: 4000 seeded bit flips are rejected or load and run cleanly") {
  std::mt19937 rng(0x5eedu);
  for (const std::string name : {std::string("cesium_man.sphc"), std::string("bcn_epileptic.sphc"), std::string("creature.sphc")}) {
    const std::vector<uint8_t> full = ReadCorpusAsset(name);
    CAPTURE(name);
    REQUIRE(full.size() > 1000);
    size_t loaded = 0, rejected = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      std::vector<uint8_t> bytes = full;
      const int flips = 1 + trial % 4;  // 1..4 bit flips per trial
      for (int k = 0; k < flips; ++k) bytes[rng() % bytes.size()] ^= uint8_t(1u << (rng() % 8));
      bool ok = false;
      // The narrow phase (its Init the slowest step) on one trial in 128: 16 flipped assets each.
      const char* broken =
          spherechain::fuzz::RunLoadAssetSequence(bytes.data(), bytes.size(), &ok, nullptr, trial % 128 == 0);
      if (broken) FAIL_CHECK("trial " << trial << ": " << broken);
      ok ? ++loaded : ++rejected;
    }
    MESSAGE(name << ": " << loaded << " flipped assets loaded and ran, " << rejected << " rejected");
    CHECK(rejected > 0);
    CHECK(loaded > 0);
  }
}

TEST_CASE("Real asset: a bind pose passing through itself everywhere is refused within the bind sweep's budget") {
  // Three assets the asset loader's fuzzer made: the creature's 1,504 triangles with a mutated bind pose that
  // intersects itself in 37,496, 91,264 and 91,382 pairs (a sweep of 206,683 to 453,738 exact tests, over
  // the budget of 16 a triangle). The unmutated creature and figure, under the same crease rule, are built.
  for (const std::string name : {std::string("found_58a2cb4fe6.sphc"), std::string("found_9c3050a604.sphc"),
                                 std::string("found_c7efeae7.sphc"), std::string("creature_crease.sphc"),
                                 std::string("figure_crease.sphc")}) {
    CAPTURE(name);
    const std::vector<uint8_t> bytes = ReadCorpusAsset(name);
    std::unique_ptr<uint64_t[]> aligned(new uint64_t[bytes.size() / 8 + 1]);
    std::memcpy(aligned.get(), bytes.data(), bytes.size());
    AssetView view;
    REQUIRE(LoadAsset(aligned.get(), bytes.size(), &view) == Status::kOk);
    REQUIRE(view.asset->bind_positions());
    REQUIRE(view.asset->crease() > 0.0f);
    const bool tangled = name.rfind("found_", 0) == 0;
    NarrowPhaseModel np;
    const Status s = np.Init(view);
    CHECK(s == (tangled ? Status::kErrorBindPoseTangled : Status::kOk));
    CHECK(np.initialized() == !tangled);
    if (!tangled) CHECK(np.bind_contact_count() < view.triangle_count);
    Model model;
    ModelOptions options;
    options.narrow_phase = true;
    CHECK(model.Init(view, options) == (tangled ? Status::kErrorBindPoseTangled : Status::kOk));
  }
}

TEST_CASE("Real asset: a frame that is no pose (collapsed, scrambled) is refused within the sweep's budget") {
  // The creature (1,504 triangles) under its crease rule: positions scrambled within a millimetre of the
  // origin intersect themselves in ~300,000 pairs (quadratic: MakeHuman's 26,756 triangles so took 36 s and
  // gave 95 million contacts): refused with kErrorFrameTangled within NarrowPhaseModel's budget, count 0,
  // unrestricted and restricted. Positions all at the origin (a part scaled to zero to hide it, taken to the
  // whole mesh) collapse every patch onto one point: no triangle has an area, so the crease rule gives such a
  // patch an empty box and looks at none of its pairs (before, all 4,656 pairs of the creature's 96 patches,
  // and MakeHuman's 1.5 million went past the budget); the other exclusions test the boxes;
  // the bind pose scaled by 2 (exact in floats), its own contacts, runs as before.
  const std::vector<uint8_t> bytes = ReadCorpusAsset("creature_crease.sphc");
  std::unique_ptr<uint64_t[]> aligned(new uint64_t[bytes.size() / 8 + 1]);
  std::memcpy(aligned.get(), bytes.data(), bytes.size());
  AssetView view;
  REQUIRE(LoadAsset(aligned.get(), bytes.size(), &view) == Status::kOk);
  NarrowPhaseModel np;
  REQUIRE(np.Init(view) == Status::kOk);
  NarrowPhaseWorkspace ws;
  REQUIRE(ws.Init(np) == Status::kOk);
  const uint32_t V = view.vertex_count, T = view.triangle_count;
  const uint64_t test_budget = uint64_t{NarrowPhaseModel::kSweepTestsPerTriangle} * T + NarrowPhaseModel::kSweepSlack;
  const uint64_t pair_budget =
      uint64_t{NarrowPhaseModel::kSweepPairsPerPatch} * np.crease_patch_count() + NarrowPhaseModel::kSweepSlack;
  const flatbuffers::Vector<float>* bind = view.asset->bind_positions();
  REQUIRE(bind);
  std::vector<float> scrambled(3 * size_t{V}), collapsed(3 * size_t{V}, 0.0f), moved(bind->begin(), bind->end());
  std::mt19937 rng(7);
  std::normal_distribution<float> mm(0.0f, 1e-3f);
  for (float& x : scrambled) x = mm(rng);
  for (float& x : moved) x *= 2.0f;  // exact in floats: the same intersections
  std::vector<Collision> every_pair;  // the restricted path behind every sphere pair
  for (uint32_t a = 0; a < view.sphere_count; ++a)
    for (uint32_t b = a + 1; b < view.sphere_count; ++b)
      every_pair.push_back(Collision{static_cast<uint16_t>(a), static_cast<uint16_t>(b), 0.0f, 0u});
  std::vector<TriangleContact> out(4096);
  std::vector<ContactDepth> depths(out.size());
  const uint64_t box_budget = uint64_t{NarrowPhaseModel::kSweepPairsPerPatch} * 16 * T + NarrowPhaseModel::kSweepSlack;
  for (const Exclusions ex : {Exclusions::kCrease, Exclusions::kAsset, Exclusions::kNone}) {
    for (const bool restricted : {false, true}) {
      for (const std::vector<float>* pos : {&scrambled, &collapsed, &moved}) {
        const bool crease = ex == Exclusions::kCrease;
        CAPTURE(static_cast<int>(ex));
        CAPTURE(restricted);
        const std::string which = pos == &scrambled ? "scrambled" : pos == &collapsed ? "collapsed" : "bind pose × 2";
        CAPTURE(which);
        uint32_t n = ~0u;
        NarrowPhaseStats stats;
        NarrowPhaseJob job;
        job.model = &np;
        job.workspace = &ws;
        job.positions = {pos->data(), V, 12};
        job.exclusions = ex;
        job.output = out.data();
        job.depths = depths.data();
        job.capacity = static_cast<uint32_t>(out.size());
        job.count = &n;
        job.stats = &stats;
        if (restricted)
          job.sphere_pairs = every_pair.data(), job.sphere_pair_count = static_cast<uint32_t>(every_pair.size());
        const Status s = job.Run();
        if (crease) {  // checked before each pair of groups: at most 16 pairs of patches of 16 x 16 more
          CHECK(stats.triangle_tests <= test_budget + 16 * 16 * 16);
          CHECK(stats.candidate_pairs <= pair_budget + 16);
        } else {  // checked before each triangle's sweep step: at most one step's boxes and tests more (a region)
          CHECK(stats.triangle_tests <= test_budget + T + 256);
          CHECK(stats.box_tests <= box_budget + T);
        }
        const bool over = stats.triangle_tests > test_budget ||
                          (crease ? stats.candidate_pairs > pair_budget : stats.box_tests > box_budget);
        if (pos == &moved) {
          CHECK(s == Status::kOk);
          if (crease) CHECK(n == np.bind_contact_count());
          if (crease) CHECK(stats.bind_contacts == n);
        } else if (pos == &collapsed && crease) {  // every patch collapsed: an empty box, no pair looked at
          CHECK(s == Status::kOk);
          CHECK(n == 0);
          CHECK(stats.candidate_pairs == 0);
          CHECK(stats.triangle_tests == 0);
        } else if (pos == &collapsed && s == Status::kOk) {  // every triangle degenerate: none tested, no contact
          CHECK(n == 0);
          CHECK(stats.triangle_tests == 0);
          CHECK(!over);
        } else {
          CHECK(s == Status::kErrorFrameTangled);
          CHECK(n == 0);
          CHECK(over);
        }
      }
    }
  }
}
