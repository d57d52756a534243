// spherechain runtime — the narrow phase under the skin's own definition (Exclusions::kCrease): every
// triangle swept against every other at once (sort and sweep on the longest axis of the mesh's box), pairs
// sharing a welded corner skipped, the rest tested exactly (TrianglesIntersect on prepared triangles), and
// each intersecting pair kept unless the crease rule (crease.h) calls it a fold.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>

#include "alloc_guard.h"
#include "spherechain/runtime/narrow_phase.h"

namespace spherechain::runtime {

namespace {
constexpr float kSweepInf = std::numeric_limits<float>::infinity();

// Maps a float to a uint32 of the same order (negative floats flipped).
uint32_t OrderedBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
}  // namespace

struct CreaseSweep {
  struct Counters {
    uint32_t box_tests = 0, adjacent = 0, tests = 0, degenerate = 0, folds = 0, contacts = 0;
  };

  /// Every triangle's box from `base`/`stride` into ws.tri_box_ and the sweep keys into ws.sweep_ (sorted);
  /// returns the number of keys, or ~0u when a corner is NaN/Inf.
  static uint32_t Boxes(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                        int* axis_out) {
    const uint32_t T = m.triangle_count_;
    float* box = w.tri_box_.data();
    float lo[3] = {kSweepInf, kSweepInf, kSweepInf}, hi[3] = {-kSweepInf, -kSweepInf, -kSweepInf};
    for (uint32_t t = 0; t < T; ++t) {
      float bl[3] = {kSweepInf, kSweepInf, kSweepInf}, bh[3] = {-kSweepInf, -kSweepInf, -kSweepInf};
      for (int j = 0; j < 3; ++j) {
        const float* p = reinterpret_cast<const float*>(base + stride * m.tri_v_[3 * size_t{t} + j]);
        for (int k = 0; k < 3; ++k) {
          if (!std::isfinite(p[k])) return ~0u;
          bl[k] = std::min(bl[k], p[k]);
          bh[k] = std::max(bh[k], p[k]);
        }
      }
      for (int k = 0; k < 3; ++k) {
        box[k * size_t{T} + t] = bl[k];
        box[(3 + k) * size_t{T} + t] = bh[k];
        lo[k] = std::min(lo[k], bl[k]);
        hi[k] = std::max(hi[k], bh[k]);
      }
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    *axis_out = axis;
    uint32_t n = 0;
    for (uint32_t t = 0; t < T; ++t) {
      const uint32_t* v = &m.tri_v_[3 * size_t{t}];
      const uint32_t w0 = m.weld_[v[0]], w1 = m.weld_[v[1]], w2 = m.weld_[v[2]];
      if (w0 == w1 || w1 == w2 || w0 == w2) continue;  // index-degenerate: never tested
      w.sweep_[n++] = uint64_t{OrderedBits(box[axis * size_t{T} + t])} << 32 | t;
    }
    std::sort(w.sweep_.begin(), w.sweep_.begin() + n);
    std::fill(w.tri_state_.begin(), w.tri_state_.end(), uint8_t{0});
    return n;
  }

  static bool Prepared(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                       uint32_t t, Counters* c) {
    uint8_t& state = w.tri_state_[t];
    if (state == 0) {
      const uint32_t* v = &m.tri_v_[3 * size_t{t}];
      const float* p[3];
      for (int j = 0; j < 3; ++j) p[j] = reinterpret_cast<const float*>(base + stride * v[j]);
      state = PrepareTriangle(p[0], p[1], p[2], &w.tri_prepared_[t]) ? 1 : 2;
      c->degenerate += state == 2;
    }
    return state == 1;
  }

  /// Sweeps the sorted keys; calls on_contact(t, u) for each intersecting pair the crease rule keeps.
  template <class OnContact>
  static void Sweep(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                    uint32_t n, int axis, float crease, Counters* c, OnContact&& on_contact) {
    const uint32_t T = m.triangle_count_;
    const float* box = w.tri_box_.data();
    const float* hi_axis = box + (3 + axis) * size_t{T};
    const int o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
    const float *lo1 = box + o1 * size_t{T}, *hi1 = box + (3 + o1) * size_t{T};
    const float *lo2 = box + o2 * size_t{T}, *hi2 = box + (3 + o2) * size_t{T};
    const float* lo_axis = box + axis * size_t{T};
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t t = static_cast<uint32_t>(w.sweep_[i]);
      const float end = hi_axis[t];
      const uint32_t* tv = &m.tri_v_[3 * size_t{t}];
      const uint32_t tw[3] = {m.weld_[tv[0]], m.weld_[tv[1]], m.weld_[tv[2]]};
      for (uint32_t j = i + 1; j < n; ++j) {
        const uint32_t u = static_cast<uint32_t>(w.sweep_[j]);
        if (lo_axis[u] > end) break;
        ++c->box_tests;
        if (lo1[u] > hi1[t] || hi1[u] < lo1[t] || lo2[u] > hi2[t] || hi2[u] < lo2[t]) continue;
        const uint32_t* uv = &m.tri_v_[3 * size_t{u}];
        const uint32_t uw[3] = {m.weld_[uv[0]], m.weld_[uv[1]], m.weld_[uv[2]]};
        bool shared = false;
        for (int a = 0; a < 3; ++a)
          shared |= tw[a] == uw[0] || tw[a] == uw[1] || tw[a] == uw[2];
        if (shared) {
          ++c->adjacent;
          continue;
        }
        if (!Prepared(m, w, base, stride, t, c)) break;  // t degenerate: in no contact
        if (!Prepared(m, w, base, stride, u, c)) continue;
        ++c->tests;
        if (!TrianglesIntersect(w.tri_prepared_[t], w.tri_prepared_[u])) continue;
        if (w.crease_scratch_.Near(m.crease_graph_, tv, uv, crease)) {
          ++c->folds;
          continue;
        }
        ++c->contacts;
        on_contact(t, u);
      }
    }
  }

  /// Model part: the index buffer, the graph and the bind pose's own contacts (one sweep of the bind pose).
  static Status InitModel(NarrowPhaseModel& m, const AssetView& view) {
    const schema::Asset& a = *view.asset;
    const auto* bind = a.bind_positions();
    if (!bind || !(a.crease() > 0.0f)) return Status::kOk;  // no crease rule: kCrease jobs refused
    const auto* tris = a.triangles();
    m.tri_v_.assign(tris->begin(), tris->end());
    if (Status s = m.crease_graph_.Init(bind->data(), view.vertex_count, m.tri_v_.data(), view.triangle_count,
                                        m.weld_.data(), a.crease());
        s != Status::kOk)
      return s;
    NarrowPhaseWorkspace w;
    if (Status s = InitWorkspace(w, m); s != Status::kOk) return s;
    int axis = 0;
    const char* base = reinterpret_cast<const char*>(bind->data());
    const uint32_t n = Boxes(m, w, base, 12, &axis);
    Counters c;
    Sweep(m, w, base, 12, n, axis, m.crease_graph_.crease(), &c, [&](uint32_t t, uint32_t u) {
      m.bind_contacts_.push_back(uint64_t{std::min(t, u)} << 32 | std::max(t, u));
    });
    std::sort(m.bind_contacts_.begin(), m.bind_contacts_.end());
    return Status::kOk;
  }

  static Status InitWorkspace(NarrowPhaseWorkspace& w, const NarrowPhaseModel& m) {
    if (!m.crease_graph_.initialized()) return Status::kOk;
    const uint32_t T = m.triangle_count_ ? m.triangle_count_ : static_cast<uint32_t>(m.tri_v_.size() / 3);
    w.tri_box_.assign(6 * size_t{T}, 0.0f);
    w.sweep_.assign(T, 0);
    w.tri_prepared_.assign(T, PreparedTriangle{});
    w.tri_state_.assign(T, 0);
    return w.crease_scratch_.Init(m.crease_graph_);
  }

  static Status Run(const NarrowPhaseJob& job) {
    const NarrowPhaseModel& m = *job.model;
    NarrowPhaseWorkspace& w = *job.workspace;
    NarrowPhaseStats st;
    *job.count = 0;
    if (job.stats) *job.stats = st;
    const char* base = static_cast<const char*>(job.positions.data);
    const size_t stride = job.positions.stride_bytes;
    int axis = 0;
    const uint32_t n = Boxes(m, w, base, stride, &axis);
    if (n == ~0u) return Status::kErrorNonFinitePositions;
    const float crease = job.crease > 0.0f ? job.crease : m.crease_graph_.crease();
    w.crease_scratch_.Reset();
    Counters c;
    uint32_t written = 0;
    Sweep(m, w, base, stride, n, axis, crease, &c, [&](uint32_t t, uint32_t u) {
      st.bind_contacts += m.IntersectsAtBind(t, u);
      if (written >= job.capacity) return;
      uint16_t sa = m.tri_sphere_[t], sb = m.tri_sphere_[u];
      if (sa > sb || (sa == sb && t > u)) std::swap(sa, sb), std::swap(t, u);
      job.output[written++] = TriangleContact{t, u, sa, sb};
    });
    st.box_tests = c.box_tests;
    st.adjacent_skipped = c.adjacent;
    st.triangle_tests = c.tests;
    st.degenerate_triangles = c.degenerate;
    st.crease_folds = c.folds;
    st.contacts = c.contacts;
    *job.count = written;
    if (job.stats) *job.stats = st;
    return st.contacts > job.capacity ? Status::kOkTruncated : Status::kOk;
  }
};

bool NarrowPhaseModel::IntersectsAtBind(uint32_t t, uint32_t u) const {
  const uint64_t key = uint64_t{std::min(t, u)} << 32 | std::max(t, u);
  return std::binary_search(bind_contacts_.begin(), bind_contacts_.end(), key);
}

Status InitCreaseModel(NarrowPhaseModel& m, const AssetView& view) { return CreaseSweep::InitModel(m, view); }
Status InitCreaseWorkspace(NarrowPhaseWorkspace& w, const NarrowPhaseModel& m) {
  return CreaseSweep::InitWorkspace(w, m);
}
Status RunCrease(const NarrowPhaseJob& job) { return CreaseSweep::Run(job); }

}  // namespace spherechain::runtime
