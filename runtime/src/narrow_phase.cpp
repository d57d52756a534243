#include "spherechain/runtime/narrow_phase.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <new>

#include "alloc_guard.h"
#include "spherechain/runtime/triangle_intersect.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define SPHERECHAIN_NARROW_SSE2 1
#include <immintrin.h>
#endif

namespace spherechain::runtime {

namespace {

constexpr uint16_t kNoSphere = 0xFFFF;
constexpr uint32_t kNotCulled = 0xFFFFFFFFu;  // NarrowPhaseContext::kept_: region not culled this frame
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kPrefetch = 32;  // RegionBoxes: vertices read ahead
constexpr uint32_t kSentinels = 4;  // after each culled list: the sweep reads four boxes a step

// Four floats (x, y, z, w) and lane masks: SSE2 on x86-64 (its baseline), scalar elsewhere. Every mask
// is read through `& 7` or `& 15` as the caller needs: w lanes of vertex loads are never trusted.
#if SPHERECHAIN_NARROW_SSE2
using F4 = __m128;
using M4 = __m128;
inline F4 Load4(const float* p) { return _mm_loadu_ps(p); }
inline F4 Set1(float v) { return _mm_set1_ps(v); }
inline void Store4(float* p, F4 v) { _mm_storeu_ps(p, v); }
inline F4 Min4(F4 v, F4 acc) { return _mm_min_ps(v, acc); }  // a NaN lane of v keeps acc
inline F4 Max4(F4 v, F4 acc) { return _mm_max_ps(v, acc); }
inline M4 Le(F4 a, F4 b) { return _mm_cmple_ps(a, b); }
inline M4 Lt(F4 a, F4 b) { return _mm_cmplt_ps(a, b); }
inline M4 NanEither(F4 a, F4 b) { return _mm_cmpunord_ps(a, b); }
inline M4 And(M4 a, M4 b) { return _mm_and_ps(a, b); }
inline M4 Or(M4 a, M4 b) { return _mm_or_ps(a, b); }
inline M4 NoLanes() { return _mm_setzero_ps(); }
inline uint32_t Bits(M4 m) { return static_cast<uint32_t>(_mm_movemask_ps(m)); }
#else
struct F4 {
  float v[4];
};
using M4 = uint32_t;
inline F4 Load4(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
inline F4 Set1(float v) { return {{v, v, v, v}}; }
inline void Store4(float* p, F4 v) { std::memcpy(p, v.v, 16); }
inline F4 Min4(F4 v, F4 acc) {
  for (int k = 0; k < 4; ++k) acc.v[k] = v.v[k] < acc.v[k] ? v.v[k] : acc.v[k];
  return acc;
}
inline F4 Max4(F4 v, F4 acc) {
  for (int k = 0; k < 4; ++k) acc.v[k] = v.v[k] > acc.v[k] ? v.v[k] : acc.v[k];
  return acc;
}
inline M4 Le(F4 a, F4 b) {
  return M4{a.v[0] <= b.v[0]} | M4{a.v[1] <= b.v[1]} << 1 | M4{a.v[2] <= b.v[2]} << 2 | M4{a.v[3] <= b.v[3]} << 3;
}
inline M4 Lt(F4 a, F4 b) {
  return M4{a.v[0] < b.v[0]} | M4{a.v[1] < b.v[1]} << 1 | M4{a.v[2] < b.v[2]} << 2 | M4{a.v[3] < b.v[3]} << 3;
}
inline M4 NanEither(F4 a, F4 b) {
  M4 m = 0;
  for (int k = 0; k < 4; ++k) m |= M4{a.v[k] != a.v[k] || b.v[k] != b.v[k]} << k;
  return m;
}
inline M4 And(M4 a, M4 b) { return a & b; }
inline M4 Or(M4 a, M4 b) { return a | b; }
inline M4 NoLanes() { return 0; }
inline uint32_t Bits(M4 m) { return m; }
#endif

// Per 4-bit mask: its set lanes in order, then lane 0 again (padding); and how many are set.
constexpr uint8_t kHitLane[16][4] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}, {2, 0, 0, 0}, {0, 2, 0, 0},
                                     {1, 2, 0, 0}, {0, 1, 2, 0}, {3, 0, 0, 0}, {0, 3, 0, 0}, {1, 3, 0, 0}, {0, 1, 3, 0},
                                     {2, 3, 0, 0}, {0, 2, 3, 0}, {1, 2, 3, 0}, {0, 1, 2, 3}};
constexpr uint8_t kHitCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

/// Float → uint32 with the same order for finite values; −0 counts as +0 (equal floats, equal bits).
inline uint32_t OrderedBits(float f) {
  f += 0.0f;  // −0 + 0 = +0 (IEEE, round to nearest): not folded away without -ffast-math
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

inline void Prefetch(const void* p) {
#if defined(__GNUC__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

inline const float* Vertex(const char* base, size_t stride, uint32_t v) {
  return reinterpret_cast<const float*>(base + size_t{v} * stride);
}

/// Vertex v as (x, y, z, w); w is the next float of the buffer, or 0 for the buffer's last vertex
/// (`last`), which may end the buffer.
inline F4 LoadVertex(const char* base, size_t stride, uint32_t v, uint32_t last) {
  const float* p = Vertex(base, stride, v);
  if (v != last) return Load4(p);
  const float w[4] = {p[0], p[1], p[2], 0.0f};
  return Load4(w);
}

// Closed-interval overlap (touching counts) of two 8-float boxes: conservative for closed triangles.
inline bool BoxesOverlap(const float* a, const float* b) {
  return (a[0] <= b[4]) & (b[0] <= a[4]) & (a[1] <= b[5]) & (b[1] <= a[5]) & (a[2] <= b[6]) & (b[2] <= a[6]);
}

}  // namespace

struct NarrowPhaseContext::Internal {
  using Culled = NarrowPhaseContext::Culled;

  /// Region boxes of every sphere; false when a position of a region is not finite.
  static bool RegionBoxes(NarrowPhaseContext& c, const char* base, size_t stride) {
    const uint32_t last = c.vertex_count_ - 1;
    M4 nan = NoLanes();  // min/max skip a NaN: flagged apart; ±Inf reach the box
    bool finite = true;
    for (uint32_t s = 0; s < c.sphere_count_; ++s) {
      float* box = &c.box_[8 * size_t{s}];
      const uint32_t begin = c.vert_offsets_[s], end = c.vert_offsets_[s + 1];
      if (begin == end) {  // empty region: an inverted box that overlaps nothing
        Store4(box, Set1(1.0f));
        Store4(box + 4, Set1(-1.0f));
        for (int k = 0; k < 6; ++k) c.box_soa_[k * c.box_pitch_ + s] = k < 3 ? 1.0f : -1.0f;
        continue;
      }
      F4 lo0 = Set1(kInf), hi0 = Set1(-kInf), lo1 = lo0, hi1 = hi0;  // two chains: min/max latency
      const uint32_t* ids = c.vert_ids_.data();
      const uint32_t stop = end - (ids[end - 1] == last);  // ids ascending: only the last can be #V−1
      uint32_t i = begin;
      for (; i + 2 <= stop; i += 2) {
        Prefetch(Vertex(base, stride, ids[i + kPrefetch]));  // ids padded; a hint, never a fault
        const F4 p = Load4(Vertex(base, stride, ids[i])), q = Load4(Vertex(base, stride, ids[i + 1]));
        lo0 = Min4(p, lo0), hi0 = Max4(p, hi0), lo1 = Min4(q, lo1), hi1 = Max4(q, hi1);
        nan = Or(nan, NanEither(p, q));
      }
      for (; i < end; ++i) {
        const F4 p = LoadVertex(base, stride, ids[i], last);
        lo0 = Min4(p, lo0), hi0 = Max4(p, hi0);
        nan = Or(nan, NanEither(p, p));
      }
      Store4(box, Min4(lo1, lo0));
      Store4(box + 4, Max4(hi1, hi0));
      box[3] = box[7] = 0.0f;
      for (int k = 0; k < 8; ++k) finite &= box[k] - box[k] == 0.0f;  // ±Inf
      for (int k = 0; k < 3; ++k)
        c.box_soa_[k * c.box_pitch_ + s] = box[k], c.box_soa_[(3 + k) * c.box_pitch_ + s] = box[4 + k];
    }
    return finite && (Bits(nan) & 7) == 0;
  }

  /// Every candidate sphere pair (a, b), a < b, in output order: region boxes overlap, not excluded.
  template <class Fn>
  static void ForEachCandidate(const NarrowPhaseContext& c, const NarrowPhaseJob& job, Fn&& fn) {
    const bool skip_excluded = job.exclusions == Exclusions::kAsset;
    if (job.sphere_pairs) {
      for (uint32_t i = 0; i < job.sphere_pair_count; ++i) {
        const uint32_t a = job.sphere_pairs[i].a, b = job.sphere_pairs[i].b;
        if (!BoxesOverlap(&c.box_[8 * size_t{a}], &c.box_[8 * size_t{b}])) continue;
        if (skip_excluded && c.IsExcluded(a, b)) continue;
        fn(a, b);
      }
      return;
    }
    // Every pair: a's box against four boxes b at a time (SoA copies; inverted boxes pad the end).
    const uint32_t S = c.sphere_count_;
    const size_t P = c.box_pitch_;
    const float* soa = c.box_soa_.data();
    for (uint32_t a = 0; a < S; ++a) {
      const float* ba = &c.box_[8 * size_t{a}];
      const F4 alo_x = Set1(ba[0]), alo_y = Set1(ba[1]), alo_z = Set1(ba[2]);
      const F4 ahi_x = Set1(ba[4]), ahi_y = Set1(ba[5]), ahi_z = Set1(ba[6]);
      const uint16_t* ex = c.excl_partners_.data() + c.excl_offsets_[a];
      const uint16_t* ex_end = c.excl_partners_.data() + c.excl_offsets_[a + 1];
      for (uint32_t b0 = a + 1; b0 < S; b0 += 4) {
        uint32_t hit = Bits(And(And(And(Le(Load4(soa + b0), ahi_x), Le(alo_x, Load4(soa + 3 * P + b0))),
                                    And(Le(Load4(soa + P + b0), ahi_y), Le(alo_y, Load4(soa + 4 * P + b0)))),
                                And(Le(Load4(soa + 2 * P + b0), ahi_z), Le(alo_z, Load4(soa + 5 * P + b0)))));
        for (; hit; hit &= hit - 1) {
          const uint32_t b = b0 + static_cast<uint32_t>(std::countr_zero(hit));
          if (skip_excluded) {  // partners ascending: walk the list alongside b
            while (ex != ex_end && *ex < b) ++ex;
            if (ex != ex_end && *ex == b) continue;
          }
          fn(a, b);
        }
      }
    }
  }

  /// Grows the clip of sphere s by its region box ∩ the box `other` (which overlaps it).
  static void GrowClip(NarrowPhaseContext& c, uint32_t s, const float* other) {
    const float* own = &c.box_[8 * size_t{s}];
    float* clip = &c.clip_[8 * size_t{s}];
    for (int k = 0; k < 3; ++k) {
      clip[k] = std::min(clip[k], std::max(own[k], other[k]));
      clip[4 + k] = std::max(clip[4 + k], std::min(own[4 + k], other[4 + k]));
    }
  }

  /// Once a frame per sphere s that has a candidate: the triangles of its region whose box meets its
  /// clip, with their boxes, in slot order. Exact and read once from the region's vertices: each vertex
  /// gets an outcode (below / above the clip on each axis, Cohen–Sutherland), and a triangle's box misses
  /// the clip exactly when its three corners share a bit. A triangle box meeting a partner's region box
  /// meets the clip (the triangle lies in its own region box), so the per-pair cull loses nothing.
  static void CullRegion(NarrowPhaseContext& c, uint32_t s, const char* base, size_t stride) {
    const F4 clo = Load4(&c.clip_[8 * size_t{s}]), chi = Load4(&c.clip_[8 * size_t{s} + 4]);
    const uint32_t vbegin = c.vert_offsets_[s], vend = c.vert_offsets_[s + 1], last = c.vertex_count_ - 1;
    uint8_t* code = c.outcode_.data();
    float* corner = c.corner_.data();
    for (uint32_t i = vbegin; i < vend; ++i) {
      const F4 p = LoadVertex(base, stride, c.vert_ids_[i], last);
      Store4(corner + 4 * size_t{i - vbegin}, p);
      code[i - vbegin] = static_cast<uint8_t>((Bits(Lt(p, clo)) & 7) | (Bits(Lt(chi, p)) & 7) << 3);
    }
    const uint32_t first = c.region_offsets_[s], end = c.region_offsets_[s + 1];
    std::fill(&c.tri_state_[first], &c.tri_state_[first] + (end - first), uint8_t{0});  // degeneracy: unknown
    const uint32_t* local = c.region_local_.data();
    float* boxes = &c.kept_box_[8 * size_t{first}];
    uint32_t* slots = &c.kept_slot_[first];
    uint32_t n = 0;
    for (uint32_t k = first; k < end; ++k) {  // branch-free: written always, counted when kept
      const uint32_t* l = local + 3 * size_t{k};
      slots[n] = k;
      n += (code[l[0]] & code[l[1]] & code[l[2]]) == 0;
    }
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t* l = local + 3 * size_t{slots[i]};
      const F4 p = Load4(corner + 4 * size_t{l[0]}), q = Load4(corner + 4 * size_t{l[1]});
      const F4 r = Load4(corner + 4 * size_t{l[2]});
      Store4(boxes + 8 * size_t{i}, Min4(r, Min4(q, p)));
      Store4(boxes + 8 * size_t{i} + 4, Max4(r, Max4(q, p)));
    }
    c.kept_[s] = n;
  }

  /// Triangles of sphere s whose box meets `other` (the partner's region box), in sweep order: keyed by
  /// the box minimum on `axis`, ties by cull (slot) order; their slots and boxes beside. Returns their
  /// number. The sort: a counting sort into n buckets over the range of the minima (bucket =
  /// ⌊(start − lo)·scale⌋: monotone in the start, float rounding being monotone), each record written
  /// at its bucket's place, then an insertion pass that only moves records within their bucket: linear
  /// for spread minima, and the exact order whatever they are.
  static uint32_t Cull(NarrowPhaseContext& c, uint32_t s, const float* other, int axis, const char* base,
                       size_t stride, Culled* list) {
    if (c.kept_[s] == kNotCulled) CullRegion(c, s, base, stride);
    const uint32_t first = c.region_offsets_[s], m = c.kept_[s];
    const float* boxes = &c.kept_box_[8 * size_t{first}];
    const F4 olo = Load4(other), ohi = Load4(other + 4);
    float* start = list->start.data();
    uint32_t* kept = list->kept.data();
    uint32_t n = 0;
    for (uint32_t i = 0; i < m; ++i) {  // branch-free: written always, counted when kept
      const float* b = boxes + 8 * size_t{i};
      start[n] = b[axis];
      kept[n] = i;
      n += (Bits(And(Le(Load4(b), ohi), Le(olo, Load4(b + 4)))) & 7) == 7;
    }
    uint64_t* key = list->key.data();
    uint32_t* slot = list->slot.data();
    float* lo[3] = {list->lo[0].data(), list->lo[1].data(), list->lo[2].data()};
    float* hi[3] = {list->hi[0].data(), list->hi[1].data(), list->hi[2].data()};
    for (uint32_t r = n; r < n + kSentinels; ++r)  // sentinels: start after every box, overlap nothing
      for (int k = 0; k < 3; ++k) lo[k][r] = kInf, hi[k][r] = -kInf;
    if (n == 0) return 0;
    F4 lo4 = Set1(start[0]), hi4 = lo4;
    uint32_t k4 = 0;
    for (; k4 + 4 <= n; k4 += 4) lo4 = Min4(Load4(start + k4), lo4), hi4 = Max4(Load4(start + k4), hi4);
    float lanes[8];
    Store4(lanes, lo4);
    Store4(lanes + 4, hi4);
    float s_lo = std::min(std::min(lanes[0], lanes[1]), std::min(lanes[2], lanes[3]));
    float s_hi = std::max(std::max(lanes[4], lanes[5]), std::max(lanes[6], lanes[7]));
    for (; k4 < n; ++k4) s_lo = std::min(s_lo, start[k4]), s_hi = std::max(s_hi, start[k4]);
    // (s_hi − s_lo)·scale < n in exact arithmetic; the clamp takes the rounding; a range too small for
    // a finite scale gets one bucket (still sorted, by the insertion pass alone).
    float scale = s_hi > s_lo ? static_cast<float>(n) / (s_hi - s_lo) * 0.999f : 0.0f;
    if (!(scale < 1e30f)) scale = 0.0f;
    const uint32_t top = n - 1;
    uint32_t* bucket = list->bucket.data();
    std::fill(bucket, bucket + n + 1, 0u);
    for (uint32_t k = 0; k < n; ++k) ++bucket[std::min(top, static_cast<uint32_t>((start[k] - s_lo) * scale)) + 1];
    for (uint32_t k = 1; k < n; ++k) bucket[k] += bucket[k - 1];
    for (uint32_t k = 0; k < n; ++k) {
      const uint32_t r = bucket[std::min(top, static_cast<uint32_t>((start[k] - s_lo) * scale))]++;
      const uint32_t i = kept[k];
      const float* b = boxes + 8 * size_t{i};
      key[r] = uint64_t{OrderedBits(start[k])} << 32 | k;
      slot[r] = c.kept_slot_[first + i];
      for (int d = 0; d < 3; ++d) lo[d][r] = b[d], hi[d][r] = b[4 + d];
    }
    for (uint32_t k = 1; k < n; ++k) {
      if (!(key[k - 1] > key[k])) continue;  // rare: only within a bucket
      const uint64_t x = key[k];
      const uint32_t x_slot = slot[k];
      const float x_lo[3] = {lo[0][k], lo[1][k], lo[2][k]}, x_hi[3] = {hi[0][k], hi[1][k], hi[2][k]};
      uint32_t j = k;
      for (; j > 0 && key[j - 1] > x; --j) {
        key[j] = key[j - 1];
        slot[j] = slot[j - 1];
        for (int d = 0; d < 3; ++d) lo[d][j] = lo[d][j - 1], hi[d][j] = hi[d][j - 1];
      }
      key[j] = x;
      slot[j] = x_slot;
      for (int d = 0; d < 3; ++d) lo[d][j] = x_lo[d], hi[d][j] = x_hi[d];
    }
    return n;
  }

  /// The exact test of two box-overlapping triangles of different spheres (adjacency, degeneracy, predicate).
  static void Test(NarrowPhaseContext& c, uint32_t ka, uint32_t kb, uint32_t a, uint32_t b, const char* base,
                   size_t stride, const NarrowPhaseJob& job, NarrowPhaseStats& st) {
    const uint32_t* wa = &c.region_w_[3 * size_t{ka}];
    const uint32_t* wb = &c.region_w_[3 * size_t{kb}];
    if ((wa[0] == wb[0]) | (wa[0] == wb[1]) | (wa[0] == wb[2]) | (wa[1] == wb[0]) | (wa[1] == wb[1]) |
        (wa[1] == wb[2]) | (wa[2] == wb[0]) | (wa[2] == wb[1]) | (wa[2] == wb[2])) {  // one branch
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

  /// Test() on the buffered hits, in order.
  static void Tests(NarrowPhaseContext& c, const uint64_t* hits, uint32_t n, uint32_t a, uint32_t b,
                    const char* base, size_t stride, const NarrowPhaseJob& job, NarrowPhaseStats& st) {
    for (uint32_t h = 0; h < n; ++h)
      Test(c, static_cast<uint32_t>(hits[h] >> 32), static_cast<uint32_t>(hits[h]), a, b, base, stride, job, st);
  }

  /// Every contact of candidate (a, b), a < b: both regions culled to the other's box, then a
  /// sort-and-sweep of the two lists along the longest axis of the boxes' overlap.
  static void Pair(NarrowPhaseContext& c, uint32_t a, uint32_t b, const char* base, size_t stride,
                   const NarrowPhaseJob& job, NarrowPhaseStats* out_stats) {
    NarrowPhaseStats st = *out_stats;  // counters in registers, written back once
    const float* ba = &c.box_[8 * size_t{a}];
    const float* bb = &c.box_[8 * size_t{b}];
    int axis = 0;
    float extent = -1.0f;
    for (int k = 0; k < 3; ++k) {
      const float e = std::min(ba[4 + k], bb[4 + k]) - std::max(ba[k], bb[k]);
      if (e > extent) extent = e, axis = k;
    }
    Culled& la = c.list_a_;
    Culled& lb = c.list_b_;
    const uint32_t na = Cull(c, a, bb, axis, base, stride, &la);
    const uint32_t nb = na ? Cull(c, b, ba, axis, base, stride, &lb) : 0;
    st.culled_triangles += na + nb;
    // Sweep: take the list whose next box starts first; test it against the other list's boxes that
    // start before it ends (on `axis` those overlap: the order says so), on the two other axes, four at
    // a time. Each overlapping pair is met exactly once. The sentinels end the inner loop. No branch on
    // the data but the loop ends: the hits (slot in a << 32 | slot in b) go to a buffer, tested in order.
    struct View {
      const uint32_t* slot;
      const float *start, *end, *lo_u, *hi_u, *lo_v, *hi_v;
      uint32_t shift;  // of its slot in a hit: 32 for a, 0 for b
    };
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const View view[2] = {
        {la.slot.data(), la.lo[axis].data(), la.hi[axis].data(), la.lo[u].data(), la.hi[u].data(), la.lo[v].data(),
         la.hi[v].data(), 32},
        {lb.slot.data(), lb.lo[axis].data(), lb.hi[axis].data(), lb.lo[u].data(), lb.hi[u].data(), lb.lo[v].data(),
         lb.hi[v].data(), 0}};
    const uint64_t* key_a = la.key.data();
    const uint64_t* key_b = lb.key.data();
    uint64_t* hits = c.hits_.data();
    const uint32_t flush_at = static_cast<uint32_t>(c.hits_.size()) - 4;
    uint32_t n_hits = 0;
    uint32_t i = 0, j = 0;  // next of a, of b
    while (i < na && j < nb) {
      const uint32_t side = key_a[i] <= key_b[j] ? 0 : 1;  // same order as the minima (ties: cull order)
      const View& x = view[side];
      const View& o = view[side ^ 1];
      const uint32_t xi = side ? j : i;
      const F4 x_end = Set1(x.end[xi]);
      const F4 xlo_u = Set1(x.lo_u[xi]), xhi_u = Set1(x.hi_u[xi]);
      const F4 xlo_v = Set1(x.lo_v[xi]), xhi_v = Set1(x.hi_v[xi]);
      const uint64_t x_slot = uint64_t{x.slot[xi]} << x.shift;
      for (uint32_t k = side ? i : j;; k += 4) {
        const uint32_t started = Bits(Le(Load4(o.start + k), x_end));  // a prefix: minima ascending
        const uint32_t hit = started & Bits(And(And(Le(Load4(o.lo_u + k), xhi_u), Le(xlo_u, Load4(o.hi_u + k))),
                                                And(Le(Load4(o.lo_v + k), xhi_v), Le(xlo_v, Load4(o.hi_v + k)))));
        st.box_tests += static_cast<uint32_t>(std::countr_one(started));
        if (n_hits > flush_at) {
          Tests(c, hits, n_hits, a, b, base, stride, job, st);
          n_hits = 0;
        }
        if (hit) {  // rare: most boxes that start in time miss on another axis
          for (uint32_t t = 0; t < 4; ++t)  // the hit lanes packed to the front; all four written
            hits[n_hits + t] = x_slot | uint64_t{o.slot[k + kHitLane[hit][t]]} << o.shift;
          n_hits += kHitCount[hit];
        }
        if (started != 15) break;
      }
      i += side ^ 1;
      j += side;
    }
    Tests(c, hits, n_hits, a, b, base, stride, job, st);
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
  SPHERECHAIN_TRY {
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
    vert_ids_.resize(vert_ids_.size() + kPrefetch, 0);  // read ahead by RegionBoxes' prefetch
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
    box_.assign(8 * size_t{S}, 0.0f);
    box_pitch_ = S + 4;
    box_soa_.assign(6 * box_pitch_, 0.0f);
    for (uint32_t s = S; s < box_pitch_; ++s)  // padding: inverted boxes
      for (int k = 0; k < 6; ++k) box_soa_[k * box_pitch_ + s] = k < 3 ? kInf : -kInf;
    clip_.assign(8 * size_t{S}, 0.0f);
    kept_.assign(S, kNotCulled);
    tri_state_.assign(region_tri_.size(), 0);
    outcode_.assign(largest_verts, 0);
    corner_.assign(4 * size_t{largest_verts}, 0.0f);
    kept_slot_.assign(region_tri_.size(), 0);
    kept_box_.assign(8 * region_tri_.size(), 0.0f);
    hits_.assign(256, 0);
    candidates_.assign(std::min(size_t{S} * (S - 1) / 2, 16 * size_t{S} + 64), 0);
    for (Culled* l : {&list_a_, &list_b_}) {
      l->key.assign(largest, 0);
      l->start.assign(largest, 0.0f);
      l->bucket.assign(largest + 1, 0);
      l->kept.assign(largest, 0);
      l->slot.assign(largest + kSentinels, 0);
      for (int k = 0; k < 3; ++k) l->lo[k].assign(largest + kSentinels, 0.0f), l->hi[k].assign(largest + kSentinels, 0.0f);
    }
    sphere_count_ = S;
    vertex_count_ = V;
    triangle_count_ = T;
  } SPHERECHAIN_CATCH_BAD_ALLOC {
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
  std::fill(c.kept_.begin(), c.kept_.end(), kNotCulled);               // regions: culled on first use
  // Pass 1: each sphere's clip, the box of its candidate partners' boxes ∩ its own (inverted: none);
  // the candidates kept for pass 2 while they fit (else enumerated again).
  for (size_t i = 0; i < c.clip_.size(); ++i) c.clip_[i] = i % 8 < 4 ? kInf : -kInf;
  uint32_t n_cand = 0;
  const uint32_t cand_capacity = static_cast<uint32_t>(c.candidates_.size());
  NarrowPhaseContext::Internal::ForEachCandidate(c, *this, [&](uint32_t a, uint32_t b) {
    NarrowPhaseContext::Internal::GrowClip(c, a, &c.box_[8 * size_t{b}]);
    NarrowPhaseContext::Internal::GrowClip(c, b, &c.box_[8 * size_t{a}]);
    if (n_cand < cand_capacity) c.candidates_[n_cand] = a << 16 | b;
    ++n_cand;
  });
  // Pass 2: the same candidates, in output order.
  auto pair = [&](uint32_t a, uint32_t b) {
    ++st.candidate_pairs;
    NarrowPhaseContext::Internal::Pair(c, a, b, base, stride, *this, &st);
  };
  if (n_cand <= cand_capacity) {
    for (uint32_t i = 0; i < n_cand; ++i) pair(c.candidates_[i] >> 16, c.candidates_[i] & 0xFFFFu);
  } else {
    NarrowPhaseContext::Internal::ForEachCandidate(c, *this, pair);
  }
  *count = std::min(st.contacts, capacity);
  if (stats) *stats = st;
  return st.contacts > capacity ? Status::kOkTruncated : Status::kOk;
}

}  // namespace spherechain::runtime
