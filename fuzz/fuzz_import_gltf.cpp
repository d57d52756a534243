// libFuzzer target: untrusted bytes as a glTF character (`.glb` when they start with "glTF", else `.gltf` JSON
// with data-URI buffers) through what a bake does with it: bake_sequence.h RunImportGltfInput.
// Seeds: fuzz/corpus/import_gltf/; dictionary fuzz/dict/gltf.dict; fuzz/README.md.
#include <cstdio>
#include <cstdlib>

#include "bake_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (const char* broken = spherechain::fuzz::RunImportGltfInput(data, size)) {
    std::fprintf(stderr, "spherechain fuzz_import_gltf: invariant broken: %s\n", broken);
    std::abort();
  }
  return 0;
}
