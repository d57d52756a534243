// Private: job kernels with access to Model's and Workspace's arrays (one definition, used by
// refit.cpp / detect.cpp / batch.cpp), and the SIMD kernels (kernels.cpp) they dispatch to.
#pragma once

#include <cstddef>
#include <cstdint>

#include <algorithm>

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::runtime {

/// One limit of the narrow phase's budget (NarrowPhaseModel::kSweepTestsPerTriangle): `per` × `units` +
/// kSweepSlack, kept 65,536 under UINT32_MAX so the uint32 counters it bounds stop before they could wrap.
/// Used by the crease rule's sweep (Init's bind sweep, each job) and the other exclusions' jobs.
inline uint32_t SweepLimit(uint64_t per, uint64_t units) {
  return static_cast<uint32_t>(std::min<uint64_t>(per * units + NarrowPhaseModel::kSweepSlack, UINT32_MAX - 65536));
}

#if defined(__GNUC__) && defined(__x86_64__)
/// The float filter of PrepareTriangle and TrianglesIntersect(const PreparedTriangle&, const PreparedTriangle&)
/// on 16 triangles by lane (triangle_intersect.cpp section 7): the same values by the same operations, so the
/// same decisions. Compiled for AVX-512 (avx512_target.h): call only where kernels::Best() is kAvx512 (the
/// crease rule's AVX-512 sweep).
/// `f`: 16 rows of 16 floats. Rows 0–8 hold the corners on input (p x, y, z, q x, y, z, r x, y, z; the
/// triangle's own vertex order), rows 9–15 are written: the float plane (n x, y, z, δ) and the error terms
/// G, A, M. Returns the lanes of `lanes` that PrepareTriangle accepts with a certified area (finite, in the
/// filter's range, not a sliver); the others must go through PrepareTriangle. ~25 ns; no allocation.
uint32_t PrepareFilter16(float* f, uint32_t lanes);
/// The lanes of `u` (rows of PrepareFilter16) whose pair with lane `i` (< 16) of `t` the float filter
/// rejects: all three vertices of one triangle certified strictly on one side of the other's plane, either
/// way. Meaningful for certified lanes only. ~10 ns; no allocation.
uint32_t FilterRejects16(const float* t, uint32_t i, const float* u);
#endif

struct Model::Internal {
  static void Refit(const RefitJob& job, uint32_t begin, uint32_t end);
  static Status Detect(const DetectJob& job);
  /// JointRefitJob::Run after its argument checks: kErrorNonFiniteJoints (nothing written) or the blend
  /// over the model's joint records and kOk.
  static Status JointRefit(const JointRefitJob& job);
  /// Shared argument checks of the jobs: kErrorNullArgument (either null), kErrorInvalidJob (either not
  /// initialised), kErrorWorkspaceModel (the workspace was made for another model), else kOk.
  static Status CheckPair(const Model* model, const Workspace* ws) {
    if (!model || !ws) return Status::kErrorNullArgument;
    if (!model->initialized() || !ws->initialized()) return Status::kErrorInvalidJob;
    if (!ws->made_for(*model)) return Status::kErrorWorkspaceModel;
    return Status::kOk;
  }
};

/// Kernels over plain arrays, compiled three times (kernels.cpp): SSE2 (any x86-64), AVX and AVX-512
/// (function-level targets), one set picked per model at Init (`Best()`: the CPU's and OS's support,
/// `__builtin_cpu_supports`); a scalar build elsewhere. Same operations in the same order — the formulas
/// themselves are spherechain/runtime/formulas.inl, included once per instruction set — no FMA: every
/// variant gives bit-identical results (tests/runtime/formulas_test.cpp, kernels_test.cpp).
namespace kernels {

/// Instruction sets of the kernels, in order: a CPU that runs one runs the ones before it.
enum class Isa : uint8_t {
  kSse2 = 0,    ///< baseline x86-64 (and the scalar build on other targets)
  kAvx = 1,     ///< AVX + POPCNT: 8 lanes
  kAvx512 = 2,  ///< AVX-512 F/VL/DQ/BW + POPCNT: 16 lanes, mask registers, two-source permutes
};
inline constexpr int kIsaCount = 3;
const char* ToString(Isa isa);  ///< "sse2", "avx", "avx512"
/// True when this CPU (and OS: the register state is saved) runs `isa`'s kernels; kSse2 always.
bool Supported(Isa isa);
/// The best supported set, capped by the environment variable SPHERECHAIN_ISA (sse2, avx or avx512: for
/// benchmarks and tests of the lower paths; an unknown value is ignored). Read once (thread-safe).
Isa Best();

/// Refit of spheres [begin, end) (see RefitJob, refit.h). Per-sphere arrays are readable up to a
/// multiple of 8 past `end` (padded); outputs are written for [begin, end) only. The x86 kernels read
/// each pivot vertex as four floats (x, y, z and the next float of the buffer, unused) except the
/// buffer's last vertex (`last_vertex`), which may end the buffer.
struct RefitArgs {
  const char* base;               // positions (strided)
  size_t stride;                  // bytes
  uint32_t last_vertex;           // #V − 1
  const uint32_t* pivot_vertices; // #S×12
  const float *local_x, *local_y, *local_z, *offset_x, *offset_y, *offset_z, *radius_scale;
  float *x, *y, *z, *r;
  bool frame_mode;                // kPivotFrame
};

/// Broad phase of DetectJob (M1 and M2 share it), one row block per call: spheres sit in blocks of 8
/// (Model::Init's layout: per chain-membership class, bind-pose kd split), gathered per frame in
/// block order (x, y, z, r grown by the margin; padding lanes NaN). Row block I is tested against
/// every block J >= I that the method's static table keeps (`live`: some allowed lane); a block pair
/// survives when the distance between the boxes of the two blocks' centres is below the sum of their
/// largest |radius| — computed with the sphere test's own float operations, so that it never drops a
/// pair the sphere test would report (see kernels.inl) — then the sphere tests of the pair run, masked
/// by `allowed` (row r's lanes in byte r: not padding, j > i on the diagonal block, not excluded, and for
/// M1 sharing a chain). Each hit writes (first common chain, M1 only) << 32 | min(a,b) << 16 | max(a,b)
/// (row blocks [begin, end) of a call: the keys written contiguously at `keys`, in no particular order —
/// the job sorts them). Returns the number of keys; the counters of the rows go to *box_tests (live block
/// pairs) / *sphere_tests (allowed lanes of the kept pairs).
struct BroadPhaseArgs {
  const float *x, *y, *z, *r;             // G = 8·B gathered spheres, block order
  const float *lx, *hx, *ly, *hy, *lz, *hz, *br;  // per block (B + 8, padding blocks empty): box of
                                          // the centres, largest |grown radius| (NaN lanes ignored)
  const uint32_t* order;                  // G: sphere id per slot (padding: #S)
  const uint32_t* chain_mask;             // #S + 1
  const uint64_t* allowed;                // B×B, [I·B + J] for J >= I: lanes of the pair, byte r = row r
  const uint8_t* live;                    // B × live_stride: bit k of byte c ⇔ allowed[I][I+8c+k] != 0
  uint32_t blocks, live_stride;
  bool m1;                                // keys carry the first common chain
};

/// Block boxes of the transposed gathered spheres: t* hold lane l of block I at [l · pitch + I]
/// (pitch a multiple of 8 >= B; padding NaN). Writes lx..br for I < pitch.
struct BlockBoxArgs {
  const float *tx, *ty, *tz, *tr;
  uint32_t pitch;
  float *lx, *hx, *ly, *hy, *lz, *hz, *br;
};

/// The detection's gather and block boxes in one pass (the AVX-512 kernel; the others return false and the
/// job gathers one slot at a time, into a transposed copy as well, for BlockBoxes): for every slot g <
/// 8·blocks, g* [g] = sphere src[g] of x, y, z, and r + margin (src[g] == #S: padding, NaN); then per
/// block the box of its centres and its largest |grown radius|, NaN lanes ignored (BlockBoxArgs' values:
/// the same bounds up to the sign of a zero bound, which no block-pair test can tell apart — its gaps
/// are squared). [Limit: #S <= kMaxGatherSpheres, else false and nothing written]
struct GatherArgs {
  const float *x, *y, *z, *r;     // #S + 8 each
  uint32_t sphere_count;          // #S
  const uint32_t* src;            // 8·blocks: sphere id per slot
  uint32_t blocks;
  float margin;
  float *gx, *gy, *gz, *gr;       // 8·blocks
  float *lx, *hx, *ly, *hy, *lz, *hz, *br;  // blocks rounded up to 8
};
inline constexpr uint32_t kMaxGatherSpheres = 256;

/// JointRefitJob's blend and transform over the model's joint records (Model::Init: one record a
/// sphere, grouped by the number of influences it uses, 1..4 — the leading nonzero weights after the
/// first). Record k (of group n: group_end[n−2] <= k < group_end[n−1], group_end[−1] = 0) writes sphere
/// sphere[k]'s centre: M = ((w0·M_j0 + w1·M_j1) + w2·M_j2) + w3·M_j3 over its first n influences (3×4,
/// row-major, 12 floats at matrices + offsets[4k + i]), then per row ρ (ρ0·bx + ρ1·by) + (ρ2·bz + ρ3·1)
/// with bind[4k .. 4k + 3] = (bx, by, bz, 1).
struct JointRefitArgs {
  const float* matrices;          // #J × 12
  const uint32_t* sphere;         // #S: sphere id per record
  const uint32_t* offsets;        // #S × 4: matrix offsets [floats] (joint × 12; unused: 0)
  const float* weights;           // #S × 4 (unused: 0)
  const float* bind;              // #S × 4: bind centre and 1
  uint32_t group_end[4];          // records using 1, 2, 3, 4 influences end here
  float *x, *y, *z;
};

/// One instruction set's kernels.
struct Table {
  void (*refit)(const RefitArgs& a, uint32_t begin, uint32_t end);
  void (*block_boxes)(const BlockBoxArgs& a);
  uint32_t (*block_rows)(const BroadPhaseArgs& a, uint32_t begin, uint32_t end, uint64_t* keys, uint32_t* box_tests,
                         uint32_t* sphere_tests);
  bool (*gather_boxes)(const GatherArgs& a);  // false: not handled (the caller gathers), nothing written
  void (*joint_refit)(const JointRefitArgs& a);
  bool (*finite)(const float* p, uint32_t n);  // all n floats finite (n a multiple of 4)
};
/// The kernels of `isa` [Limit: Supported(isa), else the CPU may fault].
const Table& Kernels(Isa isa);

}  // namespace kernels
}  // namespace spherechain::runtime
