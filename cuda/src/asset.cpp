// DeviceAsset::Upload — the runtime::Model's SoA arrays, packed into one device block.
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
  size_t Add(const T* v, size_t count) {
    const size_t off = (bytes.size() + 15) & ~size_t{15};
    bytes.resize(off + count * sizeof(T) + 16);  // +16: never an empty section
    if (count) std::memcpy(bytes.data() + off, v, count * sizeof(T));
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

Status DeviceAsset::Upload(const runtime::Model& model) {
  Release();
  if (!model.initialized()) return Status::kErrorNullArgument;
  const runtime::ModelArrays& a = model.arrays();
  const uint32_t S = model.sphere_count(), C = model.chain_count();
  Packer pk;
  size_t o_pv, o_local, o_offset, o_bind, o_mask, o_coff, o_cs, o_eoff, o_en, o_reg = 0, o_joff = 0, o_jw = 0, o_slots = 0, o_bp[2] = {};
  uint32_t bp_count[2] = {};
  const bool joints = model.joint_count() > 0 && a.sphere_joints && a.sphere_joint_weights;
  const bool fold = model.fold_margin() >= 0.0f;
  try {
    // The model's SoA arrays, packed as float4 rows (x, y, z, w) for the device's 16-byte loads: the same
    // floats, so the same arithmetic as the CPU jobs.
    std::vector<float4> local(S), offset(S), bind(S);
    for (uint32_t s = 0; s < S; ++s) {
      bind[s] = float4{a.bind_x[s], a.bind_y[s], a.bind_z[s], a.bind_r[s]};
      local[s] = float4{a.local_x[s], a.local_y[s], a.local_z[s], a.radius_scale[s]};
      offset[s] = float4{a.offset_x[s], a.offset_y[s], a.offset_z[s], 0.0f};
    }
    o_pv = pk.Add(a.pivot_vertices, size_t{12} * S);
    o_local = pk.Add(local.data(), local.size());
    o_offset = pk.Add(offset.data(), offset.size());
    o_bind = pk.Add(bind.data(), bind.size());
    o_mask = pk.Add(a.chain_mask, S);
    o_coff = pk.Add(a.chain_offsets, C + 1);
    o_cs = pk.Add(a.chain_spheres, a.chain_offsets[C]);
    o_eoff = pk.Add(a.excl_offsets, S + 1);
    o_en = pk.Add(a.excl_neighbors, a.excluded_count);
    if (fold) {  // the regions tell a fold pair (one region) from a contact pair (two)
      std::vector<uint8_t> regions(S);
      for (uint32_t s = 0; s < S; ++s) regions[s] = model.fold_region(s);
      o_reg = pk.Add(regions.data(), regions.size());
    }
    {  // DetectJob's broad-phase layout: slots and, per method, the block pairs with a lane to test
      const uint32_t B = a.broad_blocks;
      std::vector<uint16_t> slots(size_t{8} * B);
      for (size_t i = 0; i < slots.size(); ++i) slots[i] = a.broad_order[i] < S ? uint16_t(a.broad_order[i]) : uint16_t{0xFFFF};
      o_slots = pk.Add(slots.data(), slots.size());
      for (int m = 0; m < 2; ++m) {
        std::vector<uint4> pairs;
        for (uint32_t I = 0; I < B; ++I)
          for (uint32_t J = I; J < B; ++J)
            if (const uint64_t lanes = a.broad_allowed[m][size_t{I} * B + J])
              pairs.push_back(uint4{I | (J << 16), uint32_t(lanes), uint32_t(lanes >> 32), 0u});
        bp_count[m] = static_cast<uint32_t>(pairs.size());
        o_bp[m] = pk.Add(pairs.data(), pairs.size());
      }
    }
    if (joints) {  // JointRefitJob's inputs per sphere: 4 matrix offsets [floats] and 4 weights
      std::vector<uint4> offsets(S);
      std::vector<float4> weights(S);
      for (uint32_t s = 0; s < S; ++s) {
        const uint16_t* j = a.sphere_joints + 4 * size_t{s};
        const float* w = a.sphere_joint_weights + 4 * size_t{s};
        offsets[s] = uint4{j[0] * 12u, w[1] != 0.0f ? j[1] * 12u : 0u, w[2] != 0.0f ? j[2] * 12u : 0u,
                           w[3] != 0.0f ? j[3] * 12u : 0u};
        weights[s] = float4{w[0], w[1], w[2], w[3]};
      }
      o_joff = pk.Add(offsets.data(), offsets.size());
      o_jw = pk.Add(weights.data(), weights.size());
    }
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
  desc_.vertex_count = model.vertex_count();
  desc_.chain_count = C;
  desc_.max_chain_length = a.max_chain_length;
  desc_.excluded_count = a.excluded_count;
  desc_.contact_margin = model.contact_margin();  // Asset.contact_margin (absent in v1 assets: 0)
  desc_.sphere_regions = fold ? base + o_reg : nullptr;
  desc_.fold_margin = fold ? model.fold_margin() : -1.0f;  // Asset.fold_margin (absent: none)
  desc_.slot_spheres = reinterpret_cast<const uint16_t*>(base + o_slots);
  desc_.block_count = a.broad_blocks;
  for (int m = 0; m < 2; ++m) {
    desc_.block_pairs[m] = reinterpret_cast<const uint4*>(base + o_bp[m]);
    desc_.block_pair_count[m] = bp_count[m];
  }
  desc_.joint_offsets = joints ? reinterpret_cast<const uint4*>(base + o_joff) : nullptr;
  desc_.joint_weights = joints ? reinterpret_cast<const float4*>(base + o_jw) : nullptr;
  desc_.joint_count = joints ? model.joint_count() : 0u;
  return Status::kOk;
}

}  // namespace spherechain::cuda
