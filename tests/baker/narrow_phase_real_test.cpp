// The runtime narrow phase on real characters equals the exact ground truth, contact for contact:
// MakeHuman (morph key frames) against CGAL box intersection + exact do_intersect (ExactSelfIntersections),
// CesiumMan and BCN_Epileptic (clip frames) also against brute force over every triangle pair. The reach
// regions' model (NarrowPhaseRegions::kReach) equals it unrestricted; restricted to a list of sphere pairs
// it finds exactly the contacts whose triangles stand behind a listed pair (computed here from
// ReachTriangles), each once, under their owners — where the surrounding regions' model finds only those
// whose two owners are listed.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#include "spherechain/playback/animation.h"
#include "spherechain/baker/bake.h"
#include "spherechain/baker/contacts.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/morph.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"
#include "spherechain/runtime/triangle_intersect.h"
#include "test_data.h"

using namespace spherechain;

namespace {

struct Baked {
  baker::BakeResult bake;
  import::LoadedAsset loaded;  // the baked bytes, aligned and verified (import::LoadAssetBytes)
  runtime::AssetView view;
  runtime::NarrowPhaseModel narrow, reach;
  runtime::NarrowPhaseWorkspace narrow_ws, reach_ws;
  std::vector<uint32_t> weld;
};

bool BakeAndLoad(const std::string& path, Baked* b, const baker::BakeConfig& config = {}) {
  baker::Context ctx;
  auto r = baker::Bake(path, config, &ctx);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  b->bake = std::move(r).value();
  REQUIRE(import::LoadAssetBytes(b->bake.asset.data(), b->bake.asset.size(), "the bake", &b->loaded).ok());
  b->view = b->loaded.view;
  REQUIRE(b->narrow.Init(b->view) == runtime::Status::kOk);
  REQUIRE(b->narrow_ws.Init(b->narrow) == runtime::Status::kOk);
  REQUIRE(b->reach.Init(b->view, runtime::NarrowPhaseRegions::kReach) == runtime::Status::kOk);
  REQUIRE(b->reach.regions() == runtime::NarrowPhaseRegions::kReach);
  REQUIRE(b->reach_ws.Init(b->reach) == runtime::Status::kOk);
  b->weld = baker::ComputeWeldIds(b->bake.mesh.positions);
  for (uint32_t v = 0; v < b->view.vertex_count; ++v) REQUIRE(b->narrow.weld_id(v) == b->weld[v]);
  return true;
}

using PairSet = std::set<baker::TrianglePair>;

PairSet NarrowContacts(Baked* b, const std::vector<float>& pos, runtime::NarrowPhaseStats* stats, bool reach = false,
                       const std::vector<runtime::Collision>* pairs = nullptr) {
  std::vector<runtime::TriangleContact> out(1u << 20);
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = reach ? &b->reach : &b->narrow;
  job.workspace = reach ? &b->reach_ws : &b->narrow_ws;
  if (pairs) job.sphere_pairs = pairs->data(), job.sphere_pair_count = static_cast<uint32_t>(pairs->size());
  job.positions = {pos.data(), b->view.vertex_count, 12};
  job.output = out.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = &n;
  job.stats = stats;
  REQUIRE(job.Run() == runtime::Status::kOk);
  PairSet s;
  for (uint32_t i = 0; i < n; ++i) {
    const auto& c = out[i];
    CHECK(b->narrow.triangle_sphere(c.triangle_a) == c.sphere_a);
    CHECK(b->narrow.triangle_sphere(c.triangle_b) == c.sphere_b);
    CHECK(c.sphere_a < c.sphere_b);
    CHECK_FALSE(b->narrow.IsExcluded(c.sphere_a, c.sphere_b));
    s.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)});
  }
  CHECK(s.size() == n);  // no contact reported twice
  return s;
}

/// Contacts of the ground truth: owning spheres differ, assigned, not an excluded pair.
PairSet CountedContacts(const Baked& b, const std::vector<baker::TrianglePair>& all) {
  PairSet s;
  for (const auto& p : all) {
    const uint32_t sa = b.narrow.triangle_sphere(p.a), sb = b.narrow.triangle_sphere(p.b);
    if (sa == 0xFFFF || sb == 0xFFFF || sa == sb || b.narrow.IsExcluded(sa, sb)) continue;
    s.insert(p);
  }
  return s;
}

/// Every triangle pair, no boxes: non-adjacent by weld id, exact predicate.
std::vector<baker::TrianglePair> BruteForce(const Baked& b, const std::vector<float>& pos) {
  const auto& idx = b.bake.mesh.indices;
  const uint32_t T = b.view.triangle_count;
  std::vector<baker::TrianglePair> out;
  auto v = [&](uint32_t t, int k) { return &pos[3 * size_t{idx[3 * t + k]}]; };
  for (uint32_t s = 0; s < T; ++s) {
    const uint32_t ws[3] = {b.weld[idx[3 * s]], b.weld[idx[3 * s + 1]], b.weld[idx[3 * s + 2]]};
    for (uint32_t t = s + 1; t < T; ++t) {
      const uint32_t w0 = b.weld[idx[3 * t]], w1 = b.weld[idx[3 * t + 1]], w2 = b.weld[idx[3 * t + 2]];
      bool adjacent = false;
      for (uint32_t w : ws) adjacent |= w == w0 || w == w1 || w == w2;
      if (adjacent) continue;
      if (runtime::TrianglesIntersect(v(s, 0), v(s, 1), v(s, 2), v(t, 0), v(t, 1), v(t, 2))) out.push_back({s, t});
    }
  }
  return out;
}

void CheckFrame(Baked* b, const std::vector<float>& pos, bool brute_force, const std::string& what, size_t* total) {
  runtime::NarrowPhaseStats stats;
  const PairSet narrow = NarrowContacts(b, pos, &stats);
  auto exact = baker::ExactSelfIntersections(pos.data(), b->view.vertex_count, b->bake.mesh.indices, b->weld);
  REQUIRE(exact.ok());
  const PairSet truth = CountedContacts(*b, exact.value());
  CHECK_MESSAGE(narrow == truth, what << ": narrow " << narrow.size() << " vs exact " << truth.size());
  if (brute_force) {
    const PairSet brute = CountedContacts(*b, BruteForce(*b, pos));
    CHECK_MESSAGE(narrow == brute, what << ": narrow " << narrow.size() << " vs brute force " << brute.size());
  }
  CHECK_MESSAGE(NarrowContacts(b, pos, nullptr, true) == truth, what << ": reach regions, unrestricted");

  // Restricted: for each contact, one sphere pair — a sphere its first triangle stands behind other than
  // its owner (when there is one), with the owner of the second — plus every third contact's owner pair.
  std::vector<std::vector<uint32_t>> behind(b->view.triangle_count);
  for (uint32_t s = 0; s < b->view.sphere_count; ++s) {
    const runtime::TriangleSpan span = runtime::ReachTriangles(b->view, s);
    for (uint32_t i = 0; i < span.count; ++i) behind[span.data[i]].push_back(s);
  }
  std::set<std::pair<uint32_t, uint32_t>> listed;
  size_t k = 0;
  for (const baker::TrianglePair& p : truth) {
    const uint32_t oa = b->narrow.triangle_sphere(p.a), ob = b->narrow.triangle_sphere(p.b);
    uint32_t x = oa;
    for (uint32_t s : behind[p.a])
      if (s != oa && s != ob) x = s;
    if (x != ob && !b->narrow.IsExcluded(x, ob)) listed.insert({std::min(x, ob), std::max(x, ob)});
    if (k++ % 3 == 0) listed.insert({std::min(oa, ob), std::max(oa, ob)});
  }
  std::vector<runtime::Collision> list;
  for (const auto& [x, y] : listed) list.push_back({uint16_t(x), uint16_t(y), 0.0f, 0u});
  PairSet expect_reach, expect_owners;
  for (const baker::TrianglePair& p : truth) {
    const uint32_t oa = b->narrow.triangle_sphere(p.a), ob = b->narrow.triangle_sphere(p.b);
    if (listed.count({std::min(oa, ob), std::max(oa, ob)})) expect_owners.insert(p);
    for (uint32_t x : behind[p.a])
      for (uint32_t y : behind[p.b])
        if (x != y && listed.count({std::min(x, y), std::max(x, y)})) expect_reach.insert(p);
  }
  const PairSet got_reach = NarrowContacts(b, pos, nullptr, true, &list);
  const PairSet got_owners = NarrowContacts(b, pos, nullptr, false, &list);
  CHECK_MESSAGE(got_reach == expect_reach, what << ": reach regions, restricted: " << got_reach.size() << " vs " << expect_reach.size());
  CHECK_MESSAGE(got_owners == expect_owners, what << ": surrounding regions, restricted: " << got_owners.size() << " vs " << expect_owners.size());
  if (!truth.empty()) MESSAGE(what << ": restricted to " << list.size() << " pairs: surrounding regions find " << got_owners.size()
                                   << ", reach regions " << got_reach.size() << " of " << truth.size());

  *total += truth.size();
  const double all_pairs = 0.5 * double(b->view.triangle_count) * double(b->view.triangle_count - 1);
  MESSAGE(what << ": " << truth.size() << " contacts, " << stats.candidate_pairs << " candidate sphere pairs, "
               << stats.triangle_tests << " triangle tests (all pairs / tests = "
               << (stats.triangle_tests ? all_pairs / stats.triangle_tests : 0.0) << ")");
}

}  // namespace

TEST_CASE("heavy: narrow phase on real frames: MakeHuman morph key poses equal the exact ground truth") {
  const std::string path = test::SharedData("makehuman/base.obj");
  const std::string poses_dir = test::SourceFile("data/poses/makehuman");
  if (!test::Require(path) || !test::Require(poses_dir)) return;
  Baked b;
  BakeAndLoad(path, &b);
  auto poses = playback::LoadPoseFolder(poses_dir, *b.bake.mesh.skin);
  REQUIRE(poses.ok());
  const uint32_t frames = 40, keys = static_cast<uint32_t>(poses->size());
  std::vector<float> pos(b.bake.mesh.positions.size());
  playback::SkinningScratch scratch;
  size_t total = 0;
  CheckFrame(&b, b.bake.mesh.positions, false, "MakeHuman bind", &total);
  for (uint32_t k = 0; k < keys; ++k) {
    const uint32_t f = playback::MorphKeyFrame(k, frames, keys);
    REQUIRE(playback::SkinMorphFrame(b.bake.mesh, poses.value(), f, frames, &scratch, pos.data(), pos.size()).ok());
    CheckFrame(&b, pos, false, "MakeHuman frame " + std::to_string(f) + " (" + poses.value()[k].name + ")", &total);
  }
  CHECK(total > 0);  // the key poses do make contacts (arms crossed, knee to chest, ...)
}

TEST_CASE("heavy: narrow phase on real frames: CesiumMan walk and BCN_Epileptic clip equal brute force") {
  test::SomeInputs inputs;
  for (const std::string& path :
       {test::SharedData("gltf/CesiumMan.gltf"), test::AssimpModel("X/BCN_Epileptic.X")}) {
    if (!inputs.Found(path)) continue;
    Baked b;
    BakeAndLoad(path, &b);
    REQUIRE(!b.bake.mesh.clips.empty());
    const baker::Clip& clip = b.bake.mesh.clips.front();
    std::vector<float> pos(b.bake.mesh.positions.size());
    playback::SkinningScratch scratch;
    size_t total = 0;
    for (uint32_t f = 0; f < 40; f += 8) {
      const float t = clip.duration_s * float(f) / 40.0f;
      REQUIRE(playback::SkinClip(b.bake.mesh, clip, t, &scratch, pos.data(), pos.size()).ok());
      CheckFrame(&b, pos, true, path + " frame " + std::to_string(f), &total);
    }
  }
}

namespace {

// The skin's definition computed apart from the runtime's sweep: CGAL's box intersection + exact
// do_intersect (ExactSelfIntersections) on the frame, kept unless a crease graph built here from the mesh
// alone (its own weld ids and bind positions, not the asset's) calls the pair a fold.
PairSet SkinTruth(const Baked& b, const std::vector<float>& pos, float crease) {
  const baker::Mesh& mesh = b.bake.mesh;
  runtime::CreaseGraph graph;
  REQUIRE(graph.Init(mesh.positions.data(), mesh.vertex_count(), mesh.indices.data(), mesh.triangle_count(),
                     b.weld.data(), crease) == runtime::Status::kOk);
  runtime::CreaseScratch scratch;
  REQUIRE(scratch.Init(graph) == runtime::Status::kOk);
  auto exact = baker::ExactSelfIntersections(pos.data(), mesh.vertex_count(), mesh.indices, b.weld);
  REQUIRE(exact.ok());
  PairSet truth;
  for (const baker::TrianglePair& p : exact.value())
    if (!scratch.Near(graph, &mesh.indices[3 * size_t{p.a}], &mesh.indices[3 * size_t{p.b}], crease)) truth.insert(p);
  return truth;
}

PairSet CreaseContacts(Baked* b, const std::vector<float>& pos, runtime::NarrowPhaseStats* stats, float crease = 0,
                       const std::vector<runtime::Collision>* pairs = nullptr) {
  std::vector<runtime::TriangleContact> out(1u << 18);
  std::vector<runtime::ContactDepth> depth(out.size());
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &b->narrow;
  job.workspace = &b->narrow_ws;
  job.depths = depth.data();
  job.exclusions = runtime::Exclusions::kCrease;
  job.crease = crease;
  static const runtime::Collision kNoPair{};  // an empty list is a non-null pointer (null: every pair)
  if (pairs) job.sphere_pairs = pairs->empty() ? &kNoPair : pairs->data(), job.sphere_pair_count = static_cast<uint32_t>(pairs->size());
  job.positions = {pos.data(), b->view.vertex_count, 12};
  job.output = out.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = &n;
  job.stats = stats;
  REQUIRE(job.Run() == runtime::Status::kOk);
  PairSet s;
  for (uint32_t i = 0; i < n; ++i) {
    const auto& c = out[i];
    CHECK(b->narrow.triangle_sphere(c.triangle_a) == c.sphere_a);
    CHECK(b->narrow.triangle_sphere(c.triangle_b) == c.sphere_b);
    CHECK((c.sphere_a < c.sphere_b || (c.sphere_a == c.sphere_b && c.triangle_a < c.triangle_b)));
    s.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)});
    // Its depth: what ContactDepthOf says of the two triangles, never more than the larger one's diameter
    // (a corner's distance behind the other's plane, the other's corners straddling it), a unit direction.
    const uint32_t* tri = b->view.asset->triangles()->data();
    const float* pa[3];
    const float* pb[3];
    double diameter = 0;
    for (int j = 0; j < 3; ++j) {
      pa[j] = &pos[3 * size_t{tri[3 * size_t{c.triangle_a} + j]}];
      pb[j] = &pos[3 * size_t{tri[3 * size_t{c.triangle_b} + j]}];
    }
    for (const float* const* p : {pa, pb})
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          const double dx = p[j][0] - p[k][0], dy = p[j][1] - p[k][1], dz = p[j][2] - p[k][2];
          diameter = std::max(diameter, std::sqrt(dx * dx + dy * dy + dz * dz));
        }
    runtime::ContactDepth expect{};
    runtime::ContactDepthOf(pa, pb, &expect);
    const runtime::ContactDepth& d = depth[i];
    CHECK(d.depth == expect.depth);
    CHECK(d.depth >= 0.0f);
    CHECK(d.depth <= diameter * (1 + 1e-6));
    const double len = std::sqrt(double(d.direction[0]) * d.direction[0] + double(d.direction[1]) * d.direction[1] +
                                 double(d.direction[2]) * d.direction[2]);
    CHECK(len == doctest::Approx(1.0).epsilon(1e-5));
  }
  CHECK(s.size() == n);
  return s;
}

}  // namespace

namespace {
// One crease job on `pos`, with the frame's skinning matrices (column-major, SkinningScratch::matrices)
// or without (null): its records and depths, in order.
struct CullRun {
  std::vector<runtime::TriangleContact> contacts;
  std::vector<runtime::ContactDepth> depths;
  runtime::NarrowPhaseStats stats;
};
CullRun CreaseRun(Baked* b, const std::vector<float>& pos, const std::vector<playback::Matrix4>* matrices) {
  CullRun r;
  r.contacts.resize(1u << 18), r.depths.resize(r.contacts.size());
  std::vector<float> joints;
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &b->narrow;
  job.workspace = &b->narrow_ws;
  job.exclusions = runtime::Exclusions::kCrease;
  job.positions = {pos.data(), b->view.vertex_count, 12};
  job.output = r.contacts.data();
  job.depths = r.depths.data();
  job.capacity = static_cast<uint32_t>(r.contacts.size());
  job.count = &n;
  job.stats = &r.stats;
  if (matrices) {
    joints.resize(matrices->size() * runtime::kJointMatrixFloats);
    for (size_t j = 0; j < matrices->size(); ++j)
      runtime::JointMatrixFromColumnMajor((*matrices)[j].data(), &joints[j * runtime::kJointMatrixFloats]);
    job.joint_matrices = joints.data();
    job.joint_count = static_cast<uint32_t>(matrices->size());
  }
  REQUIRE(job.Run() == runtime::Status::kOk);
  r.contacts.resize(n), r.depths.resize(n);
  return r;
}

// The joint-matrix cull changes nothing the job reports: the same records, depths and order, frame for frame.
// The restricted path (kCrease with sphere_pairs) on one frame whose exact skin contacts are `all`: it reports
// a subset of them, each once, and at least every contact whose two triangles' owners are a listed pair or one
// listed sphere (their patches hold triangles behind them) and every contact of the bind pose. Listing every
// sphere pair finds every contact between owned triangles. Returns the restricted contacts.
PairSet CheckRestricted(Baked* b, const std::vector<float>& pos, const PairSet& all,
                        const std::vector<runtime::Collision>& listed) {
  runtime::NarrowPhaseStats st;
  std::set<std::pair<uint32_t, uint32_t>> pairs;
  for (const runtime::Collision& c : listed) pairs.insert({c.a, c.b}), pairs.insert({c.a, c.a}), pairs.insert({c.b, c.b});
  const PairSet some = CreaseContacts(b, pos, &st, 0.0f, &listed);
  CHECK(st.contacts == some.size());
  for (const baker::TrianglePair& p : some) CHECK(all.count(p) == 1);
  for (const baker::TrianglePair& p : all) {
    const uint32_t sa = b->narrow.triangle_sphere(p.a), sb = b->narrow.triangle_sphere(p.b);
    if (pairs.count({std::min(sa, sb), std::max(sa, sb)}) || b->narrow.IntersectsAtBind(p.a, p.b)) CHECK(some.count(p) == 1);
  }
  std::vector<runtime::Collision> every;
  for (uint32_t a = 0; a < b->view.sphere_count; ++a)
    for (uint32_t c = a + 1; c < b->view.sphere_count; ++c) every.push_back({uint16_t(a), uint16_t(c), 0.0f, 0u});
  const PairSet whole = CreaseContacts(b, pos, &st, 0.0f, &every);
  for (const baker::TrianglePair& p : all) {
    const uint32_t sa = b->narrow.triangle_sphere(p.a), sb = b->narrow.triangle_sphere(p.b);
    if (sa != 0xFFFF && sb != 0xFFFF) CHECK(whole.count(p) == 1);
  }
  for (const baker::TrianglePair& p : whole) CHECK(all.count(p) == 1);
  return some;
}

void CheckJointCull(Baked* b, const std::vector<float>& pos, const playback::SkinningScratch& scratch,
                    uint64_t* culled, uint64_t* contacts) {
  const CullRun plain = CreaseRun(b, pos, nullptr);
  const CullRun cull = CreaseRun(b, pos, &scratch.matrices);
  REQUIRE(cull.contacts.size() == plain.contacts.size());
  CHECK(std::memcmp(cull.contacts.data(), plain.contacts.data(), plain.contacts.size() * sizeof(runtime::TriangleContact)) == 0);
  CHECK(std::memcmp(cull.depths.data(), plain.depths.data(), plain.depths.size() * sizeof(runtime::ContactDepth)) == 0);
  CHECK(cull.stats.contacts == plain.stats.contacts);
  CHECK(cull.stats.bind_contacts == plain.stats.bind_contacts);
  CHECK(cull.stats.candidate_pairs == plain.stats.candidate_pairs);  // culled pairs are still counted
  CHECK(plain.stats.joint_culled == 0);
  CHECK(cull.stats.box_tests <= plain.stats.box_tests);
  *culled += cull.stats.joint_culled;
  *contacts += cull.contacts.size();
}
}  // namespace

TEST_CASE("heavy: the crease rule on real frames: CesiumMan walk and BCN_Epileptic clip equal the skin's truth") {
  // Every self-contact the skin makes, whichever spheres own it: the crease job equals the definition computed
  // apart (at the asset's crease and at twice it), and it finds contacts the exclusion-based job cannot (pairs
  // of one sphere or of an excluded pair) — the walking arm on the flank. Baked with the skin weights: the
  // job given the frame's joint matrices reports the same, in the same order (the joint-matrix cull).
  test::SomeInputs inputs;
  baker::BakeConfig config;
  config.skin_weights = true;
  for (const std::string& path :
       {test::SharedData("gltf/CesiumMan.gltf"), test::AssimpModel("X/BCN_Epileptic.X")}) {
    if (!inputs.Found(path)) continue;
    CAPTURE(path);
    Baked b;
    BakeAndLoad(path, &b, config);
    REQUIRE(b.narrow.has_crease());
    REQUIRE(b.narrow.has_joint_cull());
    CHECK(b.narrow.crease() == doctest::Approx(0.03 * b.bake.fit.body_height).epsilon(1e-5));
    const baker::Clip& clip = b.bake.mesh.clips.front();
    std::vector<float> pos(b.bake.mesh.positions.size());
    playback::SkinningScratch scratch;
    size_t total = 0, hidden = 0, restricted = 0;
    uint64_t culled = 0, cull_contacts = 0;
    // The restricted path behind the first ten excluded pairs (neighbours the proxy never reports).
    std::vector<runtime::Collision> folds;
    for (uint32_t i = 0; i < 10 && i < b.view.asset->excluded_pairs()->size(); ++i) {
      const auto* e = b.view.asset->excluded_pairs()->Get(i);
      folds.push_back({e->a(), e->b(), 0.0f, 0u});
    }
    for (uint32_t f = 0; f < 40; f += 8) {
      CAPTURE(f);
      REQUIRE(playback::SkinClip(b.bake.mesh, clip, clip.duration_s * float(f) / 40.0f, &scratch, pos.data(), pos.size()).ok());
      CheckJointCull(&b, pos, scratch, &culled, &cull_contacts);
      for (float scale : {1.0f, 2.0f}) {
        const float crease = scale * b.narrow.crease();
        runtime::NarrowPhaseStats st;
        const PairSet found = CreaseContacts(&b, pos, &st, scale == 1.0f ? 0.0f : crease);
        const PairSet truth = SkinTruth(b, pos, crease);
        CHECK(found == truth);
        if (scale != 1.0f) continue;
        restricted += CheckRestricted(&b, pos, found, folds).size();
        total += found.size();
        for (const baker::TrianglePair& p : found) {
          const uint32_t sa = b.narrow.triangle_sphere(p.a), sb = b.narrow.triangle_sphere(p.b);
          hidden += sa == sb || b.narrow.IsExcluded(sa, sb);
        }
      }
    }
    MESSAGE(path << ": " << total << " skin contacts over 5 frames, " << hidden << " of them in one sphere or an excluded pair; "
                 << culled << " pairs of patches culled by the joint matrices; " << restricted
                 << " behind ten excluded pairs (restricted path)");
    CHECK(restricted < total);  // the restriction leaves contacts out
    CHECK(total > 0);
    CHECK(cull_contacts == total);
    CHECK(culled > 0);
    CHECK(hidden > 0);  // what the exclusion-based definition hid
  }
}

TEST_CASE("heavy: the crease rule never reads the exclusions: ten times the bind-near exclusions, the same contacts") {
  // The same character baked twice, the second with near_rel 10x (many more sphere pairs excluded as near at
  // bind). The exclusion-based job loses contacts to them; the skin's contacts stay the same, frame for frame.
  test::SomeInputs inputs;
  for (const std::string& path : {test::SharedData("gltf/CesiumMan.gltf"), test::AssimpModel("X/BCN_Epileptic.X")}) {
    if (!inputs.Found(path)) continue;
    CAPTURE(path);
    Baked plain, wide;
    BakeAndLoad(path, &plain);
    baker::BakeConfig config;
    config.near_rel = 10 * config.near_rel;
    BakeAndLoad(path, &wide, config);
    const auto& pe = *plain.view.asset->excluded_pairs();
    const auto& we = *wide.view.asset->excluded_pairs();
    CHECK(we.size() > pe.size() + 20);
    REQUIRE(plain.view.sphere_count == wide.view.sphere_count);
    const baker::Clip& clip = plain.bake.mesh.clips.front();
    std::vector<float> pos(plain.bake.mesh.positions.size());
    playback::SkinningScratch scratch;
    size_t total = 0, asset_plain = 0, asset_wide = 0;
    for (uint32_t f = 0; f < 40; f += 4) {
      CAPTURE(f);
      REQUIRE(playback::SkinClip(plain.bake.mesh, clip, clip.duration_s * float(f) / 40.0f, &scratch, pos.data(), pos.size()).ok());
      runtime::NarrowPhaseStats st;
      const PairSet a = CreaseContacts(&plain, pos, &st), b = CreaseContacts(&wide, pos, &st);
      CHECK(a == b);
      total += a.size();
      asset_plain += NarrowContacts(&plain, pos, &st).size();
      asset_wide += NarrowContacts(&wide, pos, &st).size();
    }
    MESSAGE(path << ": " << total << " skin contacts over 10 frames with either asset; the exclusion-based job "
                 << asset_plain << " and " << asset_wide);
    CHECK(total > 0);
    CHECK(asset_wide < asset_plain);  // the exclusions do hide contacts from the old definition
  }
}

TEST_CASE("the crease rule: the synthetic creature's crossing fore legs are contacts; bad jobs and old assets refused") {
  const std::string creature = test::SourceFile("tests/data/creature/creature.gltf");
  Baked b;
  BakeAndLoad(creature, &b);
  REQUIRE(b.narrow.has_crease());
  CHECK(b.narrow.bind_contact_count() == 0);  // the cubes' surface does not pass through itself
  const baker::Clip* cross = nullptr;
  for (const baker::Clip& c : b.bake.mesh.clips)
    if (c.name == "cross") cross = &c;
  REQUIRE(cross);
  std::vector<float> pos(b.bake.mesh.positions.size());
  playback::SkinningScratch scratch;
  // Mid-clip the left fore leg lies across the right one: contacts, every one between the two fore legs
  // (regions ForeLeg_L and ForeLeg_R), none a fold. At bind pose: nothing.
  REQUIRE(playback::SkinClip(b.bake.mesh, *cross, 0.5f, &scratch, pos.data(), pos.size()).ok());
  runtime::NarrowPhaseStats st;
  const PairSet mid = CreaseContacts(&b, pos, &st);
  CHECK(mid == SkinTruth(b, pos, b.narrow.crease()));
  REQUIRE(!mid.empty());
  const auto& layout = b.bake.segmentation.layout;
  for (const baker::TrianglePair& p : mid) {
    const std::string ra = layout.Name(baker::Region(b.bake.segmentation.triangle_regions[p.a]));
    const std::string rb = layout.Name(baker::Region(b.bake.segmentation.triangle_regions[p.b]));
    CHECK(((ra == "ForeLeg_L" && rb == "ForeLeg_R") || (ra == "ForeLeg_R" && rb == "ForeLeg_L")));
  }
  CHECK(CreaseContacts(&b, b.bake.mesh.positions, &st).empty());
  // The restricted path: behind no sphere pair (an empty list), only the bind pose's contacts are swept —
  // none here, so no vertex is read (NaN positions pass); behind the two fore legs' spheres, every contact.
  {
    runtime::NarrowPhaseStats none_st;
    const std::vector<runtime::Collision> none;
    std::vector<float> nan_pos(pos.size(), std::numeric_limits<float>::quiet_NaN());
    CHECK(CreaseContacts(&b, nan_pos, &none_st, 0.0f, &none).empty());
    CHECK(none_st.candidate_pairs == 0);
    std::set<uint16_t> legs;
    for (const baker::TrianglePair& p : mid) legs.insert(b.narrow.triangle_sphere(p.a)), legs.insert(b.narrow.triangle_sphere(p.b));
    std::vector<runtime::Collision> leg_pairs;
    for (uint16_t x : legs)
      for (uint16_t y : legs)
        if (x < y) leg_pairs.push_back({x, y, 0.0f, 0u});
    REQUIRE(!leg_pairs.empty());
    CHECK(CreaseContacts(&b, pos, &none_st, 0.0f, &leg_pairs) == mid);
  }
  // FoldPairs: the excluded pairs whose centres came closer than at bind by more than `closing`. The bind
  // spheres themselves: none; one sphere moved onto its excluded partner: that pair, its overlap as depth.
  {
    const auto* sp = b.view.asset->spheres();
    const uint32_t S = b.view.sphere_count;
    std::vector<float> x(S), y(S), z(S), r(S);
    for (uint32_t i = 0; i < S; ++i)
      x[i] = sp->Get(i)->center().x(), y[i] = sp->Get(i)->center().y(), z[i] = sp->Get(i)->center().z(), r[i] = sp->Get(i)->radius();
    runtime::SphereArrays arrays{x.data(), y.data(), z.data(), r.data(), S};
    std::vector<runtime::Collision> folds(b.narrow.fold_pair_count());
    REQUIRE(b.narrow.fold_pair_count() == b.view.asset->excluded_pairs()->size());
    REQUIRE(!folds.empty());
    uint32_t count = 99;
    CHECK(runtime::FoldPairs(b.narrow, arrays, 0.0f, folds.data(), uint32_t(folds.size()), &count) == runtime::Status::kOk);
    CHECK(count == 0);
    const auto* e = b.view.asset->excluded_pairs()->Get(0);
    const float d = std::hypot(x[e->a()] - x[e->b()], y[e->a()] - y[e->b()], z[e->a()] - z[e->b()]);
    x[e->b()] = x[e->a()], y[e->b()] = y[e->a()], z[e->b()] = z[e->a()];
    CHECK(runtime::FoldPairs(b.narrow, arrays, 0.5f * d, folds.data(), uint32_t(folds.size()), &count) == runtime::Status::kOk);
    REQUIRE(count >= 1);
    bool seen = false;
    for (uint32_t i = 0; i < count; ++i) {
      CHECK(folds[i].a < folds[i].b);
      CHECK(b.narrow.IsExcluded(folds[i].a, folds[i].b));
      if (folds[i].a != e->a() || folds[i].b != e->b()) continue;
      seen = true;
      CHECK(folds[i].depth == r[e->a()] + r[e->b()]);
    }
    CHECK(seen);
    CHECK(runtime::FoldPairs(b.narrow, arrays, 2.0f * d, folds.data(), uint32_t(folds.size()), &count) == runtime::Status::kOk);
    for (uint32_t i = 0; i < count; ++i) CHECK_FALSE((folds[i].a == e->a() && folds[i].b == e->b()));
    CHECK(runtime::FoldPairs(b.narrow, arrays, 0.5f * d, nullptr, 0, &count) == runtime::Status::kOkTruncated);
    CHECK(count >= 1);
    CHECK(runtime::FoldPairs(b.narrow, arrays, -1.0f, folds.data(), 1, &count) == runtime::Status::kErrorInvalidJob);
    CHECK(runtime::FoldPairs(b.narrow, arrays, std::numeric_limits<float>::quiet_NaN(), folds.data(), 1, &count) ==
          runtime::Status::kErrorInvalidJob);
    CHECK(runtime::FoldPairs(b.narrow, arrays, 0.0f, folds.data(), 1, nullptr) == runtime::Status::kErrorNullArgument);
    arrays.count = S - 1;
    CHECK(runtime::FoldPairs(b.narrow, arrays, 0.0f, folds.data(), 1, &count) == runtime::Status::kErrorCountMismatch);
    runtime::NarrowPhaseModel empty;
    arrays.count = S;
    CHECK(runtime::FoldPairs(empty, arrays, 0.0f, folds.data(), 1, &count) == runtime::Status::kErrorInvalidJob);
  }
  // Bad jobs: a crease below the asset's, or not finite.
  runtime::NarrowPhaseJob job;
  std::vector<runtime::TriangleContact> out(16);
  uint32_t n = 0;
  job.model = &b.narrow;
  job.workspace = &b.narrow_ws;
  job.exclusions = runtime::Exclusions::kCrease;
  job.positions = {pos.data(), b.view.vertex_count, 12};
  job.output = out.data();
  job.capacity = 16;
  job.count = &n;
  job.crease = 0.5f * b.narrow.crease();
  CHECK(job.Run() == runtime::Status::kErrorInvalidJob);
  job.crease = std::numeric_limits<float>::quiet_NaN();
  CHECK(job.Run() == runtime::Status::kErrorInvalidJob);
  job.crease = 0.0f;
  runtime::Collision one{};
  one.a = 1, one.b = 1;  // a >= b
  job.sphere_pairs = &one, job.sphere_pair_count = 1;
  CHECK(job.Run() == runtime::Status::kErrorIndexOutOfRange);
  job.sphere_pairs = nullptr, job.sphere_pair_count = 0;
  CHECK(job.Run() == runtime::Status::kOkTruncated);  // more than 16 contacts: the first 16, count complete
  CHECK(n == 16);
  // An asset baked before the rule (the golden v4 creature): loads, runs the old definition, and a crease
  // job gets kErrorMissingField.
  const std::string golden = test::SourceFile("tests/data/golden/v4/creature.sphc");
  REQUIRE(std::filesystem::exists(golden));
  import::LoadedAsset old_asset;
  REQUIRE(import::LoadAssetFile(golden, &old_asset).ok());
  const runtime::AssetView& old_view = old_asset.view;
  runtime::NarrowPhaseModel old_model;
  runtime::NarrowPhaseWorkspace old_ws;
  REQUIRE(old_model.Init(old_view) == runtime::Status::kOk);
  REQUIRE(old_ws.Init(old_model) == runtime::Status::kOk);
  CHECK_FALSE(old_model.has_crease());
  job.model = &old_model, job.workspace = &old_ws;
  job.positions = {pos.data(), old_view.vertex_count, 12};
  if (old_view.vertex_count == b.view.vertex_count) CHECK(job.Run() == runtime::Status::kErrorMissingField);
  job.exclusions = runtime::Exclusions::kAsset;
  if (old_view.vertex_count == b.view.vertex_count) CHECK(runtime::Succeeded(job.Run()));
}

TEST_CASE("heavy: the joint-matrix cull on real frames: the MakeHuman morph unchanged") {
  // Baked with the skin weights, the narrow phase given the frame's skinning matrices skips neighbouring
  // patches that moved nearly rigidly; the contacts, depths and their order stay those of the job without
  // matrices on every frame, and the cull does skip most of those pairs (CesiumMan and BCN_Epileptic: with
  // the crease rule's test on their clips).
  baker::BakeConfig config;
  config.skin_weights = true;
  test::SomeInputs inputs;
  const std::string mh = test::SharedData("makehuman/base.obj");
  const std::string poses_dir = test::SourceFile("data/poses/makehuman");
  if (inputs.Found(mh) && inputs.Found(poses_dir)) {
    Baked b;
    BakeAndLoad(mh, &b, config);
    REQUIRE(b.narrow.has_joint_cull());
    CHECK(b.narrow.joint_count() == b.bake.mesh.skin->joints.size());
    auto poses = playback::LoadPoseFolder(poses_dir, *b.bake.mesh.skin);
    REQUIRE(poses.ok());
    std::vector<float> pos(b.bake.mesh.positions.size());
    playback::SkinningScratch scratch;
    uint64_t culled = 0, contacts = 0, pairs = 0;
    for (uint32_t f = 0; f < 40; f += 2) {
      CAPTURE(f);
      REQUIRE(playback::SkinMorphFrame(b.bake.mesh, poses.value(), f, 40, &scratch, pos.data(), pos.size()).ok());
      CheckJointCull(&b, pos, scratch, &culled, &contacts);
      runtime::NarrowPhaseStats st;
      CreaseContacts(&b, pos, &st);
      pairs += st.candidate_pairs;
    }
    MESSAGE("MakeHuman morph, 20 frames: " << contacts << " contacts; " << culled << " of " << pairs
                                           << " pairs of patches culled by the joint matrices");
    CHECK(contacts > 0);
    CHECK(culled * 2 > pairs);  // 2,487 of 3,393 a frame measured
  }
}

TEST_CASE("the joint-matrix cull: the creature's crossing legs unchanged; bad matrices and assets without weights refused") {
  const std::string creature = test::SourceFile("tests/data/creature/creature.gltf");
  baker::BakeConfig config;
  config.skin_weights = true;
  Baked b, plain;
  BakeAndLoad(creature, &b, config);
  BakeAndLoad(creature, &plain);
  REQUIRE(b.narrow.has_joint_cull());
  CHECK_FALSE(plain.narrow.has_joint_cull());
  CHECK(plain.narrow.joint_count() == 0);
  // The skin rows: one count per vertex, weights summing to 255 a vertex.
  const schema::Asset& a = *b.view.asset;
  REQUIRE(a.skin_counts());
  CHECK(a.skin_counts()->size() == b.view.vertex_count);
  CHECK_FALSE(plain.view.asset->skin_counts());
  size_t e = 0;
  for (uint8_t c : *a.skin_counts()) {
    int sum = 0;
    for (uint32_t k = 0; k < c; ++k) sum += a.skin_weights()->Get(e++);
    CHECK((c == 0 || sum == 255));
  }
  CHECK(b.bake.asset.size() > plain.bake.asset.size() + 3 * e);
  const baker::Clip* cross = nullptr;
  for (const baker::Clip& c : b.bake.mesh.clips)
    if (c.name == "cross") cross = &c;
  REQUIRE(cross);
  std::vector<float> pos(b.bake.mesh.positions.size());
  playback::SkinningScratch scratch;
  uint64_t culled = 0, contacts = 0;
  for (float t : {0.0f, 0.25f, 0.5f, 0.75f}) {
    REQUIRE(playback::SkinClip(b.bake.mesh, *cross, t * cross->duration_s, &scratch, pos.data(), pos.size()).ok());
    CheckJointCull(&b, pos, scratch, &culled, &contacts);
  }
  CHECK(contacts > 0);
  // Bad jobs.
  std::vector<float> joints(scratch.matrices.size() * runtime::kJointMatrixFloats);
  for (size_t j = 0; j < scratch.matrices.size(); ++j)
    runtime::JointMatrixFromColumnMajor(scratch.matrices[j].data(), &joints[j * runtime::kJointMatrixFloats]);
  std::vector<runtime::TriangleContact> out(1024);
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &b.narrow;
  job.workspace = &b.narrow_ws;
  job.exclusions = runtime::Exclusions::kCrease;
  job.positions = {pos.data(), b.view.vertex_count, 12};
  job.output = out.data();
  job.capacity = 1024;
  job.count = &n;
  job.joint_matrices = joints.data();
  job.joint_count = b.narrow.joint_count();
  CHECK(job.Run() == runtime::Status::kOk);
  job.joint_count = b.narrow.joint_count() + 1;
  CHECK(job.Run() == runtime::Status::kErrorJointCount);
  job.joint_count = b.narrow.joint_count();
  job.exclusions = runtime::Exclusions::kAsset;
  CHECK(job.Run() == runtime::Status::kErrorInvalidJob);
  job.exclusions = runtime::Exclusions::kCrease;
  job.joint_matrices = reinterpret_cast<const float*>(reinterpret_cast<const char*>(joints.data()) + 1);
  CHECK(job.Run() == runtime::Status::kErrorAlignment);
  job.joint_matrices = joints.data();
  joints[5] = std::numeric_limits<float>::quiet_NaN();
  n = 77;
  CHECK(job.Run() == runtime::Status::kErrorNonFiniteJoints);
  CHECK(n == 0);
  job.model = &plain.narrow, job.workspace = &plain.narrow_ws;
  CHECK(job.Run() == runtime::Status::kErrorMissingField);
}

TEST_CASE("the joint-matrix cull: skin rows that do not sum to 255 (an asset the baker did not write) cull nothing wrong") {
  // LoadAsset takes rows whose weights sum to 255 within half their count (weights rounded by another tool).
  // An engine skinning with those weights as stored (q / 255) moves such a vertex by (Σq/255 − 1) of its
  // skinned position away from the rigid motion the cull's bound assumes: far from the origin, more than the
  // bound. The creature baked with the skin weights, one unit taken off one weight of every row of two or more
  // joints (sum 254, still loaded), the bind pose turned and moved 10 and 20 extents away by the same matrix
  // for every joint and skinned with the stored weights: the job with the matrices reports what it reports
  // without them.
  baker::BakeConfig config;
  config.skin_weights = true;
  Baked b;
  BakeAndLoad(test::SourceFile("tests/data/creature/creature.gltf"), &b, config);
  const schema::Asset& a = *b.view.asset;
  REQUIRE(a.skin_counts());
  std::vector<uint8_t> bytes = b.bake.asset;
  const size_t at = static_cast<size_t>(a.skin_weights()->data() - b.loaded.bytes());  // the weights' offset
  size_t e = 0, changed = 0;
  for (uint8_t c : *a.skin_counts()) {
    if (c >= 2 && bytes[at + e] > 1) --bytes[at + e], ++changed;
    e += c;
  }
  REQUIRE(changed >= 20);  // 40 of the creature's rows have two joints or more
  Baked m;
  REQUIRE(import::LoadAssetBytes(bytes.data(), bytes.size(), "the changed bake", &m.loaded).ok());
  m.view = m.loaded.view;
  REQUIRE(m.narrow.Init(m.view) == runtime::Status::kOk);
  REQUIRE(m.narrow_ws.Init(m.narrow) == runtime::Status::kOk);
  REQUIRE(m.narrow.has_joint_cull());
  const schema::Asset& ma = *m.view.asset;
  double h = 0;  // the bind pose's largest extent
  for (int r = 0; r < 3; ++r) {
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (size_t i = r; i < b.bake.mesh.positions.size(); i += 3)
      lo = std::min(lo, b.bake.mesh.positions[i]), hi = std::max(hi, b.bake.mesh.positions[i]);
    h = std::max(h, double{hi} - lo);
  }
  uint64_t contacts = 0;
  for (double k : {10.0, 20.0}) {
    CAPTURE(k);
    const float angle = 0.35f, c = std::cos(angle), sn = std::sin(angle);
    const float t[3] = {float(k * h), float(0.5 * k * h), float(0.25 * k * h)};
    playback::Matrix4 mat = {c, 0, -sn, 0, 0, 1, 0, 0, sn, 0, c, 0, t[0], t[1], t[2], 1};  // column-major: turn about y, move
    const std::vector<playback::Matrix4> matrices(b.narrow.joint_count(), mat);
    std::vector<float> pos(b.bake.mesh.positions.size());
    size_t row = 0;
    for (uint32_t v = 0; v < m.view.vertex_count; ++v) {
      const float* x = &b.bake.mesh.positions[3 * size_t{v}];
      const uint8_t count = ma.skin_counts()->Get(v);
      double w = 0;  // Σ q / 255: every matrix is the same
      for (uint32_t i = 0; i < count; ++i) w += ma.skin_weights()->Get(uint32_t(row + i)) / 255.0;
      row += count;
      if (count == 0) w = 1.0;
      for (int r = 0; r < 3; ++r)
        pos[3 * size_t{v} + r] = float(w * (mat[r] * x[0] + mat[4 + r] * x[1] + mat[8 + r] * x[2] + mat[12 + r]));
    }
    const CullRun plain = CreaseRun(&m, pos, nullptr), cull = CreaseRun(&m, pos, &matrices);
    REQUIRE(cull.contacts.size() == plain.contacts.size());
    CHECK(std::memcmp(cull.contacts.data(), plain.contacts.data(), plain.contacts.size() * sizeof(runtime::TriangleContact)) == 0);
    contacts += plain.contacts.size();
  }
  MESSAGE(changed << " rows summing to 254; " << contacts << " contacts at 10 and 20 extents away");
  CHECK(contacts > 0);  // the rows' drift crumples the skin: there is something to lose
}

namespace {
// The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5), in double.
void ClosestOnTriangle(const double p[3], const double a[3], const double b[3], const double c[3], double out[3]) {
  auto sub = [](const double* x, const double* y, double* r) { for (int k = 0; k < 3; ++k) r[k] = x[k] - y[k]; };
  auto dot = [](const double* x, const double* y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  auto at = [&](double u, double v, double w) { for (int k = 0; k < 3; ++k) out[k] = u * a[k] + v * b[k] + w * c[k]; };
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  sub(b, a, ab), sub(c, a, ac), sub(p, a, ap);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return at(1, 0, 0);
  sub(p, b, bp);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) { const double v = d1 / (d1 - d3); return at(1 - v, v, 0); }
  sub(p, c, cp);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) { const double w = d2 / (d2 - d6); return at(1 - w, 0, w); }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) { const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); return at(0, 1 - w, w); }
  const double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
  at(1 - v - w, v, w);
}
}  // namespace

TEST_CASE("heavy: a contact's depth on a real character: CesiumMan's hand in its thigh, against the penetration computed apart") {
  // CesiumMan's walk at 0.529 s (frame 16 at 30 fps) swings the left hand into the left thigh. Computed apart
  // from the narrow phase: how deep each hand vertex lies inside the thigh (the distance to its nearest leg
  // crossing triangle, for a corner of a crossing hand triangle behind that face) and each leg vertex inside
  // the hand. The deepest contact the narrow phase reports between the two regions is a separating-axis
  // estimate per triangle pair (ContactDepth); it must come out near the shallower of the two (measured: 1.05 %
  // of the height against 1.09 % of thigh in the hand; the hand is 2.7 % in the thigh).
  const std::string path = test::SharedData("gltf/CesiumMan.gltf");
  if (!test::Require(path)) return;
  Baked b;
  BakeAndLoad(path, &b);
  int hand = -1, leg = -1;
  for (uint32_t r = 0; r < runtime::RegionCount(b.view); ++r) {
    if (std::string(runtime::RegionName(b.view, r)) == "left_hand") hand = int(r);
    if (std::string(runtime::RegionName(b.view, r)) == "left_leg") leg = int(r);
  }
  REQUIRE(hand >= 0);
  REQUIRE(leg >= 0);
  const baker::Clip& clip = b.bake.mesh.clips.front();
  std::vector<float> pos(b.bake.mesh.positions.size());
  playback::SkinningScratch scratch;
  REQUIRE(playback::SkinClip(b.bake.mesh, clip, 0.5287357f, &scratch, pos.data(), pos.size()).ok());
  const uint32_t* tri = b.view.asset->triangles()->data();
  const auto* regions = b.view.asset->triangle_regions();
  // The two regions' triangles that cross each other (every pair, the exact predicate), and how deep the
  // corners of one side's crossing triangles lie behind the other side's crossing surface.
  std::vector<uint32_t> crossing[2];
  {
    std::vector<uint32_t> side[2];
    for (uint32_t t = 0; t < b.view.triangle_count; ++t) {
      if (regions->Get(t) == hand) side[0].push_back(t);
      if (regions->Get(t) == leg) side[1].push_back(t);
    }
    auto v = [&](uint32_t t, int k) { return &pos[3 * size_t{tri[3 * size_t{t} + k]}]; };
    std::set<uint32_t> in[2];
    for (uint32_t t : side[0])
      for (uint32_t u : side[1])
        if (runtime::TrianglesIntersect(v(t, 0), v(t, 1), v(t, 2), v(u, 0), v(u, 1), v(u, 2))) in[0].insert(t), in[1].insert(u);
    for (int k = 0; k < 2; ++k) crossing[k].assign(in[k].begin(), in[k].end());
  }
  REQUIRE(!crossing[0].empty());
  auto penetration = [&](const std::vector<uint32_t>& from, const std::vector<uint32_t>& faces) {
    std::vector<uint32_t> verts;
    for (uint32_t t : from) verts.insert(verts.end(), tri + 3 * size_t{t}, tri + 3 * size_t{t} + 3);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    double deepest = 0;
    for (uint32_t v : verts) {
      const double p[3] = {pos[3 * size_t{v}], pos[3 * size_t{v} + 1], pos[3 * size_t{v} + 2]};
      double best = 1e300, side = 0;
      for (uint32_t t : faces) {
        double c[3][3], q[3];
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) c[j][k] = pos[3 * size_t{tri[3 * size_t{t} + j]} + k];
        ClosestOnTriangle(p, c[0], c[1], c[2], q);
        const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
        if (d2 >= best) continue;
        best = d2;
        const double e1[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]};
        const double e2[3] = {c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]};
        const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        side = n[0] * (p[0] - q[0]) + n[1] * (p[1] - q[1]) + n[2] * (p[2] - q[2]);
      }
      if (side < 0) deepest = std::max(deepest, std::sqrt(best));  // behind its nearest face: inside
    }
    return deepest;
  };
  const double hand_in_leg = penetration(crossing[0], crossing[1]), leg_in_hand = penetration(crossing[1], crossing[0]);
  // The narrow phase's deepest contact between the two regions.
  std::vector<runtime::TriangleContact> out(1u << 16);
  std::vector<runtime::ContactDepth> depth(out.size());
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &b.narrow;
  job.workspace = &b.narrow_ws;
  job.exclusions = runtime::Exclusions::kCrease;
  job.positions = {pos.data(), b.view.vertex_count, 12};
  job.output = out.data();
  job.depths = depth.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = &n;
  REQUIRE(job.Run() == runtime::Status::kOk);
  double deepest = 0;
  uint32_t between = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const int ra = regions->Get(out[i].triangle_a), rb = regions->Get(out[i].triangle_b);
    if (std::min(ra, rb) != std::min(hand, leg) || std::max(ra, rb) != std::max(hand, leg)) continue;
    ++between;
    deepest = std::max(deepest, double(depth[i].depth));
  }
  const double height = b.bake.fit.body_height;
  MESSAGE("hand in thigh: " << between << " contacts, deepest " << deepest / height * 100 << " % of the height; hand vertices "
          << hand_in_leg / height * 100 << " % inside the thigh, thigh vertices " << leg_in_hand / height * 100 << " % inside the hand");
  REQUIRE(between > 0);
  // ContactDepth is the smaller of the two ways out (one triangle's corners behind the other's plane, or the
  // other's behind its): it follows the shallower side's penetration.
  const double truth = std::min(hand_in_leg, leg_in_hand);
  CHECK(truth > 0.005 * height);  // a real press, not a graze
  CHECK(deepest <= 1.25 * truth);
  CHECK(deepest >= 0.75 * truth);
}
