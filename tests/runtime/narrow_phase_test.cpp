// NarrowPhaseJob on shapes with known answers (crossing tubes, a tube folded on itself), against brute
// force over every triangle pair, and its statuses on bad input.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <tuple>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/triangle_intersect.h"

namespace rt = spherechain::runtime;
namespace st = spherechain::test;

namespace {

struct Loaded {
  st::AlignedBytes bytes;
  rt::AssetView view;
};

Loaded Load(const st::AssetData& d) {
  Loaded l;
  l.bytes = st::Serialize(d);
  REQUIRE(rt::LoadAsset(l.bytes.data(), l.bytes.size, &l.view) == rt::Status::kOk);
  return l;
}

using Contact = std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>;  // sphere a, sphere b, tri a, tri b

/// Every contact by brute force: all triangle pairs of different spheres (not excluded unless
/// `all_pairs`), no shared corner by weld id, TrianglesIntersect. The reference for NarrowPhaseJob.
std::set<Contact> BruteForce(const st::AssetData& d, const std::vector<float>& pos, bool all_pairs) {
  std::set<Contact> out;
  const uint32_t T = d.triangle_count;
  auto excluded = [&](uint32_t a, uint32_t b) {
    for (const auto& p : d.excluded)
      if (p.a() == std::min(a, b) && p.b() == std::max(a, b)) return true;
    return false;
  };
  auto vtx = [&](uint32_t t, int k) { return &pos[3 * size_t{d.triangles[3 * t + k]}]; };
  for (uint32_t s = 0; s < T; ++s)
    for (uint32_t t = s + 1; t < T; ++t) {
      const uint32_t sa = d.triangle_spheres[s], sb = d.triangle_spheres[t];
      if (sa == sb || (!all_pairs && excluded(sa, sb))) continue;
      bool adjacent = false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          adjacent |= d.weld_ids[d.triangles[3 * s + i]] == d.weld_ids[d.triangles[3 * t + j]];
      if (adjacent) continue;
      if (!rt::TrianglesIntersect(vtx(s, 0), vtx(s, 1), vtx(s, 2), vtx(t, 0), vtx(t, 1), vtx(t, 2))) continue;
      if (sa < sb)
        out.insert({sa, sb, s, t});
      else
        out.insert({sb, sa, t, s});
    }
  return out;
}

struct Run {
  rt::Status status;
  rt::NarrowPhaseStats stats;
  std::vector<rt::TriangleContact> contacts;
};

// One character's narrow phase: the per-asset model and its workspace.
struct Narrow {
  rt::NarrowPhaseModel model;
  rt::NarrowPhaseWorkspace ws;
  rt::Status Init(const rt::AssetView& view) {
    rt::Status s = model.Init(view);
    return s == rt::Status::kOk ? ws.Init(model) : s;
  }
};

Run RunJob(Narrow* ctx, const std::vector<float>& pos, rt::Exclusions ex, uint32_t capacity = 100000,
           const std::vector<rt::Collision>& only = {}) {
  Run r;
  r.contacts.resize(capacity);
  uint32_t n = 0;
  rt::NarrowPhaseJob job;
  job.model = &ctx->model;
  job.workspace = &ctx->ws;
  job.positions = {pos.data(), static_cast<uint32_t>(pos.size() / 3), 12};
  job.exclusions = ex;
  job.output = r.contacts.data();
  job.capacity = capacity;
  job.count = &n;
  job.stats = &r.stats;
  if (!only.empty()) {
    job.sphere_pairs = only.data();
    job.sphere_pair_count = static_cast<uint32_t>(only.size());
  }
  r.status = job.Run();
  r.contacts.resize(n);
  return r;
}

// The crease rule's job (kCrease) on `pos`, with the joint-matrix cull when `matrices` (#J × 12) is given and
// the depths when `depths` is: its status, stats and contacts (depths resized alike).
Run RunCrease(Narrow* ctx, const std::vector<float>& pos, const std::vector<float>* matrices = nullptr,
              std::vector<rt::ContactDepth>* depths = nullptr, uint32_t capacity = 1u << 16) {
  Run r;
  r.contacts.resize(capacity);
  if (depths) depths->assign(capacity, rt::ContactDepth{});
  uint32_t n = 77;
  rt::NarrowPhaseJob job;
  job.model = &ctx->model;
  job.workspace = &ctx->ws;
  job.exclusions = rt::Exclusions::kCrease;
  job.positions = {pos.data(), static_cast<uint32_t>(pos.size() / 3), 12};
  job.output = r.contacts.data();
  job.capacity = capacity;
  job.depths = depths ? depths->data() : nullptr;
  job.count = &n;
  job.stats = &r.stats;
  if (matrices) job.joint_matrices = matrices->data(), job.joint_count = static_cast<uint32_t>(matrices->size() / 12);
  r.status = job.Run();
  r.contacts.resize(n);
  if (depths) depths->resize(n);
  return r;
}

std::set<Contact> AsSet(const std::vector<rt::TriangleContact>& v) {
  std::set<Contact> s;
  for (const auto& c : v) s.insert({c.sphere_a, c.sphere_b, c.triangle_a, c.triangle_b});
  return s;
}

/// One tube of `rings` rings along x, folded at ring `bend` by `degrees` about the z axis through the
/// ring's centre: rings after `bend` are rotated rigidly, so for a sharp fold the second half passes
/// through the first half just after the bend.
std::vector<float> Fold(const st::Mesh& mesh, const st::Tube& tube, uint32_t bend, float degrees) {
  std::vector<float> out = mesh.positions;
  const float a = degrees * 3.14159265f / 180.0f, c = std::cos(a), s = std::sin(a);
  const float px = tube.origin[0] + tube.spacing * float(bend);
  for (uint32_t v = (bend + 1) * tube.sides; v < mesh.vertex_count(); ++v) {
    const float x = out[3 * v] - px, y = out[3 * v + 1];
    out[3 * v] = px + c * x - s * y;
    out[3 * v + 1] = c * y + s * x;
  }
  return out;
}

// The skin's contacts by brute force: every pair of triangles of `d` that share no welded corner, intersect at
// `pos` (#V×3) and are not near on `graph` at `crease`.
std::set<std::pair<uint32_t, uint32_t>> SkinContactsBruteForce(const st::AssetData& d, const std::vector<float>& pos,
                                                                const rt::CreaseGraph& graph, float crease) {
  std::set<std::pair<uint32_t, uint32_t>> truth;
  rt::CreaseScratch scratch;
  REQUIRE(scratch.Init(graph) == rt::Status::kOk);
  auto vtx = [&](uint32_t t, int k) { return &pos[3 * size_t{d.triangles[3 * t + k]}]; };
  for (uint32_t t = 0; t < d.triangle_count; ++t)
    for (uint32_t u = t + 1; u < d.triangle_count; ++u) {
      bool shared = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) shared |= d.weld_ids[d.triangles[3 * t + a]] == d.weld_ids[d.triangles[3 * u + b]];
      if (shared || !rt::TrianglesIntersect(vtx(t, 0), vtx(t, 1), vtx(t, 2), vtx(u, 0), vtx(u, 1), vtx(u, 2))) continue;
      if (!scratch.Near(graph, &d.triangles[3 * size_t{t}], &d.triangles[3 * size_t{u}], crease)) truth.insert({t, u});
    }
  return truth;
}

/// A tube of 14 rings of 12 sides 0.6 apart (radius 1), straight: the asset of the folding tests (Fold at
/// ring 7).
st::AssetData ShortTube(st::Mesh* mesh, st::Tube* tube) {
  tube->rings = 14;
  tube->sides = 12;
  tube->spacing = 0.6f;
  return st::MakeTubes({*tube}, {}, mesh);
}

/// A tube of 30 rings of 12 sides 0.6 apart (radius 1, length 17.4), its straight bind pose carried by the
/// asset with a crease of 3 (the crease rule on).
st::AssetData CreaseTube(st::Mesh* mesh, st::Tube* tube) {
  tube->rings = 30;
  tube->sides = 12;
  tube->spacing = 0.6f;
  st::AssetData d = st::MakeTubes({*tube}, {}, mesh);
  d.bind_positions = mesh->positions;
  d.crease = 3.0f;
  return d;
}

}  // namespace

TEST_CASE("narrow phase: two crossing tubes touch where they cross, and equal brute force") {
  st::Mesh mesh;
  const st::AssetData d = st::TwoTubes(true, &mesh);
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  const Run r = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset);
  REQUIRE(r.status == rt::Status::kOk);
  CHECK(r.stats.contacts == r.contacts.size());
  CHECK(r.contacts.size() > 0);
  CHECK(AsSet(r.contacts) == BruteForce(d, mesh.positions, false));
  // Tube A (x axis) spheres 0..7, tube B (y axis) 8..15; both cross the origin between rings 3 and 4
  // (origin at −4.2, spacing 1.2: ring 3 at −0.6, ring 4 at 0.6). Cylinders of radius 1 meet for |x|, |y| ≤ 1.
  for (const auto& c : r.contacts) {
    CHECK(c.sphere_a < 8);
    CHECK(c.sphere_b >= 8);
    CHECK(c.sphere_a >= 2);
    CHECK(c.sphere_a <= 4);
    CHECK(c.sphere_b >= 10);
    CHECK(c.sphere_b <= 12);
  }
  // Restricted to one sphere pair: the subset of the full answer.
  const rt::Collision only{3, 11, 0.0f, 0u};
  const Run sub = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset, 100000, {only});
  std::set<Contact> expect;
  for (const Contact& c : AsSet(r.contacts))
    if (std::get<0>(c) == 3 && std::get<1>(c) == 11) expect.insert(c);
  CHECK(AsSet(sub.contacts) == expect);
  CHECK(sub.stats.candidate_pairs <= 1);
}

TEST_CASE("narrow phase: tubes apart have no candidate pair between them and no contact") {
  st::Mesh mesh;
  const st::AssetData d = st::TwoTubes(false, &mesh);
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  const Run r = RunJob(&ctx, mesh.positions, rt::Exclusions::kNone);
  CHECK(r.status == rt::Status::kOk);
  CHECK(r.contacts.empty());  // consecutive spheres touch along their shared ring: adjacency, no contact
  CHECK(r.stats.adjacent_skipped > 0);
  // With the asset's exclusions (consecutive spheres) no region box meets another: nothing to test.
  const Run e = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset);
  CHECK(e.contacts.empty());
  CHECK(e.stats.candidate_pairs == 0);
  CHECK(e.stats.triangle_tests == 0);
}

TEST_CASE("narrow phase: a tube folded on itself touches just after the fold, equal to brute force") {
  st::Mesh mesh;
  st::Tube tube;
  const st::AssetData d = ShortTube(&mesh, &tube);
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  // Straight: nothing.
  CHECK(RunJob(&ctx, mesh.positions, rt::Exclusions::kNone).contacts.empty());
  // Folded by 100° at ring 7 (x = 4.2): the inner sides of the elbow pass through each other within
  // about a radius (1) of the fold — segments 5–6 before it against 7–9 after it.
  const std::vector<float> folded = Fold(mesh, tube, 7, 100.0f);
  for (rt::Exclusions ex : {rt::Exclusions::kAsset, rt::Exclusions::kNone}) {
    const Run r = RunJob(&ctx, folded, ex);
    REQUIRE(r.status == rt::Status::kOk);
    CHECK(AsSet(r.contacts) == BruteForce(d, folded, ex == rt::Exclusions::kNone));
    REQUIRE(r.contacts.size() > 0);
    for (const auto& c : r.contacts) {
      CHECK(c.sphere_a < 7);   // one side of the fold ...
      CHECK(c.sphere_b >= 7);  // ... against the other
      CHECK(c.sphere_a >= 4);  // near the fold: the far ends stay apart
      CHECK(c.sphere_b <= 10);
    }
  }
  // The asset's exclusions (consecutive spheres) can only hide some of them.
  CHECK(RunJob(&ctx, folded, rt::Exclusions::kAsset).contacts.size() <=
        RunJob(&ctx, folded, rt::Exclusions::kNone).contacts.size());
  // Folded the other way round: a contact set again (rings are staggered, so not the mirror image),
  // equal to brute force.
  const std::vector<float> other = Fold(mesh, tube, 7, -100.0f);
  CHECK(AsSet(RunJob(&ctx, other, rt::Exclusions::kAsset).contacts) == BruteForce(d, other, false));
}

// A model or workspace initialised again (an asset reloaded), or moved onto one already initialised, first
// releases its arrays from its own block: they were freed after the block (use after free; "free():
// invalid pointer" in an optimised build).
TEST_CASE("narrow phase: a model and a workspace initialised twice, or moved onto initialised ones, keep working") {
  st::Mesh mesh;
  st::Tube tube;
  const st::AssetData d = ShortTube(&mesh, &tube);
  Loaded l = Load(d);
  const std::vector<float> folded = Fold(mesh, tube, 7, 100.0f);
  const std::set<Contact> truth = BruteForce(d, folded, true);
  REQUIRE(!truth.empty());
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  REQUIRE(ctx.model.Init(l.view) == rt::Status::kOk);  // again, with its arrays in its block
  REQUIRE(ctx.ws.Init(ctx.model) == rt::Status::kOk);
  REQUIRE(ctx.ws.Init(ctx.model) == rt::Status::kOk);
  CHECK(AsSet(RunJob(&ctx, folded, rt::Exclusions::kNone).contacts) == truth);
  Narrow other;
  REQUIRE(other.Init(l.view) == rt::Status::kOk);
  ctx.model = std::move(other.model);  // onto an initialised model; the workspace is now another model's
  CHECK_FALSE(other.model.initialized());
  CHECK(RunJob(&ctx, folded, rt::Exclusions::kNone).status == rt::Status::kErrorWorkspaceModel);
  ctx.ws = std::move(other.ws);  // onto an initialised workspace
  CHECK(AsSet(RunJob(&ctx, folded, rt::Exclusions::kNone).contacts) == truth);
}

// Overlapping regions (a kReach model): each sphere's reach is its own triangles and its neighbour's
// (s ^ 1), so two triangles of the pair (2k, 2k + 1) are both behind both spheres and the sweep of that
// pair meets them twice, once each way round. Each contact is still reported once, the same as the
// surrounding regions' model gives.
TEST_CASE("narrow phase, reach regions: two triangles behind both spheres of a pair are reported once") {
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData d = ShortTube(&mesh, &tube);
  const uint32_t S = static_cast<uint32_t>(d.spheres.size());
  d.reach_offsets.assign(1, 0);
  for (uint32_t s = 0; s < S; ++s) {
    std::set<uint32_t> reach;
    for (uint32_t j : {s, s ^ 1u})
      if (j < S)
        for (uint32_t k = d.surrounding_offsets[j]; k < d.surrounding_offsets[j + 1]; ++k) reach.insert(d.surrounding_triangles[k]);
    d.reach_triangles.insert(d.reach_triangles.end(), reach.begin(), reach.end());
    d.reach_offsets.push_back(static_cast<uint32_t>(d.reach_triangles.size()));
  }
  Loaded l = Load(d);
  Narrow surrounding, reach;
  REQUIRE(surrounding.Init(l.view) == rt::Status::kOk);
  REQUIRE(reach.model.Init(l.view, rt::NarrowPhaseRegions::kReach) == rt::Status::kOk);
  REQUIRE(reach.model.regions() == rt::NarrowPhaseRegions::kReach);
  REQUIRE(reach.ws.Init(reach.model) == rt::Status::kOk);
  const std::vector<float> folded = Fold(mesh, tube, 7, 100.0f);
  for (rt::Exclusions ex : {rt::Exclusions::kNone, rt::Exclusions::kAsset}) {
    const Run a = RunJob(&surrounding, folded, ex), b = RunJob(&reach, folded, ex);
    REQUIRE(a.status == rt::Status::kOk);
    REQUIRE(b.status == rt::Status::kOk);
    CHECK(AsSet(b.contacts).size() == b.contacts.size());  // no contact twice
    CHECK(AsSet(b.contacts) == AsSet(a.contacts));
    CHECK(b.contacts.size() == a.contacts.size());
  }
  CHECK(!RunJob(&reach, folded, rt::Exclusions::kNone).contacts.empty());
}

TEST_CASE("narrow phase: weld ids give a triangle soup its adjacency") {
  // A tube as a soup: every triangle its own three vertices. Without weld ids, neighbouring triangles
  // of consecutive spheres touch along their shared edges and would be contacts (with no exclusions).
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData d = st::MakeTubes({tube}, {}, &mesh);
  std::vector<float> soup;
  std::vector<uint32_t> tris;
  for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) soup.push_back(mesh.positions[3 * size_t{mesh.triangles[i]} + k]);
    tris.push_back(i);
  }
  d.triangles = tris;
  d.vertex_count = static_cast<uint32_t>(tris.size());
  d.pivot_vertices.clear();
  for (uint32_t t : d.pivot_triangles)
    for (int k = 0; k < 3; ++k) d.pivot_vertices.push_back(3 * t + k);
  // Welded: the lowest index of each position.
  d.weld_ids.resize(d.vertex_count);
  for (uint32_t v = 0; v < d.vertex_count; ++v) {
    d.weld_ids[v] = v;
    for (uint32_t w = 0; w < v; ++w)
      if (soup[3 * w] == soup[3 * v] && soup[3 * w + 1] == soup[3 * v + 1] && soup[3 * w + 2] == soup[3 * v + 2]) {
        d.weld_ids[v] = w;
        break;
      }
  }
  {
    Loaded l = Load(d);
    Narrow ctx;
    REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
    const Run r = RunJob(&ctx, soup, rt::Exclusions::kNone);
    CHECK(r.contacts.empty());
    CHECK(r.stats.adjacent_skipped > 0);
  }
  // Unwelded (identity ids): every ring's edges now make contacts between consecutive spheres.
  for (uint32_t v = 0; v < d.vertex_count; ++v) d.weld_ids[v] = v;
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  const Run r = RunJob(&ctx, soup, rt::Exclusions::kNone);
  CHECK(r.contacts.size() > 0);
  for (const auto& c : r.contacts) CHECK(c.sphere_b == c.sphere_a + 1);
  CHECK(RunJob(&ctx, soup, rt::Exclusions::kAsset).contacts.empty());  // consecutive spheres are excluded pairs
}

TEST_CASE("narrow phase: a short buffer gives kOkTruncated, the first records and complete stats") {
  st::Mesh mesh;
  const st::AssetData d = st::TwoTubes(true, &mesh);
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  const Run full = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset);
  REQUIRE(full.contacts.size() > 2);
  const Run part = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset, 2);
  CHECK(part.status == rt::Status::kOkTruncated);
  REQUIRE(part.contacts.size() == 2);
  CHECK(part.stats.contacts == full.stats.contacts);
  CHECK(part.stats.triangle_tests == full.stats.triangle_tests);
  CHECK(part.contacts[0].triangle_a == full.contacts[0].triangle_a);
  CHECK(part.contacts[1].triangle_b == full.contacts[1].triangle_b);
  // Capacity 0, null output: counts only.
  const Run none = RunJob(&ctx, mesh.positions, rt::Exclusions::kAsset, 0);
  CHECK(none.status == rt::Status::kOkTruncated);
  CHECK(none.stats.contacts == full.stats.contacts);
}

TEST_CASE("narrow phase: bad input gets its status and no output") {
  st::Mesh mesh;
  st::AssetData d = st::TwoTubes(true, &mesh);
  Loaded l = Load(d);
  rt::NarrowPhaseModel ctx;
  rt::NarrowPhaseWorkspace ws;
  rt::TriangleContact out[4];
  uint32_t n = 77;
  rt::NarrowPhaseJob job;
  job.model = &ctx;
  job.workspace = &ws;
  job.positions = {mesh.positions.data(), mesh.vertex_count(), 12};
  job.output = out;
  job.capacity = 4;
  job.count = &n;
  CHECK(job.Check() == rt::Status::kErrorInvalidJob);  // not initialised
  CHECK(ws.Init(ctx) == rt::Status::kErrorInvalidJob);  // a workspace needs an initialised model
  CHECK(!ws.initialized());
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  CHECK(job.Check() == rt::Status::kErrorInvalidJob);  // the workspace is not initialised yet
  REQUIRE(ws.Init(ctx) == rt::Status::kOk);
  CHECK(ws.made_for(ctx));
  CHECK(job.Validate());
  job.workspace = nullptr;
  CHECK(job.Run() == rt::Status::kErrorNullArgument);
  job.workspace = &ws;
  job.model = nullptr;
  CHECK(job.Run() == rt::Status::kErrorNullArgument);
  // A workspace made for another model (another build of the same asset) is refused, nothing written.
  rt::NarrowPhaseModel other;
  REQUIRE(other.Init(l.view) == rt::Status::kOk);
  CHECK(other.id() != ctx.id());
  job.model = &other;
  CHECK(job.Run() == rt::Status::kErrorWorkspaceModel);
  job.model = &ctx;
  // Moving keeps the id (the workspace still fits) and leaves the source uninitialised.
  rt::NarrowPhaseModel moved = std::move(other);
  CHECK(!other.initialized());
  CHECK(moved.initialized());
  rt::NarrowPhaseWorkspace moved_ws;
  REQUIRE(moved_ws.Init(moved) == rt::Status::kOk);
  rt::NarrowPhaseWorkspace ws2 = std::move(moved_ws);
  CHECK(!moved_ws.initialized());
  CHECK(ws2.made_for(moved));
  job.positions.count = mesh.vertex_count() - 1;
  CHECK(job.Run() == rt::Status::kErrorVertexCount);
  job.positions.count = mesh.vertex_count();
  job.positions.stride_bytes = 10;
  CHECK(job.Run() == rt::Status::kErrorStride);
  job.positions.stride_bytes = 12;
  job.count = nullptr;
  CHECK(job.Run() == rt::Status::kErrorNullArgument);
  job.count = &n;
  const rt::Collision bad{5, 5, 0.0f, 0u};
  job.sphere_pairs = &bad;
  job.sphere_pair_count = 1;
  CHECK(job.Run() == rt::Status::kErrorIndexOutOfRange);
  job.sphere_pairs = nullptr;
  job.sphere_pair_count = 0;
  job.crease = 1.0f;  // a crease belongs to the crease rule: refused, not ignored, under kAsset / kNone
  CHECK(job.Run() == rt::Status::kErrorInvalidJob);
  job.exclusions = rt::Exclusions::kNone;
  CHECK(job.Run() == rt::Status::kErrorInvalidJob);
  job.exclusions = rt::Exclusions::kAsset;
  job.crease = 0.0f;
  CHECK(n == 77);  // untouched by argument errors
  std::vector<float> nan = mesh.positions;
  nan[3 * 20 + 1] = std::numeric_limits<float>::quiet_NaN();
  job.positions.data = nan.data();
  CHECK(job.Run() == rt::Status::kErrorNonFinitePositions);
  CHECK(n == 0);
  // An asset without the narrow-phase arrays (baked before them) is refused at Init.
  d.triangles.clear();
  Loaded old = Load(d);
  rt::NarrowPhaseModel ctx_old;
  CHECK(ctx_old.Init(old.view) == rt::Status::kErrorMissingField);
  CHECK(!ctx_old.initialized());
  // Asked of a Model, in caller memory: RequiredBytes says 0, and InitInPlace the reason, not the buffer's size.
  rt::ModelOptions with_narrow;
  with_narrow.narrow_phase = true;
  CHECK(rt::Model::RequiredBytes(old.view, with_narrow) == 0);
  alignas(64) static unsigned char small_block[64];
  rt::Model old_model;
  CHECK(old_model.InitInPlace(old.view, with_narrow, small_block, 0) == rt::Status::kErrorMissingField);
  CHECK(old_model.InitInPlace(old.view, with_narrow, small_block, sizeof small_block) == rt::Status::kErrorMissingField);
  // Corrupt narrow-phase arrays are refused by LoadAsset.
  st::Mesh m2, m3;
  st::AssetData bad_weld = st::TwoTubes(true, &m2);
  bad_weld.weld_ids[3] = 5;  // points forward
  st::AlignedBytes bytes = st::Serialize(bad_weld);
  rt::AssetView view;
  CHECK(rt::LoadAsset(bytes.data(), bytes.size, &view) == rt::Status::kErrorIndexOutOfRange);
  st::AssetData bad_tris = st::TwoTubes(true, &m3);
  bad_tris.triangles.pop_back();
  bytes = st::Serialize(bad_tris);
  CHECK(rt::LoadAsset(bytes.data(), bytes.size, &view) == rt::Status::kErrorCountMismatch);
}

TEST_CASE("ContactDepthOf: a triangle piercing another, depth and push direction computed by hand") {
  // b lies in z = 0 with its normal +z; a stands through it, its lowest corner 0.3 below. The corners of b
  // behind a's plane lie 0.396 deep (by hand: a's normal (-0.08, -0.08, 0.01)/0.11358, b's corner (1, 0, 0)
  // at -0.045/0.11358), so the separating-axis estimate takes b's normal and 0.3.
  const float b0[3] = {0, 0, 0}, b1[3] = {1, 0, 0}, b2[3] = {0, 1, 0};
  const float a0[3] = {0.2f, 0.2f, -0.3f}, a1[3] = {0.3f, 0.2f, 0.5f}, a2[3] = {0.2f, 0.3f, 0.5f};
  REQUIRE(rt::TrianglesIntersect(a0, a1, a2, b0, b1, b2));
  const float* a[3] = {a0, a1, a2};
  const float* b[3] = {b0, b1, b2};
  rt::ContactDepth d{};
  rt::ContactDepthOf(a, b, &d);
  CHECK(d.depth == doctest::Approx(0.3).epsilon(1e-6));
  CHECK(d.direction[0] == doctest::Approx(0.0));
  CHECK(d.direction[1] == doctest::Approx(0.0));
  CHECK(d.direction[2] == doctest::Approx(1.0));
  // The other order: the same depth, and b moves down (minus its own normal).
  rt::ContactDepthOf(b, a, &d);
  CHECK(d.depth == doctest::Approx(0.3).epsilon(1e-6));
  CHECK(d.direction[2] == doctest::Approx(-1.0));
  // Lower a's corner: the estimate follows it until the other axis (0.396 + ...) is the smaller.
  const float deep[3] = {0.2f, 0.2f, -0.6f};
  const float* a_deep[3] = {deep, a1, a2};
  rt::ContactDepthOf(a_deep, b, &d);
  CHECK(d.depth < 0.6f);  // b's corners are less deep behind a's (tilted) plane than 0.6
  CHECK(d.depth > 0.3f);
  const double n = std::sqrt(double(d.direction[0]) * d.direction[0] + double(d.direction[1]) * d.direction[1] +
                             double(d.direction[2]) * d.direction[2]);
  CHECK(n == doctest::Approx(1.0));
  // A zero-area triangle: depth 0, no direction.
  const float* flat[3] = {b0, b0, b1};
  rt::ContactDepthOf(a, flat, &d);
  CHECK(d.depth == 0.0f);
  CHECK(d.direction[0] == 0.0f);
}

TEST_CASE("narrow phase, crease rule: a bent tube's fold is not a contact, its ends meeting are") {
  // A tube of 30 rings 0.6 apart (radius 1, length 17.4), its bind pose straight, crease 3. Bent by 100° at
  // ring 15, the inner sides of the elbow pass through each other within about a radius of the fold: along
  // the surface those triangles are less than the crease apart, so they are a fold and not reported (while
  // the plain narrow phase reports them). Bent by 178° instead, the far part comes back onto the near one:
  // rings 15 + k and 15 − k meet, 2k rings apart along the tube, and from about k = 3 on those are contacts.
  // Both equal brute force over every triangle pair with the rule.
  st::Mesh mesh;
  st::Tube tube;
  const st::AssetData d = CreaseTube(&mesh, &tube);
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  REQUIRE(ctx.model.has_crease());
  CHECK(ctx.model.crease() == 3.0f);
  CHECK(ctx.model.bind_contact_count() == 0);
  CHECK(ctx.model.crease_graph().components() == 1);
  auto crease_run = [&](const std::vector<float>& pos, std::vector<rt::ContactDepth>* depths = nullptr) {
    Run r = RunCrease(&ctx, pos, nullptr, depths);
    REQUIRE(r.status == rt::Status::kOk);
    return std::make_pair(r.contacts, r.stats);
  };
  // Straight: nothing.
  CHECK(crease_run(mesh.positions).first.empty());
  // One elbow: the plain narrow phase sees the fold, the crease rule skips it.
  const std::vector<float> elbow = Fold(mesh, tube, 15, 100.0f);
  REQUIRE(!RunJob(&ctx, elbow, rt::Exclusions::kNone).contacts.empty());
  const auto [fold_contacts, fold_stats] = crease_run(elbow);
  CHECK(fold_contacts.empty());
  // Each of the fold's intersections is near on the bind surface: what the rule skipped.
  {
    rt::CreaseScratch near;
    REQUIRE(near.Init(ctx.model.crease_graph()) == rt::Status::kOk);
    for (const auto& c : RunJob(&ctx, elbow, rt::Exclusions::kNone).contacts)
      CHECK(near.Near(ctx.model.crease_graph(), &d.triangles[3 * size_t{c.triangle_a}], &d.triangles[3 * size_t{c.triangle_b}], 3.0f));
  }
  CHECK(fold_stats.crease_folds == 0);  // at the asset's crease the near pairs are skipped before any test
  // A hairpin: the far half back along the near one.
  const std::vector<float> hairpin = Fold(mesh, tube, 15, 178.0f);
  std::vector<rt::ContactDepth> depths;
  const auto [contacts, stats] = crease_run(hairpin, &depths);
  REQUIRE(!contacts.empty());
  // Every one of them lies more than the crease apart along the tube (ring distance × spacing) and equals
  // brute force over all triangle pairs with the rule.
  // The geodesic between two triangles' bind centroids on the unrolled cylinder (radius 1): sqrt((Δangle)² +
  // Δx²). A triangle is under 0.6 × 0.52 across, so a pair's corners are within ~1.2 of its centroids'.
  const auto geodesic = [&](uint32_t t, uint32_t u) {
    double c[2][3] = {};
    for (int s2 = 0; s2 < 2; ++s2)
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) c[s2][a] += mesh.positions[3 * size_t{d.triangles[3 * size_t{s2 ? u : t} + k]} + a] / 3;
    double dang = std::abs(std::atan2(c[0][2], c[0][1]) - std::atan2(c[1][2], c[1][1]));
    dang = std::min(dang, 2 * 3.14159265358979 - dang);
    return std::sqrt(dang * dang + (c[0][0] - c[1][0]) * (c[0][0] - c[1][0]));
  };
  for (const auto& c : RunJob(&ctx, elbow, rt::Exclusions::kNone).contacts)
    CHECK(geodesic(c.triangle_a, c.triangle_b) < 3.0 + 1.2);  // the elbow's pairs: within the crease
  const std::set<std::pair<uint32_t, uint32_t>> truth = SkinContactsBruteForce(d, hairpin, ctx.model.crease_graph(), 3.0f);
  std::set<std::pair<uint32_t, uint32_t>> found;
  for (size_t i = 0; i < contacts.size(); ++i) {
    const auto& c = contacts[i];
    found.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)});
    CHECK(geodesic(c.triangle_a, c.triangle_b) > 3.0 - 1.2);  // beyond the crease along the skin
    CHECK(depths[i].depth >= 0.0f);
    CHECK(depths[i].depth <= 2.0f);  // never more than a triangle's size here (edges ≤ 0.6, ring chords ≤ 0.52)
  }
  CHECK(found == truth);
  CHECK(found.size() == contacts.size());
}

TEST_CASE("narrow phase, crease rule: a mesh whose every triangle is degenerate by weld ids has no contact") {
  // Each ring's vertices welded into one: every triangle has two corners of one ring, so none is a triangle of
  // the welded surface and no patch holds any. The job reports nothing, with kOk, on every ISA (the SIMD
  // pass once took the empty box of no patches for a non-finite position).
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData d = CreaseTube(&mesh, &tube);
  for (uint32_t v = 0; v < d.vertex_count; ++v) d.weld_ids[v] = v - v % tube.sides;
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  REQUIRE(ctx.model.has_crease());
  for (const std::vector<float>& pos : {mesh.positions, Fold(mesh, tube, 15, 178.0f)}) {
    const Run r = RunCrease(&ctx, pos, nullptr, nullptr, 16);
    CHECK(r.status == rt::Status::kOk);
    CHECK(r.contacts.empty());
  }
}

namespace {

// `d` refused by Init's budgets: the narrow phase's model and a Model with its narrow phase, both
// kErrorCreaseTooWide, neither initialised.
void CheckRefusedCreaseTooWide(const st::AssetData& d) {
  Loaded l = Load(d);
  rt::NarrowPhaseModel model;
  CHECK(model.Init(l.view) == rt::Status::kErrorCreaseTooWide);
  CHECK(!model.initialized());
  rt::Model whole;
  rt::ModelOptions options;
  options.narrow_phase = true;
  CHECK(whole.Init(l.view, options) == rt::Status::kErrorCreaseTooWide);
  CHECK(!whole.initialized());
}

}  // namespace

TEST_CASE("narrow phase, crease rule: a bind pose collapsed onto a few points is refused within the searches' budget") {
  // st::CreaseTube: straight, the model builds; its bind pose shrunk 1,000 times, every node reaches all 2,400,
  // past the budget, so Init refuses it (kErrorCreaseTooWide) instead of building near rows between every pair
  // of patches; so does a Model with its narrow phase.
  st::Mesh mesh;
  st::AssetData d = st::CreaseTube(1.0f, &mesh);
  REQUIRE(d.vertex_count == 2400);
  {
    Loaded l = Load(d);
    Narrow ctx;
    CHECK(ctx.Init(l.view) == rt::Status::kOk);
    CHECK(ctx.model.has_crease());
  }
  for (float& x : d.bind_positions) x *= 1e-3f;  // = st::CreaseTube(1e-3f, ...)
  CheckRefusedCreaseTooWide(d);
  CHECK(size_t{rt::NarrowPhaseModel::kReachPerNode} * 2400 + rt::NarrowPhaseModel::kSweepSlack < size_t{2400} * 2400);
}

TEST_CASE("narrow phase, crease rule: a welded vertex shared by thousands of triangles is refused within the growth's budget") {
  // st::CreaseTube's 4,768 triangles re-made as one fan around vertex 0 (triangle k: 0, 1 + k mod 2399, its
  // successor): every patch grown there scans the centre's triangles, about #T²/2 steps in all, past
  // kGrowPerTriangle × #T, so Init refuses it (kErrorCreaseTooWide) instead of growing patches quadratically.
  st::Mesh mesh;
  st::AssetData d = st::CreaseTube(1.0f, &mesh);
  const uint32_t T = d.triangle_count, rim = d.vertex_count - 1;
  REQUIRE(d.triangles.size() == size_t{3} * T);
  for (uint32_t k = 0; k < T; ++k) {
    d.triangles[3 * size_t{k}] = 0;
    d.triangles[3 * size_t{k} + 1] = 1 + k % rim;
    d.triangles[3 * size_t{k} + 2] = 1 + (k + 1) % rim;
  }
  CHECK(uint64_t{T} * T / 2 > uint64_t{rt::NarrowPhaseModel::kGrowPerTriangle} * T + rt::NarrowPhaseModel::kSweepSlack);
  CheckRefusedCreaseTooWide(d);
}

TEST_CASE("narrow phase, crease rule: the joint-matrix cull counts a joint listed twice in a row at its whole weight") {
  // The bent tube skinned to two joints: joint 0 fixed, joint 1 turning about the z axis through ring 15, the
  // weight of joint 1 rising from 0 at ring 12 to 1 at ring 18; the frame is the linear blend of those
  // (rounded) weights. Asset `merged` lists each joint once per vertex; asset `split` lists each weight as two
  // entries of the same joint (the same sums). The cull must take a split joint at its whole weight: on every
  // frame `split` reports what the job without matrices reports, and culls no more pairs than `merged` (a
  // joint's largest entry alone, half its weight, would under-bound how far the skin strays and cull more).
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData base = CreaseTube(&mesh, &tube);
  base.joint_count = 2;
  for (size_t i = 0; i < base.spheres.size(); ++i) {
    base.sphere_joints.insert(base.sphere_joints.end(), {uint16_t(i < 15 ? 0 : 1), 0, 0, 0});
    base.sphere_joint_weights.insert(base.sphere_joint_weights.end(), {1.0f, 0.0f, 0.0f, 0.0f});
  }
  std::vector<uint32_t> q1(base.vertex_count);  // joint 1's weight × 255 per vertex
  for (uint32_t v = 0; v < base.vertex_count; ++v) {
    const float ring = static_cast<float>(v / tube.sides);
    q1[v] = static_cast<uint32_t>(std::lround(255.0f * std::clamp((ring - 12.0f) / 6.0f, 0.0f, 1.0f)));
  }
  st::AssetData merged = base, split = base;
  for (uint32_t v = 0; v < base.vertex_count; ++v) {
    const uint32_t q[2] = {255 - q1[v], q1[v]};
    uint8_t count_m = 0, count_s = 0;
    for (uint16_t j = 0; j < 2; ++j) {
      if (q[j] == 0) continue;
      merged.skin_joints.push_back(j), merged.skin_weights.push_back(static_cast<uint8_t>(q[j])), ++count_m;
      const uint32_t half = q[j] / 2;
      for (uint32_t part : {half, q[j] - half})
        if (part) split.skin_joints.push_back(j), split.skin_weights.push_back(static_cast<uint8_t>(part)), ++count_s;
    }
    merged.skin_counts.push_back(count_m), split.skin_counts.push_back(count_s);
  }
  Loaded lm = Load(merged), ls = Load(split);
  Narrow cm, cs;
  REQUIRE(cm.Init(lm.view) == rt::Status::kOk);
  REQUIRE(cs.Init(ls.view) == rt::Status::kOk);
  REQUIRE(cm.model.has_joint_cull());
  REQUIRE(cs.model.has_joint_cull());
  const float px = tube.origin[0] + tube.spacing * 15.0f;
  uint64_t culled_merged = 0, culled_split = 0, contacts = 0;
  for (float degrees : {30.0f, 60.0f, 90.0f, 120.0f, 150.0f, 170.0f, 178.0f}) {
    CAPTURE(degrees);
    const float a = degrees * 3.14159265f / 180.0f, c = std::cos(a), s = std::sin(a);
    // Row-major 3×4: joint 0 the identity, joint 1 the turn about (px, 0, z).
    const std::vector<float> matrices = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0,
                                         c, -s, 0, px - c * px, s, c, 0, -s * px, 0, 0, 1, 0};
    std::vector<float> pos(mesh.positions.size());
    for (uint32_t v = 0; v < base.vertex_count; ++v) {
      const float* x = &mesh.positions[3 * size_t{v}];
      const float w1 = static_cast<float>(q1[v]) / 255.0f, w0 = 1.0f - w1;
      for (int r = 0; r < 3; ++r) {
        const float* m1 = &matrices[12 + 4 * r];
        pos[3 * size_t{v} + r] = w0 * x[r] + w1 * (m1[0] * x[0] + m1[1] * x[1] + m1[2] * x[2] + m1[3]);
      }
    }
    const Run plain = RunCrease(&cs, pos), with_split = RunCrease(&cs, pos, &matrices),
              with_merged = RunCrease(&cm, pos, &matrices);
    REQUIRE(plain.status == rt::Status::kOk);
    REQUIRE(with_split.status == rt::Status::kOk);
    REQUIRE(with_merged.status == rt::Status::kOk);
    CHECK(AsSet(with_split.contacts) == AsSet(plain.contacts));
    CHECK(AsSet(with_merged.contacts) == AsSet(plain.contacts));
    CHECK(with_split.stats.joint_culled <= with_merged.stats.joint_culled);
    culled_merged += with_merged.stats.joint_culled, culled_split += with_split.stats.joint_culled;
    contacts += plain.contacts.size();
  }
  CHECK(contacts > 0);       // the hairpins meet
  CHECK(culled_split > 0);   // and the cull still works on the split rows
  MESSAGE("pairs culled: " << culled_merged << " merged, " << culled_split << " split; " << contacts << " contacts");
}

TEST_CASE("narrow phase, crease rule: two tubes joined by a long bridge are far along the skin, however near in space") {
  // Tubes A and B side by side along x (radius 1, axes 2.2 apart: 0.2 apart at bind), joined at their far ends
  // by a ribbon that runs 12 units out and back, so along the surface they are ~24 apart — far beyond the
  // crease (3) — though within it through the air. Pressed together (B moved 0.5 towards A) their facing
  // sides are contacts: the rule measures along the skin, not through space. Equal to brute force over every
  // triangle pair with the rule; at bind nothing touches.
  st::Mesh mesh;
  st::Tube a, b;
  a.rings = b.rings = 12;
  a.sides = b.sides = 12;
  a.spacing = b.spacing = 0.6f;
  b.origin[1] = 2.2f;
  st::AssetData d = st::MakeTubes({a, b}, {}, &mesh);
  const uint32_t tube_vertices = mesh.vertex_count(), tube_triangles = mesh.triangle_count();
  // The ribbon: two rails from A's last-ring vertices 0 and 1 out to x + 12, across to B, back to B's same two.
  const uint32_t a_end = (a.rings - 1) * a.sides, b_end = a.rings * a.sides + (b.rings - 1) * b.sides;
  std::vector<uint32_t> rail[2];
  for (int r = 0; r < 2; ++r) {
    const float* pa = &mesh.positions[3 * size_t{a_end + r}];
    const float* pb = &mesh.positions[3 * size_t{b_end + r}];
    const float way[4][3] = {{pa[0], pa[1], pa[2]}, {pa[0] + 12, pa[1], pa[2]}, {pb[0] + 12, pb[1], pb[2]}, {pb[0], pb[1], pb[2]}};
    rail[r].push_back(a_end + r);
    for (int s = 0; s < 3; ++s) {
      const int steps = s == 1 ? 4 : 20;  // stations ~0.6 apart
      for (int i = 1; i <= steps; ++i) {
        if (s == 2 && i == steps) break;  // B's vertex itself
        const float u = float(i) / float(steps);
        for (int k = 0; k < 3; ++k) mesh.positions.push_back(way[s][k] + u * (way[s + 1][k] - way[s][k]));
        rail[r].push_back(mesh.vertex_count() - 1);
      }
    }
    rail[r].push_back(b_end + r);
  }
  REQUIRE(rail[0].size() == rail[1].size());
  for (size_t j = 0; j + 1 < rail[0].size(); ++j)
    for (uint32_t v : {rail[0][j], rail[1][j], rail[0][j + 1], rail[1][j], rail[1][j + 1], rail[0][j + 1]})
      mesh.triangles.push_back(v);
  for (uint32_t t = tube_triangles; t < mesh.triangle_count(); ++t) d.triangle_spheres.push_back(0);  // in no region
  d.vertex_count = mesh.vertex_count();
  d.triangle_count = mesh.triangle_count();
  d.triangles = mesh.triangles;
  d.weld_ids.resize(d.vertex_count);
  for (uint32_t v = 0; v < d.vertex_count; ++v) d.weld_ids[v] = v;
  d.bind_positions = mesh.positions;
  d.crease = 3.0f;
  Loaded l = Load(d);
  Narrow ctx;
  REQUIRE(ctx.Init(l.view) == rt::Status::kOk);
  REQUIRE(ctx.model.has_crease());
  CHECK(ctx.model.crease_graph().components() == 1);  // one skin: the bridge joins them
  CHECK(ctx.model.bind_contact_count() == 0);
  CHECK(ctx.model.unassigned_triangles() == mesh.triangle_count() - tube_triangles);
  const uint32_t a_triangles = 2 * (a.rings - 1) * a.sides;
  auto on_a = [&](uint32_t t) { return t < a_triangles; };
  auto on_b = [&](uint32_t t) { return t >= a_triangles && t < tube_triangles; };
  // At bind: nothing touches, and the facing sides, 0.2 apart in space, are not near along the skin.
  CHECK(RunJob(&ctx, mesh.positions, rt::Exclusions::kCrease).contacts.empty());
  rt::CreaseScratch scratch;
  REQUIRE(scratch.Init(ctx.model.crease_graph()) == rt::Status::kOk);
  uint32_t facing = 0;
  for (uint32_t t = 0; t < a_triangles; ++t)
    for (uint32_t u = a_triangles; u < tube_triangles; ++u) {
      float gap = 1e30f;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const float* p = &mesh.positions[3 * size_t{mesh.triangles[3 * t + i]}];
          const float* q = &mesh.positions[3 * size_t{mesh.triangles[3 * u + j]}];
          gap = std::min(gap, std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])));
        }
      if (gap > 1.0f) continue;  // well within the crease through the air
      ++facing;
      CHECK_FALSE(scratch.Near(ctx.model.crease_graph(), &mesh.triangles[3 * size_t{t}], &mesh.triangles[3 * size_t{u}], 3.0f));
    }
  CHECK(facing > 20);
  // Pressed together: B (its tube, not the ribbon) moved 0.5 towards A.
  std::vector<float> pressed = mesh.positions;
  for (uint32_t v = a.rings * a.sides; v < tube_vertices; ++v) pressed[3 * size_t{v} + 1] -= 0.5f;
  const Run r = RunJob(&ctx, pressed, rt::Exclusions::kCrease);
  REQUIRE(r.status == rt::Status::kOk);
  std::set<std::pair<uint32_t, uint32_t>> found;
  for (const auto& c : r.contacts) {
    found.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)});
    CHECK(((on_a(c.triangle_a) && on_b(c.triangle_b)) || (on_b(c.triangle_a) && on_a(c.triangle_b))));
  }
  const std::set<std::pair<uint32_t, uint32_t>> truth = SkinContactsBruteForce(d, pressed, ctx.model.crease_graph(), 3.0f);
  CHECK(!found.empty());
  CHECK(found == truth);
  CHECK(found.size() == r.contacts.size());
}

TEST_CASE("narrow phase held by the runtime Model: one block each, the same contacts as a NarrowPhaseModel of its own") {
  // The bent tube with the crease rule (crease 3): its elbow (100°) folds adjacent spheres, an excluded
  // pair, into each other; its hairpin (178°) brings far rings together. A Model built with the narrow
  // phase and a Workspace of it must give, for every Exclusions, the contacts a NarrowPhaseModel and
  // NarrowPhaseWorkspace of their own give; its kAsset must read the excluded pairs from the Model's index
  // (kNone sees the elbow's pairs of adjacent spheres, kAsset does not). Built in caller memory too.
  st::Mesh mesh;
  st::Tube tube;
  const st::AssetData d = CreaseTube(&mesh, &tube);
  Loaded l = Load(d);
  Narrow alone;
  REQUIRE(alone.Init(l.view) == rt::Status::kOk);
  CHECK(alone.model.bytes() > 0);
  CHECK(alone.model.workspace_bytes() > 0);

  rt::ModelOptions options;
  options.narrow_phase = true;
  rt::Model model;
  REQUIRE(model.Init(l.view, options) == rt::Status::kOk);
  REQUIRE(model.narrow_phase() != nullptr);
  const rt::NarrowPhaseModel& held = *model.narrow_phase();
  CHECK(held.has_crease());
  CHECK(held.triangle_count() == alone.model.triangle_count());
  CHECK(held.bind_contact_count() == alone.model.bind_contact_count());
  CHECK(held.IsExcluded(3, 4));
  CHECK(!held.IsExcluded(3, 5));
  // Its block is the model's: the broad phase's sections, then the narrow phase (which shares the excluded
  // pairs instead of indexing them again: smaller than a model of its own).
  const size_t broad = rt::Model::RequiredBytes(l.view);
  CHECK(model.bytes() == rt::Model::RequiredBytes(l.view, options));
  CHECK(model.bytes() > broad);
  CHECK(held.bytes() < alone.model.bytes());
  CHECK(reinterpret_cast<const unsigned char*>(&held) >= reinterpret_cast<const unsigned char*>(model.arrays().bind_x));
  rt::Workspace ws;
  REQUIRE(ws.Init(model) == rt::Status::kOk);
  REQUIRE(ws.narrow_phase() != nullptr);
  CHECK(rt::Workspace::RequiredBytes(model) > held.workspace_bytes());
  CHECK(ws.narrow_phase()->made_for(held));
  CHECK(!ws.narrow_phase()->made_for(alone.model));

  // The same again in caller memory (16-byte aligned, not 64: the arrays are aligned inside).
  std::vector<unsigned char> model_memory(rt::Model::RequiredBytes(l.view, options) + 16);
  std::vector<unsigned char> too_small(rt::Model::RequiredBytes(l.view, options) - 1 + 16);
  auto at16 = [](std::vector<unsigned char>& v) {
    void* p = v.data();
    size_t room = v.size();
    return std::align(16, 1, p, room);
  };
  rt::Model in_place;
  CHECK(in_place.InitInPlace(l.view, options, at16(too_small), too_small.size() - 16) == rt::Status::kErrorBufferTooSmall);
  CHECK(in_place.narrow_phase() == nullptr);
  REQUIRE(in_place.InitInPlace(l.view, options, at16(model_memory), model_memory.size() - 16) == rt::Status::kOk);
  REQUIRE(in_place.narrow_phase() != nullptr);
  std::vector<unsigned char> ws_memory(rt::Workspace::RequiredBytes(in_place) + 16);
  rt::Workspace in_place_ws;
  REQUIRE(in_place_ws.InitInPlace(in_place, at16(ws_memory), ws_memory.size() - 16) == rt::Status::kOk);
  // Moving keeps the narrow phase where it is (in the block).
  rt::Model moved = std::move(model);
  rt::Workspace moved_ws = std::move(ws);
  CHECK(model.narrow_phase() == nullptr);
  CHECK(ws.narrow_phase() == nullptr);
  CHECK(moved.narrow_phase() == &held);

  auto contacts = [&](const rt::NarrowPhaseModel& m, rt::NarrowPhaseWorkspace& w, const std::vector<float>& pos,
                      rt::Exclusions ex) {
    std::vector<rt::TriangleContact> out(1u << 16);
    uint32_t n = 0;
    rt::NarrowPhaseJob job;
    job.model = &m;
    job.workspace = &w;
    job.exclusions = ex;
    job.positions = {pos.data(), static_cast<uint32_t>(pos.size() / 3), 12};
    job.output = out.data();
    job.capacity = static_cast<uint32_t>(out.size());
    job.count = &n;
    REQUIRE(job.Run() == rt::Status::kOk);
    out.resize(n);
    return AsSet(out);
  };
  const std::vector<float> elbow = Fold(mesh, tube, 15, 100.0f), hairpin = Fold(mesh, tube, 15, 178.0f);
  for (const std::vector<float>* pos : {&elbow, &hairpin})
    for (rt::Exclusions ex : {rt::Exclusions::kAsset, rt::Exclusions::kNone, rt::Exclusions::kCrease}) {
      const std::set<Contact> expect = contacts(alone.model, alone.ws, *pos, ex);
      CHECK(contacts(held, *moved_ws.narrow_phase(), *pos, ex) == expect);
      CHECK(contacts(*in_place.narrow_phase(), *in_place_ws.narrow_phase(), *pos, ex) == expect);
    }
  const std::set<Contact> elbow_all = contacts(held, *moved_ws.narrow_phase(), elbow, rt::Exclusions::kNone);
  const std::set<Contact> elbow_asset = contacts(held, *moved_ws.narrow_phase(), elbow, rt::Exclusions::kAsset);
  CHECK(elbow_asset.size() < elbow_all.size());
  for (const Contact& c : elbow_all)
    CHECK((elbow_asset.count(c) == 1) == !held.IsExcluded(std::get<0>(c), std::get<1>(c)));
  CHECK(!contacts(held, *moved_ws.narrow_phase(), hairpin, rt::Exclusions::kCrease).empty());

  // A model without the option has none, and its workspaces neither.
  rt::Model plain;
  REQUIRE(plain.Init(l.view) == rt::Status::kOk);
  CHECK(plain.narrow_phase() == nullptr);
  CHECK(plain.bytes() == broad);
  rt::Workspace plain_ws;
  REQUIRE(plain_ws.Init(plain) == rt::Status::kOk);
  CHECK(plain_ws.narrow_phase() == nullptr);
}
