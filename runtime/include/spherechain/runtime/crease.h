// spherechain runtime — the crease rule: which intersecting triangles are a fold of the skin, not a contact.
//
// The definition of a self-contact (narrow_phase.h, Exclusions::kCrease): two triangles of the deformed
// mesh that share no welded corner, intersect (closed triangles, exact predicate), and are NOT near on the
// welded bind surface. Near means either
//   - within two triangle rings: a corner of one is a corner of the other or joined to one by a mesh edge
//     (so on a coarse mesh, whose edges are longer than the crease, a fold one ring wide is never a
//     self-contact), or
//   - a corner of one lies within `crease` of a corner of the other along the edges of the welded bind
//     mesh (Dijkstra 1959 on the edge graph: vertices merged by Asset.weld_ids, each edge weighted by its
//     bind-pose length).
// The edge-graph distance between corners is never shorter than the true geodesic distance between the two
// triangles (a path along edges is a path on the surface; the nearest points need not be corners), so the
// rule may call a pair "near" only when its geodesic distance is below the crease, and may call a pair
// "apart" whose geodesic distance is below the crease by at most the graph's detour: what it calls a fold is
// a fold. Measured against exact geodesics (CGAL Surface_mesh_shortest_path, runtime_bench --geodesics) the
// detour is ~8 % at the median and up to 1.4–1.7× on the characters of docs/runtime.md, so pairs as near as
// ~0.7 crease (exact) can be called apart. Skin that meets itself within the crease (the inside of an elbow,
// an armpit, a groin) is a fold; everything else is a self-contact, whichever spheres own the triangles.
// Default crease: 3 % of the body height (BakeConfig crease_rel), recorded in the asset (Asset.crease).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "spherechain/runtime/block_vector.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// The welded bind surface as a weighted edge graph, and the crease rule on it (file comment). Built from
/// plain arrays so the asset (Asset.bind_positions, triangles, weld_ids) and a mesh that has no asset
/// (spherechain evaluate's ground truth) use the same rule.
/// Ownership: owns its memory (BlockVector: allocated by Init on the heap; a NarrowPhaseModel moves them
/// into its block). Immutable after Init: shared by any number of CreaseScratch and threads. Move-only.
class CreaseGraph {
 public:
  CreaseGraph() = default;
  CreaseGraph(const CreaseGraph&) = delete;
  CreaseGraph& operator=(const CreaseGraph&) = delete;
  CreaseGraph(CreaseGraph&&) noexcept = default;
  CreaseGraph& operator=(CreaseGraph&&) noexcept = default;

  /// Builds the graph.
  /// @param bind_positions  \#V×3 floats [Units: model], the bind pose; borrowed during the call only.
  /// @param vertex_count    \#V
  /// @param triangles       \#T×3 vertex indices (< \#V)
  /// @param triangle_count  \#T
  /// @param weld_ids        \#V: weld_ids[v] <= v, the lowest vertex with v's bind position (Asset.weld_ids);
  ///                        null: no welding (each vertex its own)
  /// @param crease          [Units: model] > 0 and finite: the fold distance
  /// Returns kOk; kErrorNullArgument (a null array with a count > 0); kErrorInvalidJob (crease <= 0 or not
  /// finite); kErrorIndexOutOfRange (an index >= \#V, a weld id > its vertex); kErrorNonFinite (a bind
  /// coordinate); kErrorOutOfMemory. The graph is empty after a failure.
  /// Cost: O(\#T log \#T) time; memory 8 B per vertex + 8 B per directed edge (~0.3 MB for MakeHuman).
  Status Init(const float* bind_positions, uint32_t vertex_count, const uint32_t* triangles, uint32_t triangle_count,
              const uint32_t* weld_ids, float crease);

  bool initialized() const { return crease_ > 0.0f; }
  float crease() const { return crease_; }              ///< [Units: model]
  uint32_t vertex_count() const { return static_cast<uint32_t>(node_of_.size()); }  ///< \#V
  uint32_t node_count() const { return node_count_; }    ///< welded vertices
  uint32_t edge_count() const { return static_cast<uint32_t>(adj_.size() / 2); }  ///< undirected edges
  uint32_t components() const { return components_; }    ///< connected pieces of the welded surface
  /// Welded node of vertex `v` [Limit: < \#V].
  uint32_t node(uint32_t v) const { return node_of_[v]; }

  friend class CreaseScratch;

  /// Calls f(array) on each of its arrays (BlockVector): how an owner sizes its block and moves them in.
  template <class F>
  void ForEachArray(F&& f) {
    f(node_of_), f(offsets_), f(adj_), f(length_);
  }

 private:
  float crease_ = 0.0f;
  uint32_t node_count_ = 0, components_ = 0;
  BlockVector<uint32_t> node_of_;   // #V → welded node
  BlockVector<uint32_t> offsets_;   // CSR, node_count_ + 1
  BlockVector<uint32_t> adj_;       // neighbour nodes
  BlockVector<float> length_;       // bind length of each adjacency entry
};

/// Scratch of the crease rule for one thread: the distances from the last source triangle's corners. Keep
/// one per workspace; asking about many pairs that share their first triangle reuses its search.
/// Ownership: owns its memory (allocated by Init only). Not thread-safe (one caller at a time).
class CreaseScratch {
 public:
  /// Sizes the scratch for `graph`: its arrays on the heap, or carved from `arena` [opt] (a workspace's
  /// block, which must outlive the scratch; what does not fit goes to the heap). Returns kOk,
  /// kErrorInvalidJob (graph not initialised), kErrorOutOfMemory. Cost O(\#nodes + \#edges); memory 9 B
  /// per node + 20 B per directed edge.
  Status Init(const CreaseGraph& graph, BlockArena* arena = nullptr);
  /// True when sized for a graph of `graph`'s node count (what Near needs of it).
  bool made_for(const CreaseGraph& graph) const {
    return graph.initialized() && dist_.size() == graph.node_count() && heap_.capacity() >= graph.edge_count() * 2 + 3;
  }

  /// True when the triangles with corners `t` and `u` (vertex indices < \#V) are near on the bind surface
  /// (file comment) for a fold distance `crease` [Limit: 0 < crease; the graph's own crease or any other].
  /// [Limit: made_for(graph); a scratch used with several graphs of one node count must be Reset between them]
  /// Searches from t's corners out to `crease` (bounded Dijkstra, once per distinct (t, crease) in a row; on a
  /// bucket queue of 256 buckets of crease / 256, Dial 1969, or a binary heap should its entries run out —
  /// and on the heap alone for the scratch's later searches, until Reset: the same distances either way).
  /// Cost: O(k log k) for the k edges within the crease of t on a new source, O(1) after. No allocation.
  bool Near(const CreaseGraph& graph, const uint32_t t[3], const uint32_t u[3], float crease);
  /// The nodes near the triangle with corners `t` (vertex indices < \#V) for `crease`: its corners, their
  /// edge neighbours and every node within `crease` of a corner (unordered, no repeats). A triangle u is
  /// near t (Near) exactly when one of u's corners' nodes (CreaseGraph::node) is in this list. The span
  /// is the scratch's own and valid until the next Near, Reach or Reset. Same search and cost as Near.
  const BlockVector<uint32_t>& Reach(const CreaseGraph& graph, const uint32_t t[3], float crease);
  /// Forgets the last source (the next Near searches again), and goes back to the bucket queue. O(1).
  void Reset() { source_crease_ = -1.0f, heap_only_ = false; }

  /// Calls f(array) on each of its arrays (BlockVector).
  template <class F>
  void ForEachArray(F&& f) {
    f(dist_), f(ring_), f(touched_), f(heap_), f(entries_), f(next_);
  }

 private:
  friend struct CreaseScratchTestAccess;  // the tests shrink the bucket queue to reach its fallback

  void Search(const CreaseGraph& graph, const uint32_t t[3], float crease);
  bool Buckets(const CreaseGraph& graph, float crease);
  template <class Push>
  bool Relax(const CreaseGraph& graph, uint32_t n, float d, float crease, Push&& push);
  void Heap(const CreaseGraph& graph, float crease);

  static constexpr uint32_t kBuckets = 256, kNil = ~0u;

  uint32_t source_[3] = {~0u, ~0u, ~0u};
  float source_crease_ = -1.0f;
  // Set once the bucket queue's entries ran out: the surface has many edges far shorter than its crease (a
  // bind pose collapsed onto a few points), where every search would fill the buckets and then start again on
  // the heap. Later searches go to the heap directly, until Reset or Init (the same distances either way).
  bool heap_only_ = false;
  BlockVector<float> dist_;          // per node: distance from the source's corners, +inf when unreached
  BlockVector<uint8_t> ring_;        // per node: 1 when a corner of the source or joined to one by an edge
  BlockVector<uint32_t> touched_;    // nodes whose dist_ / ring_ were set (reset on the next source)
  BlockVector<uint64_t> heap_;       // (distance bits << 32 | node), min-heap; capacity #edges + 3
  BlockVector<uint64_t> entries_;    // the bucket queue's entries (same keys), #edges + 3 ...
  BlockVector<uint32_t> next_;       // ... each chained to the next of its bucket
  std::array<uint32_t, kBuckets> head_{};  // per bucket: its last entry, or kNil
};

}  // namespace spherechain::runtime
