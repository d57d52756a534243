// spherechain CLI — reading a .sphc file into aligned memory and loading it with the runtime.
#pragma once

#include <memory>
#include <string>

#include "spherechain/baker/write.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::cli {

/// The file's bytes (8-byte aligned, as LoadAsset requires) and the verified view into them.
struct LoadedAsset {
  std::unique_ptr<uint64_t[]> storage;
  size_t size = 0;
  runtime::AssetView view;
  const uint8_t* bytes() const { return reinterpret_cast<const uint8_t*>(storage.get()); }
};

/// Reads and verifies `path`. On failure `*error` says what and where (file, status).
bool LoadAssetFile(const std::string& path, LoadedAsset* out, std::string* error);

}  // namespace spherechain::cli
