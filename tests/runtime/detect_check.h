// Test helper: DetectJob's records against expected ones, pair for pair, depths to the bit.
#pragma once

#include <doctest/doctest.h>

#include <bit>
#include <cstdint>
#include <vector>

#include "spherechain/runtime/runtime.h"

namespace spherechain::test {

/// out[0..n) equals `want` in order: sphere indices, chain masks, and depth bit for bit.
inline void CheckSameCollisions(const runtime::Collision* out, uint32_t n, const std::vector<runtime::Collision>& want) {
  REQUIRE(n == want.size());
  for (uint32_t k = 0; k < n; ++k) {
    CHECK(out[k].a == want[k].a);
    CHECK(out[k].b == want[k].b);
    CHECK(out[k].chains == want[k].chains);
    CHECK(std::bit_cast<uint32_t>(out[k].depth) == std::bit_cast<uint32_t>(want[k].depth));
  }
}

}  // namespace spherechain::test
