#include "spherechain/runtime/narrow_phase.h"

#include <algorithm>
#include <cstring>
#include <new>

#include "spherechain/runtime/triangle_intersect.h"

namespace spherechain::runtime {

namespace {

constexpr uint16_t kNoSphere = 0xFFFF;

/// Float → uint32 with the same order (for finite values; −0 before +0, which both compare equal as
/// floats: the sweep then only tests more pairs, never fewer).
inline uint32_t OrderedBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

inline const float* Vertex(const char* base, size_t stride, uint32_t v) {
  return reinterpret_cast<const float*>(base + size_t{v} * stride);
}

// Closed-interval box overlap (touching counts): conservative for closed triangles.
inline bool BoxesOverlap(const float* a, const float* b) {
  return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] && b[2] <= a[5];
}

}  // namespace

struct NarrowPhaseContext::Internal {
  using Culled = NarrowPhaseContext::Culled;

  /// Region boxes of every sphere; false when a position is not finite.
  static bool RegionBoxes(NarrowPhaseContext& c, const char* base, size_t stride) {
    bool finite = true;
    for (uint32_t s = 0; s < c.sphere_count_; ++s) {
      float* box = &c.box_[6 * size_t{s}];
      box[0] = box[1] = box[2] = 1.0f;  // empty region: an inverted box that overlaps nothing
      box[3] = box[4] = box[5] = -1.0f;
      const uint32_t begin = c.vert_offsets_[s], end = c.vert_offsets_[s + 1];
      if (begin == end) continue;
      float lo[3], hi[3];
      const float* p0 = Vertex(base, stride, c.vert_ids_[begin]);
      for (int k = 0; k < 3; ++k) lo[k] = hi[k] = p0[k];
      float check = 0.0f;  // NaN/Inf propagate into it: one test per region
      for (uint32_t i = begin; i < end; ++i) {
        const float* p = Vertex(base, stride, c.vert_ids_[i]);
        for (int k = 0; k < 3; ++k) {
          lo[k] = p[k] < lo[k] ? p[k] : lo[k];
          hi[k] = p[k] > hi[k] ? p[k] : hi[k];
          check += p[k] - p[k];
        }
      }
      if (!(check == 0.0f)) finite = false;
      for (int k = 0; k < 3; ++k) box[k] = lo[k], box[3 + k] = hi[k];
    }
    return finite;
  }

  /// Region-order slots of sphere s whose triangle box meets `clip`, their boxes written, keyed by the
  /// box minimum on `axis` and sorted by it (ties by slot: deterministic). The cull is exact and reads
  /// only the region's vertices once: each vertex gets an outcode (below / above `clip` on each axis,
  /// Cohen–Sutherland), and a triangle's box misses `clip` exactly when its three corners share a bit.
  static uint32_t Cull(NarrowPhaseContext& c, uint32_t s, const float* clip, int axis, const char* base,
                       size_t stride, Culled* list) {
    const uint32_t vbegin = c.vert_offsets_[s], vend = c.vert_offsets_[s + 1];
    uint8_t* code = c.outcode_.data();
    for (uint32_t i = vbegin; i < vend; ++i) {
      const float* p = Vertex(base, stride, c.vert_ids_[i]);
      code[i - vbegin] = static_cast<uint8_t>((p[0] < clip[0]) | (p[0] > clip[3]) << 1 | (p[1] < clip[1]) << 2 |
                                              (p[1] > clip[4]) << 3 | (p[2] < clip[2]) << 4 | (p[2] > clip[5]) << 5);
    }
    uint32_t n = 0;
    for (uint32_t k = c.region_offsets_[s]; k < c.region_offsets_[s + 1]; ++k) {
      const uint32_t* l = &c.region_local_[3 * size_t{k}];
      if (code[l[0]] & code[l[1]] & code[l[2]]) continue;
      const float* p = Vertex(base, stride, c.region_v_[3 * size_t{k}]);
      const float* q = Vertex(base, stride, c.region_v_[3 * size_t{k} + 1]);
      const float* r = Vertex(base, stride, c.region_v_[3 * size_t{k} + 2]);
      float* box = &list->box[6 * size_t{n}];
      for (int j = 0; j < 3; ++j) {
        box[j] = std::min(std::min(p[j], q[j]), r[j]);
        box[3 + j] = std::max(std::max(p[j], q[j]), r[j]);
      }
      list->slot[n] = k;
      list->key[n] = uint64_t{OrderedBits(box[axis])} << 32 | n;  // ties: cull order (slot order)
      ++n;
    }
    std::sort(list->key.begin(), list->key.begin() + n);
    return n;
  }

  /// The exact test of two box-overlapping triangles of different spheres (adjacency, degeneracy, predicate).
  static void Test(NarrowPhaseContext& c, uint32_t ka, uint32_t kb, uint32_t a, uint32_t b, const char* base,
                   size_t stride, const NarrowPhaseJob& job, NarrowPhaseStats& st) {
    const uint32_t* wa = &c.region_w_[3 * size_t{ka}];
    const uint32_t* wb = &c.region_w_[3 * size_t{kb}];
    if (wa[0] == wb[0] || wa[0] == wb[1] || wa[0] == wb[2] || wa[1] == wb[0] || wa[1] == wb[1] || wa[1] == wb[2] ||
        wa[2] == wb[0] || wa[2] == wb[1] || wa[2] == wb[2]) {
      ++st.adjacent_skipped;
      return;
    }
    const uint32_t* va = &c.region_v_[3 * size_t{ka}];
    const uint32_t* vb = &c.region_v_[3 * size_t{kb}];
    const float* pa[3] = {Vertex(base, stride, va[0]), Vertex(base, stride, va[1]), Vertex(base, stride, va[2])};
    const float* pb[3] = {Vertex(base, stride, vb[0]), Vertex(base, stride, vb[1]), Vertex(base, stride, vb[2])};
    for (const auto& [k, p] : {std::pair(ka, pa), std::pair(kb, pb)}) {
      if (c.tri_state_[k] == 0) {  // degeneracy decided once a frame, for triangles that reach a test
        c.tri_state_[k] = TriangleIsDegenerate(p[0], p[1], p[2]) ? 2 : 1;
        st.degenerate_triangles += c.tri_state_[k] == 2;
      }
      if (c.tri_state_[k] == 2) return;
    }
    ++st.triangle_tests;
    if (!TrianglesIntersect(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2])) return;
    if (st.contacts < job.capacity)
      job.output[st.contacts] = {c.region_tri_[ka], c.region_tri_[kb], static_cast<uint16_t>(a), static_cast<uint16_t>(b)};
    ++st.contacts;
  }

  /// Every contact of candidate (a, b), a < b: both regions culled to the other's box, then a
  /// sort-and-sweep of the two lists along the longest axis of the boxes' overlap.
  static void Pair(NarrowPhaseContext& c, uint32_t a, uint32_t b, const char* base, size_t stride,
                   const NarrowPhaseJob& job, NarrowPhaseStats* out_stats) {
    NarrowPhaseStats st = *out_stats;  // counters in registers, written back once
    const float* ba = &c.box_[6 * size_t{a}];
    const float* bb = &c.box_[6 * size_t{b}];
    int axis = 0;
    float extent = -1.0f;
    for (int k = 0; k < 3; ++k) {
      const float e = std::min(ba[3 + k], bb[3 + k]) - std::max(ba[k], bb[k]);
      if (e > extent) extent = e, axis = k;
    }
    Culled& la = c.list_a_;
    Culled& lb = c.list_b_;
    const uint32_t na = Cull(c, a, bb, axis, base, stride, &la);
    const uint32_t nb = na ? Cull(c, b, ba, axis, base, stride, &lb) : 0;
    st.culled_triangles += na + nb;
    // Sweep: take the list whose next box starts first; test it against the other list's boxes that
    // start before it ends. Each overlapping pair is met exactly once.
    uint32_t i = 0, j = 0;
    while (i < na && j < nb) {
      const bool from_a = la.key[i] <= lb.key[j];  // same order as the minima (ties: a first)
      const Culled& xs = from_a ? la : lb;
      const Culled& os = from_a ? lb : la;
      const uint32_t xi = static_cast<uint32_t>((from_a ? la.key[i] : lb.key[j]) & 0xFFFFFFFFu);
      const uint32_t n_other = from_a ? nb : na;
      const float* bx = &xs.box[6 * size_t{xi}];
      const uint64_t end = uint64_t{OrderedBits(bx[3 + axis])} << 32 | 0xFFFFFFFFu;
      for (uint32_t o = from_a ? j : i; o < n_other && os.key[o] <= end; ++o) {
        ++st.box_tests;
        const uint32_t oi = static_cast<uint32_t>(os.key[o] & 0xFFFFFFFFu);
        const float* by = &os.box[6 * size_t{oi}];  // on `axis` they overlap: the sweep says so
        if (!((bx[0] <= by[3]) & (by[0] <= bx[3]) & (bx[1] <= by[4]) & (by[1] <= bx[4]) & (bx[2] <= by[5]) &
              (by[2] <= bx[5])))
          continue;
        if (from_a)
          Test(c, xs.slot[xi], os.slot[oi], a, b, base, stride, job, st);
        else
          Test(c, os.slot[oi], xs.slot[xi], a, b, base, stride, job, st);
      }
      from_a ? ++i : ++j;
    }
    *out_stats = st;
  }
};

Status NarrowPhaseContext::Init(const AssetView& view) {
  *this = NarrowPhaseContext{};
  if (!view.valid()) return Status::kErrorNullArgument;
  const schema::Asset& a = *view.asset;
  const auto* tris = a.triangles();
  const auto* weld = a.weld_ids();
  if (!tris || !weld) return Status::kErrorMissingField;  // LoadAsset checked their sizes and ranges
  try {
    const uint32_t S = view.sphere_count, T = view.triangle_count, V = view.vertex_count;
    weld_.assign(weld->begin(), weld->end());
    tri_sphere_.assign(T, kNoSphere);
    region_offsets_.assign(1, 0);
    vert_offsets_.assign(1, 0);
    std::vector<uint32_t> verts;
    uint32_t largest_verts = 0;
    for (uint32_t s = 0; s < S; ++s) {
      const TriangleSpan span = SurroundingTriangles(view, s);
      verts.clear();
      for (uint32_t i = 0; i < span.count; ++i) {
        const uint32_t t = span.data[i];
        if (tri_sphere_[t] != kNoSphere) continue;  // listed twice: the first region owns it
        tri_sphere_[t] = static_cast<uint16_t>(s);
        uint32_t v[3], w[3];
        for (int j = 0; j < 3; ++j) v[j] = tris->Get(3 * t + j), w[j] = weld_[v[j]];
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
          ++index_degenerate_;
          continue;
        }
        region_tri_.push_back(t);
        for (int j = 0; j < 3; ++j) region_v_.push_back(v[j]), region_w_.push_back(w[j]), verts.push_back(v[j]);
      }
      region_offsets_.push_back(static_cast<uint32_t>(region_tri_.size()));
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      for (uint32_t k = region_offsets_[s]; k < region_tri_.size(); ++k)
        for (int j = 0; j < 3; ++j)
          region_local_.push_back(static_cast<uint32_t>(
              std::lower_bound(verts.begin(), verts.end(), region_v_[3 * size_t{k} + j]) - verts.begin()));
      largest_verts = std::max(largest_verts, static_cast<uint32_t>(verts.size()));
      vert_ids_.insert(vert_ids_.end(), verts.begin(), verts.end());
      vert_offsets_.push_back(static_cast<uint32_t>(vert_ids_.size()));
    }
    unassigned_ = static_cast<uint32_t>(std::count(tri_sphere_.begin(), tri_sphere_.end(), kNoSphere));
    excl_offsets_.assign(S + 1, 0);
    if (const auto* ex = a.excluded_pairs()) {
      for (const schema::SpherePair* p : *ex) ++excl_offsets_[p->a() + 1];
      for (uint32_t s = 0; s < S; ++s) excl_offsets_[s + 1] += excl_offsets_[s];
      excl_partners_.resize(ex->size());
      for (uint32_t i = 0; i < ex->size(); ++i) excl_partners_[i] = ex->Get(i)->b();  // sorted by (a, b)
    }
    uint32_t largest = 0;
    for (uint32_t s = 0; s < S; ++s) largest = std::max(largest, region_offsets_[s + 1] - region_offsets_[s]);
    box_.assign(6 * size_t{S}, 0.0f);
    tri_state_.assign(region_tri_.size(), 0);
    outcode_.assign(largest_verts, 0);
    for (Culled* l : {&list_a_, &list_b_}) {
      l->key.assign(largest, 0);
      l->slot.assign(largest, 0);
      l->box.assign(6 * size_t{largest}, 0.0f);
    }
    sphere_count_ = S;
    vertex_count_ = V;
    triangle_count_ = T;
  } catch (const std::bad_alloc&) {
    *this = NarrowPhaseContext{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

bool NarrowPhaseContext::IsExcluded(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  if (b >= sphere_count_) return false;
  const uint16_t* begin = excl_partners_.data() + excl_offsets_[a];
  const uint16_t* end = excl_partners_.data() + excl_offsets_[a + 1];
  return std::binary_search(begin, end, static_cast<uint16_t>(b));
}

Status NarrowPhaseJob::Check() const {
  if (!context || !count || !positions.data) return Status::kErrorNullArgument;
  if (!output && capacity > 0) return Status::kErrorNullArgument;
  if (!sphere_pairs && sphere_pair_count > 0) return Status::kErrorNullArgument;
  if (!context->initialized()) return Status::kErrorInvalidJob;
  if (exclusions != Exclusions::kAsset && exclusions != Exclusions::kNone) return Status::kErrorInvalidJob;
  if (reinterpret_cast<uintptr_t>(positions.data) % 4 != 0) return Status::kErrorAlignment;
  if (positions.stride_bytes < 12 || positions.stride_bytes % 4 != 0) return Status::kErrorStride;
  if (positions.count != context->vertex_count()) return Status::kErrorVertexCount;
  for (uint32_t i = 0; i < sphere_pair_count; ++i)
    if (sphere_pairs[i].a >= sphere_pairs[i].b || sphere_pairs[i].b >= context->sphere_count())
      return Status::kErrorIndexOutOfRange;
  return Status::kOk;
}

Status NarrowPhaseJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  NarrowPhaseContext& c = *context;
  NarrowPhaseStats st;
  *count = 0;
  if (stats) *stats = st;
  const char* base = static_cast<const char*>(positions.data);
  const size_t stride = positions.stride_bytes;
  if (!NarrowPhaseContext::Internal::RegionBoxes(c, base, stride)) return Status::kErrorNonFinitePositions;
  std::fill(c.tri_state_.begin(), c.tri_state_.end(), uint8_t{0});  // degeneracy: unknown this frame
  const uint32_t S = c.sphere_count_;
  const bool skip_excluded = exclusions == Exclusions::kAsset;
  auto consider = [&](uint32_t a, uint32_t b) {
    if (!BoxesOverlap(&c.box_[6 * size_t{a}], &c.box_[6 * size_t{b}])) return;
    if (skip_excluded && c.IsExcluded(a, b)) return;
    ++st.candidate_pairs;
    NarrowPhaseContext::Internal::Pair(c, a, b, base, stride, *this, &st);
  };
  if (sphere_pairs) {
    for (uint32_t i = 0; i < sphere_pair_count; ++i) consider(sphere_pairs[i].a, sphere_pairs[i].b);
  } else {
    for (uint32_t a = 0; a < S; ++a) {
      const float* ba = &c.box_[6 * size_t{a}];
      const uint16_t* ex = c.excl_partners_.data() + c.excl_offsets_[a];
      const uint16_t* ex_end = c.excl_partners_.data() + c.excl_offsets_[a + 1];
      for (uint32_t b = a + 1; b < S; ++b) {
        if (!BoxesOverlap(ba, &c.box_[6 * size_t{b}])) continue;
        if (skip_excluded) {  // partners ascending: walk the list alongside b
          while (ex != ex_end && *ex < b) ++ex;
          if (ex != ex_end && *ex == b) continue;
        }
        ++st.candidate_pairs;
        NarrowPhaseContext::Internal::Pair(c, a, b, base, stride, *this, &st);
      }
    }
  }
  *count = std::min(st.contacts, capacity);
  if (stats) *stats = st;
  return st.contacts > capacity ? Status::kOkTruncated : Status::kOk;
}

}  // namespace spherechain::runtime
