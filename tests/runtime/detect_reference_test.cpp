// DetectJob M1 / M2 against a direct transcription of their documented semantics (per-chain loops,
// all-pairs loop), on irregular layouts: overlapping chains of odd sizes, spheres in no chain, classes
// of one sphere, many excluded pairs, dense overlaps; serial and parallel_for, every capacity.
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "runtime/asset_builder.h"
#include "runtime/detect_check.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

struct Reference {
  std::vector<Collision> pairs;
  DetectStats stats;
};

bool Excluded(const test::AssetData& d, uint32_t a, uint32_t b) {
  for (const schema::SpherePair& p : d.excluded)
    if (p.a() == std::min(a, b) && p.b() == std::max(a, b)) return true;
  return false;
}

// DetectJob's documentation, literally: M1 tests every pair of every chain (chains ascending), counts
// each non-excluded hit (raw) and reports it under the first chain holding both.
Reference ReferenceDetect(const test::AssetData& d, const SphereArrays& s, DetectMethod method) {
  Reference ref;
  auto mask = [&](uint32_t x) {
    uint32_t m = 0;
    for (size_t c = 0; c < d.chains.size(); ++c)
      if (std::binary_search(d.chains[c].begin(), d.chains[c].end(), x)) m |= 1u << c;
    return m;
  };
  auto hit = [&](uint32_t a, uint32_t b) {
    const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a], rr = s.r[b] + s.r[a];
    return dx * dx + dy * dy + dz * dz < rr * rr && !Excluded(d, a, b);
  };
  auto record = [&](uint32_t a, uint32_t b) {
    const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
    ref.pairs.push_back({static_cast<uint16_t>(a), static_cast<uint16_t>(b),
                         s.r[a] + s.r[b] - std::sqrt(dx * dx + dy * dy + dz * dz), mask(a) & mask(b)});
  };
  if (method == DetectMethod::kM1) {
    for (size_t c = 0; c < d.chains.size(); ++c) {
      const auto& list = d.chains[c];
      ref.stats.tests += static_cast<uint32_t>(list.size() * (list.size() - 1) / 2);
      for (size_t i = 0; i < list.size(); ++i)
        for (size_t j = i + 1; j < list.size(); ++j) {
          if (!hit(list[i], list[j])) continue;
          ++ref.stats.raw_pairs;
          if (static_cast<size_t>(std::countr_zero(mask(list[i]) & mask(list[j]))) == c) record(list[i], list[j]);
        }
    }
  } else {
    ref.stats.tests = s.count * (s.count - 1) / 2;
    for (uint32_t a = 0; a < s.count; ++a)
      for (uint32_t b = a + 1; b < s.count; ++b)
        if (hit(a, b)) record(a, b);
    ref.stats.raw_pairs = static_cast<uint32_t>(ref.pairs.size());
  }
  ref.stats.distinct_pairs = static_cast<uint32_t>(ref.pairs.size());
  return ref;
}

/// DetectJob's stats and records equal the reference, pair for pair, depths to the bit.
void CheckEqualsReference(const Collision* out, uint32_t n, const DetectStats& st, const Reference& ref) {
  CHECK(st.tests == ref.stats.tests);
  CHECK(st.raw_pairs == ref.stats.raw_pairs);
  CHECK(st.distinct_pairs == ref.stats.distinct_pairs);
  test::CheckSameCollisions(out, n, ref.pairs);
}

/// Random chains (sorted, unique; each sphere joins chain c with a probability drawn in
/// [p_min, p_min + 0.6); a chain that ends up with < 2 spheres becomes {0, S−1}) and random excluded
/// pairs (every pair at most `neighbour_span` apart in index, plus each other pair with `p_excluded`).
void RandomChainsAndExclusions(test::AssetData* d, std::mt19937* rng, uint32_t chain_count, float p_min,
                               uint32_t neighbour_span, float p_excluded) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const uint32_t S = static_cast<uint32_t>(d->spheres.size());
  d->chains.assign(chain_count, {});
  for (uint32_t c = 0; c < chain_count; ++c) {
    const float p = p_min + 0.6f * u(*rng);
    for (uint32_t s = 0; s < S; ++s)
      if (u(*rng) < p) d->chains[c].push_back(static_cast<uint16_t>(s));
    if (d->chains[c].size() < 2) d->chains[c] = {0, static_cast<uint16_t>(S - 1)};
  }
  d->excluded.clear();
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = a + 1; b < S; ++b)
      if (b - a <= neighbour_span || u(*rng) < p_excluded) d->excluded.emplace_back(a, b);
}

}  // namespace

TEST_CASE("DetectJob M1 and M2 equal the reference loops on irregular chains and exclusions") {
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 12; ++trial) {
    test::Mesh mesh;
    std::vector<test::Tube> tubes(3);
    for (size_t t = 0; t < tubes.size(); ++t) tubes[t].rings = 9 + 7 * static_cast<uint32_t>(t) + trial;
    test::AssetData d = test::MakeTubes(tubes, {}, &mesh);
    const uint32_t S = static_cast<uint32_t>(d.spheres.size());
    // Random chains (sorted, unique, some spheres in none) and random excluded pairs.
    RandomChainsAndExclusions(&d, &rng, 1 + trial % 7, 0.15f, 2, 0.03f);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const test::AlignedBytes bytes = test::Serialize(d);
    AssetView view;
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    test::Character ctx;
    REQUIRE(ctx.Init(view) == Status::kOk);
    uint32_t m1_candidates = 0;
    for (uint32_t a = 0; a < S; ++a)
      for (uint32_t b = a + 1; b < S; ++b) {
        bool shared = false;
        for (const auto& list : d.chains)
          shared = shared ||
                   (std::binary_search(list.begin(), list.end(), a) && std::binary_search(list.begin(), list.end(), b));
        m1_candidates += shared && !Excluded(d, a, b);
      }
    CHECK(ctx.model.m1_candidate_pairs() == m1_candidates);
    CHECK(ctx.model.m2_candidate_pairs() == S * (S - 1) / 2 - d.excluded.size());
    // Dense random spheres in a small box: many overlaps, some exactly touching (never overlapping).
    for (uint32_t s = 0; s < S; ++s) {
      ctx.ws.mutable_x()[s] = 6.0f * u(rng);
      ctx.ws.mutable_y()[s] = 6.0f * u(rng);
      ctx.ws.mutable_z()[s] = (s % 5 == 0) ? 0.0f : 6.0f * u(rng);
      ctx.ws.mutable_r()[s] = 0.2f + 0.8f * u(rng);
    }
    ctx.ws.mutable_x()[1] = ctx.ws.mutable_x()[0] + 2.0f, ctx.ws.mutable_y()[1] = ctx.ws.mutable_y()[0];
    ctx.ws.mutable_z()[1] = ctx.ws.mutable_z()[0], ctx.ws.mutable_r()[0] = ctx.ws.mutable_r()[1] = 1.0f;  // touching
    for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2}) {
      const Reference ref = ReferenceDetect(d, ctx.ws.spheres(), m);
      for (int parallel = 0; parallel < 2; ++parallel) {
        std::vector<Collision> out(DetectBound(view, m));
        uint32_t n = 0;
        DetectStats st;
        DetectJob job = test::MakeDetectJob(ctx, m, out, &n, &st);
        if (parallel)
          job.parallel_for.run = [](void*, uint32_t count, ParallelFor::Task task, void* data) {
            for (uint32_t i = count; i-- > 0;) task(data, i, i + 1);  // reverse order, one index a task
          };
        REQUIRE(job.Run() == Status::kOk);
        CAPTURE(trial);
        CAPTURE(static_cast<int>(m));
        CheckEqualsReference(out.data(), n, st, ref);
        if (m == DetectMethod::kM1) CHECK(n <= ctx.model.m1_candidate_pairs());
        // Truncation keeps the documented prefix.
        const uint32_t cap = n / 2;
        job.capacity = cap;
        CHECK(job.Run() == (cap < ref.pairs.size() ? Status::kOkTruncated : Status::kOk));
        REQUIRE(n == cap);
        for (uint32_t k = 0; k < n; ++k) CHECK((out[k].a == ref.pairs[k].a && out[k].b == ref.pairs[k].b));
      }
    }
  }
}

// The broad phase (block boxes, kernels.inl BlockRow), M1 and M2, against the brute-force reference: scenes
// with tight clusters far apart (most chunks skipped), spheres straddling clusters, pairs touching or
// within a few ulps of touching, huge and tiny magnitudes, negative / zero radii, NaN and infinite
// spheres. Outputs must be identical (pairs, order, depth bits, stats) to testing every pair.
TEST_CASE("DetectJob M1 and M2 broad cull equal brute force on clustered, far, degenerate and non-finite spheres") {
  std::mt19937 rng(777);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int trial = 0; trial < 40; ++trial) {
    test::Mesh mesh;
    std::vector<test::Tube> tubes(3);
    for (size_t t = 0; t < tubes.size(); ++t) tubes[t].rings = 11 + 9 * static_cast<uint32_t>(t) + trial % 13;
    test::AssetData d = test::MakeTubes(tubes, {}, &mesh);
    const uint32_t S = static_cast<uint32_t>(d.spheres.size());
    RandomChainsAndExclusions(&d, &rng, 1 + trial % 6, 0.3f, 1, 0.02f);
    const test::AlignedBytes bytes = test::Serialize(d);
    AssetView view;
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    test::Character ctx;
    REQUIRE(ctx.Init(view) == Status::kOk);
    float *x = ctx.ws.mutable_x(), *y = ctx.ws.mutable_y(), *z = ctx.ws.mutable_z(), *r = ctx.ws.mutable_r();
    // Scale of the scene: ordinary, huge (ulp ≫ 1) or tiny (near the subnormal range).
    const float scale = trial % 5 == 3 ? 3e15f : trial % 5 == 4 ? 1e-19f : 1.0f;
    const uint32_t clusters = 2 + trial % 5;
    for (uint32_t s = 0; s < S; ++s) {
      const uint32_t k = trial % 2 ? (s * 7 + static_cast<uint32_t>(trial)) % clusters  // interleaved
                                   : s * clusters / S;  // contiguous: whole chunks in one cluster
      x[s] = scale * (100.0f * static_cast<float>(k) + 3.0f * u(rng));
      y[s] = scale * (50.0f * static_cast<float>(k % 2) + 3.0f * u(rng));
      z[s] = scale * 3.0f * u(rng);
      r[s] = scale * (0.1f + 0.9f * u(rng));
    }
    // Pairs exactly touching (never reported) and one ulp inside / outside touching, each pair alone
    // far below the clusters along y, so that the partner's chunk box ends exactly at the contact.
    for (uint32_t s = 0; s + 3 < S; s += 9) {
      const uint32_t b = (s + 5 + static_cast<uint32_t>(trial)) % S;
      if (b % 9 == 0) continue;
      const float gap = r[s] + r[b];
      y[s] = -scale * (1000.0f + 10.0f * static_cast<float>(s));
      x[b] = x[s], y[b] = y[s] + gap, z[b] = z[s];
      if (s % 3 == 1) y[b] = std::nextafter(y[b], -INFINITY);
      if (s % 3 == 2) y[b] = std::nextafter(y[b], INFINITY);
    }
    if (trial % 4 == 1) {  // degenerate and non-finite spheres
      const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
      r[2] = -r[2];         // negative radius: (rA + rB)² still decides
      r[5] = 0.0f;
      x[7] = nan;
      r[11] = nan;
      y[13] = inf;
      r[17] = inf;          // overlaps every finite sphere
      x[19] = -inf, r[19] = inf;
      r[23] = -50.0f * scale;  // a big negative radius
      z[29] = 3e38f;        // overflowing magnitudes
      x[31] = 3e38f, r[31] = 3e38f;
      x[37] = std::numeric_limits<float>::denorm_min(), r[37] = 1e-38f;
    }
    if (trial % 4 == 2) {  // one giant sphere spanning the clusters
      x[S / 2] = 150.0f * scale, r[S / 2] = 120.0f * scale;
    }
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
      const Reference ref = ReferenceDetect(d, ctx.ws.spheres(), method);
      for (int parallel = 0; parallel < 2; ++parallel) {
        std::vector<Collision> out(DetectBound(view, method));
        uint32_t n = 0;
        DetectStats st;
        DetectJob job = test::MakeDetectJob(ctx, method, out, &n, &st);
        if (parallel)
          job.parallel_for.run = [](void*, uint32_t count, ParallelFor::Task task, void* data) {
            for (uint32_t i = count; i-- > 0;) task(data, i, i + 1);
          };
        REQUIRE(job.Run() == Status::kOk);
        CAPTURE(trial);
        CAPTURE(static_cast<int>(method));
        CheckEqualsReference(out.data(), n, st, ref);
      }
    }
  }
}
