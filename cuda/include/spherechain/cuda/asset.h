// spherechain cuda — a device copy of a .sphc asset's refit and detect data (uploaded once).
#pragma once

#include <cstdint>

#include "spherechain/cuda/status.h"
#include "spherechain/runtime/model.h"

namespace spherechain::cuda {

/// Device pointers, counts and contact margin of one uploaded asset. POD, shared by host and device
/// code; every pointer is DEVICE memory owned by the DeviceAsset it came from (lifetime: until Release /
/// the DeviceAsset's destruction). The values are runtime::Model's arrays (ModelArrays), the same floats, so
/// the device evaluates the same formulas (spherechain/runtime/formulas.h) on the same inputs:
struct DeviceAssetDesc {
  const uint32_t* pivot_vertices = nullptr;  ///< \#S×12: vertex indices (< \#V) of the 4 pivot triangles
                                             ///< (Asset.pivot_vertices)
  const float4* frame_local = nullptr;       ///< \#S: (PivotFrame.local_center xyz, bind radius /
                                             ///< PivotFrame.mean_distance)
  const float4* frame_offset = nullptr;      ///< \#S: (PivotFrame.centroid_offset xyz, 0)
  const float4* bind = nullptr;              ///< \#S: bind spheres (centre xyz, radius) (Asset.spheres)
  const uint32_t* chain_mask = nullptr;      ///< \#S: bit c ⇔ sphere in Asset.chains[c]
  const uint32_t* chain_offsets = nullptr;   ///< \#C+1 into chain_spheres
  const uint16_t* chain_spheres = nullptr;   ///< Σ|chain|, each chain ascending
  const uint32_t* excl_offsets = nullptr;    ///< \#S+1 into excl_neighbors (CSR by the smaller index a)
  const uint16_t* excl_neighbors = nullptr;  ///< \#excluded: partners b > a, ascending per a
  const uint8_t* sphere_regions = nullptr;   ///< \#S: each sphere's region (Asset.sphere_regions), only when the
                                             ///< asset has a fold margin (fold_margin >= 0); else null
  const uint4* joint_offsets = nullptr;      ///< \#S, only when the asset has joint weights (joint_count > 0):
                                             ///< per influence k the offset [floats] of its skinning matrix,
                                             ///< joint × 12 (Asset.sphere_joints; unused influences 0)
  const float4* joint_weights = nullptr;     ///< \#S, with joint_offsets: the influences' weights, descending
                                             ///< (Asset.sphere_joint_weights); the first 0 after influence 0
                                             ///< ends the blend (as JointRefitJob)
  const uint16_t* slot_spheres = nullptr;    ///< 8B: DetectJob's broad-phase layout, the sphere in each slot
                                             ///< (ModelArrays::broad_order; padding 0xFFFF)
  const uint4* block_pairs[2] = {};          ///< [M1, M2] block_pair_count[m]: the block pairs (I <= J) with a
                                             ///< lane the method tests, (I | J << 16, lanes low 32 bits, lanes
                                             ///< high 32 bits, 0) (ModelArrays::broad_allowed)
  uint32_t sphere_count = 0;                 ///< \#S (1..65535)
  uint32_t vertex_count = 0;                 ///< \#V the positions must have
  uint32_t chain_count = 0;                  ///< \#C (0..32)
  uint32_t max_chain_length = 0;             ///< longest chain (spheres)
  uint32_t excluded_count = 0;               ///< \#excluded (len(Asset.excluded_pairs))
  uint32_t block_count = 0;                  ///< B (ModelArrays::broad_blocks)
  uint32_t block_pair_count[2] = {};         ///< [M1, M2] entries of block_pairs
  uint32_t joint_count = 0;                  ///< \#J skinning matrices an instance's joint refit reads
                                             ///< (Asset.joint_count, runtime::Model::joint_count()); 0: the
                                             ///< asset holds no joint weights (no RefitSource::kJoints)
  float contact_margin = 0.0f;               ///< the asset's contact margin [Units: source units]
                                             ///< (Asset.contact_margin, schema v2; 0 for v1 assets), as
                                             ///< runtime::Model::contact_margin(): the margin
                                             ///< Batch::Run tests this asset's instances with when
                                             ///< FrameParams::margin < 0
  float fold_margin = -1.0f;                 ///< the asset's fold margin [Units: source units] (Asset.fold_margin,
                                             ///< added within schema v3), as runtime::Model::fold_margin():
                                             ///< pairs of two spheres of one region are tested with it
                                             ///< (FrameParams::fold_margin overrides it); < 0: none, every
                                             ///< pair is tested with the contact margin
};

/// Owning device copy of what refit and detect need from one asset — its runtime::Model (built once on
/// the host; the device copy reads it, it does not prepare the asset again), uploaded once. Move-only. Thread safety: Upload/Release are not thread-safe on one object; const use
/// (desc(), being referenced by a Batch) is.
class DeviceAsset {
 public:
  DeviceAsset() = default;
  DeviceAsset(const DeviceAsset&) = delete;
  DeviceAsset& operator=(const DeviceAsset&) = delete;
  DeviceAsset(DeviceAsset&& o) noexcept;
  DeviceAsset& operator=(DeviceAsset&& o) noexcept;
  ~DeviceAsset();

  /// Copies `model`'s refit/detect arrays (ModelArrays: pivot vertices, pivot-frame coordinates, radius
  /// scales, bind spheres, chains, excluded pairs; with a fold margin also the spheres' regions,
  /// Model::fold_region; with joint weights (schema v3 rigged bakes) the spheres' joints and weights for
  /// the joint refit; the broad phase's blocks of 8 spheres and the block pairs each method tests) to
  /// the current device (one cudaMalloc, one synchronous cudaMemcpy) and keeps the
  /// asset's contact margin (Model::contact_margin()) and fold margin (Model::fold_margin()). Neither the
  /// model nor the asset bytes are needed afterwards.
  /// Returns kOk; kErrorNullArgument (model not initialised); kErrorOutOfMemory (host/device allocation);
  /// kErrorCuda (LastCudaError()). On failure the object is left empty.
  /// Cost: O(\#S + Σ|chain| + \#excluded) host work, ~100 B per sphere of device memory, synchronous.
  /// Must not be called while a Batch referencing this asset runs (it frees the old copy).
  Status Upload(const runtime::Model& model);
  /// Frees the device memory (cudaFree, synchronising). Safe on an empty object.
  void Release();

  /// True after a successful Upload.
  bool valid() const { return storage_ != nullptr; }
  /// Device pointers + counts (see DeviceAssetDesc); all null/0 when empty.
  const DeviceAssetDesc& desc() const { return desc_; }
  uint32_t sphere_count() const { return desc_.sphere_count; }  ///< \#S
  uint32_t vertex_count() const { return desc_.vertex_count; }  ///< \#V
  uint32_t chain_count() const { return desc_.chain_count; }    ///< \#C
  uint32_t joint_count() const { return desc_.joint_count; }    ///< \#J (0: no joint refit)
  /// The asset's contact margin (DeviceAssetDesc::contact_margin) [Units: source units]; 0 when empty.
  float contact_margin() const { return desc_.contact_margin; }
  /// The asset's fold margin (DeviceAssetDesc::fold_margin) [Units: source units]; < 0: none (also when empty).
  float fold_margin() const { return desc_.fold_margin; }
  /// Device bytes held.
  size_t device_bytes() const { return bytes_; }

 private:
  void* storage_ = nullptr;  // one device allocation holding every array
  size_t bytes_ = 0;
  DeviceAssetDesc desc_{};
};

}  // namespace spherechain::cuda
