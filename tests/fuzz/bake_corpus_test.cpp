// Replays the importer and configuration fuzzers' corpora (fuzz/corpus/import_gltf, import_obj,
// import_makehuman, import_assimp, bake_config) through the fuzzers' own step per input (fuzz/bake_sequence.h):
// the file imported, segmented and fitted small as a bake would, or the configuration baked on a fixed body.
// Built in every configuration (no libFuzzer needed); under the asan preset with ASan + UBSan. A crash the
// fuzzers find is fixed (or contained), then its minimised input joins the corpus and is replayed here forever.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../../fuzz/bake_sequence.h"
#include "test_data.h"

namespace {

namespace sf = spherechain::fuzz;
using Step = const char* (*)(const uint8_t*, size_t, sf::Reached*);

struct Replayed {
  size_t files = 0, imported = 0, segmented = 0, fitted = 0, baked = 0;
};

Replayed Replay(const std::string& corpus, Step step) {
  const std::filesystem::path dir = spherechain::test::SourceFile("fuzz/corpus/" + corpus);
  REQUIRE(std::filesystem::is_directory(dir));
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  Replayed out;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    CAPTURE(f.filename().string());
    sf::Reached r;
    const char* broken = step(bytes.data(), bytes.size(), &r);
    CHECK_MESSAGE(broken == nullptr, (broken ? broken : ""));
    ++out.files;
    out.imported += r.imported;
    out.segmented += r.segmented;
    out.fitted += r.fitted;
    out.baked += r.baked;
  }
  MESSAGE(corpus << ": " << out.files << " inputs, " << out.imported << " imported, " << out.segmented
                 << " segmented, " << out.fitted << " fitted, " << out.baked << " baked");
  return out;
}

}  // namespace

// The seeds include real characters, so each replay also checks that the harness reaches the stages it is
// meant to fuzz (a harness that stops at the import would pass every input and find nothing).
TEST_CASE("Fuzz corpus (fuzz/corpus/import_gltf): every input imports, segments and fits cleanly or fails with a message") {
  const Replayed r = Replay("import_gltf", &sf::RunImportGltfInput);
  CHECK(r.files >= 10);
  CHECK(r.fitted >= 2);  // the figure (.gltf and .glb)
}

TEST_CASE("Fuzz corpus (fuzz/corpus/import_obj): every input imports, segments and fits cleanly or fails with a message") {
  const Replayed r = Replay("import_obj", &sf::RunImportObjInput);
  CHECK(r.files >= 10);
  CHECK(r.segmented >= 1);
}

TEST_CASE("Fuzz corpus (fuzz/corpus/import_makehuman): every rig beside the fixed body imports, segments and fits cleanly or fails with a message") {
  const Replayed r = Replay("import_makehuman", &sf::RunImportMakeHumanInput);
  CHECK(r.files >= 3);
  CHECK(r.fitted >= 1);  // figure.mh: the figure rigged with MakeHuman's bone names
}

TEST_CASE("Fuzz corpus (fuzz/corpus/import_assimp): every input imports cleanly or fails with a message") {
  const Replayed r = Replay("import_assimp", &sf::RunImportAssimpInput);
  CHECK(r.files >= 12);
  CHECK(r.imported >= 12);
}

TEST_CASE("Fuzz corpus (fuzz/corpus/bake_config): every configuration bakes the fixed body cleanly or fails with a message") {
  const Replayed r = Replay("bake_config", &sf::RunBakeConfigInput);
  CHECK(r.files >= 10);
  CHECK(r.baked >= 5);
}
