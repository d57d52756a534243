// libFuzzer target: LoadAsset on untrusted bytes, then everything a game does with a loaded asset
// (Model::Init and InitInPlace, Workspace::Init, RefitJob, DetectJob M1/M2, SurroundingTriangles). See load_asset_sequence.h and
// fuzz/README.md. Seed corpus: fuzz/corpus/load_asset/.
#include <cstdio>
#include <cstdlib>

#include "load_asset_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunLoadAssetSequence(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_load_asset: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
