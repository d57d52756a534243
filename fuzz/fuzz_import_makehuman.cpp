// libFuzzer target: untrusted bytes as a MakeHuman rig (`.mhskel`, NUL, `.mhw`) beside a fixed body
// (fuzz/data/body.obj) through what a bake does with the rigged mesh: bake_sequence.h RunImportMakeHumanInput.
// Seeds: fuzz/corpus/import_makehuman/; dictionary fuzz/dict/makehuman.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunImportMakeHumanInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_import_makehuman: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
