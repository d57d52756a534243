// Context::Init — the runtime's only allocation: copies what refit/detect need out of the asset, SoA.
#include "spherechain/runtime/context.h"

#include "alloc_guard.h"
#include "internal.h"

#include <algorithm>
#include <bit>
#include <limits>
#include <new>

namespace spherechain::runtime {

Status Context::Init(const AssetView& view) {
  *this = Context{};
  if (!view.valid()) return Status::kErrorNullArgument;
  const schema::Asset& a = *view.asset;
  const uint32_t S = view.sphere_count;
  const uint32_t C = view.chain_count;
  SPHERECHAIN_TRY {
    constexpr uint32_t kPad = 8;  // SoA rows are read in chunks of 8; padding spheres never overlap
    // Padding (id #S in the broad phase's slots): NaN, never overlaps, ignored by the block boxes.
    for (auto* v : {&x_, &y_, &z_, &r_}) v->assign(S + kPad, std::numeric_limits<float>::quiet_NaN());
    contact_margin_ = a.contact_margin();
    for (auto* v : {&bind_x_, &bind_y_, &bind_z_, &bind_r_}) v->resize(S);
    for (auto* v : {&local_x_, &local_y_, &local_z_, &offset_x_, &offset_y_, &offset_z_, &radius_scale_})
      v->assign(S + kPad, 0.0f);  // refit reads whole SIMD groups
    for (uint32_t s = 0; s < S; ++s) {
      const schema::Sphere* sp = a.spheres()->Get(s);
      bind_x_[s] = sp->center().x();
      bind_y_[s] = sp->center().y();
      bind_z_[s] = sp->center().z();
      bind_r_[s] = sp->radius();
      const schema::PivotFrame* f = a.pivot_frames()->Get(s);
      local_x_[s] = f->local_center().x();
      local_y_[s] = f->local_center().y();
      local_z_[s] = f->local_center().z();
      offset_x_[s] = f->centroid_offset().x();
      offset_y_[s] = f->centroid_offset().y();
      offset_z_[s] = f->centroid_offset().z();
      radius_scale_[s] = bind_r_[s] / f->mean_distance();
    }
    pivot_vertices_.assign(a.pivot_vertices()->begin(), a.pivot_vertices()->end());

    chain_mask_.assign(S, 0u);
    for (uint32_t c = 0; c < C; ++c) {
      const auto* list = a.chains()->Get(c)->spheres();
      const uint32_t n = list->size();
      m1_tests_ += n * (n > 0 ? n - 1 : 0) / 2;  // uint32 arithmetic, as DetectStats::tests always was
      for (uint16_t s : *list) chain_mask_[s] |= 1u << c;
    }

    // Excluded pairs as, per sphere a, the sorted list of its excluded partners b > a.
    excl_offsets_.assign(S + 1, 0u);
    const auto* ex = a.excluded_pairs();
    const uint32_t E = ex ? ex->size() : 0;
    for (uint32_t i = 0; i < E; ++i) ++excl_offsets_[ex->Get(i)->a() + 1];
    for (uint32_t s = 0; s < S; ++s) excl_offsets_[s + 1] += excl_offsets_[s];
    excl_neighbors_.resize(E);
    for (uint32_t i = 0; i < E; ++i) excl_neighbors_[i] = ex->Get(i)->b();  // sorted by (a, b) already

    // Broad-phase layout (kernels::BroadPhaseArgs): spheres grouped by body region (Asset.sphere_regions,
    // R0..R4; without it, by chain mask), groups ascending, each split at bind pose into blocks of 8
    // slots by a kd split — the left part gets 8·ceil(n/16) spheres along the longest axis of the
    // part's centres (ties by id), so every block but a group's last is full — and padded to 8 with the
    // id #S. (On MakeHuman, region groups test ~12 % fewer instructions than chain-mask classes, which
    // leave more partial blocks; one group for all spheres tests more pairs.)
    const auto* regions = a.sphere_regions();  // [opt], #S when present (LoadAsset)
    std::vector<uint32_t> ids(S), group(S);
    for (uint32_t s = 0; s < S; ++s) ids[s] = s, group[s] = regions ? regions->Get(s) : chain_mask_[s];
    std::stable_sort(ids.begin(), ids.end(), [&](uint32_t p, uint32_t q) { return group[p] < group[q]; });
    const float* bind[3] = {bind_x_.data(), bind_y_.data(), bind_z_.data()};
    auto split = [&](auto&& self, uint32_t* first, uint32_t n) -> void {
      if (n <= 8) return;
      float lo[3], hi[3];
      for (int k = 0; k < 3; ++k) lo[k] = hi[k] = bind[k][first[0]];
      for (uint32_t i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], bind[k][first[i]]), hi[k] = std::max(hi[k], bind[k][first[i]]);
      int axis = 0;
      for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
      const uint32_t left = 8 * ((n + 15) / 16);
      const float* v = bind[axis];
      std::nth_element(first, first + left, first + n, [&](uint32_t p, uint32_t q) { return v[p] < v[q] || (v[p] == v[q] && p < q); });
      self(self, first, left);
      self(self, first + left, n - left);
    };
    for (uint32_t g = 0; g < S;) {
      uint32_t e = g;
      while (e < S && group[ids[e]] == group[ids[g]]) ++e;
      split(split, ids.data() + g, e - g);
      for (uint32_t i = g; i < e; ++i) order_.push_back(ids[i]);
      while (order_.size() % 8) order_.push_back(S);
      g = e;
    }
    const uint32_t B = static_cast<uint32_t>(order_.size() / 8);
    blocks_ = B;
    box_pitch_ = (B + 7) / 8 * 8;
    live_stride_ = (B + 7) / 8;
    chain_mask1_.assign(chain_mask_.begin(), chain_mask_.end());
    chain_mask1_.push_back(0u);
    auto excluded = [&](uint32_t p, uint32_t q) {  // IsExcluded before sphere_count_ is set
      if (p > q) std::swap(p, q);
      return std::binary_search(excl_neighbors_.begin() + excl_offsets_[p], excl_neighbors_.begin() + excl_offsets_[p + 1], q);
    };
    uint64_t key_slots = 0;
    for (int method = 0; method < 2; ++method) {  // 0 = M1, 1 = M2
      allowed_[method].assign(size_t{B} * B, 0u);
      live_[method].assign(size_t{B} * live_stride_, 0u);
      key_begin_[method].assign(B + 1, 0u);
      uint64_t keys = 0;
      for (uint32_t I = 0; I < B; ++I) {
        if (keys > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
        key_begin_[method][I] = static_cast<uint32_t>(keys);
        for (uint32_t J = I; J < B; ++J) {
          uint64_t lanes = 0;
          for (uint32_t row = 0; row < 8; ++row)
            for (uint32_t l = 0; l < 8; ++l) {
              const uint32_t a = order_[8 * I + row], b = order_[8 * J + l];
              const bool ok = a < S && b < S && (I < J || l > row) && !excluded(a, b) &&
                              (method == 1 || (chain_mask_[a] & chain_mask_[b]) != 0);
              lanes |= uint64_t{ok} << (8 * row + l);
            }
          allowed_[method][size_t{I} * B + J] = lanes;
          if (lanes) live_[method][size_t{I} * live_stride_ + (J - I) / 8] |= static_cast<uint8_t>(1u << ((J - I) % 8));
          keys += static_cast<uint64_t>(std::popcount(lanes));
        }
      }
      if (keys > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
      key_begin_[method][B] = static_cast<uint32_t>(keys);
      key_slots = std::max(key_slots, keys);
    }
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto* v : {&gx_, &gy_, &gz_, &gr_}) v->assign(order_.size(), nan);
    for (auto* v : {&tx_, &ty_, &tz_, &tr_}) v->assign(size_t{8} * box_pitch_, nan);
    box_.assign(size_t{7} * (box_pitch_ + 8), 0.0f);
    for (uint32_t I = B; I < box_pitch_ + 8; ++I) {  // empty boxes past the blocks (read, never kept)
      for (int k = 0; k < 3; ++k) {
        box_[(2 * k) * (box_pitch_ + 8) + I] = std::numeric_limits<float>::infinity();
        box_[(2 * k + 1) * (box_pitch_ + 8) + I] = -std::numeric_limits<float>::infinity();
      }
    }
    keys_.resize(key_slots);
    row_hits_.assign(size_t{3} * B, 0u);
    use_avx_ = kernels::HasAvx();
  } SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = Context{};
    return Status::kErrorOutOfMemory;
  }
  sphere_count_ = S;
  vertex_count_ = view.vertex_count;
  chain_count_ = C;
  ResetToBindPose();

  // Exact candidate counts.
  const uint64_t all = uint64_t{S} * (S - 1) / 2;
  m2_candidates_ = static_cast<uint32_t>(all - excl_neighbors_.size());
  m1_candidates_ = key_begin_[0][blocks_];  // non-excluded pairs sharing a chain: M1's allowed lanes
  return Status::kOk;
}

void Context::ResetToBindPose() {
  std::copy(bind_x_.begin(), bind_x_.end(), x_.begin());
  std::copy(bind_y_.begin(), bind_y_.end(), y_.begin());
  std::copy(bind_z_.begin(), bind_z_.end(), z_.begin());
  std::copy(bind_r_.begin(), bind_r_.end(), r_.begin());
}

bool Context::IsExcluded(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  if (b >= sphere_count_) return false;
  for (uint32_t i = excl_offsets_[a], e = excl_offsets_[a + 1]; i < e; ++i)
    if (excl_neighbors_[i] == b) return true;
  return false;
}

}  // namespace spherechain::runtime
