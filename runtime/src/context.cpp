// Context::Init — the runtime's only allocation: copies what refit/detect need out of the asset, SoA.
#include "spherechain/runtime/context.h"

#include <algorithm>
#include <bit>
#include <new>

namespace spherechain::runtime {

Status Context::Init(const AssetView& view) {
  *this = Context{};
  if (!view.valid()) return Status::kErrorNullArgument;
  const schema::Asset& a = *view.asset;
  const uint32_t S = view.sphere_count;
  const uint32_t C = view.chain_count;
  try {
    constexpr uint32_t kPad = 8;  // SoA rows are processed in blocks of 8; padding spheres never overlap
    for (auto* v : {&x_, &y_, &z_}) v->assign(S + kPad, 1e18f);
    r_.assign(S + kPad, 0.0f);
    for (auto* v : {&bind_x_, &bind_y_, &bind_z_, &bind_r_, &local_x_, &local_y_, &local_z_,
                    &offset_x_, &offset_y_, &offset_z_, &radius_scale_})
      v->resize(S);
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
    chain_offsets_.assign(C + 1, 0u);
    chain_hits_offsets_.assign(C + 1, 0u);
    for (uint32_t c = 0; c < C; ++c) {
      const auto* list = a.chains()->Get(c)->spheres();
      chain_offsets_[c + 1] = chain_offsets_[c] + list->size();
      const uint64_t n = list->size();
      const uint64_t pairs = n * (n > 0 ? n - 1 : 0) / 2;
      if (chain_hits_offsets_[c] + pairs > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
      chain_hits_offsets_[c + 1] = chain_hits_offsets_[c] + static_cast<uint32_t>(pairs);
      for (uint16_t s : *list) {
        chain_spheres_.push_back(s);
        chain_mask_[s] |= 1u << c;
      }
    }
    gather_offsets_.assign(C + 1, 0u);
    for (uint32_t c = 0; c < C; ++c) gather_offsets_[c + 1] = gather_offsets_[c] + (chain_offsets_[c + 1] - chain_offsets_[c]) + kPad;
    const uint32_t G = gather_offsets_[C];
    for (auto* v : {&gx_, &gy_, &gz_}) v->assign(G, 1e18f);
    gr_.assign(G, 0.0f);
    flags_.assign(size_t{S} + kPad, 0);
    chain_hits_.resize(chain_hits_offsets_[C]);
    chain_hit_counts_.assign(C, 0u);
    chain_raw_counts_.assign(C, 0u);

    // Excluded pairs as, per sphere a, the sorted list of its excluded partners b > a.
    excl_offsets_.assign(S + 1, 0u);
    const auto* ex = a.excluded_pairs();
    const uint32_t E = ex ? ex->size() : 0;
    for (uint32_t i = 0; i < E; ++i) ++excl_offsets_[ex->Get(i)->a() + 1];
    for (uint32_t s = 0; s < S; ++s) excl_offsets_[s + 1] += excl_offsets_[s];
    excl_neighbors_.resize(E);
    for (uint32_t i = 0; i < E; ++i) excl_neighbors_[i] = ex->Get(i)->b();  // sorted by (a, b) already
  } catch (const std::bad_alloc&) {
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
  uint64_t m1 = 0;
  for (uint32_t c = 0; c < C; ++c)
    for (uint32_t i = chain_offsets_[c]; i < chain_offsets_[c + 1]; ++i)
      for (uint32_t j = i + 1; j < chain_offsets_[c + 1]; ++j) {
        const uint32_t a = chain_spheres_[i], b = chain_spheres_[j];
        if (static_cast<uint32_t>(std::countr_zero(chain_mask_[a] & chain_mask_[b])) == c && !IsExcluded(a, b)) ++m1;
      }
  m1_candidates_ = static_cast<uint32_t>(m1);
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
