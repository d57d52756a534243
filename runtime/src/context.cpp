// Context::Init — the runtime's only allocation: copies what refit/detect need out of the asset, SoA.
#include "spherechain/runtime/context.h"

#include "alloc_guard.h"
#include "internal.h"

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
  SPHERECHAIN_TRY {
    constexpr uint32_t kPad = 8;  // SoA rows are read in chunks of 8; padding spheres never overlap
    for (auto* v : {&x_, &y_, &z_}) v->assign(S + kPad, 1e18f);
    r_.assign(S + kPad, 0.0f);
    mr_.assign(S + kPad, 0.0f);
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

    // Skip streams (see kernels::ExclusionCursor): the kernels test 8-lane chunks aligned to 8 in
    // SoA blocks padded to a multiple of 8, numbered in test order; a chunk holding lanes that must
    // not count (excluded pairs, j <= i on a diagonal block, padding) gets one entry with those lanes.
    auto skip = [](std::vector<uint64_t>& stream, uint64_t chunk, uint32_t bits) {
      if (!bits) return;
      if (!stream.empty() && (stream.back() >> 32) == chunk)
        stream.back() |= bits;
      else
        stream.push_back(chunk << 32 | bits);
    };
    // M2: row i tests b in chunks from (i+1) & ~7 to the end of x_ (padded to #S + kPad).
    uint64_t chunk = 0;
    for (uint32_t i = 0; i + 1 < S; ++i) {
      const uint32_t first = (i + 1) & ~7u;
      skip(m2_excl_, chunk, (1u << (i + 1 - first)) - 1u);  // lanes first..i
      for (uint32_t e = excl_offsets_[i]; e < excl_offsets_[i + 1]; ++e) {
        const uint32_t j = excl_neighbors_[e] - first;
        skip(m2_excl_, chunk + j / 8, 1u << (j % 8));
      }
      const uint32_t chunks = (S - first + 7) / 8;
      skip(m2_excl_, chunk + chunks - 1, 0xffu & ~((1u << (S - first - 8 * (chunks - 1))) - 1u) & 0xffu);  // >= S
      chunk += chunks;
    }
    if (chunk > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
    m2_excl_.push_back(UINT64_MAX);

    // M1 layout: classes of equal chain mask (spheres in no chain left out), ascending mask then id;
    // per class A its span (A, then every later class B with mask_A & mask_B != 0), padded to 8.
    std::vector<uint32_t> by_mask;
    for (uint32_t s = 0; s < S; ++s)
      if (chain_mask_[s]) by_mask.push_back(s);
    std::stable_sort(by_mask.begin(), by_mask.end(), [&](uint32_t p, uint32_t q) { return chain_mask_[p] < chain_mask_[q]; });
    std::vector<uint32_t> class_begin;  // into by_mask, #K+1
    for (uint32_t g = 0; g < by_mask.size(); ++g)
      if (g == 0 || chain_mask_[by_mask[g]] != chain_mask_[by_mask[g - 1]]) class_begin.push_back(g);
    const uint32_t K = static_cast<uint32_t>(class_begin.size());
    class_begin.push_back(static_cast<uint32_t>(by_mask.size()));
    auto excluded = [&](uint32_t p, uint32_t q) {  // IsExcluded before sphere_count_ is set
      if (p > q) std::swap(p, q);
      return std::binary_search(excl_neighbors_.begin() + excl_offsets_[p], excl_neighbors_.begin() + excl_offsets_[p + 1], q);
    };
    uint64_t keys = 0;
    chunk = 0;
    for (uint32_t A = 0; A < K; ++A) {
      const uint32_t mask_a = chain_mask_[by_mask[class_begin[A]]];
      const uint32_t begin = static_cast<uint32_t>(m1_order_.size()), rows = class_begin[A + 1] - class_begin[A];
      for (uint32_t B = A; B < K; ++B)
        if (mask_a & chain_mask_[by_mask[class_begin[B]]])
          for (uint32_t g = class_begin[B]; g < class_begin[B + 1]; ++g) m1_order_.push_back(static_cast<uint16_t>(by_mask[g]));
      const uint32_t cols = static_cast<uint32_t>(m1_order_.size()) - begin;
      while (m1_order_.size() % 8) m1_order_.push_back(0);
      if (chunk > UINT32_MAX || m1_excl_.size() > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
      spans_.insert(spans_.end(), {begin, rows, cols, static_cast<uint32_t>(chunk), static_cast<uint32_t>(m1_excl_.size()),
                                   static_cast<uint32_t>(keys)});
      keys += uint64_t{rows} * (rows - 1) / 2 + uint64_t{rows} * (cols - rows);
      if (keys > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
      for (uint32_t i = 0; i < rows; ++i) {
        if (i + 1 >= cols) continue;
        for (uint32_t j0 = (i + 1) & ~7u; j0 < cols; j0 += 8, ++chunk) {
          uint32_t bits = 0;
          for (uint32_t k = 0; k < 8; ++k) {
            const uint32_t j = j0 + k;
            bits |= static_cast<uint32_t>(j <= i || j >= cols || excluded(m1_order_[begin + i], m1_order_[begin + j])) << k;
          }
          skip(m1_excl_, chunk, bits);
        }
      }
    }
    if (chunk > UINT32_MAX) return *this = Context{}, Status::kErrorOutOfMemory;
    m1_excl_.push_back(UINT64_MAX);
    const uint32_t G = static_cast<uint32_t>(m1_order_.size());
    for (auto* v : {&gx_, &gy_, &gz_}) v->assign(G, 1e18f);
    gr_.assign(G, 0.0f);
    m1_keys_.resize(keys);
    span_hits_.assign(K, 0u);
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
  uint64_t m1 = m1_keys_.size();  // distinct pairs sharing a chain, minus the excluded ones among them
  for (uint32_t s = 0; s < S; ++s)
    for (uint32_t i = excl_offsets_[s]; i < excl_offsets_[s + 1]; ++i)
      m1 -= (chain_mask_[s] & chain_mask_[excl_neighbors_[i]]) != 0;
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
