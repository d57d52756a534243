// formulas.h / formulas.inl: the SIMD refit kernels (SSE2, and AVX where the CPU has it) give, lane by
// lane, bit for bit what the scalar formulas give — on random, degenerate and non-finite pivots, in both
// refit modes, at every lane position (sphere counts not a multiple of the width included).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "../runtime/src/internal.h"  // kernels::RefitSse / RefitAvx (the runtime is a static library)
#include "spherechain/runtime/formulas.h"
#include "spherechain/runtime/refit.h"

using namespace spherechain::runtime;

namespace {

uint32_t Bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// Same float, or both NaN (a NaN's payload is not part of the contract).
bool SameFloat(float a, float b) { return Bits(a) == Bits(b) || (std::isnan(a) && std::isnan(b)); }

// Random pivot vertices for S spheres (12 vertices each, own vertices): mostly plain, some coincident,
// collinear, tiny, huge, infinite or NaN, so both the frame and its kPaper fallback run in every lane.
struct Case {
  std::vector<float> positions;  // #V×3, #V = 12·S
  std::vector<uint32_t> pivot_vertices;
  std::vector<float> local[3], offset[3], radius_scale;
  uint32_t S;
  explicit Case(uint32_t spheres, uint32_t seed) : S(spheres) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    std::uniform_int_distribution<int> kind(0, 15);
    positions.resize(size_t{36} * S);
    for (uint32_t s = 0; s < S; ++s) {
      const int k = kind(rng);
      float* p = &positions[size_t{36} * s];
      for (int i = 0; i < 36; ++i) p[i] = u(rng);
      if (k == 1)  // all pivots coincide: degenerate frame
        for (int i = 3; i < 36; ++i) p[i] = p[i % 3];
      if (k == 2)  // collinear pivot centroids
        for (int v = 0; v < 12; ++v) p[3 * v + 1] = p[3 * v + 2] = 0.5f;
      if (k == 3)
        for (int i = 0; i < 36; ++i) p[i] *= 1e-30f;
      if (k == 4)
        for (int i = 0; i < 36; ++i) p[i] *= 1e18f;
      if (k == 5) p[7] = std::numeric_limits<float>::quiet_NaN();
      if (k == 6) p[20] = std::numeric_limits<float>::infinity();
      if (k == 7) p[3] = p[0], p[4] = p[1], p[5] = p[2];  // two coincident vertices
      for (int v = 0; v < 12; ++v) pivot_vertices.push_back(12 * s + v);
    }
    for (int d = 0; d < 3; ++d) {
      for (uint32_t s = 0; s < S + 8; ++s) local[d].push_back(u(rng)), offset[d].push_back(u(rng));
    }
    for (uint32_t s = 0; s < S + 8; ++s) radius_scale.push_back(0.5f + 0.25f * (u(rng) + 2.0f));
  }
  // The scalar formulas for sphere s (what the CPU's scalar path, the baker and CUDA evaluate).
  void Scalar(uint32_t s, bool frame_mode, float out[4]) const {
    float px[4], py[4], pz[4];
    for (int k = 0; k < 4; ++k) {
      const float* v[3];
      for (int t = 0; t < 3; ++t) v[t] = &positions[3 * size_t{pivot_vertices[12 * s + 3 * k + t]}];
      float c[3];
      formulas::TriangleCentroid3(v[0], v[1], v[2], c);
      px[k] = c[0], py[k] = c[1], pz[k] = c[2];
    }
    formulas::RefitLanes<formulas::ScalarOps>(px, py, pz, local[0][s], local[1][s], local[2][s], offset[0][s],
                                              offset[1][s], offset[2][s], radius_scale[s], frame_mode, out);
  }
};

}  // namespace

TEST_CASE("SIMD refit lanes equal the scalar formulas bit for bit (SSE2, AVX, AVX-512)") {
  std::string isa_note = "refit kernels tested:";
  for (int isa = 0; isa < kernels::kIsaCount; ++isa)
    isa_note += std::string(" ") + kernels::ToString(kernels::Isa(isa)) +
                (kernels::Supported(kernels::Isa(isa)) ? "" : " (not on this CPU: skipped)");
  MESSAGE(isa_note);
  uint32_t degenerate = 0, lanes = 0;
  for (uint32_t S : {1u, 3u, 4u, 7u, 8u, 13u, 16u, 17u, 33u, 64u, 301u}) {
    const Case c(S, 1000 + S);
    for (bool frame_mode : {true, false})
      for (int isa = 0; isa < kernels::kIsaCount; ++isa) {
        if (!kernels::Supported(kernels::Isa(isa))) continue;
        CAPTURE(S);
        CAPTURE(frame_mode);
        CAPTURE(isa);
        std::vector<float> x(S + 8, -7.0f), y = x, z = x, r = x;
        // The last sphere's last pivot vertex ends the buffer (exactly sized: ASan sees an over-read).
        const kernels::RefitArgs args{reinterpret_cast<const char*>(c.positions.data()), 12, 12 * S - 1,
                                      c.pivot_vertices.data(),
                                      c.local[0].data(), c.local[1].data(), c.local[2].data(), c.offset[0].data(),
                                      c.offset[1].data(), c.offset[2].data(), c.radius_scale.data(), x.data(),
                                      y.data(), z.data(), r.data(), frame_mode};
        // Two ranges, so that lanes start at other positions than 0 (begin not a multiple of the width);
        // the AVX-512 kernel runs full chunks of 16 and hands the rest (and the chunk reading the
        // buffer's last vertex) to the AVX kernel.
        const uint32_t mid = S / 3;
        const kernels::Table& k = kernels::Kernels(kernels::Isa(isa));
        k.refit(args, 0, mid), k.refit(args, mid, S);
        for (uint32_t s = 0; s < S; ++s) {
          float want[4];
          c.Scalar(s, frame_mode, want);
          const bool same = SameFloat(x[s], want[0]) && SameFloat(y[s], want[1]) && SameFloat(z[s], want[2]) &&
                            SameFloat(r[s], want[3]);
          if (!same) {
            CAPTURE(s);
            CHECK(Bits(x[s]) == Bits(want[0]));
            CHECK(Bits(y[s]) == Bits(want[1]));
            CHECK(Bits(z[s]) == Bits(want[2]));
            CHECK(Bits(r[s]) == Bits(want[3]));
          }
          ++lanes;
        }
        for (uint32_t s = S; s < S + 8; ++s) CHECK(x[s] == -7.0f);  // nothing written past the range
      }
    // The refit.h helpers (the baker's BuildPivotFrame / PivotFrameToModel / PivotMeanDistance) agree
    // with the lane formulas too.
    for (uint32_t s = 0; s < S; ++s) {
      float p[4][3];
      for (int k = 0; k < 4; ++k) {
        const float* v[3];
        for (int t = 0; t < 3; ++t) v[t] = &c.positions[3 * size_t{c.pivot_vertices[12 * s + 3 * k + t]}];
        TriangleCentroid(v[0], v[1], v[2], p[k]);
      }
      PivotFrameBasis f;
      float centre[3];
      const float local[3] = {c.local[0][s], c.local[1][s], c.local[2][s]};
      if (BuildPivotFrame(p, &f)) {
        PivotFrameToModel(f, local, centre);
      } else {
        ++degenerate;
        for (int k = 0; k < 3; ++k) centre[k] = f.origin[k] + c.offset[k][s];
      }
      const float radius = c.radius_scale[s] * PivotMeanDistance(p, centre);
      float want[4];
      c.Scalar(s, true, want);
      CHECK(SameFloat(centre[0], want[0]));
      CHECK(SameFloat(centre[1], want[1]));
      CHECK(SameFloat(centre[2], want[2]));
      CHECK(SameFloat(radius, want[3]));
    }
  }
  CHECK(degenerate > 10);  // the fallback lanes were exercised
  CHECK(lanes > 1000);
}

TEST_CASE("Overlap and depth formulas: the §5.2 test and the reported depths") {
  using O = formulas::ScalarOps;
  // Touching spheres do not overlap (strict <); NaN never overlaps.
  CHECK_FALSE(formulas::OverlapLanes<O>(0, 0, 0, 1, 2, 0, 0, 1));
  CHECK(formulas::OverlapLanes<O>(0, 0, 0, 1, 1.999f, 0, 0, 1));
  CHECK_FALSE(formulas::OverlapLanes<O>(0, 0, 0, NAN, 0, 0, 0, 1));
  CHECK(formulas::SphereDepth<O>(0, 0, 0, 1, 1.5f, 0, 0, 1, 0.0f) == 0.5f);
  // With a margin: ((ra + m) + (rb + m) − d) − 2m.
  const float m = 0.1f, want = ((1.0f + m) + (1.0f + m) - 1.5f) - 2.0f * m;
  CHECK(Bits(formulas::SphereDepth<O>(0, 0, 0, 1, 1.5f, 0, 0, 1, m)) == Bits(want));
}
