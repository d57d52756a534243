// DetectJob's broad phase (blocks of 8 spheres, kernels.inl BlockRow) against a brute-force all-pairs
// loop: limb-like bodies that move (so that most block pairs are culled and some are not), asset
// contact margins and per-job overrides, random chains and exclusions, serial and two parallel_for
// hooks; sets, order, depth bits and counters must be those of testing every candidate pair. Then the
// same on the real assets of the repository (fuzz corpus, golden v2), their spheres moved per region.
#include <doctest/doctest.h>

#include <filesystem>

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "runtime/asset_builder.h"
#include "runtime/detect_check.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

struct Brute {
  std::vector<Collision> pairs;
  DetectStats stats;
};

// Every pair a < b, in the documented order, with the documented formulas: overlap when
// ‖cA − cB‖² < ((rA + m) + (rB + m))²; depth rA + rB − ‖cA − cB‖ (M1) or, as M2 computes it,
// ((rA + m) + (rB + m) − ‖cA − cB‖) − 2m when m ≠ 0. M1 keeps pairs sharing a chain, ordered by
// (first common chain, a, b); raw_pairs counts a hit once per common chain. With a fold margin (>= 0) a
// pair of two spheres of one region (Model::fold_region) overlaps on radii grown by it instead of m; the
// depth keeps m.
Brute BruteForce(test::Character& ctx, DetectMethod method, float m, float fold = -1.0f) {
  Brute out;
  const SphereArrays s = ctx.ws.spheres();
  const uint32_t S = s.count;
  std::vector<std::pair<uint64_t, Collision>> hits;
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = a + 1; b < S; ++b) {
      const uint32_t common = ctx.model.chain_mask(a) & ctx.model.chain_mask(b);
      if (ctx.model.IsExcluded(a, b) || (method == DetectMethod::kM1 && !common)) continue;
      const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
      const float ra = s.r[a] + m, rb = s.r[b] + m;
      const float mk = fold >= 0.0f && ctx.model.fold_region(a) == ctx.model.fold_region(b) ? fold : m;
      const float rr = (s.r[b] + mk) + (s.r[a] + mk);
      const float d2 = dx * dx + dy * dy + dz * dz;
      if (!(d2 < rr * rr)) continue;
      float depth;
      if (method == DetectMethod::kM1) {
        depth = s.r[a] + s.r[b] - std::sqrt(d2);
      } else {
        depth = (m != 0.0f ? ra : s.r[a]) + (m != 0.0f ? rb : s.r[b]) - std::sqrt(d2);
        if (m != 0.0f) depth -= 2.0f * m;
      }
      const uint64_t chain = method == DetectMethod::kM1 ? static_cast<uint64_t>(std::countr_zero(common)) : 0u;
      hits.push_back({chain << 32 | a << 16 | b, {static_cast<uint16_t>(a), static_cast<uint16_t>(b), depth, common}});
      out.stats.raw_pairs += method == DetectMethod::kM1 ? static_cast<uint32_t>(std::popcount(common)) : 1u;
    }
  std::sort(hits.begin(), hits.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  for (const auto& h : hits) out.pairs.push_back(h.second);
  out.stats.distinct_pairs = static_cast<uint32_t>(out.pairs.size());
  return out;
}

void ParallelReverse(void*, uint32_t count, ParallelFor::Task task, void* data) {
  for (uint32_t i = count; i-- > 0;) task(data, i, i + 1);
}
void ParallelChunks(void*, uint32_t count, ParallelFor::Task task, void* data) {  // uneven ranges, odd order
  std::vector<std::pair<uint32_t, uint32_t>> ranges;
  for (uint32_t b = 0, w = 1; b < count; b += w, w = w % 3 + 1) ranges.push_back({b, std::min(count, b + w)});
  for (size_t k = 0; k < ranges.size(); k += 2) task(data, ranges[k].first, ranges[k].second);
  for (size_t k = 1; k < ranges.size(); k += 2) task(data, ranges[k].first, ranges[k].second);
}

// Runs the job serially and with both hooks, every run checked against the brute force; a half-size
// buffer keeps the documented prefix. Returns the serial stats.
DetectStats CheckAgainstBruteForce(test::Character& ctx, DetectMethod method, float job_margin,
                                   float job_fold = -1.0f) {
  const float m = job_margin < 0.0f ? ctx.model.contact_margin() : job_margin;
  const float fold = job_fold < 0.0f ? ctx.model.fold_margin() : job_fold;
  const Brute ref = BruteForce(ctx, method, m, fold);
  const uint32_t S = ctx.model.sphere_count();
  DetectStats serial;
  for (int hook = 0; hook < 3; ++hook) {
    std::vector<Collision> out(S * (S - 1) / 2 + 1);
    uint32_t n = 0;
    DetectStats st;
    DetectJob job = test::MakeDetectJob(ctx, method, out, &n, &st);
    job.margin = job_margin;
    job.fold_margin = job_fold;
    if (hook == 1) job.parallel_for.run = &ParallelReverse;
    if (hook == 2) job.parallel_for.run = &ParallelChunks;
    REQUIRE(job.Run() == Status::kOk);
    CAPTURE(hook);
    CAPTURE(static_cast<int>(method));
    CHECK(st.raw_pairs == ref.stats.raw_pairs);
    CHECK(st.distinct_pairs == ref.stats.distinct_pairs);
    CHECK(st.sphere_tests >= st.distinct_pairs);
    CHECK(st.sphere_tests <= (method == DetectMethod::kM1 ? ctx.model.m1_candidate_pairs() : ctx.model.m2_candidate_pairs()));
    test::CheckSameCollisions(out.data(), n, ref.pairs);
    if (hook == 0) {
      serial = st;
    } else {
      CHECK(st.box_tests == serial.box_tests);
      CHECK(st.sphere_tests == serial.sphere_tests);
    }
    job.capacity = n / 2;
    CHECK(job.Run() == (n / 2 < ref.pairs.size() ? Status::kOkTruncated : Status::kOk));
    for (uint32_t k = 0; k < n; ++k) CHECK((out[k].a == ref.pairs[k].a && out[k].b == ref.pairs[k].b));
  }
  return serial;
}

// Moves each tube of spheres (a limb) as a bent chain: rigid rotation of the whole tube about its first
// sphere, then a bend at its middle sphere, plus a little noise and radius change.
void PoseTubes(const test::AssetData& d, test::Character* ctx, std::mt19937* rng, float spread) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  float *x = ctx->ws.mutable_x(), *y = ctx->ws.mutable_y(), *z = ctx->ws.mutable_z(), *r = ctx->ws.mutable_r();
  const uint32_t S = ctx->model.sphere_count();
  for (size_t t = 0; t < d.tube_first_sphere.size(); ++t) {
    const uint32_t s0 = d.tube_first_sphere[t];
    const uint32_t s1 = t + 1 < d.tube_first_sphere.size() ? d.tube_first_sphere[t + 1] : S;
    float p[3] = {spread * u(*rng), spread * u(*rng), spread * u(*rng)};
    float dir[3] = {u(*rng), u(*rng), u(*rng)};
    const uint32_t bend = (s0 + s1) / 2;
    for (uint32_t s = s0; s < s1; ++s) {
      if (s == bend)
        for (float& c : dir) c += 0.8f * u(*rng);
      const float len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]) + 1e-6f;
      for (int k = 0; k < 3; ++k) p[k] += 1.2f * dir[k] / len;
      x[s] = p[0] + 0.05f * u(*rng), y[s] = p[1] + 0.05f * u(*rng), z[s] = p[2] + 0.05f * u(*rng);
      r[s] = 1.0f + 0.3f * u(*rng);
    }
  }
}

}  // namespace

TEST_CASE("DetectJob broad phase equals brute force on moving limb-like bodies, margins, fold margins and parallel_for") {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  uint64_t culled_runs = 0, runs = 0;
  for (int trial = 0; trial < 24; ++trial) {
    test::Mesh mesh;
    std::vector<test::Tube> tubes(3 + trial % 4);
    for (size_t t = 0; t < tubes.size(); ++t) {  // bind pose: parallel limbs side by side
      tubes[t].rings = 5 + static_cast<uint32_t>((7 * t + 3 * trial) % 19);
      tubes[t].origin[2] = 4.0f * static_cast<float>(t);
    }
    test::AssetData d = test::MakeTubes(tubes, {}, &mesh);
    const uint32_t S = static_cast<uint32_t>(d.spheres.size());
    // Chains: each tube its own (the helper's default), plus a few chains of random tube pairs.
    std::vector<std::vector<uint16_t>> chains;
    for (size_t t = 0; t < tubes.size(); ++t) {
      const uint32_t s1 = t + 1 < tubes.size() ? d.tube_first_sphere[t + 1] : S;
      for (int extra = 0; extra < 2; ++extra) {
        if (extra && u(rng) < 0.5f) continue;
        const size_t other = extra ? static_cast<size_t>(rng() % tubes.size()) : t;
        std::vector<uint16_t> c;
        for (uint32_t s = d.tube_first_sphere[t]; s < s1; ++s) c.push_back(static_cast<uint16_t>(s));
        const uint32_t o1 = other + 1 < tubes.size() ? d.tube_first_sphere[other + 1] : S;
        for (uint32_t s = d.tube_first_sphere[other]; s < o1; ++s) c.push_back(static_cast<uint16_t>(s));
        std::sort(c.begin(), c.end());
        c.erase(std::unique(c.begin(), c.end()), c.end());
        chains.push_back(c);
      }
    }
    if (chains.size() > 32) chains.resize(32);
    d.chains = chains;
    d.excluded.clear();  // neighbours along a tube, and a few random pairs
    for (uint32_t a = 0; a < S; ++a)
      for (uint32_t b = a + 1; b < S; ++b)
        if (b - a <= 1 + static_cast<uint32_t>(trial % 2) || u(rng) < 0.02f) d.excluded.emplace_back(a, b);
    d.contact_margin = trial % 3 == 0 ? 0.0f : trial % 3 == 1 ? 0.05f : 0.4f;
    // Every other trial a fold margin (Asset.fold_margin) on random regions of whole tubes: smaller or larger
    // than the contact margin, so both kinds of pair get re-tested after the broad phase.
    const bool fold = trial % 2 == 1;
    if (fold) {
      d.fold_margin = trial % 4 == 1 ? 0.0f : 0.6f;
      d.sphere_regions.assign(S, 0);
      for (size_t t = 0; t < tubes.size(); ++t) {
        const uint32_t s1 = t + 1 < tubes.size() ? d.tube_first_sphere[t + 1] : S;
        const uint8_t region = static_cast<uint8_t>(rng() % 3);
        for (uint32_t s = d.tube_first_sphere[t]; s < s1; ++s) d.sphere_regions[s] = region;
      }
    }
    const test::AlignedBytes bytes = test::Serialize(d);
    AssetView view;
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    test::Character ctx;
    REQUIRE(ctx.Init(view) == Status::kOk);
    CAPTURE(trial);
    for (int pose = 0; pose < 4; ++pose) {
      PoseTubes(d, &ctx, &rng, pose == 0 ? 3.0f : 8.0f + 10.0f * static_cast<float>(pose));
      for (float job_margin : {-1.0f, 0.0f, 0.25f}) {
        for (float job_fold : fold ? std::vector<float>{-1.0f, 0.1f} : std::vector<float>{-1.0f}) {
          for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2}) {
            const DetectStats st = CheckAgainstBruteForce(ctx, m, job_margin, job_fold);
            ++runs;
            culled_runs += st.sphere_tests < (m == DetectMethod::kM1 ? ctx.model.m1_candidate_pairs() : ctx.model.m2_candidate_pairs());
          }
        }
      }
    }
  }
  // The broad phase must actually cull: spread-out poses test fewer pairs than there are candidates.
  CHECK(culled_runs * 2 > runs);
}

TEST_CASE("DetectJob broad phase culls bodies far apart and keeps every pair of a pile") {
  test::Mesh mesh;
  std::vector<test::Tube> tubes(4);
  for (size_t t = 0; t < tubes.size(); ++t) tubes[t].rings = 16, tubes[t].origin[2] = 40.0f * static_cast<float>(t);
  test::AssetData d = test::MakeTubes(tubes, {{0, 1, 2, 3}}, &mesh);
  const test::AlignedBytes bytes = test::Serialize(d);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
  test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  const uint32_t S = ctx.model.sphere_count();
  float *x = ctx.ws.mutable_x(), *y = ctx.ws.mutable_y(), *z = ctx.ws.mutable_z(), *r = ctx.ws.mutable_r();
  for (uint32_t s = 0; s < S; ++s)  // tubes 1000 apart, each a straight line of touching-free spheres
    x[s] = 1000.0f * static_cast<float>(s / 16), y[s] = 3.0f * static_cast<float>(s % 16), z[s] = 0.0f, r[s] = 1.0f;
  for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2}) {
    const DetectStats st = CheckAgainstBruteForce(ctx, m, 0.0f);
    CHECK(st.distinct_pairs == 0);
    CHECK(st.sphere_tests * 4 <= ctx.model.m2_candidate_pairs());  // only pairs inside a tube survive
  }
  for (uint32_t s = 0; s < S; ++s) x[s] = 0.0f, y[s] = 0.01f * static_cast<float>(s), z[s] = 0.0f;  // one pile
  for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2}) {
    const DetectStats st = CheckAgainstBruteForce(ctx, m, 0.0f);
    CHECK(st.distinct_pairs == ctx.model.m2_candidate_pairs());  // one chain holds all: M1 == M2 here
    CHECK(st.sphere_tests == ctx.model.m2_candidate_pairs());
  }
}

TEST_CASE("DetectJob broad phase equals brute force on the repository's real assets, spheres moved per region") {
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (const std::string rel : {std::string("fuzz/corpus/load_asset/cesium_man.sphc"),
                                std::string("fuzz/corpus/load_asset/bcn_epileptic.sphc"),
                                std::string("tests/data/golden/v2/cesium_man.sphc")}) {
    const std::string path = test::SourceFile(rel);
    REQUIRE_MESSAGE(std::filesystem::exists(path), "the asset is part of the repository");
    test::AlignedBytes bytes;
    REQUIRE(test::ReadAlignedFile(path, &bytes));
    AssetView view;
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    test::Character ctx;
    REQUIRE(ctx.Init(view) == Status::kOk);
    CAPTURE(rel);
    const uint32_t S = ctx.model.sphere_count();
    const auto* regions = view.asset->sphere_regions();
    const SphereArrays bind = ctx.ws.spheres();
    const std::vector<float> bx(bind.x, bind.x + S), by(bind.y, bind.y + S), bz(bind.z, bind.z + S);
    float lo = bx[0], hi = bx[0];
    for (uint32_t s = 0; s < S; ++s) lo = std::min({lo, bx[s], by[s], bz[s]}), hi = std::max({hi, bx[s], by[s], bz[s]});
    const float size = hi - lo;
    for (int pose = 0; pose < 12; ++pose) {
      // Each region turned about the origin by its own small angle and shifted (pose 0: bind pose).
      float angle[8], shift[8][3];
      for (int g = 0; g < 8; ++g) {
        angle[g] = pose ? 0.4f * u(rng) : 0.0f;
        for (float& v : shift[g]) v = pose ? 0.05f * size * u(rng) : 0.0f;
      }
      for (uint32_t s = 0; s < S; ++s) {
        const int g = regions ? regions->Get(s) % 8 : 0;
        const float c = std::cos(angle[g]), sn = std::sin(angle[g]);
        ctx.ws.mutable_x()[s] = c * bx[s] - sn * by[s] + shift[g][0];
        ctx.ws.mutable_y()[s] = sn * bx[s] + c * by[s] + shift[g][1];
        ctx.ws.mutable_z()[s] = bz[s] + shift[g][2];
      }
      for (DetectMethod m : {DetectMethod::kM1, DetectMethod::kM2})
        for (float job_margin : {-1.0f, 0.0f, 0.01f * size}) (void)CheckAgainstBruteForce(ctx, m, job_margin);
    }
  }
}
