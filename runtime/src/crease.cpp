// spherechain runtime — the crease rule (crease.h): the welded bind surface as an edge graph, and the
// bounded Dijkstra that decides whether two triangles are near on it.
#include "spherechain/runtime/crease.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>

#include "alloc_guard.h"

namespace spherechain::runtime {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Non-negative floats order like their bits: a heap key of distance bits << 32 | node.
uint64_t Key(float d, uint32_t node) {
  uint32_t bits;
  std::memcpy(&bits, &d, 4);
  return uint64_t{bits} << 32 | node;
}
float KeyDistance(uint64_t key) {
  const uint32_t bits = static_cast<uint32_t>(key >> 32);
  float d;
  std::memcpy(&d, &bits, 4);
  return d;
}

}  // namespace

Status CreaseGraph::Init(const float* bind, uint32_t V, const uint32_t* tris, uint32_t T, const uint32_t* weld,
                         float crease) {
  *this = CreaseGraph{};
  if ((V > 0 && !bind) || (T > 0 && !tris)) return Status::kErrorNullArgument;
  if (!(crease > 0.0f) || !std::isfinite(crease)) return Status::kErrorInvalidJob;
  for (size_t i = 0; i < size_t{3} * V; ++i)
    if (!std::isfinite(bind[i])) return Status::kErrorNonFinite;
  for (size_t i = 0; i < size_t{3} * T; ++i)
    if (tris[i] >= V) return Status::kErrorIndexOutOfRange;
  if (weld)
    for (uint32_t v = 0; v < V; ++v)
      if (weld[v] > v || weld[weld[v]] != weld[v]) return Status::kErrorIndexOutOfRange;
  SPHERECHAIN_TRY {
    CreaseGraph g;
    g.node_of_.resize(V);
    std::vector<uint32_t> rep;  // node → its representative vertex
    for (uint32_t v = 0; v < V; ++v) {
      const uint32_t w = weld ? weld[v] : v;
      if (w == v) {
        g.node_of_[v] = static_cast<uint32_t>(rep.size());
        rep.push_back(v);
      } else {
        g.node_of_[v] = g.node_of_[w];
      }
    }
    g.node_count_ = static_cast<uint32_t>(rep.size());
    // Undirected edges of the welded triangles (index-degenerate edges dropped), deduplicated.
    std::vector<uint64_t> edges;
    edges.reserve(size_t{6} * T);
    for (uint32_t t = 0; t < T; ++t)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = g.node_of_[tris[3 * t + k]], b = g.node_of_[tris[3 * t + (k + 1) % 3]];
        if (a == b) continue;
        edges.push_back(uint64_t{a} << 32 | b);
        edges.push_back(uint64_t{b} << 32 | a);
      }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    g.offsets_.assign(size_t{g.node_count_} + 1, 0);
    g.adj_.resize(edges.size());
    g.length_.resize(edges.size());
    for (size_t i = 0; i < edges.size(); ++i) {
      const uint32_t a = static_cast<uint32_t>(edges[i] >> 32), b = static_cast<uint32_t>(edges[i]);
      ++g.offsets_[a + 1];
      g.adj_[i] = b;
      const float* pa = bind + 3 * size_t{rep[a]};
      const float* pb = bind + 3 * size_t{rep[b]};
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += (double(pa[k]) - pb[k]) * (double(pa[k]) - pb[k]);
      g.length_[i] = static_cast<float>(std::sqrt(d2));
    }
    for (uint32_t n = 0; n < g.node_count_; ++n) g.offsets_[n + 1] += g.offsets_[n];
    // Connected components of the nodes some triangle uses (a vertex in no triangle is no piece of the
    // surface; a triangle whose corners weld into one node is a piece of its own).
    std::vector<uint8_t> used(g.node_count_, 0);
    for (size_t i = 0; i < size_t{3} * T; ++i) used[g.node_of_[tris[i]]] = 1;
    std::vector<uint32_t> comp(g.node_count_, ~0u), stack;
    for (uint32_t s = 0; s < g.node_count_; ++s) {
      if (comp[s] != ~0u || !used[s]) continue;
      comp[s] = g.components_;
      stack.assign(1, s);
      while (!stack.empty()) {
        const uint32_t n = stack.back();
        stack.pop_back();
        for (uint32_t i = g.offsets_[n]; i < g.offsets_[n + 1]; ++i)
          if (comp[g.adj_[i]] == ~0u) comp[g.adj_[i]] = g.components_, stack.push_back(g.adj_[i]);
      }
      ++g.components_;
    }
    g.crease_ = crease;
    *this = std::move(g);
  }
  SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = CreaseGraph{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

Status CreaseScratch::Init(const CreaseGraph& graph, BlockArena* arena) {
  *this = CreaseScratch{};
  if (!graph.initialized()) return Status::kErrorInvalidJob;
  SPHERECHAIN_TRY {
    ForEachArray([&](auto& v) { UseBlock(v, arena); });
    dist_.assign(graph.node_count_, kInf);
    ring_.assign(graph.node_count_, 0);
    touched_.reserve(graph.node_count_);
    heap_.reserve(graph.adj_.size() + 3);
    entries_.assign(graph.adj_.size() + 3, 0);
    next_.assign(graph.adj_.size() + 3, 0);
  }
  SPHERECHAIN_CATCH_BAD_ALLOC {
    *this = CreaseScratch{};
    return Status::kErrorOutOfMemory;
  }
  return Status::kOk;
}

void CreaseScratch::Search(const CreaseGraph& g, const uint32_t t[3], float crease) {
  uint32_t src[3];
  for (int k = 0; k < 3; ++k) src[k] = g.node_of_[t[k]];
  if (!(src[0] == source_[0] && src[1] == source_[1] && src[2] == source_[2] && crease == source_crease_)) {
    for (uint32_t n : touched_) dist_[n] = kInf, ring_[n] = 0;
    touched_.clear();
    heap_.clear();
    auto touch = [&](uint32_t n) {
      if (dist_[n] == kInf && !ring_[n]) touched_.push_back(n);
    };
    for (uint32_t s : src) {
      touch(s);
      ring_[s] = 1;
      for (uint32_t i = g.offsets_[s]; i < g.offsets_[s + 1]; ++i) touch(g.adj_[i]), ring_[g.adj_[i]] = 1;
    }
    for (uint32_t s : src) dist_[s] = 0.0f;
    const size_t ring_nodes = touched_.size();
    if (heap_only_ || !Buckets(g, crease)) {
      // The bucket queue's entries ran out (a mesh with many edges far shorter than its crease), now or in an
      // earlier search since Reset: the search on a binary heap, whose entries never run out. Every node but
      // the sources is forgotten, including those reached at distance 0 (edges of length 0 between nodes not
      // welded): kept at 0 they would never be expanded again, and those past the ring would stay at 0 for
      // later searches.
      for (size_t i = 0; i < touched_.size(); ++i) {
        const uint32_t n = touched_[i];
        if (n != src[0] && n != src[1] && n != src[2]) dist_[n] = kInf;
      }
      touched_.resize(ring_nodes);
      heap_.clear();
      for (uint32_t s : src) heap_.push_back(Key(0.0f, s));
      std::sort(heap_.begin(), heap_.end());
      heap_.erase(std::unique(heap_.begin(), heap_.end()), heap_.end());
      Heap(g, crease);
      heap_only_ = true;
    }
    for (int k = 0; k < 3; ++k) source_[k] = src[k];
    source_crease_ = crease;
  }
}

// The edges of node n, settled at distance d: each neighbour that gets nearer than both its distance and the
// crease takes the new distance, is recorded as touched, and is pushed (push(distance, node)); false as soon
// as push refuses.
template <class Push>
bool CreaseScratch::Relax(const CreaseGraph& g, uint32_t n, float d, float crease, Push&& push) {
  for (uint32_t i = g.offsets_[n]; i < g.offsets_[n + 1]; ++i) {
    const uint32_t m = g.adj_[i];
    const float nd = d + g.length_[i];
    if (!(nd < crease) || !(nd < dist_[m])) continue;
    if (dist_[m] == kInf && !ring_[m]) touched_.push_back(m);
    dist_[m] = nd;
    if (!push(nd, m)) return false;
  }
  return true;
}

// Bounded Dijkstra (Dijkstra 1959) from the nodes at distance 0, every node closer than `crease` settled,
// on a bucket queue (Dial 1969): 256 buckets of crease / 256, entries chained in entries_ / next_. A node
// is relaxed from its bucket in any order within it; a relaxation into the same bucket (an edge shorter
// than a bucket) is processed later in the same bucket, so every node ends at the minimum over paths of its
// left-to-right float sum, as the binary heap gives (float addition is monotone). False when the entries
// ran out (the search is then incomplete: the caller runs Heap).
bool CreaseScratch::Buckets(const CreaseGraph& g, float crease) {
  const float width = crease / kBuckets;
  head_.fill(kNil);
  uint32_t used = 0;
  const uint32_t capacity = static_cast<uint32_t>(entries_.size());
  for (uint32_t n : touched_)
    if (dist_[n] == 0.0f) {
      if (used == capacity) return false;
      entries_[used] = Key(0.0f, n), next_[used] = head_[0], head_[0] = used++;
    }
  for (uint32_t b = 0; b < kBuckets; ++b)
    while (head_[b] != kNil) {
      const uint32_t e = head_[b];
      head_[b] = next_[e];
      const uint32_t n = static_cast<uint32_t>(entries_[e]);
      const float d = KeyDistance(entries_[e]);
      if (d > dist_[n]) continue;  // stale
      const bool room = Relax(g, n, d, crease, [&](float nd, uint32_t m) {
        if (used == capacity) return false;
        // The last bucket when nd / width is not below it, or is NaN or infinite (a crease so small that
        // its bucket width rounds to 0): converting those to an integer is undefined.
        const float at = nd / width;
        const uint32_t to = std::max(b, at < static_cast<float>(kBuckets - 1) ? static_cast<uint32_t>(at) : kBuckets - 1);
        entries_[used] = Key(nd, m), next_[used] = head_[to], head_[to] = used++;
        return true;
      });
      if (!room) return false;
    }
  return true;
}

// The same search on a binary heap of (distance, node) keys (heap_ holds the sources at distance 0). Each
// push follows a strict improvement of one adjacency entry's target, so the heap never holds more than
// #edges + 3 keys (its capacity).
void CreaseScratch::Heap(const CreaseGraph& g, float crease) {
  std::make_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
    const uint64_t key = heap_.back();
    heap_.pop_back();
    const uint32_t n = static_cast<uint32_t>(key);
    const float d = KeyDistance(key);
    if (d > dist_[n]) continue;  // stale
    Relax(g, n, d, crease, [&](float nd, uint32_t m) {
      if (heap_.size() < heap_.capacity()) {
        heap_.push_back(Key(nd, m));
        std::push_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
      }
      return true;
    });
  }
}

const BlockVector<uint32_t>& CreaseScratch::Reach(const CreaseGraph& g, const uint32_t t[3], float crease) {
  Search(g, t, crease);
  return touched_;
}

bool CreaseScratch::Near(const CreaseGraph& g, const uint32_t t[3], const uint32_t u[3], float crease) {
  Search(g, t, crease);
  uint32_t dst[3];
  for (int k = 0; k < 3; ++k) dst[k] = g.node_of_[u[k]];
  for (uint32_t n : dst)
    if (ring_[n] || dist_[n] < crease) return true;
  return false;
}

}  // namespace spherechain::runtime
