// libFuzzer target: untrusted bytes as a file of a format the baker reads through assimp (the first byte picks
// FBX, DAE, X, BLEND, 3DS, PLY, STL, IQM, SMD, MD5MESH, MS3D or B3D) through what a bake does with it:
// bake_sequence.h RunImportAssimpInput. Debian's libassimp is not instrumented: coverage guides the fuzzer
// through our importer only, and ASan sees assimp's heap (malloc/free) but not its reads and writes.
// Seeds: fuzz/corpus/import_assimp/; dictionary fuzz/dict/assimp.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

// ASan's quarantine (freed memory held back to catch a use after free) at 16 MB instead of 256: assimp runs in
// a child process forked from the fuzzer for every input (ImportOptions::isolate_assimp, as in the product), and
// the kernel's copy and teardown of the fuzzer's page tables took 64 % of the target's time at a resident size
// of 440 MB; at 120–150 MB it takes 21 %, and the target runs 1.5 to 2 times the executions a second
// (fuzz/README.md, "Limits"). ASAN_OPTIONS in the environment still overrides it.
extern "C" const char* __asan_default_options() { return "quarantine_size_mb=16"; }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunImportAssimpInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_import_assimp: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
