#include "spherechain/runtime/narrow_phase.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <atomic>
#include <bit>
#include <cstring>
#include <limits>
#include <new>

#include "alloc_guard.h"
#include "internal.h"
#include "spherechain/runtime/triangle_intersect.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define SPHERECHAIN_NARROW_SSE2 1
#include <immintrin.h>
#endif

namespace spherechain::runtime {

// Exclusions::kCrease (skin_contacts.cpp).
Status InitCreaseModel(NarrowPhaseModel& m, const AssetView& view);
Status InitCreaseWorkspace(NarrowPhaseWorkspace& w, const NarrowPhaseModel& m, BlockArena* arena);
Status RunCrease(const NarrowPhaseJob& job);

namespace {

constexpr uint16_t kNoSphere = 0xFFFF;
constexpr uint32_t kNotCulled = 0xFFFFFFFFu;  // NarrowPhaseWorkspace::kept_: region not culled this frame
constexpr uint32_t kUnprepared = 0xFFFFFFFFu;  // NarrowPhaseWorkspace::prepared_at_: not yet met by a test this frame
constexpr uint32_t kDegenerate = 0xFFFFFFFEu;  // NarrowPhaseWorkspace::prepared_at_: met, zero area
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kPrefetch = 32;  // RegionBoxes: vertices read ahead
constexpr uint32_t kSentinels = 4;  // after each culled list: the sweep reads four boxes a step
constexpr uint32_t kChunk = 8;      // kept triangles per chunk box (CullRegion, Cull)
std::atomic<uint64_t> g_next_narrow_model_id{1};  // NarrowPhaseModel::id()

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
inline void Transpose4(F4& a, F4& b, F4& c, F4& d) { _MM_TRANSPOSE4_PS(a, b, c, d); }
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
inline void Transpose4(F4& a, F4& b, F4& c, F4& d) {
  F4* r[4] = {&a, &b, &c, &d};
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) std::swap(r[i]->v[j], r[j]->v[i]);
}
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

struct NarrowPhaseInternal {
  using Culled = NarrowPhaseWorkspace::Culled;
  /// One Run's view: the per-asset data (read only) and the character's scratch.
  struct Frame {
    const NarrowPhaseModel& m;
    NarrowPhaseWorkspace& w;
    uint32_t test_budget = UINT32_MAX, box_budget = UINT32_MAX;  // Run's (NarrowPhaseModel::kSweepTests…)
  };
  static bool OverBudget(const Frame& c, const NarrowPhaseStats& st) {
    return st.triangle_tests > c.test_budget || st.box_tests > c.box_budget;
  }

  /// The word of NarrowPhaseWorkspace::listed_ holding candidate (a, b)'s bit, a < b (reach models).
  static uint64_t& ListedWord(const Frame& c, uint32_t a, uint32_t b) {
    return c.w.listed_[a * ((size_t{c.m.sphere_count_} + 63) / 64) + b / 64];
  }

  /// Region boxes of every sphere; false when a position of a region is not finite.
  static bool RegionBoxes(Frame& c, const char* base, size_t stride) {
    const uint32_t last = c.m.vertex_count_ - 1;
    M4 nan = NoLanes();  // min/max skip a NaN: flagged apart; ±Inf reach the box
    bool finite = true;
    for (uint32_t s = 0; s < c.m.sphere_count_; ++s) {
      float* box = &c.w.box_[8 * size_t{s}];
      const uint32_t begin = c.m.vert_offsets_[s], end = c.m.vert_offsets_[s + 1];
      if (begin == end) {  // empty region: an inverted box that overlaps nothing
        Store4(box, Set1(1.0f));
        Store4(box + 4, Set1(-1.0f));
        for (int k = 0; k < 6; ++k) c.w.box_soa_[k * c.m.box_pitch_ + s] = k < 3 ? 1.0f : -1.0f;
        continue;
      }
      F4 lo0 = Set1(kInf), hi0 = Set1(-kInf), lo1 = lo0, hi1 = hi0;  // two chains: min/max latency
      const uint32_t* ids = c.m.vert_ids_.data();
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
        c.w.box_soa_[k * c.m.box_pitch_ + s] = box[k], c.w.box_soa_[(3 + k) * c.m.box_pitch_ + s] = box[4 + k];
    }
    return finite && (Bits(nan) & 7) == 0;
  }

  /// Every candidate sphere pair (a, b), a < b, in output order: region boxes overlap, not excluded.
  template <class Fn>
  static void ForEachCandidate(const Frame& c, const NarrowPhaseJob& job, Fn&& fn) {
    const bool skip_excluded = job.exclusions == Exclusions::kAsset;
    if (job.sphere_pairs) {
      for (uint32_t i = 0; i < job.sphere_pair_count; ++i) {
        const uint32_t a = job.sphere_pairs[i].a, b = job.sphere_pairs[i].b;
        if (!BoxesOverlap(&c.w.box_[8 * size_t{a}], &c.w.box_[8 * size_t{b}])) continue;
        if (skip_excluded && c.m.IsExcluded(a, b)) continue;
        fn(a, b);
      }
      return;
    }
    // Every pair: a's box against four boxes b at a time (SoA copies; inverted boxes pad the end).
    const uint32_t S = c.m.sphere_count_;
    const size_t P = c.m.box_pitch_;
    const float* soa = c.w.box_soa_.data();
    for (uint32_t a = 0; a < S; ++a) {
      const float* ba = &c.w.box_[8 * size_t{a}];
      const F4 alo_x = Set1(ba[0]), alo_y = Set1(ba[1]), alo_z = Set1(ba[2]);
      const F4 ahi_x = Set1(ba[4]), ahi_y = Set1(ba[5]), ahi_z = Set1(ba[6]);
      const uint16_t* ex = c.m.excl_nb_ + c.m.excl_off_[a];
      const uint16_t* ex_end = c.m.excl_nb_ + c.m.excl_off_[a + 1];
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
  static void GrowClip(Frame& c, uint32_t s, const float* other) {
    const float* own = &c.w.box_[8 * size_t{s}];
    float* clip = &c.w.clip_[8 * size_t{s}];
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
  /// Written from the region's pool offset: slots and boxes (8 floats), inverted boxes padding the last
  /// chunk of kChunk; each chunk's box (the box of its boxes) as six rows from the region's chunk offset,
  /// inverted chunks padding to a multiple of four.
  static void CullRegion(Frame& c, uint32_t s, const char* base, size_t stride) {
    const F4 clo = Load4(&c.w.clip_[8 * size_t{s}]), chi = Load4(&c.w.clip_[8 * size_t{s} + 4]);
    const uint32_t vbegin = c.m.vert_offsets_[s], vend = c.m.vert_offsets_[s + 1], last = c.m.vertex_count_ - 1;
    uint8_t* code = c.w.outcode_.data();
    float* corner = c.w.corner_.data();
    for (uint32_t i = vbegin; i < vend; ++i) {
      const F4 p = LoadVertex(base, stride, c.m.vert_ids_[i], last);
      Store4(corner + 4 * size_t{i - vbegin}, p);
      code[i - vbegin] = static_cast<uint8_t>((Bits(Lt(p, clo)) & 7) | (Bits(Lt(chi, p)) & 7) << 3);
    }
    const uint32_t first = c.m.region_offsets_[s], end = c.m.region_offsets_[s + 1];
    std::fill(&c.w.prepared_at_[first], &c.w.prepared_at_[first] + (end - first), kUnprepared);  // degeneracy: unknown
    const uint32_t* local = c.m.region_local_.data();
    const uint32_t pool = c.m.pool_offsets_[s];
    uint32_t* slots = &c.w.kept_slot_[pool];
    float* boxes = &c.w.kept_box_[8 * size_t{pool}];
    uint32_t n = 0;
    for (uint32_t k = first; k < end; ++k) {  // branch-free: written always, counted when kept
      const uint32_t* l = local + 3 * size_t{k};
      slots[n] = k;
      n += (code[l[0]] & code[l[1]] & code[l[2]]) == 0;
    }
    float* chunk_row[6];
    ChunkRows(c, s, chunk_row);
    const uint32_t chunks = (n + kChunk - 1) / kChunk;
    for (uint32_t q = 0; q < chunks; ++q) {
      F4 chunk_lo = Set1(kInf), chunk_hi = Set1(-kInf);
      for (uint32_t i = q * kChunk; i < (q + 1) * kChunk; ++i) {
        F4 lo = Set1(kInf), hi = Set1(-kInf);  // padding: an inverted box
        if (i < n) {
          const uint32_t* l = local + 3 * size_t{slots[i]};
          const F4 p = Load4(corner + 4 * size_t{l[0]}), q4 = Load4(corner + 4 * size_t{l[1]});
          const F4 r = Load4(corner + 4 * size_t{l[2]});
          lo = Min4(r, Min4(q4, p)), hi = Max4(r, Max4(q4, p));
        }
        Store4(boxes + 8 * size_t{i}, lo);
        Store4(boxes + 8 * size_t{i} + 4, hi);
        chunk_lo = Min4(lo, chunk_lo), chunk_hi = Max4(hi, chunk_hi);
      }
      float box[8];
      Store4(box, chunk_lo);
      Store4(box + 4, chunk_hi);
      for (int d = 0; d < 3; ++d) chunk_row[d][q] = box[d], chunk_row[3 + d][q] = box[4 + d];
    }
    for (uint32_t q = chunks; q < (chunks + 3) / 4 * 4; ++q)
      for (int d = 0; d < 3; ++d) chunk_row[d][q] = kInf, chunk_row[3 + d][q] = -kInf;
    c.w.kept_[s] = n;
  }

  /// The six rows (min x, y, z, max x, y, z) of sphere s's chunk boxes.
  static void ChunkRows(Frame& c, uint32_t s, float* row[6]) {
    for (int d = 0; d < 6; ++d) row[d] = &c.w.chunk_box_[d * c.m.chunk_pitch_ + c.m.chunk_offsets_[s]];
  }

  /// Lanes (bits 0..3) of the four chunk boxes at `at` of six rows (min x, y, z, max x, y, z) that meet
  /// the box (lo, hi) (each F4 one coordinate broadcast), closed intervals.
  static uint32_t Overlap4(float* const row[6], size_t at, const F4 lo[3], const F4 hi[3]) {
    return Bits(And(And(And(Le(Load4(row[0] + at), hi[0]), Le(lo[0], Load4(row[3] + at))),
                        And(Le(Load4(row[1] + at), hi[1]), Le(lo[1], Load4(row[4] + at)))),
                    And(Le(Load4(row[2] + at), hi[2]), Le(lo[2], Load4(row[5] + at)))));
  }

  /// True when the 8-float box at b meets the box (lo, hi): closed intervals on x, y, z.
  static bool Meets(const float* b, F4 lo, F4 hi) {
    return (Bits(And(Le(Load4(b), hi), Le(lo, Load4(b + 4)))) & 7) == 7;
  }

  /// The kept triangles of sphere s (CullRegion run) whose box meets `box` (8 floats), in slot order:
  /// list->kept gets their index among the kept triangles, list->rank their rank in this order. With
  /// kInner only those also meeting `inner` (8 floats) are listed, each with its rank among those
  /// meeting `box`. Chunks whose box misses `box` are skipped four at a time. Returns the number meeting
  /// `box`; *listed: the number listed.
  template <bool kInner>
  static uint32_t Filter(Frame& c, uint32_t s, const float* box, const float* inner, Culled* list,
                         uint32_t* listed) {
    const uint32_t pool = c.m.pool_offsets_[s], m = c.w.kept_[s];
    const float* boxes = &c.w.kept_box_[8 * size_t{pool}];
    float* chunk_row[6];
    ChunkRows(c, s, chunk_row);
    const F4 lo[3] = {Set1(box[0]), Set1(box[1]), Set1(box[2])};
    const F4 hi[3] = {Set1(box[4]), Set1(box[5]), Set1(box[6])};
    const F4 olo = Load4(box), ohi = Load4(box + 4);
    const F4 ilo = Load4(kInner ? inner : box), ihi = Load4(kInner ? inner + 4 : box + 4);
    uint32_t* kept = list->kept.data();
    uint32_t* rank = list->rank.data();
    uint32_t n = 0, n_inner = 0;
    const uint32_t chunks = (m + kChunk - 1) / kChunk;
    for (uint32_t q0 = 0; q0 < chunks; q0 += 4) {
      for (uint32_t hit = Overlap4(chunk_row, q0, lo, hi); hit; hit &= hit - 1) {
        const uint32_t first = (q0 + static_cast<uint32_t>(std::countr_zero(hit))) * kChunk;
        for (uint32_t i = first; i < first + kChunk; ++i) {  // branch-free: written always, counted when kept
          const float* b = boxes + 8 * size_t{i};
          const bool meets = Meets(b, olo, ohi);
          kept[n_inner] = i;
          rank[n_inner] = n;
          n_inner += kInner ? meets & Meets(b, ilo, ihi) : meets;
          n += meets;
        }
      }
    }
    *listed = n_inner;
    return n;
  }

  /// The box (8 floats) of the boxes of the n listed triangles of sphere s; inverted when n is 0.
  static void ListBox(const Frame& c, uint32_t s, const Culled& list, uint32_t n, float* out) {
    const float* boxes = &c.w.kept_box_[8 * size_t{c.m.pool_offsets_[s]}];
    F4 lo = Set1(kInf), hi = Set1(-kInf);
    for (uint32_t k = 0; k < n; ++k) {
      const float* b = boxes + 8 * size_t{list.kept[k]};
      lo = Min4(Load4(b), lo), hi = Max4(Load4(b + 4), hi);
    }
    Store4(out, lo);
    Store4(out + 4, hi);
  }

  /// Drops from the n listed triangles of sphere s those whose box misses `box`; ranks kept. Returns
  /// the number left.
  static uint32_t Tighten(const Frame& c, uint32_t s, const float* box, Culled* list, uint32_t n) {
    const float* boxes = &c.w.kept_box_[8 * size_t{c.m.pool_offsets_[s]}];
    const F4 lo = Load4(box), hi = Load4(box + 4);
    uint32_t* kept = list->kept.data();
    uint32_t* rank = list->rank.data();
    uint32_t left = 0;
    for (uint32_t k = 0; k < n; ++k) {  // branch-free: written always, counted when kept
      const uint32_t i = kept[k], r = rank[k];
      kept[left] = i;
      rank[left] = r;
      left += Meets(boxes + 8 * size_t{i}, lo, hi);
    }
    return left;
  }

  /// The n listed triangles of sphere s in sweep order: keyed by the box minimum on `axis`, ties by rank
  /// (slot order); their slots and boxes beside, by coordinate; sentinels after. The sort: a counting
  /// sort into n buckets over the range of the minima (bucket = ⌊(start − lo)·scale⌋: monotone in the
  /// start, float rounding being monotone), each key written at its bucket's place, then an insertion
  /// pass that only moves keys within their bucket (linear for spread minima, the exact order whatever
  /// they are), then the records gathered in key order.
  static void Sort(const Frame& c, uint32_t s, int axis, Culled* list, uint32_t n) {
    const uint32_t pool = c.m.pool_offsets_[s];
    const float* boxes = &c.w.kept_box_[8 * size_t{pool}];
    const uint32_t* kept = list->kept.data();
    const uint32_t* rank = list->rank.data();
    float* start = list->start.data();
    uint64_t* key = list->key.data();
    uint32_t* slot = list->slot.data();
    float* lo[3] = {list->lo[0].data(), list->lo[1].data(), list->lo[2].data()};
    float* hi[3] = {list->hi[0].data(), list->hi[1].data(), list->hi[2].data()};
    for (uint32_t r = n; r < n + kSentinels; ++r)  // sentinels: start after every box, overlap nothing
      for (int k = 0; k < 3; ++k) lo[k][r] = kInf, hi[k][r] = -kInf;
    if (n == 0) return;
    float s_lo = kInf, s_hi = -kInf;
    for (uint32_t k = 0; k < n; ++k) {
      start[k] = boxes[8 * size_t{kept[k]} + axis];
      s_lo = std::min(s_lo, start[k]), s_hi = std::max(s_hi, start[k]);
    }
    // (s_hi − s_lo)·scale < n in exact arithmetic; the clamp takes the rounding; a range too small for
    // a finite scale gets one bucket (still sorted, by the insertion pass alone).
    const uint32_t buckets = 2 * n;
    float scale = s_hi > s_lo ? static_cast<float>(buckets) / (s_hi - s_lo) * 0.999f : 0.0f;
    if (!(scale < 1e30f)) scale = 0.0f;
    const uint32_t top = buckets - 1;
    uint32_t* bucket = list->bucket.data();
    uint32_t* bucket_of = list->bucket_of.data();
    std::fill(bucket, bucket + buckets + 1, 0u);
    for (uint32_t k = 0; k < n; ++k) {
      bucket_of[k] = std::min(top, static_cast<uint32_t>((start[k] - s_lo) * scale));
      ++bucket[bucket_of[k] + 1];
    }
    for (uint32_t k = 1; k < buckets; ++k) bucket[k] += bucket[k - 1];
    // Sorted by (start, k): the same order as (start, rank), ranks ascending in k.
    for (uint32_t k = 0; k < n; ++k) key[bucket[bucket_of[k]]++] = uint64_t{OrderedBits(start[k])} << 32 | k;
    for (uint32_t k = 1; k < n; ++k) {
      if (!(key[k - 1] > key[k])) continue;  // rare: only within a bucket
      const uint64_t x = key[k];
      uint32_t j = k;
      for (; j > 0 && key[j - 1] > x; --j) key[j] = key[j - 1];
      key[j] = x;
    }
    // The records in key order; the boxes four at a time, transposed into the coordinate rows.
    uint32_t r = 0;
    for (; r + 4 <= n; r += 4) {
      const float* b[4];
      for (uint32_t t = 0; t < 4; ++t) {
        const uint32_t k = static_cast<uint32_t>(key[r + t]), i = kept[k];
        b[t] = boxes + 8 * size_t{i};
        key[r + t] = (key[r + t] & 0xFFFFFFFF00000000u) | rank[k];  // the sweep's order: (start, rank)
        slot[r + t] = c.w.kept_slot_[pool + i];
      }
      F4 l0 = Load4(b[0]), l1 = Load4(b[1]), l2 = Load4(b[2]), l3 = Load4(b[3]);
      F4 h0 = Load4(b[0] + 4), h1 = Load4(b[1] + 4), h2 = Load4(b[2] + 4), h3 = Load4(b[3] + 4);
      Transpose4(l0, l1, l2, l3);
      Transpose4(h0, h1, h2, h3);
      Store4(lo[0] + r, l0), Store4(lo[1] + r, l1), Store4(lo[2] + r, l2);
      Store4(hi[0] + r, h0), Store4(hi[1] + r, h1), Store4(hi[2] + r, h2);
    }
    for (; r < n; ++r) {
      const uint32_t k = static_cast<uint32_t>(key[r]), i = kept[k];
      const float* b = boxes + 8 * size_t{i};
      key[r] = (key[r] & 0xFFFFFFFF00000000u) | rank[k];
      slot[r] = c.w.kept_slot_[pool + i];
      for (int d = 0; d < 3; ++d) lo[d][r] = b[d], hi[d][r] = b[4 + d];
    }
  }

  /// The exact test of two box-overlapping triangles of different spheres (adjacency, degeneracy,
  /// predicate): position ia of a's sorted list, ib of b's.
  static void Test(Frame& c, uint32_t ia, uint32_t ib, uint32_t a, uint32_t b, const char* base,
                   size_t stride, const NarrowPhaseJob& job, NarrowPhaseStats& st) {
    const uint32_t ka = c.w.list_a_.slot[ia], kb = c.w.list_b_.slot[ib];
    const uint32_t* wa = &c.m.region_w_[3 * size_t{ka}];
    const uint32_t* wb = &c.m.region_w_[3 * size_t{kb}];
    if ((wa[0] == wb[0]) | (wa[0] == wb[1]) | (wa[0] == wb[2]) | (wa[1] == wb[0]) | (wa[1] == wb[1]) |
        (wa[1] == wb[2]) | (wa[2] == wb[0]) | (wa[2] == wb[1]) | (wa[2] == wb[2])) {  // one branch
      ++st.adjacent_skipped;
      return;
    }
    uint32_t ta = c.m.region_tri_[ka], tb = c.m.region_tri_[kb];
    uint32_t sa = a, sb = b;
    if (c.m.reach_) {
      // Overlapping regions: a contact is the owners' (different, not excluded), reported under the
      // listed candidate of lowest (a, b) that has the two triangles behind its two spheres.
      const uint16_t oa = c.m.tri_sphere_[ta], ob = c.m.tri_sphere_[tb];
      if (oa == ob) return;
      if (job.exclusions == Exclusions::kAsset && c.m.IsExcluded(oa, ob)) return;
      // Two triangles each behind both a and b meet twice under (a, b): once with ta in a's list, once
      // with it in b's. Only the meeting whose a-side triangle has the lower id goes on.
      auto behind = [&](uint32_t t, uint32_t s) {
        for (uint32_t i = c.m.behind_offsets_[t]; i < c.m.behind_offsets_[t + 1]; ++i)
          if (c.m.behind_[i] == s) return true;
        return false;
      };
      if (ta > tb && behind(ta, b) && behind(tb, a)) return;
      const uint32_t key = a << 16 | b;
      for (uint32_t i = c.m.behind_offsets_[ta]; i < c.m.behind_offsets_[ta + 1]; ++i)
        for (uint32_t j = c.m.behind_offsets_[tb]; j < c.m.behind_offsets_[tb + 1]; ++j) {
          const uint32_t x = c.m.behind_[i], y = c.m.behind_[j];
          if (x == y) continue;
          const uint32_t lo = std::min(x, y), hi = std::max(x, y);
          if ((lo << 16 | hi) < key && (ListedWord(c, lo, hi) >> (hi % 64) & 1)) return;
        }
      if (oa < ob) {
        sa = oa, sb = ob;
      } else {
        sa = ob, sb = oa;
        std::swap(ta, tb);
      }
    }
    uint32_t at[2] = {c.w.prepared_at_[ka], c.w.prepared_at_[kb]};
    if ((at[0] | at[1]) >= kDegenerate) {  // not both prepared already (the usual case once a pair is under way)
      for (int side = 0; side < 2; ++side) {
        const uint32_t k = side ? kb : ka;
        if (at[side] == kUnprepared) {  // prepared (degeneracy decided) once a frame, for triangles that reach a test
          const uint32_t* v = &c.m.region_v_[3 * size_t{k}];
          const bool usable = PrepareTriangle(Vertex(base, stride, v[0]), Vertex(base, stride, v[1]),
                                              Vertex(base, stride, v[2]), &c.w.prepared_[c.w.prepared_count_]);
          // Positions are finite (RegionBoxes): not usable ⇔ degenerate.
          c.w.prepared_at_[k] = at[side] = usable ? c.w.prepared_count_++ : kDegenerate;
          st.degenerate_triangles += !usable;
        }
        if (at[side] == kDegenerate) return;
      }
    }
    ++st.triangle_tests;
    if (!TrianglesIntersect(c.w.prepared_[at[0]], c.w.prepared_[at[1]])) return;
    if (st.contacts < job.capacity)
      job.output[st.contacts] = {ta, tb, static_cast<uint16_t>(sa), static_cast<uint16_t>(sb)};
    ++st.contacts;
  }

  /// Test() on the buffered hits, in order; the triangle data of the hits a few ahead fetched early.
  static void Tests(Frame& c, const uint64_t* hits, uint32_t n, uint32_t a, uint32_t b,
                    const char* base, size_t stride, const NarrowPhaseJob& job, NarrowPhaseStats& st) {
    constexpr uint32_t kAhead = 4;  // a hint, never a fault
    for (uint32_t h = 0; h < n; ++h) {
      if (h + kAhead < n) {
        // Unprepared (or degenerate) triangles have no data yet: the hint then lands past the pool's end.
        Prefetch(&c.w.prepared_[std::min(c.w.prepared_at_[c.w.list_a_.slot[static_cast<uint32_t>(hits[h + kAhead] >> 32)]], c.w.prepared_count_)]);
        Prefetch(&c.w.prepared_[std::min(c.w.prepared_at_[c.w.list_b_.slot[static_cast<uint32_t>(hits[h + kAhead])]], c.w.prepared_count_)]);
      }
      Test(c, static_cast<uint32_t>(hits[h] >> 32), static_cast<uint32_t>(hits[h]), a, b, base, stride, job, st);
    }
  }

  /// Every contact of candidate (a, b), a < b: both regions culled to the other's box, then a
  /// sort-and-sweep of the two lists along the longest axis of the boxes' overlap.
  static void Pair(Frame& c, uint32_t a, uint32_t b, const char* base, size_t stride,
                   const NarrowPhaseJob& job, NarrowPhaseStats* out_stats) {
    NarrowPhaseStats st = *out_stats;  // counters in registers, written back once
    const float* ba = &c.w.box_[8 * size_t{a}];
    const float* bb = &c.w.box_[8 * size_t{b}];
    int axis = 0;
    float extent = -1.0f;
    for (int k = 0; k < 3; ++k) {
      const float e = std::min(ba[4 + k], bb[4 + k]) - std::max(ba[k], bb[k]);
      if (e > extent) extent = e, axis = k;
    }
    Culled& la = c.w.list_a_;
    Culled& lb = c.w.list_b_;
    // The triangles of a whose box meets b's region box, and those of b meeting a's (counted: the
    // culled triangles); of those of b only the ones meeting a's listed boxes' box are listed, then of
    // a's only those meeting b's listed boxes' box. The dropped ones meet no box of the other list, so
    // the sweep below meets the same triangle pairs in the same order as on the full lists: ranks (the
    // order in the full lists) break ties of the minima.
    if (c.w.kept_[a] == kNotCulled) CullRegion(c, a, base, stride);
    uint32_t listed_a = 0, listed_b = 0, nb = 0;
    uint32_t na = Filter<false>(c, a, bb, nullptr, &la, &listed_a);
    if (na) {
      if (c.w.kept_[b] == kNotCulled) CullRegion(c, b, base, stride);
      float box_a[8], box_b[8];
      ListBox(c, a, la, na, box_a);
      nb = Filter<true>(c, b, ba, box_a, &lb, &listed_b);
      ListBox(c, b, lb, listed_b, box_b);
      st.culled_triangles += na + nb;
      na = Tighten(c, a, box_b, &la, na);
      nb = listed_b;
    }
    Sort(c, a, axis, &la, na);
    Sort(c, b, axis, &lb, nb);
    // Sweep: take the list whose next box starts first; test it against the other list's boxes that
    // start before it ends (on `axis` those overlap: the order says so), on the two other axes, four at
    // a time. Each overlapping pair is met exactly once. The sentinels end the inner loop. No branch on
    // the data but the loop ends: each step writes a record (its element, side, first box and hit
    // lanes), kept when it has a hit; the records become hits (position in a's list << 32 | in b's),
    // tested in order.
    struct View {
      const float *start, *end, *lo_u, *hi_u, *lo_v, *hi_v;
    };
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const View view[2] = {
        {la.lo[axis].data(), la.hi[axis].data(), la.lo[u].data(), la.hi[u].data(), la.lo[v].data(), la.hi[v].data()},
        {lb.lo[axis].data(), lb.hi[axis].data(), lb.lo[u].data(), lb.hi[u].data(), lb.lo[v].data(), lb.hi[v].data()}};
    const uint64_t* key_a = la.key.data();
    const uint64_t* key_b = lb.key.data();
    uint64_t* records = c.w.records_.data();
    const uint32_t records_full = static_cast<uint32_t>(c.w.records_.size()) - 1;
    uint32_t n_records = 0;
    auto flush = [&] {  // records → hits → tests
      uint64_t* hits = c.w.hits_.data();
      uint32_t n_hits = 0;
      for (uint32_t r = 0; r < n_records; ++r) {
        const uint64_t rec = records[r];
        const uint64_t x = rec >> 32, side = rec >> 31 & 1;
        const uint32_t k = static_cast<uint32_t>(rec >> 4) & 0x7FFFFFFu, hit = static_cast<uint32_t>(rec) & 15;
        for (uint32_t t = 0; t < 4; ++t) {  // the hit lanes packed to the front; all four written
          const uint64_t o = k + kHitLane[hit][t];
          hits[n_hits + t] = side ? (o << 32 | x) : (x << 32 | o);
        }
        n_hits += kHitCount[hit];
      }
      Tests(c, hits, n_hits, a, b, base, stride, job, st);
      n_records = 0;
    };
    uint32_t i = 0, j = 0;  // next of a, of b
    while (i < na && j < nb && !OverBudget(c, st)) {
      const uint32_t side = key_a[i] <= key_b[j] ? 0 : 1;  // same order as the minima (ties: rank, then a)
      const View& x = view[side];
      const View& o = view[side ^ 1];
      const uint32_t xi = side ? j : i;
      const F4 x_end = Set1(x.end[xi]);
      const F4 xlo_u = Set1(x.lo_u[xi]), xhi_u = Set1(x.hi_u[xi]);
      const F4 xlo_v = Set1(x.lo_v[xi]), xhi_v = Set1(x.hi_v[xi]);
      const uint64_t x_record = uint64_t{xi} << 32 | uint64_t{side} << 31;
      for (uint32_t k = side ? i : j;; k += 4) {
        const uint32_t started = Bits(Le(Load4(o.start + k), x_end));  // a prefix: minima ascending
        const uint32_t hit = started & Bits(And(And(Le(Load4(o.lo_u + k), xhi_u), Le(xlo_u, Load4(o.hi_u + k))),
                                                And(Le(Load4(o.lo_v + k), xhi_v), Le(xlo_v, Load4(o.hi_v + k)))));
        st.box_tests += static_cast<uint32_t>(std::countr_one(started));
        records[n_records] = x_record | uint64_t{k} << 4 | hit;
        n_records += hit != 0;
        if (n_records == records_full) flush();
        if (started != 15) break;
      }
      i += side ^ 1;
      j += side;
    }
    flush();
    *out_stats = st;
  }
};

template <class F>
void NarrowPhaseModel::ForEachArray(F&& f) {
  crease_graph_.ForEachArray(f);
  f(tri_v_), f(bind_contacts_);
  f(cl_tri_), f(cl_vert_offsets_), f(cl_vert_), f(near_far_), f(near_rows_);
  f(near_win_), f(near_base_), f(near_out_offsets_), f(near_out_), f(group_near_);
  f(cl_valid_), f(cl_local_), f(cl_count_);
  f(cull_pairs_), f(cl_ref_), f(cl_cull_offsets_), f(cl_cull_pair_), f(near_cross_);
  f(cull_anchor_), f(cl_slack_), f(cl_cull_w_), f(cl_cull_reach_), f(near_gap_), f(near_cross_reach_);
  f(sphere_patch_offsets_), f(sphere_patches_), f(patch_sphere_bits_), f(bind_patches_), f(patch_bind_);
  f(fold_pairs_), f(fold_bind_distance_);
  f(behind_offsets_), f(behind_), f(weld_), f(tri_sphere_);
  f(region_offsets_), f(region_tri_), f(region_v_), f(region_w_), f(vert_offsets_), f(vert_ids_), f(region_local_);
  f(excl_offsets_), f(excl_partners_), f(pool_offsets_), f(chunk_offsets_);
}

size_t NarrowPhaseModel::ArrayBytes() {
  size_t n = 0;
  ForEachArray([&](auto& v) { n += BlockBytesOf(v); });
  return n;
}

void NarrowPhaseModel::MoveInto(BlockArena* arena) {
  ForEachArray([&](auto& v) { MoveIntoBlock(v, arena); });
  excl_off_ = excl_offsets_.data();
  excl_nb_ = excl_partners_.data();
}

// The arrays carved from block_ release their storage through the arena header at the block's start, so
// they must go before the block does. The destructor destroys the members in reverse order (arrays first,
// block_ last); a memberwise move assignment would replace block_ first and free the block under them.
NarrowPhaseModel& NarrowPhaseModel::operator=(NarrowPhaseModel&& o) noexcept {
  if (this != &o) {
    this->~NarrowPhaseModel();
    new (this) NarrowPhaseModel(std::move(o));
  }
  return *this;
}

NarrowPhaseWorkspace& NarrowPhaseWorkspace::operator=(NarrowPhaseWorkspace&& o) noexcept {
  if (this != &o) {
    this->~NarrowPhaseWorkspace();
    new (this) NarrowPhaseWorkspace(std::move(o));
  }
  return *this;
}

Status NarrowPhaseModel::Init(const AssetView& view, NarrowPhaseRegions regions) {
  *this = NarrowPhaseModel{};
  if (Status s = Build(view, regions); s != Status::kOk) return s;
  BlockPtr block;  // outlives the reset below: arrays already moved into it are released through it
  SPHERECHAIN_TRY {
    const size_t bytes = BlockArena::BlockBytes(ArrayBytes());
    block = AllocateBlock(bytes);
    BlockArena* arena = BlockArena::Create(block.get(), bytes);
    MoveInto(arena);
    assert(arena->fallbacks == 0);
    arena->cursor = arena->end;  // sealed
    block_ = std::move(block);
    bytes_ = bytes;
  } SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = NarrowPhaseModel{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

Status NarrowPhaseModel::Build(const AssetView& view, NarrowPhaseRegions regions) {
  *this = NarrowPhaseModel{};
  if (!view.valid()) return Status::kErrorNullArgument;
  if (regions != NarrowPhaseRegions::kSurrounding && regions != NarrowPhaseRegions::kReach) return Status::kErrorInvalidJob;
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
    // Reach regions overlap: the owners come from the surrounding regions first.
    const bool reach = regions == NarrowPhaseRegions::kReach && a.reach_offsets();
    if (reach) {
      for (uint32_t s = 0; s < S; ++s) {
        const TriangleSpan span = SurroundingTriangles(view, s);
        for (uint32_t i = 0; i < span.count; ++i)
          if (tri_sphere_[span.data[i]] == kNoSphere) tri_sphere_[span.data[i]] = static_cast<uint16_t>(s);
      }
      behind_offsets_.assign(size_t{T} + 1, 0);
      for (uint32_t s = 0; s < S; ++s) {
        const TriangleSpan span = ReachTriangles(view, s);
        for (uint32_t i = 0; i < span.count; ++i) ++behind_offsets_[span.data[i] + 1];
      }
      for (uint32_t t = 0; t < T; ++t) behind_offsets_[t + 1] += behind_offsets_[t];
      behind_.assign(behind_offsets_[T], 0);
      std::vector<uint32_t> cursor(behind_offsets_.begin(), behind_offsets_.end() - 1);
      for (uint32_t s = 0; s < S; ++s) {
        const TriangleSpan span = ReachTriangles(view, s);
        for (uint32_t i = 0; i < span.count; ++i) behind_[cursor[span.data[i]]++] = static_cast<uint16_t>(s);
      }
    }
    for (uint32_t s = 0; s < S; ++s) {
      const TriangleSpan span = reach ? ReachTriangles(view, s) : SurroundingTriangles(view, s);
      verts.clear();
      for (uint32_t i = 0; i < span.count; ++i) {
        const uint32_t t = span.data[i];
        if (reach) {
          if (tri_sphere_[t] == kNoSphere) continue;  // no owner: in no contact
        } else {
          if (tri_sphere_[t] != kNoSphere) continue;  // listed twice: the first region owns it
          tri_sphere_[t] = static_cast<uint16_t>(s);
        }
        uint32_t v[3], w[3];
        for (int j = 0; j < 3; ++j) v[j] = tris->Get(3 * t + j), w[j] = weld_[v[j]];
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
          index_degenerate_ += !reach || tri_sphere_[t] == s;  // counted once, in its owner's region
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
    for (uint32_t s = 0; s < S; ++s)
      largest_region_ = std::max(largest_region_, region_offsets_[s + 1] - region_offsets_[s]);
    largest_region_vertices_ = largest_verts;
    box_pitch_ = S + 4;
    pool_offsets_.assign(1, 0);
    chunk_offsets_.assign(1, 0);
    for (uint32_t s = 0; s < S; ++s) {
      const uint32_t chunks = (region_offsets_[s + 1] - region_offsets_[s] + kChunk - 1) / kChunk;
      pool_offsets_.push_back(pool_offsets_[s] + chunks * kChunk);
      chunk_offsets_.push_back(chunk_offsets_[s] + (chunks + 3) / 4 * 4);
    }
    chunk_pitch_ = chunk_offsets_[S];
    sphere_count_ = S;
    vertex_count_ = V;
    triangle_count_ = T;
    reach_ = reach;
    if (Status cs = InitCreaseModel(*this, view); cs != Status::kOk) {
      *this = NarrowPhaseModel{};
      return cs;
    }
    excl_off_ = excl_offsets_.data();
    excl_nb_ = excl_partners_.data();
    id_ = g_next_narrow_model_id.fetch_add(1, std::memory_order_relaxed);
    NarrowPhaseWorkspace sizing;  // on the heap: what its block must hold
    if (Status ws = sizing.Build(*this, nullptr); ws != Status::kOk) {
      *this = NarrowPhaseModel{};
      return ws;
    }
    workspace_bytes_ = 0;
    sizing.ForEachArray([&](auto& v) { workspace_bytes_ += BlockBytesOf(v); });
    workspace_bytes_ = BlockArena::BlockBytes(workspace_bytes_);
  } SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = NarrowPhaseModel{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

template <class F>
void NarrowPhaseWorkspace::ForEachArray(F&& f) {
  f(box_), f(box_soa_), f(clip_), f(kept_), f(prepared_at_), f(prepared_), f(outcode_), f(corner_);
  f(kept_slot_), f(kept_box_), f(chunk_box_), f(records_), f(hits_), f(candidates_), f(listed_);
  for (Culled* l : {&list_a_, &list_b_}) {
    f(l->key), f(l->kept), f(l->rank), f(l->start), f(l->bucket), f(l->bucket_of), f(l->slot);
    for (int k = 0; k < 3; ++k) f(l->lo[k]), f(l->hi[k]);
  }
  f(patch_box_), f(group_box_), f(sweep_), f(sweep_box_), f(sweep_hits_), f(patch_tri_box_), f(tri_prepared_), f(tri_frame_);
  f(filter_pool_), f(filter_mask_), f(patch_filter_);
  f(cull_t_), f(cull_f_), f(cull_smin_), f(cull_e_), f(patch_tri_frame_), f(patch_active_), f(patch_partner_bits_);
  crease_scratch_.ForEachArray(f);
}

Status NarrowPhaseWorkspace::Init(const NarrowPhaseModel& model) {
  *this = NarrowPhaseWorkspace{};
  if (!model.initialized()) return Status::kErrorInvalidJob;
  BlockPtr block;  // outlives the reset below: arrays already carved from it are released through it
  SPHERECHAIN_TRY {
    block = AllocateBlock(model.workspace_bytes_);
    BlockArena* arena = BlockArena::Create(block.get(), model.workspace_bytes_);
    if (Status s = Build(model, arena); s != Status::kOk) return s;
    assert(arena->fallbacks == 0);  // workspace_bytes() measured the same arrays
    block_ = std::move(block);
  } SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = NarrowPhaseWorkspace{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

Status NarrowPhaseWorkspace::Build(const NarrowPhaseModel& model, BlockArena* arena) {
  *this = NarrowPhaseWorkspace{};
  if (!model.initialized()) return Status::kErrorInvalidJob;
  SPHERECHAIN_TRY {
    ForEachArray([&](auto& v) { UseBlock(v, arena); });
    const uint32_t S = model.sphere_count_;
    const uint32_t largest = model.largest_region_, largest_verts = model.largest_region_vertices_;
    const size_t box_pitch = model.box_pitch_;
    box_.assign(8 * size_t{S}, 0.0f);
    box_soa_.assign(6 * box_pitch, 0.0f);
    for (uint32_t s = S; s < box_pitch; ++s)  // padding: inverted boxes
      for (int k = 0; k < 6; ++k) box_soa_[k * box_pitch + s] = k < 3 ? kInf : -kInf;
    clip_.assign(8 * size_t{S}, 0.0f);
    kept_.assign(S, kNotCulled);
    prepared_at_.assign(model.region_tri_.size(), kUnprepared);
    prepared_.assign(model.region_tri_.size() + 1, PreparedTriangle{});  // + 1: a prefetch target past the used ones
    outcode_.assign(largest_verts, 0);
    corner_.assign(4 * size_t{largest_verts}, 0.0f);
    const size_t pool = model.pool_offsets_[S];
    kept_slot_.assign(pool, 0);
    kept_box_.assign(8 * pool, 0.0f);
    chunk_box_.assign(6 * size_t{model.chunk_pitch_}, 0.0f);
    records_.assign(64, 0);
    hits_.assign(4 * records_.size(), 0);
    candidates_.assign(std::min(size_t{S} * (S - 1) / 2, 16 * size_t{S} + 64), 0);
    if (model.reach_) listed_.assign(size_t{S} * ((S + 63) / 64), 0);
    for (Culled* l : {&list_a_, &list_b_}) {
      l->key.assign(largest, 0);
      l->start.assign(largest, 0.0f);
      l->bucket.assign(2 * size_t{largest} + 1, 0);
      l->bucket_of.assign(largest, 0);
      l->kept.assign(largest + kChunk, 0);  // Filter writes one past the listed ones (padding included)
      l->rank.assign(largest + kChunk, 0);
      l->slot.assign(largest + kSentinels, 0);
      for (int k = 0; k < 3; ++k) l->lo[k].assign(largest + kSentinels, 0.0f), l->hi[k].assign(largest + kSentinels, 0.0f);
    }
    if (Status cs = InitCreaseWorkspace(*this, model, arena); cs != Status::kOk) {
      *this = NarrowPhaseWorkspace{};
      return cs;
    }
    if (arena) arena->cursor = arena->end;  // sealed
    model_id_ = model.id_;
  } SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = NarrowPhaseWorkspace{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

bool NarrowPhaseModel::IsExcluded(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  if (b >= sphere_count_) return false;
  const uint16_t* begin = excl_nb_ + excl_off_[a];
  const uint16_t* end = excl_nb_ + excl_off_[a + 1];
  return std::binary_search(begin, end, static_cast<uint16_t>(b));
}

Status NarrowPhaseJob::Check() const {
  if (!model || !workspace || !count || !positions.data) return Status::kErrorNullArgument;
  if (!output && capacity > 0) return Status::kErrorNullArgument;
  if (!sphere_pairs && sphere_pair_count > 0) return Status::kErrorNullArgument;
  if (!model->initialized() || !workspace->initialized()) return Status::kErrorInvalidJob;
  if (!workspace->made_for(*model)) return Status::kErrorWorkspaceModel;
  if (exclusions != Exclusions::kAsset && exclusions != Exclusions::kNone && exclusions != Exclusions::kCrease)
    return Status::kErrorInvalidJob;
  if (exclusions == Exclusions::kCrease) {
    if (!model->has_crease()) return Status::kErrorMissingField;
    if (!std::isfinite(crease) || crease < 0.0f || (crease > 0.0f && crease < model->crease()))
      return Status::kErrorInvalidJob;
  } else if (crease != 0.0f) {
    return Status::kErrorInvalidJob;  // a crease means the crease rule; silently ignored it would mislead
  }
  if (joint_matrices) {
    if (exclusions != Exclusions::kCrease) return Status::kErrorInvalidJob;
    if (!model->has_joint_cull()) return Status::kErrorMissingField;
    if (joint_count != model->joint_count()) return Status::kErrorJointCount;
    if (reinterpret_cast<uintptr_t>(joint_matrices) % 4 != 0) return Status::kErrorAlignment;
  }
  if (reinterpret_cast<uintptr_t>(positions.data) % 4 != 0) return Status::kErrorAlignment;
  if (positions.stride_bytes < 12 || positions.stride_bytes % 4 != 0) return Status::kErrorStride;
  if (positions.count != model->vertex_count()) return Status::kErrorVertexCount;
  for (uint32_t i = 0; i < sphere_pair_count; ++i)
    if (sphere_pairs[i].a >= sphere_pairs[i].b || sphere_pairs[i].b >= model->sphere_count())
      return Status::kErrorIndexOutOfRange;
  return Status::kOk;
}

Status NarrowPhaseJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  if (exclusions == Exclusions::kCrease) return RunCrease(*this);
  NarrowPhaseInternal::Frame c{*model, *workspace};
  {  // the budget (NarrowPhaseModel::kSweepTestsPerTriangle): the crease rule's tests, and its box tests at its
     // pairs of patches' budget (16 x 16 a pair, 16 triangles a patch)
    const uint64_t T = model->triangle_count();
    c.test_budget = SweepLimit(NarrowPhaseModel::kSweepTestsPerTriangle, T);
    c.box_budget = SweepLimit(uint64_t{NarrowPhaseModel::kSweepPairsPerPatch} * 16, T);
  }
  NarrowPhaseStats st;
  *count = 0;
  if (stats) *stats = st;
  const char* base = static_cast<const char*>(positions.data);
  const size_t stride = positions.stride_bytes;
  if (!NarrowPhaseInternal::RegionBoxes(c, base, stride)) return Status::kErrorNonFinitePositions;
  std::fill(c.w.kept_.begin(), c.w.kept_.end(), kNotCulled);               // regions: culled on first use
  c.w.prepared_count_ = 0;
  // Pass 1: each sphere's clip, the box of its candidate partners' boxes ∩ its own (inverted: none);
  // the candidates kept for pass 2 while they fit (else enumerated again).
  for (size_t i = 0; i < c.w.clip_.size(); ++i) c.w.clip_[i] = i % 8 < 4 ? kInf : -kInf;
  uint32_t n_cand = 0;
  const uint32_t cand_capacity = static_cast<uint32_t>(c.w.candidates_.size());
  const bool reach = c.m.reach_;
  NarrowPhaseInternal::ForEachCandidate(c, *this, [&](uint32_t a, uint32_t b) {
    NarrowPhaseInternal::GrowClip(c, a, &c.w.box_[8 * size_t{b}]);
    NarrowPhaseInternal::GrowClip(c, b, &c.w.box_[8 * size_t{a}]);
    if (n_cand < cand_capacity) c.w.candidates_[n_cand] = a << 16 | b;
    ++n_cand;
    if (reach) NarrowPhaseInternal::ListedWord(c, a, b) |= uint64_t{1} << (b % 64);
  });
  // Pass 2: the same candidates, in output order.
  auto pair = [&](uint32_t a, uint32_t b) {
    if (NarrowPhaseInternal::OverBudget(c, st)) return;  // positions that are no pose: the rest skipped
    ++st.candidate_pairs;
    NarrowPhaseInternal::Pair(c, a, b, base, stride, *this, &st);
  };
  if (n_cand <= cand_capacity) {
    for (uint32_t i = 0; i < n_cand; ++i) pair(c.w.candidates_[i] >> 16, c.w.candidates_[i] & 0xFFFFu);
  } else {
    NarrowPhaseInternal::ForEachCandidate(c, *this, pair);
  }
  if (reach) {  // the candidates' bits, cleared for the next Run
    auto clear = [&](uint32_t a, uint32_t b) { NarrowPhaseInternal::ListedWord(c, a, b) = 0; };
    if (n_cand <= cand_capacity) {
      for (uint32_t i = 0; i < n_cand; ++i) clear(c.w.candidates_[i] >> 16, c.w.candidates_[i] & 0xFFFFu);
    } else {
      NarrowPhaseInternal::ForEachCandidate(c, *this, clear);
    }
  }
  if (stats) *stats = st;
  if (NarrowPhaseInternal::OverBudget(c, st)) return Status::kErrorFrameTangled;  // count 0
  *count = std::min(st.contacts, capacity);
  return st.contacts > capacity ? Status::kOkTruncated : Status::kOk;
}

Status FoldPairs(const NarrowPhaseModel& model, const SphereArrays& spheres, float closing, Collision* out,
                 uint32_t capacity, uint32_t* count) {
  if (count) *count = 0;
  if (!count || (!out && capacity > 0) || !spheres.x || !spheres.y || !spheres.z || !spheres.r)
    return Status::kErrorNullArgument;
  if (!model.initialized() || !model.has_crease() || !std::isfinite(closing) || closing < 0.0f)
    return Status::kErrorInvalidJob;
  if (spheres.count != model.sphere_count()) return Status::kErrorCountMismatch;
  uint32_t n = 0;
  for (size_t i = 0; i < model.fold_pairs_.size(); ++i) {
    const uint32_t a = model.fold_pairs_[i] >> 16, b = model.fold_pairs_[i] & 0xFFFFu;
    const float dx = spheres.x[a] - spheres.x[b], dy = spheres.y[a] - spheres.y[b], dz = spheres.z[a] - spheres.z[b];
    const float d = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(d < model.fold_bind_distance_[i] - closing)) continue;  // NaN: false
    if (n < capacity)
      out[n] = Collision{static_cast<uint16_t>(a), static_cast<uint16_t>(b), spheres.r[a] + spheres.r[b] - d, 0u};
    ++n;
  }
  *count = n;
  return n > capacity ? Status::kOkTruncated : Status::kOk;
}

}  // namespace spherechain::runtime
