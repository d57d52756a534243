// DeviceAsset::Upload — the SoA arrays runtime::Context::Init builds, packed into one device block.
#include "spherechain/cuda/asset.h"

#include <cstring>
#include <new>
#include <utility>
#include <vector>

#include "internal.h"

namespace spherechain::cuda {
namespace {

// Packs arrays into one host byte buffer with 16-byte aligned sections; offsets are later rebased
// onto the device allocation.
struct Packer {
  std::vector<unsigned char> bytes;
  template <typename T>
  size_t Add(const std::vector<T>& v) {
    const size_t off = (bytes.size() + 15) & ~size_t{15};
    bytes.resize(off + v.size() * sizeof(T) + 16);  // +16: never an empty section
    if (!v.empty()) std::memcpy(bytes.data() + off, v.data(), v.size() * sizeof(T));
    return off;
  }
};

}  // namespace

DeviceAsset::DeviceAsset(DeviceAsset&& o) noexcept
    : storage_(std::exchange(o.storage_, nullptr)), bytes_(std::exchange(o.bytes_, 0)), desc_(std::exchange(o.desc_, {})) {}

DeviceAsset& DeviceAsset::operator=(DeviceAsset&& o) noexcept {
  if (this != &o) {
    Release();
    storage_ = std::exchange(o.storage_, nullptr);
    bytes_ = std::exchange(o.bytes_, 0);
    desc_ = std::exchange(o.desc_, {});
  }
  return *this;
}

DeviceAsset::~DeviceAsset() { Release(); }

void DeviceAsset::Release() {
  if (storage_) (void)cudaFree(storage_);
  storage_ = nullptr;
  bytes_ = 0;
  desc_ = {};
}

Status DeviceAsset::Upload(const runtime::AssetView& view) {
  Release();
  if (!view.valid()) return Status::kErrorNullArgument;
  const schema::Asset& a = *view.asset;
  const uint32_t S = view.sphere_count, C = view.chain_count;
  Packer pk;
  size_t o_pv, o_local, o_offset, o_bind, o_mask, o_coff, o_cs, o_eoff, o_en;
  uint32_t max_chain = 0;
  try {
    // Same values as Context::Init (radius_scale = bind radius / mean_distance, one float division).
    std::vector<float4> local(S), offset(S), bind(S);
    for (uint32_t s = 0; s < S; ++s) {
      const schema::Sphere* sp = a.spheres()->Get(s);
      const schema::PivotFrame* f = a.pivot_frames()->Get(s);
      bind[s] = float4{sp->center().x(), sp->center().y(), sp->center().z(), sp->radius()};
      local[s] = float4{f->local_center().x(), f->local_center().y(), f->local_center().z(),
                        sp->radius() / f->mean_distance()};
      offset[s] = float4{f->centroid_offset().x(), f->centroid_offset().y(), f->centroid_offset().z(), 0.0f};
    }
    std::vector<uint32_t> pv(a.pivot_vertices()->begin(), a.pivot_vertices()->end());
    std::vector<uint32_t> mask(S, 0u), coff(C + 1, 0u);
    std::vector<uint16_t> cs;
    for (uint32_t c = 0; c < C; ++c) {
      const auto* list = a.chains()->Get(c)->spheres();
      coff[c + 1] = coff[c] + list->size();
      max_chain = list->size() > max_chain ? list->size() : max_chain;
      for (uint16_t s : *list) {
        cs.push_back(s);
        mask[s] |= 1u << c;
      }
    }
    const auto* ex = a.excluded_pairs();
    const uint32_t E = ex ? ex->size() : 0;
    std::vector<uint32_t> eoff(S + 1, 0u);
    std::vector<uint16_t> en(E);
    for (uint32_t i = 0; i < E; ++i) ++eoff[ex->Get(i)->a() + 1];
    for (uint32_t s = 0; s < S; ++s) eoff[s + 1] += eoff[s];
    for (uint32_t i = 0; i < E; ++i) en[i] = ex->Get(i)->b();  // sorted by (a, b) (LoadAsset checked)

    o_pv = pk.Add(pv);
    o_local = pk.Add(local);
    o_offset = pk.Add(offset);
    o_bind = pk.Add(bind);
    o_mask = pk.Add(mask);
    o_coff = pk.Add(coff);
    o_cs = pk.Add(cs);
    o_eoff = pk.Add(eoff);
    o_en = pk.Add(en);
  } catch (const std::bad_alloc&) {
    return Status::kErrorOutOfMemory;
  }

  void* dev = nullptr;
  if (Status s = detail::CudaStatus(cudaMalloc(&dev, pk.bytes.size())); s != Status::kOk) return s;
  if (Status s = detail::CudaStatus(cudaMemcpy(dev, pk.bytes.data(), pk.bytes.size(), cudaMemcpyHostToDevice));
      s != Status::kOk) {
    (void)cudaFree(dev);
    return s;
  }
  auto* base = static_cast<unsigned char*>(dev);
  storage_ = dev;
  bytes_ = pk.bytes.size();
  desc_.pivot_vertices = reinterpret_cast<const uint32_t*>(base + o_pv);
  desc_.frame_local = reinterpret_cast<const float4*>(base + o_local);
  desc_.frame_offset = reinterpret_cast<const float4*>(base + o_offset);
  desc_.bind = reinterpret_cast<const float4*>(base + o_bind);
  desc_.chain_mask = reinterpret_cast<const uint32_t*>(base + o_mask);
  desc_.chain_offsets = reinterpret_cast<const uint32_t*>(base + o_coff);
  desc_.chain_spheres = reinterpret_cast<const uint16_t*>(base + o_cs);
  desc_.excl_offsets = reinterpret_cast<const uint32_t*>(base + o_eoff);
  desc_.excl_neighbors = reinterpret_cast<const uint16_t*>(base + o_en);
  desc_.sphere_count = S;
  desc_.vertex_count = view.vertex_count;
  desc_.chain_count = C;
  desc_.max_chain_length = max_chain;
  desc_.excluded_count = a.excluded_pairs() ? a.excluded_pairs()->size() : 0;
  desc_.contact_margin = a.contact_margin();  // as Context::Init (field absent in v1 assets: 0)
  return Status::kOk;
}

}  // namespace spherechain::cuda
