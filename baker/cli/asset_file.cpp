#include "asset_file.h"

#include <cstring>

namespace spherechain::cli {

bool LoadAssetFile(const std::string& path, LoadedAsset* out, std::string* error) {
  auto bytes = baker::ReadFileBytes(path, runtime::kMaxAssetBytes);
  if (!bytes.ok()) {
    *error = bytes.error().message;
    return false;
  }
  out->size = bytes->size();
  out->storage.reset(new uint64_t[(out->size + 7) / 8 + 1]);
  if (out->size) std::memcpy(out->storage.get(), bytes->data(), out->size);
  const runtime::Status s = runtime::LoadAsset(out->bytes(), out->size, &out->view);
  if (runtime::Failed(s)) {
    *error = "'" + path + "' is not a loadable .sphc asset: " + runtime::ToString(s);
    return false;
  }
  return true;
}

}  // namespace spherechain::cli
