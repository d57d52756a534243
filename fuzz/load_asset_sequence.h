// The sequence the load_asset fuzzer runs on one input, shared with the corpus-replay doctest
// (tests/runtime/fuzz_corpus_test.cpp) so every configuration replays the corpus without libFuzzer.
//
// Bytes → LoadAsset → (if it loads) Model::Init (and InitInPlace) → Workspace::Init → RefitJob (both modes, positions derived from the
// input, NaN/Inf/huge/denormal included) → DetectJob M1 and M2 into DetectBound-sized buffers (and
// once more truncated) → SurroundingTriangles / PivotTriangles for every sphere → the narrow phase in the
// Model (ModelOptions::narrow_phase, also in caller memory) and its NarrowPhaseJob under each Exclusions, on
// the derived positions and on the asset's bind pose, checking the documented invariants of each output.
// Header-only; needs only spherechain::runtime.
#pragma once

#include <spherechain/runtime/runtime.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <utility>
#include <vector>

namespace spherechain::fuzz {

/// Biggest vertex buffer / output buffer the harness allocates (the asset's counts are untrusted:
/// Fingerprint.vertex_count may say 4e9). Above it the step is skipped (refit) or truncated (detect).
inline constexpr uint32_t kMaxHarnessVertices = uint32_t{1} << 22;
inline constexpr uint32_t kMaxHarnessCollisions = uint32_t{1} << 22;

/// Biggest mesh the harness gives the narrow phase (its Init is O(#T log #T) plus a bounded Dijkstra per
/// patch node, within NarrowPhaseModel's work budgets, which are linear in the mesh: an asset's triangle count
/// is bounded by its bytes, but a dense 4 MB one would be slow). Past a budget Init returns
/// kErrorCreaseTooWide, which the sequence accepts as a documented refusal.
inline constexpr uint32_t kMaxHarnessNarrowTriangles = uint32_t{1} << 13;

/// Exact triangle tests after which the harness runs no other Exclusions on the same positions. The exact
/// predicate takes ~1 µs a test where the geometry is degenerate (coplanar or coincident triangles: a
/// mutated bind pose, or the positions derived from the input bytes), ~20 times the usual, and the fuzz
/// build is another ~11 times slower: one pathological set of positions run under three Exclusions, and the
/// narrow phase built twice, took 11.6 s (1.0 s optimised) on a 1,504-triangle input. One job on such
/// positions checks the same invariants.
inline constexpr uint32_t kHarnessTestBudget = 100000;

/// Bind contacts (a bind pose that already intersects itself in that many pairs is a mutated one; the
/// real characters have at most 6,586) above which the harness neither builds the narrow phase a second
/// time in caller memory (a build repeats the first one's work, its sweep of the bind pose included, and
/// checks only the layout, which every other input checks) nor runs jobs at the bind pose (Init swept it).
/// A 1,504-triangle input whose bind pose intersected itself in 91,264 pairs spent 0.46 s optimised in
/// Init alone, 5 s in the fuzz build; Init now refuses such a bind pose within its budget
/// (kErrorBindPoseTangled, NarrowPhaseModel::kSweepTestsPerTriangle), and this rule is left for the
/// bind poses with many contacts that fit in it.
inline constexpr uint32_t kHarnessJunkBindContacts = 16384;

/// The narrow phase of `view` held by a Model, run on `positions` (\#V×3, packed) and at the bind pose
/// under every Exclusions the model supports, each output checked: kCrease first, and after a job past
/// kHarnessTestBudget exact tests no other on those positions; past kHarnessJunkBindContacts, nothing at
/// the bind pose and no second build in caller memory. nullptr when everything behaved as documented.
/// `*crease_ran` (opt) is set when a kCrease job ran to completion.
inline const char* RunNarrowPhaseSequence(const runtime::AssetView& view, const std::vector<float>* positions_or_null,
                                          bool* crease_ran = nullptr) {
  using namespace spherechain::runtime;
  ModelOptions options;
  options.narrow_phase = true;
  Model model;
  const Status init = model.Init(view, options);
  if (init == Status::kErrorMissingField || init == Status::kErrorOutOfMemory || init == Status::kErrorBindPoseTangled ||
      init == Status::kErrorCreaseTooWide)
    return nullptr;  // documented
  if (init != Status::kOk) return "Model::Init with the narrow phase failed on a loaded asset";
  if (!model.narrow_phase()) return "Model::Init with the narrow phase gave no narrow phase";
  const NarrowPhaseModel& np = *model.narrow_phase();
  const uint32_t S = view.sphere_count, T = view.triangle_count;
  if (np.triangle_count() != T || np.sphere_count() != S) return "NarrowPhaseModel counts differ from the view";
  const bool junk_bind = np.bind_contact_count() > kHarnessJunkBindContacts;
  if (!junk_bind) {
    // the caller-memory variant in the model's size (each call builds the narrow phase again: RequiredBytes
    // and a buffer one byte short are left to the unit tests)
    const size_t need = model.bytes();
    std::unique_ptr<uint64_t[]> mem(new uint64_t[need / 8 + 2]);
    Model in_place;
    if (in_place.InitInPlace(view, options, mem.get(), need) != Status::kOk) return "Model::InitInPlace(options) failed";
    if (!in_place.narrow_phase() || in_place.bytes() != need) return "Model::InitInPlace(options) is not Init's model";
  }
  Workspace ws;
  if (ws.Init(model) != Status::kOk || !ws.narrow_phase()) return "Workspace::Init failed for a narrow-phase model";
  const auto* bind = view.asset->bind_positions();
  std::vector<float> bind_pose;
  if (np.has_crease() && bind && !junk_bind) bind_pose.assign(bind->begin(), bind->end());
  std::vector<TriangleContact> out(4096);
  std::vector<ContactDepth> depths(out.size());
  const std::vector<float>* frames[2] = {positions_or_null, bind_pose.empty() ? nullptr : &bind_pose};
  for (const std::vector<float>* pos : frames) {
    if (!pos) continue;
    const bool at_bind = pos == &bind_pose;
    bool heavy = false;
    for (Exclusions ex : {Exclusions::kCrease, Exclusions::kAsset, Exclusions::kNone}) {
      if (ex == Exclusions::kCrease && !np.has_crease()) continue;
      if (heavy) break;
      uint32_t n = ~0u;
      NarrowPhaseStats stats;
      NarrowPhaseJob job;
      job.model = &np;
      job.workspace = ws.narrow_phase();
      job.positions = {pos->data(), view.vertex_count, 12};
      job.exclusions = ex;
      job.output = out.data();
      job.capacity = static_cast<uint32_t>(out.size());
      job.depths = depths.data();
      job.count = &n;
      job.stats = &stats;
      const Status s = job.Run();
      if (s == Status::kErrorNonFinitePositions) {
        if (n != 0) return "NarrowPhaseJob: non-finite positions with contacts written";
        if (at_bind) return "NarrowPhaseJob: kErrorNonFinitePositions on the bind pose (finite: the crease graph checked it)";
        continue;
      }
      if (s == Status::kErrorFrameTangled) {  // documented: past the job's budget on these positions
        if (n != 0) return "NarrowPhaseJob: kErrorFrameTangled with contacts counted";
        if (at_bind && ex == Exclusions::kCrease)
          return "NarrowPhaseJob: kErrorFrameTangled on the bind pose (Init swept it within the budget)";
        heavy = true;
        continue;
      }
      if (Failed(s)) return "NarrowPhaseJob failed on valid arguments";
      heavy = stats.triangle_tests > kHarnessTestBudget;
      if (n > out.size() || n > stats.contacts) return "NarrowPhaseJob wrote more than capacity or than it counted";
      if ((s == Status::kOkTruncated) != (stats.contacts > out.size())) return "NarrowPhaseJob truncation flag inconsistent";
      std::set<std::pair<uint32_t, uint32_t>> seen;
      for (uint32_t i = 0; i < n; ++i) {
        const TriangleContact& c = out[i];
        if (c.triangle_a >= T || c.triangle_b >= T || c.triangle_a == c.triangle_b)
          return "NarrowPhaseJob: a contact's triangle out of range or twice";
        if (!seen.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)}).second)
          return "NarrowPhaseJob: a triangle pair reported twice";
        if (ex == Exclusions::kCrease) {
          if (c.sphere_a != np.triangle_sphere(c.triangle_a) || c.sphere_b != np.triangle_sphere(c.triangle_b))
            return "NarrowPhaseJob kCrease: a contact's spheres are not its triangles' owners";
          if (!(depths[i].depth >= 0.0f)) return "NarrowPhaseJob: a depth NaN or negative";
          if (at_bind && !np.IntersectsAtBind(c.triangle_a, c.triangle_b))
            return "NarrowPhaseJob kCrease: a contact at bind pose that Init did not find";
        } else {
          if (!(c.sphere_a < c.sphere_b) || c.sphere_b >= S) return "NarrowPhaseJob: spheres not a < b < #S";
          if (ex == Exclusions::kAsset && np.IsExcluded(c.sphere_a, c.sphere_b))
            return "NarrowPhaseJob kAsset: reported an excluded pair";
        }
      }
      if (ex == Exclusions::kCrease && at_bind && stats.contacts != np.bind_contact_count())
        return "NarrowPhaseJob kCrease at bind pose: not the bind contacts Init found";
      if (ex == Exclusions::kCrease && at_bind && np.has_joint_cull()) {
        // The bind pose is the skin under identity matrices: the joint-matrix cull may skip pairs, never a contact.
        std::vector<float> identity(size_t{np.joint_count()} * kJointMatrixFloats, 0.0f);
        for (uint32_t j = 0; j < np.joint_count(); ++j)
          for (int k = 0; k < 3; ++k) identity[size_t{j} * kJointMatrixFloats + 5 * k] = 1.0f;
        job.joint_matrices = identity.data();
        job.joint_count = np.joint_count();
        NarrowPhaseStats culled;
        job.stats = &culled;
        if (Failed(job.Run())) return "NarrowPhaseJob kCrease with joint matrices failed on valid arguments";
        if (culled.contacts != stats.contacts) return "NarrowPhaseJob kCrease: the joint-matrix cull lost a bind contact";
      }
      if (ex == Exclusions::kCrease && !heavy && s == Status::kOk) {
        // The restricted path: behind the folds of the current spheres (the bind pose's after Init, at closing
        // 0: the excluded pairs that are closer than their bind distance) and a few neighbouring index pairs:
        // a subset of the contacts above, each once, the listing accepted as documented.
        std::vector<Collision> pairs(size_t{np.fold_pair_count()} + 8);
        uint32_t folds = 0;
        if (FoldPairs(np, ws.spheres(), 0.0f, pairs.data(), np.fold_pair_count(), &folds) != Status::kOk)
          return "FoldPairs failed on valid arguments";
        if (folds > np.fold_pair_count()) return "FoldPairs found more folds than excluded pairs";
        for (uint32_t i = 0; i < folds; ++i)
          if (!(pairs[i].a < pairs[i].b) || !np.IsExcluded(pairs[i].a, pairs[i].b)) return "FoldPairs: a fold not an excluded a < b";
        uint32_t listed = folds;
        for (uint32_t a = 0; a + 1 < S && listed < pairs.size(); a += 1 + S / 8)
          pairs[listed++] = Collision{static_cast<uint16_t>(a), static_cast<uint16_t>(a + 1), 0.0f, 0u};
        job.sphere_pairs = pairs.data();
        job.sphere_pair_count = listed;
        job.joint_matrices = nullptr;  // the cull's identity matrices above are gone with their block
        job.joint_count = 0;
        uint32_t m = ~0u;
        NarrowPhaseStats restricted;
        job.count = &m;
        job.stats = &restricted;
        const Status rs = job.Run();
        if (rs != Status::kOk && rs != Status::kOkTruncated) return "NarrowPhaseJob kCrease behind pairs failed on valid arguments";
        if (restricted.contacts > stats.contacts) return "NarrowPhaseJob kCrease behind pairs found more than unrestricted";
        std::set<std::pair<uint32_t, uint32_t>> once;
        for (uint32_t i = 0; i < m; ++i) {
          const std::pair<uint32_t, uint32_t> k{std::min(out[i].triangle_a, out[i].triangle_b), std::max(out[i].triangle_a, out[i].triangle_b)};
          if (!seen.count(k)) return "NarrowPhaseJob kCrease behind pairs: a contact the unrestricted job did not report";
          if (!once.insert(k).second) return "NarrowPhaseJob kCrease behind pairs: a triangle pair reported twice";
        }
        job.sphere_pairs = nullptr;
        job.sphere_pair_count = 0;
        job.count = &n;
        job.stats = &stats;
      }
      if (ex == Exclusions::kCrease && crease_ran) *crease_ran = true;
    }
  }
  return nullptr;
}

/// Runs the sequence on `data[0..size)`. Returns nullptr when every runtime call behaved as
/// documented (including a clean rejection by LoadAsset), else a static description of the broken
/// invariant. `*loaded` (opt) receives whether LoadAsset accepted the bytes, `*crease_ran` (opt) whether a
/// narrow phase under the crease rule ran. `narrow_phase` false leaves the narrow phase out (its Init is
/// the sequence's slowest step: callers running thousands of inputs in a test run it on some).
inline const char* RunLoadAssetSequence(const uint8_t* data, size_t size, bool* loaded = nullptr,
                                        bool* crease_ran = nullptr, bool narrow_phase = true) {
  using namespace spherechain::runtime;
  if (loaded) *loaded = false;
  if (crease_ran) *crease_ran = false;
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

  // The narrow phase, on finite positions derived from the input (the specials above would only reach its
  // kErrorNonFinitePositions) and at the bind pose.
  if (narrow_phase && T > 0 && T <= kMaxHarnessNarrowTriangles && V > 0 && V <= kMaxHarnessVertices) {
    // Half the inputs (by their first byte): the bind pose, where the asset has one, each coordinate moved by
    // up to 2 % of its extent (a pose the jobs run through, their outputs checked); the others scattered
    // through a 16-unit cube (positions that are no pose: the jobs' budget, kErrorFrameTangled).
    std::vector<float> pos(size_t{V} * 3);
    const auto* bind = view.asset->bind_positions();
    if ((data[0] & 1) && bind && bind->size() == pos.size()) {
      float extent = 0.0f;
      for (float x : *bind) extent = std::max(extent, std::fabs(x));
      for (size_t i = 0; i < pos.size(); ++i)
        pos[i] = bind->Get(static_cast<flatbuffers::uoffset_t>(i)) +
                 (static_cast<float>(data[(i * 5 + 1) % size]) - 128.0f) / 128.0f * 0.02f * extent;
    } else {
      for (size_t i = 0; i < pos.size(); ++i)
        pos[i] = (static_cast<float>(data[(i * 5 + 1) % size]) - 128.0f) * 0.0625f;
    }
    if (const char* why = RunNarrowPhaseSequence(view, &pos, crease_ran)) return why;
  }
  return nullptr;
}

}  // namespace spherechain::fuzz
