// The sequence the load_asset fuzzer runs on one input, shared with the corpus-replay doctest
// (tests/runtime/fuzz_corpus_test.cpp) so every configuration replays the corpus without libFuzzer.
//
// Bytes → LoadAsset → (if it loads) Model::Init (and InitInPlace) → Workspace::Init → RefitJob (both modes, positions derived from the
// input, NaN/Inf/huge/denormal included) → DetectJob M1 and M2 into DetectBound-sized buffers (and
// once more truncated) → SurroundingTriangles / PivotTriangles for every sphere, checking the
// documented invariants of each output. Header-only; needs only spherechain::runtime.
#pragma once

#include <spherechain/runtime/runtime.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

namespace spherechain::fuzz {

/// Biggest vertex buffer / output buffer the harness allocates (the asset's counts are untrusted:
/// Fingerprint.vertex_count may say 4e9). Above it the step is skipped (refit) or truncated (detect).
inline constexpr uint32_t kMaxHarnessVertices = uint32_t{1} << 22;
inline constexpr uint32_t kMaxHarnessCollisions = uint32_t{1} << 22;

/// Runs the sequence on `data[0..size)`. Returns nullptr when every runtime call behaved as
/// documented (including a clean rejection by LoadAsset), else a static description of the broken
/// invariant. `*loaded` (opt) receives whether LoadAsset accepted the bytes.
inline const char* RunLoadAssetSequence(const uint8_t* data, size_t size, bool* loaded = nullptr) {
  using namespace spherechain::runtime;
  if (loaded) *loaded = false;
  // Exact-size heap copy: operator new[] is at least 16-byte aligned (LoadAsset needs 8), and ASan
  // still sees a 1-byte over-read past the end.
  std::unique_ptr<uint8_t[]> buf(new uint8_t[size ? size : 1]);
  if (size) std::memcpy(buf.get(), data, size);

  AssetView view;
  const Status load = LoadAsset(buf.get(), size, &view);
  if (load != Status::kOk) return view.valid() ? "LoadAsset failed but left a valid view" : nullptr;
  if (!view.valid() || view.sphere_count == 0) return "LoadAsset kOk with an empty view";
  if (loaded) *loaded = true;

  Model model;
  const Status init = model.Init(view);
  if (init == Status::kErrorOutOfMemory) return nullptr;  // documented, e.g. a huge chain
  if (init != Status::kOk) return "Model::Init failed on a loaded asset";
  const uint32_t S = view.sphere_count, V = view.vertex_count, T = view.triangle_count;
  if (model.sphere_count() != S || model.vertex_count() != V) return "Model counts differ from the view";
  if (model.bytes() != Model::RequiredBytes(view)) return "Model::RequiredBytes differs from the model's size";
  {  // the caller-memory variant: same size, too small refused
    const size_t need = Model::RequiredBytes(view);
    std::unique_ptr<uint64_t[]> mem(new uint64_t[need / 8 + 2]);
    Model in_place;
    if (in_place.InitInPlace(view, mem.get(), need - 1) != Status::kErrorBufferTooSmall)
      return "Model::InitInPlace accepted a buffer one byte short";
    if (in_place.InitInPlace(view, mem.get(), need) != Status::kOk) return "Model::InitInPlace failed";
  }
  Workspace ctx;
  if (ctx.Init(model) != Status::kOk) return "Workspace::Init failed";

  // Surrounding regions and pivots: every index in range.
  for (uint32_t s = 0; s < S; ++s) {
    const TriangleSpan st = SurroundingTriangles(view, s);
    if (st.count && !st.data) return "SurroundingTriangles: null data with a count";
    for (uint32_t i = 0; i < st.count; ++i)
      if (st.data[i] >= T) return "SurroundingTriangles: triangle index >= #T";
    const TriangleSpan pt = PivotTriangles(view, s);
    if (pt.count != kPivotsPerSphere) return "PivotTriangles: not 4 triangles";
    for (uint32_t i = 0; i < pt.count; ++i)
      if (pt.data[i] >= T) return "PivotTriangles: triangle index >= #T";
  }

  // Positions from the input bytes: specials (NaN, ±Inf, ±FLT_MAX, denormals, ±0) and plain values.
  if (V > 0 && V <= kMaxHarnessVertices) {
    const uint32_t stride_floats = (data[size - 1] & 1) ? 4 : 3;
    std::vector<float> pos(size_t{V} * stride_floats);
    static constexpr float kSpecial[8] = {std::numeric_limits<float>::quiet_NaN(), INFINITY, -INFINITY, FLT_MAX,
                                          -FLT_MAX, FLT_TRUE_MIN, 0.0f, -0.0f};
    for (size_t i = 0; i < pos.size(); ++i) {
      const uint8_t b = data[(i * 7 + 3) % size];
      pos[i] = b < 8 ? kSpecial[b] : (static_cast<float>(b) - 128.0f) * 0.03125f * static_cast<float>(i % 5 + 1);
    }
    for (RefitMode mode : {RefitMode::kPivotFrame, RefitMode::kPaper}) {
      RefitJob refit;
      refit.model = &model;
      refit.workspace = &ctx;
      refit.mode = mode;
      refit.positions = {pos.data(), V, stride_floats * 4u};
      if (refit.Run() != Status::kOk) return "RefitJob failed on valid arguments";
    }
  }

  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
    const uint32_t bound = DetectBound(view, method);
    const uint32_t cap = bound < kMaxHarnessCollisions ? bound : kMaxHarnessCollisions;
    std::vector<Collision> out(cap ? cap : 1);
    for (uint32_t capacity : {cap, cap / 2}) {
      uint32_t n = ~0u;
      DetectStats stats;
      DetectJob detect;
      detect.model = &model;
      detect.workspace = &ctx;
      detect.method = method;
      detect.output = out.data();
      detect.capacity = capacity;
      detect.count = &n;
      detect.stats = &stats;
      const Status s = detect.Run();
      if (Failed(s)) return "DetectJob failed on valid arguments";
      if (n > capacity) return "DetectJob wrote more than capacity";
      if (capacity == bound && s == Status::kOkTruncated) return "DetectBound-sized buffer was truncated";
      if ((s == Status::kOkTruncated) != (stats.distinct_pairs > n)) return "DetectJob truncation flag inconsistent";
      for (uint32_t i = 0; i < n; ++i) {
        const Collision& c = out[i];
        if (!(c.a < c.b) || c.b >= S) return "DetectJob: pair not a < b < #S";
        if (model.IsExcluded(c.a, c.b)) return "DetectJob: reported an excluded pair";
        if (method == DetectMethod::kM1 && c.chains == 0) return "DetectJob M1: pair with no chain";
      }
    }
  }
  if (ctx.ResetToBindPose(model) != Status::kOk) return "ResetToBindPose failed";
  return nullptr;
}

}  // namespace spherechain::fuzz
