// DetectJob (§5.2): M1 / M2, excluded pairs, truncation, bounds.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "runtime/asset_builder.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

struct Scene {
  test::Mesh mesh;
  test::AssetData data;
  test::AlignedBytes bytes;
  AssetView view;
  test::Character ctx;
  explicit Scene(test::AssetData d, test::Mesh m) : mesh(std::move(m)), data(std::move(d)) {
    bytes = test::Serialize(data);
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    REQUIRE(ctx.Init(view) == Status::kOk);
    RefitJob refit;
    refit.model = &ctx.model;
    refit.workspace = &ctx.ws;
    refit.positions = {mesh.positions.data(), mesh.vertex_count(), 12};
    REQUIRE(refit.Run() == Status::kOk);
  }
  std::vector<Collision> Detect(DetectMethod method, DetectStats* stats = nullptr, Status* status = nullptr,
                                ParallelFor pf = {}) {
    std::vector<Collision> out(DetectBound(view, method));
    uint32_t n = 0;
    DetectJob job = test::MakeDetectJob(ctx, method, out, &n, stats);
    job.parallel_for = pf;
    const Status s = job.Run();
    if (status) *status = s;
    REQUIRE(s == Status::kOk);
    out.resize(n);
    return out;
  }
};

Scene TwoTubes(bool crossing) {
  test::Mesh mesh;
  test::AssetData d = test::TwoTubes(crossing, &mesh);
  return Scene(std::move(d), std::move(mesh));
}

std::set<std::pair<int, int>> Pairs(const std::vector<Collision>& v) {
  std::set<std::pair<int, int>> s;
  for (const Collision& c : v) s.insert({c.a, c.b});
  return s;
}

}  // namespace

TEST_CASE("Two crossing tubes report exactly their crossing spheres (M1 and M2)") {
  Scene sc = TwoTubes(true);
  const SphereArrays s = sc.ctx.ws.spheres();
  // Brute-force reference from the bind spheres: pairs between tube A (0..7) and tube B (8..15).
  std::set<std::pair<int, int>> want;
  for (int a = 0; a < 16; ++a)
    for (int b = a + 1; b < 16; ++b) {
      const float d = std::sqrt((s.x[a] - s.x[b]) * (s.x[a] - s.x[b]) + (s.y[a] - s.y[b]) * (s.y[a] - s.y[b]) +
                                (s.z[a] - s.z[b]) * (s.z[a] - s.z[b]));
      if (d < s.r[a] + s.r[b] && !(b == a + 1 && b != 8)) want.insert({a, b});
    }
  REQUIRE(!want.empty());
  for (const auto& p : want) CHECK((p.first < 8 && p.second >= 8));  // only crossings
  DetectStats st1, st2;
  const auto m1 = sc.Detect(DetectMethod::kM1, &st1);
  const auto m2 = sc.Detect(DetectMethod::kM2, &st2);
  CHECK(Pairs(m1) == want);
  CHECK(Pairs(m2) == want);
  CHECK(m1.size() == want.size());  // distinct: each pair once
  for (const Collision& c : m1) {
    CHECK(c.a < c.b);
    CHECK(c.chains == 1u);  // only chain 0 = A ∪ B holds a crossing pair
    CHECK(c.depth > 0.0f);
    const float d = std::sqrt((s.x[c.a] - s.x[c.b]) * (s.x[c.a] - s.x[c.b]) + (s.y[c.a] - s.y[c.b]) * (s.y[c.a] - s.y[c.b]) +
                              (s.z[c.a] - s.z[c.b]) * (s.z[c.a] - s.z[c.b]));
    CHECK(c.depth == doctest::Approx(s.r[c.a] + s.r[c.b] - d));
  }
  CHECK(st1.distinct_pairs == want.size());
  CHECK(st1.raw_pairs == want.size());
  CHECK(st1.tests == 16 * 15 / 2 + 2 * (8 * 7 / 2));
  CHECK(st2.tests == 16 * 15 / 2);
}

TEST_CASE("Tubes apart report no collision") {
  Scene sc = TwoTubes(false);
  CHECK(sc.Detect(DetectMethod::kM1).empty());
  CHECK(sc.Detect(DetectMethod::kM2).empty());
}

TEST_CASE("Excluded (adjacent) pairs are never reported even though they overlap") {
  Scene sc = TwoTubes(true);
  // Neighbouring rings overlap (spacing 1.2 < 2 r): the raw test hits them; they must be skipped.
  const SphereArrays s = sc.ctx.ws.spheres();
  CHECK(std::fabs(s.x[1] - s.x[0]) < s.r[0] + s.r[1]);
  for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2})
    for (const Collision& c : sc.Detect(m)) CHECK_FALSE(sc.ctx.model.IsExcluded(c.a, c.b));
  // Removing the exclusions makes them appear: the test can fail.
  test::Mesh mesh;
  test::AssetData d = test::TwoTubes(false, &mesh);
  d.excluded.clear();
  Scene open(std::move(d), std::move(mesh));
  CHECK(open.Detect(DetectMethod::kM2).size() == 14);
}

TEST_CASE("M1 distinct pairs are a subset of M2 pairs, and raw M1 counts duplicates across chains") {
  test::Mesh mesh;
  test::Tube a, b, c;
  a.origin[0] = -4.2f;
  b.origin[1] = -4.2f;
  b.direction[0] = 0;
  b.direction[1] = 1;
  c.origin[0] = -4.2f;  // tube C crosses A 1.5 below, in no chain with A
  c.origin[2] = -1.5f;
  c.origin[1] = 0.3f;
  // Chains: {A, B}, {A, B} again (duplicates), {C}
  test::AssetData d = test::MakeTubes({a, b, c}, {{0, 1}, {0, 1}, {2}}, &mesh);
  Scene sc(std::move(d), std::move(mesh));
  DetectStats st;
  const auto m1 = sc.Detect(DetectMethod::kM1, &st);
  const auto m2 = sc.Detect(DetectMethod::kM2);
  const auto p1 = Pairs(m1), p2 = Pairs(m2);
  CHECK(std::includes(p2.begin(), p2.end(), p1.begin(), p1.end()));
  CHECK(p2.size() > p1.size());  // A×C pairs only in M2
  CHECK(st.raw_pairs == 2 * st.distinct_pairs);
  CHECK(st.distinct_pairs == m1.size());
  for (const Collision& col : m1) CHECK(col.chains == 3u);
  for (const Collision& col : m2)
    if (!p1.count({col.a, col.b})) CHECK(col.chains == 0u);
  CHECK(m1.size() <= sc.ctx.model.m1_candidate_pairs());
  CHECK(sc.ctx.model.m1_candidate_pairs() <= DetectBound(sc.view, DetectMethod::kM1));
  CHECK(sc.ctx.model.m2_candidate_pairs() == 24 * 23 / 2 - 21);
}

TEST_CASE("A too-small output buffer gives kOkTruncated with count == capacity") {
  Scene sc = TwoTubes(true);
  for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2}) {
    const auto full = sc.Detect(m);
    REQUIRE(full.size() > 2);
    std::vector<Collision> out(2);
    uint32_t n = 99;
    DetectStats st;
    DetectJob job;
    job.model = &sc.ctx.model;
    job.workspace = &sc.ctx.ws;
    job.method = m;
    job.output = out.data();
    job.capacity = 2;
    job.count = &n;
    job.stats = &st;
    const Status s = job.Run();
    CHECK(s == Status::kOkTruncated);
    CHECK(Succeeded(s));
    CHECK(n == 2);
    CHECK(st.distinct_pairs == full.size());
    CHECK(out[0].a == full[0].a);
    CHECK(out[1].b == full[1].b);
    job.output = nullptr;
    job.capacity = 0;
    CHECK(job.Run() == Status::kOkTruncated);
    CHECK(n == 0);
  }
}

TEST_CASE("DetectJob argument errors and the parallel_for path") {
  Scene sc = TwoTubes(true);
  DetectJob job;
  uint32_t n = 0;
  CHECK(job.Run() == Status::kErrorNullArgument);
  job.model = &sc.ctx.model;
  job.workspace = &sc.ctx.ws;
  CHECK(job.Run() == Status::kErrorNullArgument);  // count null
  job.count = &n;
  job.capacity = 4;
  CHECK(job.Run() == Status::kErrorNullArgument);  // output null with capacity
  job.capacity = 0;
  job.method = static_cast<DetectMethod>(9);
  CHECK(job.Run() == Status::kErrorInvalidJob);
  CHECK(DetectBound(sc.view, static_cast<DetectMethod>(9)) == 0);
  CHECK(DetectBound(AssetView{}, DetectMethod::kM1) == 0);
  job.method = DetectMethod::kM2;
  CHECK(!Failed(job.Run()));  // capacity 0: kOkTruncated on these crossing tubes
  job.fold_margin = std::numeric_limits<float>::quiet_NaN();
  CHECK(job.Run() == Status::kErrorInvalidJob);
  job.fold_margin = 0.1f;  // this asset has no fold margin, so no regions to tell one kind of pair from the other
  CHECK(sc.ctx.model.fold_margin() < 0.0f);
  CHECK(job.Run() == Status::kErrorInvalidJob);
  job.fold_margin = -1.0f;

  const auto serial = sc.Detect(DetectMethod::kM1);
  ParallelFor pf;
  pf.run = [](void*, uint32_t count, ParallelFor::Task task, void* data) {
    for (uint32_t i = count; i-- > 0;) task(data, i, i + 1);
  };
  const auto parallel = sc.Detect(DetectMethod::kM1, nullptr, nullptr, pf);
  REQUIRE(parallel.size() == serial.size());
  for (size_t i = 0; i < serial.size(); ++i) {
    CHECK(parallel[i].a == serial[i].a);
    CHECK(parallel[i].b == serial[i].b);
  }
}
