// libFuzzer target: untrusted bytes as a Wavefront `.obj` (our own reader) through what a bake does with it:
// bake_sequence.h RunImportObjInput. Seeds: fuzz/corpus/import_obj/; dictionary fuzz/dict/obj.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunImportObjInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_import_obj: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
