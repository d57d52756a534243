// Model and Workspace: the runtime's only allocations (one block each, or caller memory).
#include "spherechain/runtime/model.h"

#include <algorithm>
#include <cassert>
#include <atomic>
#include <bit>
#include <cstring>
#include <limits>
#include <new>
#include <utility>

#include "alloc_guard.h"
#include "internal.h"
#include "spherechain/runtime/narrow_phase.h"

namespace spherechain::runtime {
namespace {

constexpr size_t kAlign = 64;      // every section of a block (and an owned block) starts on 64 bytes
constexpr size_t kMinAlign = 16;   // caller memory [Limit]
constexpr uint32_t kPad = 8;       // SoA rows are read in chunks of 8

std::atomic<uint64_t> g_next_model_id{1};

size_t AlignUp(size_t n) { return (n + kAlign - 1) & ~(kAlign - 1); }

// Sections of a block, laid out in order, each 64-byte aligned.
struct Carver {
  size_t size = 0;
  unsigned char* base = nullptr;  // null while measuring
  template <typename T>
  T* Take(size_t count) {
    const size_t off = AlignUp(size);
    size = off + count * sizeof(T);
    return base ? reinterpret_cast<T*>(base + off) : nullptr;
  }
};

// The chain mask of sphere s read from the asset (chains ascending: LoadAsset checked). O(#C log n).
uint32_t AssetChainMask(const schema::Asset& a, uint32_t C, uint32_t s) {
  uint32_t mask = 0;
  for (uint32_t c = 0; c < C; ++c) {
    const auto* list = a.chains()->Get(c)->spheres();
    if (std::binary_search(list->begin(), list->end(), static_cast<uint16_t>(s))) mask |= 1u << c;
  }
  return mask;
}

// Broad-phase group of sphere s: its region (Asset.sphere_regions) when present, else its chain mask.
uint32_t Group(const schema::Asset& a, uint32_t s, uint32_t chain_mask) {
  return a.sphere_regions() ? a.sphere_regions()->Get(s) : chain_mask;
}

// Number of blocks of 8 of the layout: Σ over groups of ceil(n_g / 8). No allocation. By region: one count
// per region value, O(#S). By chain mask: the spheres in no chain are one group; every other mask's spheres
// all lie in the list of its lowest chain, so each such group is counted once, from there:
// O(#S · #C log n + Σ_c n_c² · #C log n), the second bounded by kMaxChainPairs (LoadAsset). (Comparing each
// sphere's group with every earlier sphere's was O(#S² · #C log n): minutes for a hostile asset of 65,535
// spheres.)
uint32_t CountBlocks(const AssetView& view) {
  const schema::Asset& a = *view.asset;
  const uint32_t S = view.sphere_count, C = view.chain_count;
  uint32_t blocks = 0;
  if (const auto* regions = a.sphere_regions()) {  // values < kMaxRegions <= 256 (LoadAsset)
    uint32_t count[256] = {};
    for (uint32_t s = 0; s < S; ++s) ++count[regions->Get(s)];
    for (uint32_t n : count) blocks += (n + 7) / 8;
    return blocks;
  }
  uint32_t unchained = 0;
  for (uint32_t s = 0; s < S; ++s) unchained += AssetChainMask(a, C, s) == 0;
  blocks += (unchained + 7) / 8;
  for (uint32_t c = 0; c < C; ++c) {
    const auto* list = a.chains()->Get(c)->spheres();
    for (uint32_t i = 0; i < list->size(); ++i) {
      const uint32_t mask = AssetChainMask(a, C, list->Get(i));
      if (static_cast<uint32_t>(std::countr_zero(mask)) != c) continue;  // counted from its lowest chain
      bool first = true;
      for (uint32_t j = 0; j < i && first; ++j) first = AssetChainMask(a, C, list->Get(j)) != mask;
      if (!first) continue;
      uint32_t n = 0;
      for (uint32_t j = i; j < list->size(); ++j) n += AssetChainMask(a, C, list->Get(j)) == mask;
      blocks += (n + 7) / 8;
    }
  }
  return blocks;
}

// The model's sections, in block order. With `base` null only measures (returns the size).
struct ModelSections {
  ModelArrays a{};
  float *bind[4] = {}, *local[3] = {}, *offset[3] = {}, *radius_scale = nullptr;
  uint32_t *pivot_vertices = nullptr, *chain_mask = nullptr, *chain_offsets = nullptr, *excl_offsets = nullptr;
  uint16_t *chain_spheres = nullptr, *excl_neighbors = nullptr, *joints = nullptr;
  float* weights = nullptr;
  uint32_t* order = nullptr;
  uint32_t *joint_sphere = nullptr, *joint_offsets = nullptr;
  float *joint_weights = nullptr, *joint_bind = nullptr;
  uint64_t* allowed[2] = {};
  uint8_t* live[2] = {};
  uint32_t* key_begin[2] = {};
  uint8_t* fold_region = nullptr;  // #S: Asset.sphere_regions, only with a fold margin (Asset.fold_margin >= 0)
  size_t size = 0;

  ModelSections(const AssetView& view, uint32_t B, unsigned char* base) {
    const schema::Asset& asset = *view.asset;
    const uint32_t S = view.sphere_count, C = view.chain_count;
    uint32_t chained = 0;
    for (uint32_t c = 0; c < C; ++c) chained += asset.chains()->Get(c)->spheres()->size();
    const uint32_t E = asset.excluded_pairs() ? asset.excluded_pairs()->size() : 0;
    const bool has_joints = asset.sphere_joints() && asset.sphere_joint_weights() && asset.joint_count() > 0;
    const uint32_t live_stride = (B + 7) / 8;
    Carver k{0, base};
    for (auto& p : bind) p = k.Take<float>(S);
    pivot_vertices = k.Take<uint32_t>(size_t{12} * S);
    for (auto& p : local) p = k.Take<float>(S + kPad);
    for (auto& p : offset) p = k.Take<float>(S + kPad);
    radius_scale = k.Take<float>(S + kPad);
    chain_mask = k.Take<uint32_t>(S + 1);
    chain_offsets = k.Take<uint32_t>(C + 1);
    chain_spheres = k.Take<uint16_t>(chained);
    excl_offsets = k.Take<uint32_t>(S + 1);
    excl_neighbors = k.Take<uint16_t>(E);
    if (has_joints) joints = k.Take<uint16_t>(size_t{4} * S), weights = k.Take<float>(size_t{4} * S);
    order = k.Take<uint32_t>(size_t{8} * B);
    if (has_joints) {
      joint_sphere = k.Take<uint32_t>(S);
      joint_offsets = k.Take<uint32_t>(size_t{4} * S);
      joint_weights = k.Take<float>(size_t{4} * S);
      joint_bind = k.Take<float>(size_t{4} * S);
    }
    for (int m = 0; m < 2; ++m) {
      allowed[m] = k.Take<uint64_t>(size_t{B} * B);
      live[m] = k.Take<uint8_t>(size_t{B} * live_stride);
      key_begin[m] = k.Take<uint32_t>(B + 1);
    }
    if (asset.fold_margin() >= 0.0f) fold_region = k.Take<uint8_t>(S);
    size = AlignUp(k.size);
    a = ModelArrays{bind[0], bind[1], bind[2], bind[3], pivot_vertices, local[0], local[1], local[2],
                    offset[0], offset[1], offset[2], radius_scale, chain_mask, chain_offsets, chain_spheres,
                    excl_offsets, excl_neighbors, joints, weights, E, 0, nullptr, {nullptr, nullptr}, 0};
  }
};

}  // namespace

// ---- Model -----------------------------------------------------------------------------------------

Model::Model(Model&& o) noexcept { *this = std::move(o); }

Model& Model::operator=(Model&& o) noexcept {
  if (this != &o) {
    Release();
    std::memcpy(static_cast<void*>(this), static_cast<const void*>(&o), sizeof(Model));
    o.storage_ = nullptr, o.owned_ = false, o.narrow_ = nullptr;
    o.Release();
  }
  return *this;
}

Model::~Model() { Release(); }

void Model::Release() {
  if (narrow_) narrow_->~NarrowPhaseModel();  // its arrays live in the block: nothing freed one by one
  narrow_ = nullptr;
  if (owned_ && storage_) ::operator delete(storage_, std::align_val_t{kAlign});
  storage_ = nullptr, owned_ = false, bytes_ = 0, id_ = 0;
  sphere_count_ = vertex_count_ = chain_count_ = joint_count_ = 0;
  m1_candidates_ = m2_candidates_ = m1_tests_ = 0;
  contact_margin_ = 0.0f;
  fold_margin_ = -1.0f;
  fold_region_ = nullptr;
  a_ = ModelArrays{};
  isa_ = 0;
  blocks_ = box_pitch_ = live_stride_ = key_slots_ = 0;
  order_ = nullptr;
  joint_sphere_ = joint_offsets_ = nullptr;
  joint_weights_ = joint_bind_ = nullptr;
  std::fill(joint_group_end_, joint_group_end_ + 4, 0u);
  for (int m = 0; m < 2; ++m) allowed_[m] = nullptr, live_[m] = nullptr, key_begin_[m] = nullptr;
}

size_t Model::RequiredBytes(const AssetView& view) {
  if (!view.valid()) return 0;
  return ModelSections(view, CountBlocks(view), nullptr).size;
}

Status Model::Init(const AssetView& view) {
  Release();
  if (!view.valid()) return Status::kErrorNullArgument;
  const size_t bytes = RequiredBytes(view);
  auto* memory = static_cast<unsigned char*>(::operator new(bytes, std::align_val_t{kAlign}, std::nothrow));
  if (!memory) return Status::kErrorOutOfMemory;
  const Status s = Build(view, memory, bytes, nullptr);
  if (s != Status::kOk) {
    ::operator delete(memory, std::align_val_t{kAlign});
    return s;
  }
  owned_ = true;
  return Status::kOk;
}

Status Model::InitInPlace(const AssetView& view, void* memory, size_t bytes) {
  Release();
  if (!view.valid() || !memory) return Status::kErrorNullArgument;
  if (reinterpret_cast<uintptr_t>(memory) % kMinAlign != 0) return Status::kErrorAlignment;
  if (bytes < RequiredBytes(view)) return Status::kErrorBufferTooSmall;
  return Build(view, static_cast<unsigned char*>(memory), bytes, nullptr);
}

// The narrow phase of a Model, built on the heap: without its own index of excluded pairs (it reads the
// Model's), and the bytes it takes in the Model's block (the object, then its arrays in a BlockArena).
Status Model::BuildNarrow(const AssetView& view, const ModelOptions& options, NarrowPhaseModel& out, size_t& bytes) {
  if (Status s = out.Build(view, options.narrow_phase_regions); s != Status::kOk) return s;
  BlockVector<uint32_t>().swap(out.excl_offsets_);
  BlockVector<uint16_t>().swap(out.excl_partners_);
  bytes = AlignUp(sizeof(NarrowPhaseModel)) + BlockArena::BlockBytes(out.ArrayBytes());
  return Status::kOk;
}

size_t Model::RequiredBytes(const AssetView& view, const ModelOptions& options) {
  if (!view.valid()) return 0;
  if (!options.narrow_phase) return RequiredBytes(view);
  NarrowPhaseModel narrow;
  size_t narrow_bytes = 0;
  if (BuildNarrow(view, options, narrow, narrow_bytes) != Status::kOk) return 0;
  return RequiredBytes(view) + narrow_bytes;
}

Status Model::Init(const AssetView& view, const ModelOptions& options) {
  Release();
  if (!view.valid()) return Status::kErrorNullArgument;
  if (!options.narrow_phase) return Init(view);
  NarrowPhaseModel narrow;
  size_t narrow_bytes = 0;
  if (Status s = BuildNarrow(view, options, narrow, narrow_bytes); s != Status::kOk) return s;
  const size_t bytes = RequiredBytes(view) + narrow_bytes;
  auto* memory = static_cast<unsigned char*>(::operator new(bytes, std::align_val_t{kAlign}, std::nothrow));
  if (!memory) return Status::kErrorOutOfMemory;
  const Status s = Build(view, memory, bytes, &narrow);
  if (s != Status::kOk) {
    ::operator delete(memory, std::align_val_t{kAlign});
    return s;
  }
  owned_ = true;
  return Status::kOk;
}

Status Model::InitInPlace(const AssetView& view, const ModelOptions& options, void* memory, size_t bytes) {
  Release();
  if (!options.narrow_phase) return InitInPlace(view, memory, bytes);
  if (!view.valid() || !memory) return Status::kErrorNullArgument;
  if (reinterpret_cast<uintptr_t>(memory) % kMinAlign != 0) return Status::kErrorAlignment;
  // The narrow phase first: when it cannot be built, RequiredBytes(view, options) said 0, and the reason (a
  // missing field, out of memory) is what the caller needs, not kErrorBufferTooSmall.
  NarrowPhaseModel narrow;
  size_t narrow_bytes = 0;
  if (Status s = BuildNarrow(view, options, narrow, narrow_bytes); s != Status::kOk) return s;
  if (bytes < RequiredBytes(view) + narrow_bytes) return Status::kErrorBufferTooSmall;
  return Build(view, static_cast<unsigned char*>(memory), bytes, &narrow);
}

// Fills the block: the SoA refit data, chain masks and lists, the excluded pairs as per-sphere sorted
// partner lists, the joint weights, and the broad-phase layout. Sections start on 64 bytes from `memory`,
// so a 16-byte aligned block keeps every array aligned for its type. No allocation.
Status Model::Build(const AssetView& view, unsigned char* memory, size_t bytes, NarrowPhaseModel* narrow) {
  const schema::Asset& a = *view.asset;
  const uint32_t S = view.sphere_count, C = view.chain_count;
  const uint32_t B = CountBlocks(view);
  ModelSections k(view, B, memory);
  if (k.size > bytes) return Status::kErrorBufferTooSmall;
  if (narrow && AlignUp(k.size) + AlignUp(sizeof(NarrowPhaseModel)) + BlockArena::BlockBytes(narrow->ArrayBytes()) > bytes)
    return Status::kErrorBufferTooSmall;
  std::memset(memory, 0, k.size);

  if (k.fold_region)  // LoadAsset: a fold margin comes with sphere_regions
    for (uint32_t s = 0; s < S; ++s) k.fold_region[s] = a.sphere_regions()->Get(s);
  for (uint32_t s = 0; s < S; ++s) {
    const schema::Sphere* sp = a.spheres()->Get(s);
    k.bind[0][s] = sp->center().x();
    k.bind[1][s] = sp->center().y();
    k.bind[2][s] = sp->center().z();
    k.bind[3][s] = sp->radius();
    const schema::PivotFrame* f = a.pivot_frames()->Get(s);
    k.local[0][s] = f->local_center().x();
    k.local[1][s] = f->local_center().y();
    k.local[2][s] = f->local_center().z();
    k.offset[0][s] = f->centroid_offset().x();
    k.offset[1][s] = f->centroid_offset().y();
    k.offset[2][s] = f->centroid_offset().z();
    k.radius_scale[s] = k.bind[3][s] / f->mean_distance();
  }
  std::copy(a.pivot_vertices()->begin(), a.pivot_vertices()->end(), k.pivot_vertices);

  uint32_t m1_tests = 0, max_chain = 0;
  for (uint32_t c = 0; c < C; ++c) {
    const auto* list = a.chains()->Get(c)->spheres();
    const uint32_t n = list->size();
    m1_tests += n * (n > 0 ? n - 1 : 0) / 2;  // uint32 arithmetic, as DetectStats::tests always was
    max_chain = std::max(max_chain, n);
    k.chain_offsets[c + 1] = k.chain_offsets[c] + n;
    uint16_t* out = k.chain_spheres + k.chain_offsets[c];
    for (uint16_t s : *list) k.chain_mask[s] |= 1u << c, *out++ = s;
  }
  k.a.max_chain_length = max_chain;

  // Excluded pairs as, per sphere a, the sorted list of its excluded partners b > a.
  const auto* ex = a.excluded_pairs();
  const uint32_t E = k.a.excluded_count;
  for (uint32_t i = 0; i < E; ++i) ++k.excl_offsets[ex->Get(i)->a() + 1];
  for (uint32_t s = 0; s < S; ++s) k.excl_offsets[s + 1] += k.excl_offsets[s];
  for (uint32_t i = 0; i < E; ++i) k.excl_neighbors[i] = ex->Get(i)->b();  // sorted by (a, b) already

  uint32_t joint_group_end[4] = {};
  if (k.joints) {
    std::copy(a.sphere_joints()->begin(), a.sphere_joints()->end(), k.joints);
    std::copy(a.sphere_joint_weights()->begin(), a.sphere_joint_weights()->end(), k.weights);
    // Joint records (kernels::JointRefitArgs): a sphere uses influence 0 and then influences 1, 2, 3
    // while their weight is not 0 (the weights are stored by descending weight: the first 0 ends them).
    // Records grouped by that count, so the kernels run a fixed number of blends per group (no branch
    // per sphere); ids ascending in a group. Unused influences: offset 0, weight 0 (never read).
    auto influences = [&](uint32_t s) {
      uint32_t n = 1;
      while (n < 4 && k.weights[4 * s + n] != 0.0f) ++n;
      return n;
    };
    uint32_t rec = 0;
    for (uint32_t n = 1; n <= 4; ++n) {
      for (uint32_t s = 0; s < S; ++s) {
        if (influences(s) != n) continue;
        k.joint_sphere[rec] = s;
        for (uint32_t i = 0; i < 4; ++i) {
          k.joint_offsets[4 * rec + i] = i < n ? uint32_t{k.joints[4 * s + i]} * 12u : 0u;
          k.joint_weights[4 * rec + i] = i < n ? k.weights[4 * s + i] : 0.0f;
        }
        k.joint_bind[4 * rec + 0] = k.bind[0][s];
        k.joint_bind[4 * rec + 1] = k.bind[1][s];
        k.joint_bind[4 * rec + 2] = k.bind[2][s];
        k.joint_bind[4 * rec + 3] = 1.0f;
        ++rec;
      }
      joint_group_end[n - 1] = rec;
    }
  }

  // Broad-phase layout (kernels::BroadPhaseArgs): spheres grouped by body region (Asset.sphere_regions,
  // R0..R4; without it, by chain mask), groups ascending, each split at bind pose into blocks of 8
  // slots by a kd split — the left part gets 8·ceil(n/16) spheres along the longest axis of the
  // part's centres (ties by id), so every block but a group's last is full — and padded to 8 with the
  // id #S. (On MakeHuman, region groups test ~12 % fewer instructions than chain-mask classes, which
  // leave more partial blocks; one group for all spheres tests more pairs.)
  // Built in place: the ids sorted by (group, id) in the first #S slots, split, then each group moved
  // (last first, so nothing is overwritten) to its 8-aligned place.
  uint32_t* order = k.order;
  auto group = [&](uint32_t s) { return Group(a, s, k.chain_mask[s]); };
  for (uint32_t s = 0; s < S; ++s) order[s] = s;
  std::sort(order, order + S, [&](uint32_t p, uint32_t q) { return group(p) < group(q) || (group(p) == group(q) && p < q); });
  const float* bind[3] = {k.bind[0], k.bind[1], k.bind[2]};
  auto split = [&](auto&& self, uint32_t* first, uint32_t n) -> void {
    if (n <= 8) return;
    float lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d] = hi[d] = bind[d][first[0]];
    for (uint32_t i = 1; i < n; ++i)
      for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], bind[d][first[i]]), hi[d] = std::max(hi[d], bind[d][first[i]]);
    int axis = 0;
    for (int d = 1; d < 3; ++d)
      if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
    const uint32_t left = 8 * ((n + 15) / 16);
    const float* v = bind[axis];
    std::nth_element(first, first + left, first + n, [&](uint32_t p, uint32_t q) { return v[p] < v[q] || (v[p] == v[q] && p < q); });
    self(self, first, left);
    self(self, first + left, n - left);
  };
  for (uint32_t g = 0; g < S;) {  // split each group where it lies
    uint32_t e = g;
    while (e < S && group(order[e]) == group(order[g])) ++e;
    split(split, order + g, e - g);
    g = e;
  }
  {  // spread: group boundaries from the end, each group to its padded start
    uint32_t dst_end = 8 * B, e = S;
    while (e > 0) {
      uint32_t g = e;
      const uint32_t gid = group(order[e - 1]);
      while (g > 0 && group(order[g - 1]) == gid) --g;
      const uint32_t n = e - g, padded = (n + 7) / 8 * 8, dst = dst_end - padded;
      std::memmove(order + dst, order + g, sizeof(uint32_t) * n);
      for (uint32_t i = dst + n; i < dst_end; ++i) order[i] = S;
      dst_end = dst, e = g;
    }
  }
  const uint32_t live_stride = (B + 7) / 8;
  const uint32_t* excl_off = k.excl_offsets;
  const uint16_t* excl_nb = k.excl_neighbors;
  auto excluded = [&](uint32_t p, uint32_t q) {
    if (p > q) std::swap(p, q);
    return std::binary_search(excl_nb + excl_off[p], excl_nb + excl_off[p + 1], static_cast<uint16_t>(q));
  };
  uint64_t key_slots = 0;
  for (int method = 0; method < 2; ++method) {  // 0 = M1, 1 = M2
    uint64_t keys = 0;
    for (uint32_t I = 0; I < B; ++I) {
      if (keys > UINT32_MAX) return Status::kErrorOutOfMemory;
      k.key_begin[method][I] = static_cast<uint32_t>(keys);
      for (uint32_t J = I; J < B; ++J) {
        uint64_t lanes = 0;
        for (uint32_t row = 0; row < 8; ++row)
          for (uint32_t l = 0; l < 8; ++l) {
            const uint32_t p = order[8 * I + row], q = order[8 * J + l];
            const bool ok = p < S && q < S && (I < J || l > row) && !excluded(p, q) &&
                            (method == 1 || (k.chain_mask[p] & k.chain_mask[q]) != 0);
            lanes |= uint64_t{ok} << (8 * row + l);
          }
        k.allowed[method][size_t{I} * B + J] = lanes;
        if (lanes) k.live[method][size_t{I} * live_stride + (J - I) / 8] |= static_cast<uint8_t>(1u << ((J - I) % 8));
        keys += static_cast<uint64_t>(std::popcount(lanes));
      }
    }
    if (keys > UINT32_MAX) return Status::kErrorOutOfMemory;
    k.key_begin[method][B] = static_cast<uint32_t>(keys);
    key_slots = std::max(key_slots, keys);
  }

  storage_ = memory;
  owned_ = false;
  bytes_ = k.size;
  if (narrow) {  // after the sections: the object, then its arrays (BuildNarrow measured both)
    unsigned char* at = memory + AlignUp(k.size);
    const size_t arrays = BlockArena::BlockBytes(narrow->ArrayBytes());
    narrow_ = new (at) NarrowPhaseModel(std::move(*narrow));
    BlockArena* arena = BlockArena::Create(at + AlignUp(sizeof(NarrowPhaseModel)), arrays);
    narrow_->MoveInto(arena);
    assert(arena->fallbacks == 0);  // BuildNarrow measured every array: all of them fit
    arena->cursor = arena->end;  // sealed
    narrow_->excl_off_ = k.a.excl_offsets;  // one index of excluded pairs: the model's
    narrow_->excl_nb_ = k.a.excl_neighbors;
    narrow_->bytes_ = arrays;
    bytes_ = AlignUp(k.size) + AlignUp(sizeof(NarrowPhaseModel)) + arrays;
  }
  id_ = g_next_model_id.fetch_add(1, std::memory_order_relaxed);
  sphere_count_ = S;
  vertex_count_ = view.vertex_count;
  chain_count_ = C;
  joint_count_ = k.joints ? a.joint_count() : 0;
  contact_margin_ = a.contact_margin();
  fold_margin_ = k.fold_region ? a.fold_margin() : -1.0f;
  fold_region_ = k.fold_region;
  a_ = k.a;
  isa_ = static_cast<uint8_t>(kernels::Best());
  m1_tests_ = m1_tests;
  blocks_ = B, box_pitch_ = (B + 7) / 8 * 8, live_stride_ = live_stride;
  key_slots_ = static_cast<uint32_t>(key_slots);
  order_ = order;
  for (int m = 0; m < 2; ++m) allowed_[m] = k.allowed[m], live_[m] = k.live[m], key_begin_[m] = k.key_begin[m];
  a_.broad_order = order;
  a_.broad_allowed[0] = k.allowed[0], a_.broad_allowed[1] = k.allowed[1];
  a_.broad_blocks = B;
  joint_sphere_ = k.joint_sphere, joint_offsets_ = k.joint_offsets, joint_weights_ = k.joint_weights;
  joint_bind_ = k.joint_bind;
  std::copy(joint_group_end, joint_group_end + 4, joint_group_end_);
  const uint64_t all = uint64_t{S} * (S - 1) / 2;
  m2_candidates_ = static_cast<uint32_t>(all - E);
  m1_candidates_ = key_begin_[0][B];  // non-excluded pairs sharing a chain: M1's allowed lanes
  return Status::kOk;
}

bool Model::IsExcluded(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  if (b >= sphere_count_) return false;
  for (uint32_t i = a_.excl_offsets[a], e = a_.excl_offsets[a + 1]; i < e; ++i)
    if (a_.excl_neighbors[i] == b) return true;
  return false;
}

// ---- Workspace -------------------------------------------------------------------------------------

namespace {

struct WorkspaceSections {
  float *sphere[4] = {}, *gathered[4] = {}, *lanes[4] = {}, *box = nullptr;
  uint64_t* keys = nullptr;
  uint32_t* row_hits = nullptr;
  size_t size = 0;
  WorkspaceSections(uint32_t S, uint32_t B, uint32_t pitch, uint32_t key_slots, unsigned char* base) {
    Carver k{0, base};
    for (auto& p : sphere) p = k.Take<float>(S + kPad);
    for (auto& p : gathered) p = k.Take<float>(size_t{8} * B);
    for (auto& p : lanes) p = k.Take<float>(size_t{8} * pitch);
    box = k.Take<float>(size_t{7} * (pitch + 8));
    keys = k.Take<uint64_t>(key_slots);
    row_hits = k.Take<uint32_t>(size_t{3} * B);
    size = AlignUp(k.size);
  }
};

}  // namespace

Workspace::Workspace(Workspace&& o) noexcept { *this = std::move(o); }

Workspace& Workspace::operator=(Workspace&& o) noexcept {
  if (this != &o) {
    Release();
    std::memcpy(static_cast<void*>(this), static_cast<const void*>(&o), sizeof(Workspace));
    o.storage_ = nullptr, o.owned_ = false, o.narrow_ = nullptr;
    o.Release();
  }
  return *this;
}

Workspace::~Workspace() { Release(); }

void Workspace::Release() {
  if (narrow_) narrow_->~NarrowPhaseWorkspace();  // its arrays live in the block
  narrow_ = nullptr;
  if (owned_ && storage_) ::operator delete(storage_, std::align_val_t{kAlign});
  storage_ = nullptr, owned_ = false, model_id_ = 0, sphere_count_ = 0;
  x_ = y_ = z_ = r_ = gx_ = gy_ = gz_ = gr_ = tx_ = ty_ = tz_ = tr_ = box_ = nullptr;
  keys_ = nullptr;
  row_hits_ = nullptr;
}

size_t Workspace::RequiredBytes(const Model& m) {
  if (!m.initialized()) return 0;
  const size_t broad = WorkspaceSections(m.sphere_count_, m.blocks_, m.box_pitch_, m.key_slots_, nullptr).size;
  return broad + (m.narrow_ ? AlignUp(sizeof(NarrowPhaseWorkspace)) + m.narrow_->workspace_bytes() : 0);
}

Status Workspace::Init(const Model& model) {
  Release();
  if (!model.initialized()) return Status::kErrorInvalidJob;
  const size_t bytes = RequiredBytes(model);
  auto* memory = static_cast<unsigned char*>(::operator new(bytes, std::align_val_t{kAlign}, std::nothrow));
  if (!memory) return Status::kErrorOutOfMemory;
  if (Status s = Build(model, memory); s != Status::kOk) {
    ::operator delete(memory, std::align_val_t{kAlign});
    return s;
  }
  owned_ = true;
  return Status::kOk;
}

Status Workspace::InitInPlace(const Model& model, void* memory, size_t bytes) {
  Release();
  if (!memory) return Status::kErrorNullArgument;
  if (!model.initialized()) return Status::kErrorInvalidJob;
  if (reinterpret_cast<uintptr_t>(memory) % kMinAlign != 0) return Status::kErrorAlignment;
  if (bytes < RequiredBytes(model)) return Status::kErrorBufferTooSmall;
  return Build(model, static_cast<unsigned char*>(memory));
}

Status Workspace::Build(const Model& m, unsigned char* memory) {
  const uint32_t S = m.sphere_count_, B = m.blocks_, P = m.box_pitch_;
  WorkspaceSections k(S, B, P, m.key_slots_, memory);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // Padding (id #S in the broad phase's slots): NaN, never overlaps, ignored by the block boxes.
  for (float* p : k.sphere) std::fill(p, p + S + kPad, nan);
  for (float* p : k.gathered) std::fill(p, p + size_t{8} * B, nan);
  for (float* p : k.lanes) std::fill(p, p + size_t{8} * P, nan);
  std::fill(k.box, k.box + size_t{7} * (P + 8), 0.0f);
  for (uint32_t I = B; I < P + 8; ++I)  // empty boxes past the blocks (read, never kept)
    for (int d = 0; d < 3; ++d) {
      k.box[(2 * d) * (P + 8) + I] = inf;
      k.box[(2 * d + 1) * (P + 8) + I] = -inf;
    }
  std::fill(k.keys, k.keys + m.key_slots_, uint64_t{0});
  std::fill(k.row_hits, k.row_hits + size_t{3} * B, 0u);
  storage_ = memory;
  model_id_ = m.id_;
  sphere_count_ = S;
  x_ = k.sphere[0], y_ = k.sphere[1], z_ = k.sphere[2], r_ = k.sphere[3];
  gx_ = k.gathered[0], gy_ = k.gathered[1], gz_ = k.gathered[2], gr_ = k.gathered[3];
  tx_ = k.lanes[0], ty_ = k.lanes[1], tz_ = k.lanes[2], tr_ = k.lanes[3];
  box_ = k.box;
  keys_ = k.keys;
  row_hits_ = k.row_hits;
  if (m.narrow_) {  // after the sections: the narrow phase's scratch, its arrays carved from the rest
    unsigned char* at = memory + k.size;
    narrow_ = new (at) NarrowPhaseWorkspace();
    BlockArena* arena = BlockArena::Create(at + AlignUp(sizeof(NarrowPhaseWorkspace)), m.narrow_->workspace_bytes());
    const Status s = narrow_->Build(*m.narrow_, arena);
    assert(s != Status::kOk || arena->fallbacks == 0);  // workspace_bytes() measured the same arrays
    if (s != Status::kOk) {
      Release();  // not owned yet: the caller's memory, or Init frees its own
      return s;
    }
  }
  return ResetToBindPose(m);
}

Status Workspace::ResetToBindPose(const Model& model) {
  if (!initialized()) return Status::kErrorInvalidJob;
  if (!made_for(model)) return Status::kErrorWorkspaceModel;
  const ModelArrays& a = model.arrays();
  std::copy(a.bind_x, a.bind_x + sphere_count_, x_);
  std::copy(a.bind_y, a.bind_y + sphere_count_, y_);
  std::copy(a.bind_z, a.bind_z + sphere_count_, z_);
  std::copy(a.bind_r, a.bind_r + sphere_count_, r_);
  return Status::kOk;
}

}  // namespace spherechain::runtime
