// spherechain import — tinygltf's implementation (its single-header TINYGLTF_IMPLEMENTATION mode), compiled
// into the static import library instead of taken from Debian's libtinygltf.so. Why: Debian's libdraco, which
// libassimp pulls in, exports the symbols of an older tinygltf with another Model layout. A program whose link
// line names libdraco before libtinygltf — CMake's order for a find_package(spherechain) consumer of
// spherechain::import (and so the baker, playback) — bound our calls to draco's copies and crashed in the first glTF import
// (heap corruption in ~Model). Definitions inside the static library are resolved at link time, before any
// shared library is searched, so the link order no longer matters. Images are never decoded or written by
// the baker (import_gltf.cpp installs a loader that skips them), hence no stb_image.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>
