// libFuzzer target: untrusted bytes as a bake configuration (JSON, then after a NUL its region map) and the
// whole bake of a fixed small body with them: bake_sequence.h RunBakeConfigInput.
// Seeds: fuzz/corpus/bake_config/; dictionary fuzz/dict/bake_config.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunBakeConfigInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_bake_config: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
