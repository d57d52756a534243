// libFuzzer target: untrusted bytes as a file of a format the baker reads through assimp (the first byte picks
// FBX, DAE, X, BLEND, 3DS, PLY, STL, IQM, SMD, MD5MESH, MS3D or B3D) through what a bake does with it:
// bake_sequence.h RunImportAssimpInput. Debian's libassimp is not instrumented: coverage guides the fuzzer
// through our importer only, and ASan sees assimp's heap (malloc/free) but not its reads and writes.
// Seeds: fuzz/corpus/import_assimp/; dictionary fuzz/dict/assimp.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunImportAssimpInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_import_assimp: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
