// Replays the libFuzzer seed corpus (fuzz/corpus/load_asset/) through the fuzzer's own sequence
// (fuzz/load_asset_sequence.h): LoadAsset → Model::Init → RefitJob → DetectJob M1/M2 →
// SurroundingTriangles → the narrow phase held by the Model (every Exclusions, at the bind pose too). Built in every configuration (no libFuzzer needed); under the asan preset it
// runs with ASan + UBSan. A crash the fuzzer finds is fixed, then its input is added to the corpus.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../fuzz/load_asset_sequence.h"
#include "test_data.h"

namespace {

std::vector<uint8_t> ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST_CASE("Fuzz corpus (fuzz/corpus/load_asset): every input runs the fuzzer's sequence cleanly") {
  const std::filesystem::path dir = spherechain::test::SourceFile("fuzz/corpus/load_asset");
  REQUIRE(std::filesystem::is_directory(dir));
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 3);
  size_t loaded_count = 0, crease_count = 0;
  for (const auto& f : files) {
    const std::vector<uint8_t> bytes = ReadAll(f);
    CAPTURE(f.filename().string());
    bool loaded = false, crease = false;
    const char* broken = spherechain::fuzz::RunLoadAssetSequence(bytes.data(), bytes.size(), &loaded, &crease);
    CHECK_MESSAGE(broken == nullptr, (broken ? broken : ""));
    loaded_count += loaded;
    crease_count += crease;
  }
  // The untouched real assets (bcn_epileptic.sphc, cesium_man.sphc) must load, and the two baked with the
  // crease rule (creature_crease.sphc, figure_crease.sphc) reach the narrow phase under it.
  CHECK(loaded_count >= 4);
  CHECK(crease_count >= 2);
}

TEST_CASE("Fuzz finding: reach offsets that go past the end and fall back are refused, kErrorOffsets") {
  // A mutated asset whose reach_offsets rise past reach_triangles' length and fall back at a later sphere:
  // the loader walked each sphere's range before checking the next offset and read past the vector
  // (fuzz_load_asset, 30 November, 2,593 s into a campaign; a flatbuffers assertion in the fuzz build).
  const std::vector<uint8_t> bytes =
      ReadAll(spherechain::test::SourceFile("fuzz/corpus/load_asset/crash_reach_offsets_unordered.sphc"));
  REQUIRE(bytes.size() > 8);
  spherechain::runtime::AssetView view;
  CHECK(spherechain::runtime::LoadAsset(bytes.data(), bytes.size(), &view) == spherechain::runtime::Status::kErrorOffsets);
  CHECK_FALSE(view.valid());
}
