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
