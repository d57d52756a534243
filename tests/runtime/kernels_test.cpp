// The SIMD kernels of every instruction set this CPU runs (kernels::Table: SSE2, AVX, AVX-512) against a
// scalar reference or the SSE2 kernel, bit for bit: the joint refit's blend and transform, the matrices'
// finiteness check, the detection's gather and block boxes (AVX-512 computes them in one pass), the
// broad phase's row blocks (keys and counters), and the AVX-512 refit's hand-offs (a chunk reading the
// buffer's last vertex, strided buffers). Kernels a CPU lacks are skipped, saying so. The whole runtime
// suite also runs with SPHERECHAIN_ISA=sse2 and =avx (tests/CMakeLists.txt), so the jobs are checked on
// every dispatch level the machine has.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "../runtime/src/internal.h"

using namespace spherechain::runtime;
using kernels::Isa;

namespace {

uint32_t Bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
bool SameFloat(float a, float b) { return Bits(a) == Bits(b) || (std::isnan(a) && std::isnan(b)); }

std::vector<Isa> Isas() {
  std::vector<Isa> out;
  std::string note = "kernels tested:";
  for (int i = 0; i < kernels::kIsaCount; ++i) {
    const Isa isa = static_cast<Isa>(i);
    if (kernels::Supported(isa)) out.push_back(isa);
    note += std::string(" ") + kernels::ToString(isa) + (kernels::Supported(isa) ? "" : " (not on this CPU: skipped)");
  }
  MESSAGE(note);
  return out;
}

// The joint refit as documented (JointRefitArgs), one float at a time.
void JointReference(const kernels::JointRefitArgs& a, std::vector<float>* x, std::vector<float>* y,
                    std::vector<float>* z) {
  for (uint32_t n = 1; n <= 4; ++n)
    for (uint32_t k = n == 1 ? 0 : a.group_end[n - 2]; k < a.group_end[n - 1]; ++k) {
      float m[12];
      for (int e = 0; e < 12; ++e) m[e] = a.weights[4 * k] * a.matrices[a.offsets[4 * k] + e];
      for (uint32_t i = 1; i < n; ++i)
        for (int e = 0; e < 12; ++e) m[e] = m[e] + a.weights[4 * k + i] * a.matrices[a.offsets[4 * k + i] + e];
      const float* b = a.bind + 4 * k;
      float c[3];
      for (int row = 0; row < 3; ++row)
        c[row] = (m[4 * row] * b[0] + m[4 * row + 1] * b[1]) + (m[4 * row + 2] * b[2] + m[4 * row + 3] * b[3]);
      const uint32_t s = a.sphere[k];
      (*x)[s] = c[0], (*y)[s] = c[1], (*z)[s] = c[2];
    }
}

}  // namespace

TEST_CASE("Joint refit kernels equal the scalar blend and transform bit for bit, every influence count") {
  const std::vector<Isa> isas = Isas();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f), w01(0.0f, 1.0f);
  for (uint32_t J : {1u, 2u, 5u, 163u}) {
    for (uint32_t S : {1u, 4u, 9u, 96u, 128u}) {
      // Exactly sized matrices (the last joint's 12 floats end the buffer: ASan sees an over-read).
      std::vector<float> matrices(size_t{12} * J);
      for (float& f : matrices) f = u(rng);
      if (J > 1) matrices[3] = -0.0f, matrices[12 * J - 1] = 1e30f;  // a signed zero, a huge translation
      std::vector<uint32_t> sphere(S), offsets(4 * S, 0);
      std::vector<float> weights(4 * S, 0.0f), bind(4 * S);
      for (uint32_t s = 0; s < S; ++s) sphere[s] = (s * 7 + 3) % S;  // a permutation when gcd(7, S) = 1
      if (S % 7 == 0)
        for (uint32_t s = 0; s < S; ++s) sphere[s] = S - 1 - s;
      const uint32_t counts[4] = {S / 7, S / 5, S / 3, S - S / 7 - S / 5 - S / 3};
      uint32_t group_end[4], k = 0;
      for (uint32_t n = 1; n <= 4; ++n) {
        for (uint32_t i = 0; i < counts[n - 1]; ++i, ++k) {
          for (uint32_t j = 0; j < n; ++j) {
            offsets[4 * k + j] = 12 * (rng() % J);
            weights[4 * k + j] = j == 0 && i % 5 == 4 ? 0.0f : w01(rng);  // a leading zero weight too
          }
          bind[4 * k] = u(rng), bind[4 * k + 1] = u(rng), bind[4 * k + 2] = i % 6 == 5 ? -0.0f : u(rng);
          bind[4 * k + 3] = 1.0f;
        }
        group_end[n - 1] = k;
      }
      std::vector<float> wx(S + 8, -7.0f), wy = wx, wz = wx;
      kernels::JointRefitArgs args{matrices.data(), sphere.data(), offsets.data(), weights.data(), bind.data(),
                                   {group_end[0], group_end[1], group_end[2], group_end[3]},
                                   wx.data(), wy.data(), wz.data()};
      JointReference(args, &wx, &wy, &wz);
      for (Isa isa : isas) {
        CAPTURE(kernels::ToString(isa));
        CAPTURE(J);
        CAPTURE(S);
        std::vector<float> x(S + 8, -7.0f), y = x, z = x;
        args.x = x.data(), args.y = y.data(), args.z = z.data();
        kernels::Kernels(isa).joint_refit(args);
        uint32_t same = 0;
        for (uint32_t s = 0; s < S; ++s)
          same += SameFloat(x[s], wx[s]) && SameFloat(y[s], wy[s]) && SameFloat(z[s], wz[s]);
        CHECK(same == S);
        for (uint32_t s = S; s < S + 8; ++s) CHECK(x[s] == -7.0f);  // nothing written past #S
      }
    }
  }
}

TEST_CASE("Finiteness kernels: true for finite floats, false for a NaN or an infinity at any position") {
  const std::vector<Isa> isas = Isas();
  for (uint32_t n : {4u, 12u, 60u, 64u, 68u, 1956u}) {
    std::vector<float> p(n);
    for (uint32_t i = 0; i < n; ++i) p[i] = i % 3 == 0 ? -0.0f : 1e38f * (i % 2 ? 1.0f : -1.0f);
    for (Isa isa : isas) {
      CAPTURE(kernels::ToString(isa));
      CAPTURE(n);
      CHECK(kernels::Kernels(isa).finite(p.data(), n));
      uint32_t caught = 0;
      for (uint32_t i = 0; i < n; ++i)
        for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()}) {
          std::vector<float> q = p;
          q[i] = bad;
          caught += !kernels::Kernels(isa).finite(q.data(), n);
        }
      CHECK(caught == 3 * n);
    }
  }
}

namespace {

// Random spheres for the broad phase: clustered centres, some NaN / infinite / signed-zero coordinates
// and radii, #S + 8 each with NaN padding; a slot order of B blocks with padding slots (id #S).
struct Slots {
  uint32_t S, B, P;
  std::vector<float> x, y, z, r;
  std::vector<uint32_t> order;
  Slots(uint32_t spheres, uint32_t seed) : S(spheres) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f), rad(0.05f, 0.6f);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (auto* v : {&x, &y, &z, &r}) v->assign(S + 8, nan);
    for (uint32_t s = 0; s < S; ++s) {
      x[s] = u(rng), y[s] = u(rng), z[s] = 0.2f * u(rng), r[s] = rad(rng);
      const uint32_t kind = rng() % 23;
      if (kind == 0) x[s] = nan;
      if (kind == 1) r[s] = nan;
      if (kind == 2) y[s] = inf;
      if (kind == 3) z[s] = -0.0f, x[s] = 0.0f;
      if (kind == 4) r[s] = -r[s];  // a negative radius: |r| bounds it
    }
    // Groups of random sizes, each padded to 8, ids shuffled.
    std::vector<uint32_t> ids(S);
    for (uint32_t s = 0; s < S; ++s) ids[s] = s;
    std::shuffle(ids.begin(), ids.end(), rng);
    for (uint32_t at = 0; at < S;) {
      const uint32_t n = std::min<uint32_t>(S - at, 1 + rng() % 21);
      for (uint32_t i = 0; i < n; ++i) order.push_back(ids[at + i]);
      while (order.size() % 8) order.push_back(S);
      at += n;
    }
    B = static_cast<uint32_t>(order.size() / 8);
    P = (B + 7) / 8 * 8;
  }
  // The scalar gather (DetectJob's) into plain and transposed slots, then the SSE2 BlockBoxes.
  void Reference(float margin, std::vector<float> g[4], std::vector<float>* box) const {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> t[4];
    for (int c = 0; c < 4; ++c) g[c].assign(size_t{8} * B, nan), t[c].assign(size_t{8} * P, nan);
    for (uint32_t I = 0; I < B; ++I)
      for (uint32_t l = 0; l < 8; ++l) {
        const uint32_t s = order[8 * I + l];
        const float v[4] = {x[s], y[s], z[s], r[s] + margin};
        for (int c = 0; c < 4; ++c) g[c][8 * I + l] = v[c], t[c][size_t{l} * P + I] = v[c];
      }
    const size_t pitch = P + 8;
    box->assign(7 * pitch, 0.0f);
    float* b = box->data();
    kernels::Kernels(Isa::kSse2).block_boxes({t[0].data(), t[1].data(), t[2].data(), t[3].data(), P, b, b + pitch,
                                              b + 2 * pitch, b + 3 * pitch, b + 4 * pitch, b + 5 * pitch, b + 6 * pitch});
  }
};

}  // namespace

TEST_CASE("AVX-512 gather and block boxes equal the scalar gather and BlockBoxes") {
  if (!kernels::Supported(Isa::kAvx512)) {
    MESSAGE("AVX-512 not on this CPU: skipped");
    return;
  }
  for (uint32_t S : {1u, 7u, 8u, 31u, 32u, 33u, 96u, 128u, 200u, 256u})
    for (float margin : {0.0f, 0.0666f}) {
      CAPTURE(S);
      CAPTURE(margin);
      const Slots k(S, 100 + S);
      std::vector<float> want[4], want_box;
      k.Reference(margin, want, &want_box);
      std::vector<float> g[4];
      for (auto& v : g) v.assign(size_t{8} * k.B, -7.0f);
      const size_t pitch = k.P + 8;
      std::vector<float> box(7 * pitch, -7.0f);
      float* b = box.data();
      REQUIRE(kernels::Kernels(Isa::kAvx512).gather_boxes({k.x.data(), k.y.data(), k.z.data(), k.r.data(), S,
                                                           k.order.data(), k.B, margin, g[0].data(), g[1].data(),
                                                           g[2].data(), g[3].data(), b, b + pitch, b + 2 * pitch,
                                                           b + 3 * pitch, b + 4 * pitch, b + 5 * pitch, b + 6 * pitch}));
      uint32_t same = 0;
      for (int c = 0; c < 4; ++c)
        for (size_t i = 0; i < g[c].size(); ++i) same += SameFloat(g[c][i], want[c][i]);
      CHECK(same == 4 * 8 * k.B);
      // The boxes of the blocks: the same values (a zero bound's sign may differ: the block test squares
      // its gaps, so it cannot tell them apart).
      uint32_t boxes = 0;
      for (int q = 0; q < 7; ++q)
        for (uint32_t I = 0; I < k.B; ++I) boxes += box[q * pitch + I] == want_box[q * pitch + I];
      CHECK(boxes == 7 * k.B);
    }
  // Over kMaxGatherSpheres the kernel declines (the job gathers one slot at a time).
  const Slots big(kernels::kMaxGatherSpheres + 1, 5);
  std::vector<float> g(size_t{8} * big.B), box(7 * (big.P + 8));
  CHECK_FALSE(kernels::Kernels(Isa::kAvx512).gather_boxes({big.x.data(), big.y.data(), big.z.data(), big.r.data(),
                                                           big.S, big.order.data(), big.B, 0.0f, g.data(), g.data(),
                                                           g.data(), g.data(), box.data(), box.data(), box.data(),
                                                           box.data(), box.data(), box.data(), box.data()}));
}

TEST_CASE("Broad-phase row blocks: every instruction set gives the SSE2 kernel's keys and counters") {
  const std::vector<Isa> isas = Isas();
  for (uint32_t S : {5u, 40u, 128u, 300u}) {
    const Slots k(S, 300 + S);
    std::mt19937 rng(S);
    std::vector<float> g[4], box;
    k.Reference(0.01f, g, &box);
    const uint32_t B = k.B, live_stride = (B + 7) / 8;
    for (bool m1 : {true, false}) {
      CAPTURE(S);
      CAPTURE(m1);
      // Chain masks and allowed lanes: random, but never padding, diagonal blocks upper triangle only.
      std::vector<uint32_t> chain_mask(S + 1, 0);
      for (uint32_t s = 0; s < S; ++s) chain_mask[s] = 1u + rng() % 63u;
      std::vector<uint64_t> allowed(size_t{B} * B, 0);
      std::vector<uint8_t> live(size_t{B} * live_stride, 0);
      for (uint32_t I = 0; I < B; ++I)
        for (uint32_t J = I; J < B; ++J) {
          uint64_t lanes = 0;
          for (uint32_t row = 0; row < 8; ++row)
            for (uint32_t l = 0; l < 8; ++l) {
              const uint32_t p = k.order[8 * I + row], q = k.order[8 * J + l];
              const bool ok = p < S && q < S && (I < J || l > row) && rng() % 7 != 0 &&
                              (!m1 || (chain_mask[p] & chain_mask[q]) != 0);
              lanes |= uint64_t{ok} << (8 * row + l);
            }
          allowed[size_t{I} * B + J] = lanes;
          if (lanes) live[size_t{I} * live_stride + (J - I) / 8] |= static_cast<uint8_t>(1u << ((J - I) % 8));
        }
      const size_t pitch = k.P + 8;
      const float* b = box.data();
      const kernels::BroadPhaseArgs args{g[0].data(), g[1].data(), g[2].data(), g[3].data(), b, b + pitch,
                                         b + 2 * pitch, b + 3 * pitch, b + 4 * pitch, b + 5 * pitch, b + 6 * pitch,
                                         k.order.data(), chain_mask.data(), allowed.data(), live.data(), B,
                                         live_stride, m1};
      std::vector<uint64_t> want(size_t{64} * B * B);
      uint32_t want_box = 0, want_sphere = 0;
      const uint32_t n = kernels::Kernels(Isa::kSse2).block_rows(args, 0, B, want.data(), &want_box, &want_sphere);
      want.resize(n);
      std::sort(want.begin(), want.end());
      if (S >= 40) CHECK(n > 0);  // the random bodies overlap somewhere
      for (Isa isa : isas) {
        CAPTURE(kernels::ToString(isa));
        // All row blocks at once, and one call per row block (the parallel_for tasks' shape).
        for (bool per_row : {false, true}) {
          std::vector<uint64_t> keys(size_t{64} * B * B);
          uint32_t boxes = 0, spheres = 0, hits = 0;
          if (per_row) {
            for (uint32_t I = 0; I < B; ++I) {
              uint32_t bt = 0, st = 0;
              hits += kernels::Kernels(isa).block_rows(args, I, I + 1, keys.data() + hits, &bt, &st);
              boxes += bt, spheres += st;
            }
          } else {
            hits = kernels::Kernels(isa).block_rows(args, 0, B, keys.data(), &boxes, &spheres);
          }
          keys.resize(hits);
          std::sort(keys.begin(), keys.end());
          CHECK(keys == want);
          CHECK(boxes == want_box);
          CHECK(spheres == want_sphere);
        }
      }
    }
  }
}

TEST_CASE("AVX-512 refit: chunks reading the buffer's last vertex, strided buffers, and the AVX hand-off") {
  if (!kernels::Supported(Isa::kAvx512)) {
    MESSAGE("AVX-512 not on this CPU: skipped");
    return;
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (uint32_t stride_floats : {3u, 4u, 8u})
    for (uint32_t S : {16u, 37u, 64u}) {
      CAPTURE(stride_floats);
      CAPTURE(S);
      const uint32_t V = 200;
      // Exactly sized: the last vertex's (x, y, z) end the buffer.
      std::vector<float> positions(size_t{stride_floats} * (V - 1) + 3);
      for (float& f : positions) f = u(rng);
      std::vector<uint32_t> pivots(size_t{12} * S);
      for (uint32_t& v : pivots) v = rng() % (V - 1);
      pivots[12 * 5 + 7] = V - 1;  // sphere 5 (inside the first full chunk) reads the last vertex
      if (S > 40) pivots[12 * 40] = V - 1;
      std::vector<float> local[3], offset[3], scale;
      for (int d = 0; d < 3; ++d)
        for (uint32_t s = 0; s < S + 8; ++s) local[d].push_back(u(rng)), offset[d].push_back(u(rng));
      for (uint32_t s = 0; s < S + 8; ++s) scale.push_back(1.0f + u(rng) * 0.5f);
      for (bool frame_mode : {true, false}) {
        std::vector<float> out[2][4];
        for (int which = 0; which < 2; ++which) {
          for (auto& v : out[which]) v.assign(S + 8, -7.0f);
          const kernels::RefitArgs args{reinterpret_cast<const char*>(positions.data()), 4 * size_t{stride_floats},
                                        V - 1, pivots.data(), local[0].data(), local[1].data(), local[2].data(),
                                        offset[0].data(), offset[1].data(), offset[2].data(), scale.data(),
                                        out[which][0].data(), out[which][1].data(), out[which][2].data(),
                                        out[which][3].data(), frame_mode};
          kernels::Kernels(which == 0 ? Isa::kSse2 : Isa::kAvx512).refit(args, 0, S);
        }
        uint32_t same = 0;
        for (int c = 0; c < 4; ++c)
          for (uint32_t s = 0; s < S + 8; ++s) same += SameFloat(out[0][c][s], out[1][c][s]);
        CHECK(same == 4 * (S + 8));
      }
    }
}
