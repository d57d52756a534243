// The crease rule's search (CreaseScratch: a bounded Dijkstra on a bucket queue, a binary heap when the
// bucket entries run out — both paths) against a textbook one (std::priority_queue, the same float edge lengths and
// left-to-right sums) on every vertex of tubes: its near nodes (Reach) are exactly the nodes closer than the
// crease plus the corners' edge neighbours, and Near agrees with them.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/crease.h"

namespace rt = spherechain::runtime;
namespace st = spherechain::test;

namespace spherechain::runtime {
// Leaves the bucket queue `entries` entries, so a search that needs more falls back to the binary heap.
struct CreaseScratchTestAccess {
  static void ShrinkBuckets(CreaseScratch& s, size_t entries) { s.entries_.resize(entries), s.next_.resize(entries); }
};
}  // namespace spherechain::runtime

namespace {

// Nodes (= vertices: no welding) within `crease` of `source` along the mesh edges, and its edge neighbours.
std::vector<uint32_t> TextbookReach(const st::Mesh& mesh, uint32_t source, float crease) {
  const uint32_t V = mesh.vertex_count();
  std::vector<std::vector<std::pair<uint32_t, float>>> adj(V);
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[3 * t + k], b = mesh.triangles[3 * t + (k + 1) % 3];
      double d2 = 0;
      for (int c = 0; c < 3; ++c)
        d2 += (double(mesh.positions[3 * a + c]) - mesh.positions[3 * b + c]) *
              (double(mesh.positions[3 * a + c]) - mesh.positions[3 * b + c]);
      const float len = static_cast<float>(std::sqrt(d2));
      adj[a].push_back({b, len});
      adj[b].push_back({a, len});
    }
  std::vector<float> dist(V, std::numeric_limits<float>::infinity());
  using Entry = std::pair<float, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  dist[source] = 0.0f;
  queue.push({0.0f, source});
  while (!queue.empty()) {
    const auto [d, n] = queue.top();
    queue.pop();
    if (d > dist[n]) continue;
    for (const auto& [m, len] : adj[n]) {
      const float nd = d + len;
      if (nd < crease && nd < dist[m]) dist[m] = nd, queue.push({nd, m});
    }
  }
  std::vector<uint32_t> near;
  for (uint32_t v = 0; v < V; ++v) {
    bool ring = v == source;
    for (const auto& e : adj[source]) ring |= e.first == v;
    if (ring || dist[v] < crease) near.push_back(v);
  }
  return near;
}

void CheckEveryVertex(const st::Mesh& mesh, float crease, size_t bucket_entries = 0) {
  rt::CreaseGraph graph;
  REQUIRE(graph.Init(mesh.positions.data(), mesh.vertex_count(), mesh.triangles.data(), mesh.triangle_count(), nullptr,
                     crease) == rt::Status::kOk);
  rt::CreaseScratch scratch;
  REQUIRE(scratch.Init(graph) == rt::Status::kOk);
  if (bucket_entries) rt::CreaseScratchTestAccess::ShrinkBuckets(scratch, bucket_entries);
  size_t total = 0;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    const uint32_t source[3] = {v, v, v};
    const auto& found = scratch.Reach(graph, source, crease);
    std::vector<uint32_t> reach(found.begin(), found.end());
    std::sort(reach.begin(), reach.end());
    const std::vector<uint32_t> truth = TextbookReach(mesh, v, crease);
    CHECK(reach == truth);
    total += reach.size();
    // Near(t, u) for a triangle at v: exactly when a corner of u is among the near nodes.
    const uint32_t u[3] = {truth.back(), truth.back(), truth.back()};
    CHECK(scratch.Near(graph, source, u, crease));
  }
  MESSAGE(mesh.vertex_count() << " sources, " << total / mesh.vertex_count() << " near nodes on average");
}

st::Mesh TubeMesh(uint32_t rings, uint32_t sides, float spacing, float radius) {
  st::Mesh mesh;
  st::Tube tube;
  tube.rings = rings;
  tube.sides = sides;
  tube.spacing = spacing;
  tube.radius = radius;
  (void)st::MakeTubes({tube}, {}, &mesh);
  return mesh;
}

// TubeMesh with rings `first`, first + 1 and first + 2 at one place (the rings after them moved back by two
// spacings): edges of length 0 between distinct nodes (coincident vertices not welded, as a hand-made asset
// may have), two of them in a row from every vertex of those rings.
st::Mesh CoincidentRings(uint32_t rings, uint32_t sides, float spacing, float radius, uint32_t first) {
  st::Mesh mesh = TubeMesh(rings, sides, spacing, radius);
  const std::vector<float> straight = mesh.positions;
  for (uint32_t i = first + 1; i < rings; ++i)  // ring i where ring max(first, i − 2) was, exactly
    for (uint32_t k = 0; k < sides; ++k)
      for (int c = 0; c < 3; ++c)
        mesh.positions[3 * (size_t{i} * sides + k) + c] = straight[3 * (size_t{std::max(first, i - 2)} * sides + k) + c];
  return mesh;
}

}  // namespace

TEST_CASE("crease rule: the bucketed search equals a textbook Dijkstra on every vertex") {
  SUBCASE("a tube, crease of a few rings") {
    const st::Mesh mesh = TubeMesh(24, 12, 0.6f, 1.0f);
    CheckEveryVertex(mesh, 3.0f);
    CheckEveryVertex(mesh, 1.0f);
  }
  SUBCASE("a fine tube: edges far shorter than a bucket of the crease (relaxations within one bucket)") {
    CheckEveryVertex(TubeMesh(40, 16, 0.002f, 0.01f), 0.5f);  // the whole tube within the crease of every vertex
  }
  SUBCASE("the binary heap the search falls back to when the bucket queue's entries run out") {
    CheckEveryVertex(TubeMesh(24, 12, 0.6f, 1.0f), 3.0f, 8);  // 8 entries: every search with more than a few nodes falls back
  }
  SUBCASE("edges of length 0 (coincident vertices not welded), on the buckets and on the heap") {
    // The fallback must forget the nodes the buckets reached at distance 0 beyond the source's ring, or the
    // heap never expands them (0 is not below 0) and later searches find them still at 0.
    const st::Mesh mesh = CoincidentRings(24, 12, 0.6f, 1.0f, 10);
    CheckEveryVertex(mesh, 3.0f);
    CheckEveryVertex(mesh, 3.0f, 8);
  }
  SUBCASE("a crease so small that a bucket's width rounds to 0") {
    // 1e-44 / 256 is 0 in float: every distance's bucket index is 0 / 0 or d / 0; the search must still
    // settle the nodes at distance 0 (and nothing else) without converting a NaN or an infinity to an integer.
    const st::Mesh mesh = CoincidentRings(24, 12, 0.6f, 1.0f, 10);
    CheckEveryVertex(mesh, 1e-44f);
    CheckEveryVertex(mesh, 1e-44f, 8);
  }
}

TEST_CASE("crease rule: the welded surface's pieces are counted over the vertices some triangle uses") {
  // Two tubes are two pieces; vertices no triangle uses (an OBJ's or a glTF buffer's spare vertices) are no
  // piece at all; a triangle whose corners weld into one node is a piece of its own.
  st::Mesh mesh;
  st::Tube a, b;
  b.origin[1] = 5.0f;
  (void)st::MakeTubes({a, b}, {}, &mesh);
  const auto pieces = [](const st::Mesh& m, const uint32_t* weld) {
    rt::CreaseGraph graph;
    REQUIRE(graph.Init(m.positions.data(), m.vertex_count(), m.triangles.data(), m.triangle_count(), weld, 1.0f) ==
            rt::Status::kOk);
    return graph.components();
  };
  CHECK(pieces(mesh, nullptr) == 2);
  st::Mesh spare = mesh;
  for (int i = 0; i < 3; ++i) spare.positions.insert(spare.positions.end(), {9.0f + i, 9.0f, 9.0f});
  CHECK(pieces(spare, nullptr) == 2);
  st::Mesh point = spare;  // one more triangle, its three corners at one position (welded into one node)
  const uint32_t v = spare.vertex_count();
  for (int i = 0; i < 3; ++i) point.positions.insert(point.positions.end(), {-9.0f, -9.0f, -9.0f});
  point.triangles.insert(point.triangles.end(), {v, v + 1, v + 2});
  std::vector<uint32_t> weld(point.vertex_count());
  for (uint32_t k = 0; k < point.vertex_count(); ++k) weld[k] = k < v ? k : v;
  CHECK(pieces(point, weld.data()) == 3);
}
