// spherechain C API (spherechain/spherechain.h): the runtime's jobs behind opaque handles, in the shared
// library spherechain_c (not in the static runtime: runtime/CMakeLists.txt leaves this file out of it).
// Nothing here throws (the runtime returns Status and catches its own allocation failures; the handles are
// allocated with nothrow new) and nothing allocates after sc_model_create / sc_workspace_create.
#include "spherechain/spherechain.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

#include "spherechain/runtime/runtime.h"

namespace rt = spherechain::runtime;

struct sc_model {
  rt::AssetView view;  // borrows the caller's bytes
  rt::Model model;     // refit, broad phase and, with SC_MODEL_NARROW_PHASE, the narrow phase: one block
};

struct sc_workspace {
  rt::Workspace ws;  // one block, the narrow phase's scratch included when the model has it
};

namespace {

// The status values are the runtime's, bit for bit.
constexpr bool Same(sc_status c, rt::Status s) { return c == static_cast<uint32_t>(s); }
static_assert(Same(SC_OK, rt::Status::kOk) && Same(SC_OK_TRUNCATED, rt::Status::kOkTruncated));
static_assert(Same(SC_ERROR_NULL_ARGUMENT, rt::Status::kErrorNullArgument) &&
              Same(SC_ERROR_ALIGNMENT, rt::Status::kErrorAlignment) &&
              Same(SC_ERROR_INVALID_JOB, rt::Status::kErrorInvalidJob) &&
              Same(SC_ERROR_VERTEX_COUNT, rt::Status::kErrorVertexCount) &&
              Same(SC_ERROR_STRIDE, rt::Status::kErrorStride) &&
              Same(SC_ERROR_OUT_OF_MEMORY, rt::Status::kErrorOutOfMemory) &&
              Same(SC_ERROR_NON_FINITE_POSITIONS, rt::Status::kErrorNonFinitePositions) &&
              Same(SC_ERROR_JOINT_COUNT, rt::Status::kErrorJointCount) &&
              Same(SC_ERROR_NON_FINITE_JOINTS, rt::Status::kErrorNonFiniteJoints) &&
              Same(SC_ERROR_WORKSPACE_MODEL, rt::Status::kErrorWorkspaceModel) &&
              Same(SC_ERROR_BUFFER_TOO_SMALL, rt::Status::kErrorBufferTooSmall) &&
              Same(SC_ERROR_FRAME_TANGLED, rt::Status::kErrorFrameTangled));
static_assert(Same(SC_ERROR_ASSET_TOO_SMALL, rt::Status::kErrorAssetTooSmall) &&
              Same(SC_ERROR_ASSET_TOO_LARGE, rt::Status::kErrorAssetTooLarge) &&
              Same(SC_ERROR_IDENTIFIER, rt::Status::kErrorIdentifier) &&
              Same(SC_ERROR_VERSION_TOO_OLD, rt::Status::kErrorVersionTooOld) &&
              Same(SC_ERROR_VERSION_TOO_NEW, rt::Status::kErrorVersionTooNew) &&
              Same(SC_ERROR_CORRUPT, rt::Status::kErrorCorrupt));
static_assert(Same(SC_ERROR_MISSING_FIELD, rt::Status::kErrorMissingField) &&
              Same(SC_ERROR_NO_SPHERES, rt::Status::kErrorNoSpheres) &&
              Same(SC_ERROR_TOO_MANY_SPHERES, rt::Status::kErrorTooManySpheres) &&
              Same(SC_ERROR_TOO_MANY_CHAINS, rt::Status::kErrorTooManyChains) &&
              Same(SC_ERROR_COUNT_MISMATCH, rt::Status::kErrorCountMismatch) &&
              Same(SC_ERROR_INDEX_OUT_OF_RANGE, rt::Status::kErrorIndexOutOfRange) &&
              Same(SC_ERROR_OFFSETS, rt::Status::kErrorOffsets) &&
              Same(SC_ERROR_NON_FINITE, rt::Status::kErrorNonFinite) &&
              Same(SC_ERROR_RADIUS, rt::Status::kErrorRadius) &&
              Same(SC_ERROR_PIVOT_FRAME, rt::Status::kErrorPivotFrame) &&
              Same(SC_ERROR_CHAIN_ORDER, rt::Status::kErrorChainOrder) &&
              Same(SC_ERROR_EXCLUDED_PAIRS, rt::Status::kErrorExcludedPairs) &&
              Same(SC_ERROR_CONTACT_MARGIN, rt::Status::kErrorContactMargin) &&
              Same(SC_ERROR_SKIN_WEIGHTS, rt::Status::kErrorSkinWeights) &&
              Same(SC_ERROR_REGIONS, rt::Status::kErrorRegions) &&
              Same(SC_ERROR_BIND_POSE_TANGLED, rt::Status::kErrorBindPoseTangled) &&
              Same(SC_ERROR_CREASE_TOO_WIDE, rt::Status::kErrorCreaseTooWide));

// The C records are the runtime's, byte for byte: the jobs write into (and read from) the caller's arrays.
static_assert(sizeof(sc_pair) == sizeof(rt::Collision) && offsetof(sc_pair, a) == offsetof(rt::Collision, a) &&
              offsetof(sc_pair, b) == offsetof(rt::Collision, b) &&
              offsetof(sc_pair, depth) == offsetof(rt::Collision, depth) &&
              offsetof(sc_pair, chains) == offsetof(rt::Collision, chains));
static_assert(sizeof(sc_contact) == sizeof(rt::TriangleContact) &&
              offsetof(sc_contact, triangle_a) == offsetof(rt::TriangleContact, triangle_a) &&
              offsetof(sc_contact, triangle_b) == offsetof(rt::TriangleContact, triangle_b) &&
              offsetof(sc_contact, sphere_a) == offsetof(rt::TriangleContact, sphere_a) &&
              offsetof(sc_contact, sphere_b) == offsetof(rt::TriangleContact, sphere_b));
static_assert(sizeof(sc_contact_depth) == sizeof(rt::ContactDepth) &&
              offsetof(sc_contact_depth, depth) == offsetof(rt::ContactDepth, depth) &&
              offsetof(sc_contact_depth, direction) == offsetof(rt::ContactDepth, direction));
static_assert(std::is_standard_layout_v<rt::Collision> && std::is_standard_layout_v<rt::TriangleContact> &&
              std::is_standard_layout_v<rt::ContactDepth>);
static_assert(sizeof(sc_detect_method) == 4 && sizeof(sc_exclusions) == 4);

sc_status C(rt::Status s) { return static_cast<sc_status>(s); }

// A stride the runtime's PositionsView can hold; larger ones are refused as a bad stride.
bool StrideFits(size_t stride_bytes) { return stride_bytes <= UINT32_MAX; }

}  // namespace

// The header's versions are the build's: CMake passes PROJECT_VERSION's parts, the runtime its schema range.
static_assert(SC_VERSION_MAJOR == SPHERECHAIN_VERSION_MAJOR && SC_VERSION_MINOR == SPHERECHAIN_VERSION_MINOR &&
                  SC_VERSION_PATCH == SPHERECHAIN_VERSION_PATCH,
              "spherechain.h's SC_VERSION_* differ from the project's version (CMakeLists.txt project())");
static_assert(SC_SCHEMA_VERSION_OLDEST == spherechain::runtime::kMinSchemaVersion &&
                  SC_SCHEMA_VERSION_NEWEST == spherechain::runtime::kSchemaVersion,
              "spherechain.h's SC_SCHEMA_VERSION_* differ from the runtime's (runtime/asset.h)");

extern "C" {

SC_API uint32_t sc_version(void) { return SC_VERSION; }

SC_API const char* sc_status_string(sc_status status) {
  switch (status) {
    case SC_OK: return "SC_OK";
    case SC_OK_TRUNCATED:
      return "SC_OK_TRUNCATED: success, but the output buffer was too small (count holds the full count)";
    case SC_ERROR_NULL_ARGUMENT: return "SC_ERROR_NULL_ARGUMENT: a required pointer is null";
    case SC_ERROR_ALIGNMENT:
      return "SC_ERROR_ALIGNMENT: asset bytes must be 8-byte aligned, positions and matrices 4-byte aligned";
    case SC_ERROR_INVALID_JOB:
      return "SC_ERROR_INVALID_JOB: arguments inconsistent (unknown method, flag or exclusions, margin or crease not "
             "allowed, or no narrow phase in the model)";
    case SC_ERROR_VERTEX_COUNT: return "SC_ERROR_VERTEX_COUNT: vertex count differs from the asset's";
    case SC_ERROR_STRIDE: return "SC_ERROR_STRIDE: stride must be >= 12 bytes, a multiple of 4 and below 2^32";
    case SC_ERROR_OUT_OF_MEMORY: return "SC_ERROR_OUT_OF_MEMORY: model or workspace allocation failed";
    case SC_ERROR_NON_FINITE_POSITIONS:
      return "SC_ERROR_NON_FINITE_POSITIONS: a deformed vertex position is NaN or infinite";
    case SC_ERROR_JOINT_COUNT:
      return "SC_ERROR_JOINT_COUNT: the joint matrix count differs from the asset's joint count";
    case SC_ERROR_NON_FINITE_JOINTS: return "SC_ERROR_NON_FINITE_JOINTS: a joint matrix holds a NaN or an infinity";
    case SC_ERROR_WORKSPACE_MODEL:
      return "SC_ERROR_WORKSPACE_MODEL: the workspace was made for another model (nothing written)";
    case SC_ERROR_BUFFER_TOO_SMALL: return "SC_ERROR_BUFFER_TOO_SMALL: caller memory too small";
    case SC_ERROR_FRAME_TANGLED:
      return "SC_ERROR_FRAME_TANGLED: the frame's skin passes through itself beyond the narrow phase's budget";
    case SC_ERROR_ASSET_TOO_SMALL:
      return "SC_ERROR_ASSET_TOO_SMALL: asset truncated (smaller than a FlatBuffer header)";
    case SC_ERROR_ASSET_TOO_LARGE: return "SC_ERROR_ASSET_TOO_LARGE: asset larger than 1 GiB";
    case SC_ERROR_IDENTIFIER: return "SC_ERROR_IDENTIFIER: not a .sphc asset (file_identifier is not SPHC)";
    case SC_ERROR_VERSION_TOO_OLD:
      return "SC_ERROR_VERSION_TOO_OLD: asset schema_version is older than this SDK reads (re-bake)";
    case SC_ERROR_VERSION_TOO_NEW: return "SC_ERROR_VERSION_TOO_NEW: asset schema_version is newer than this SDK";
    case SC_ERROR_CORRUPT: return "SC_ERROR_CORRUPT: FlatBuffers verification failed (truncated or corrupted)";
    case SC_ERROR_MISSING_FIELD: return "SC_ERROR_MISSING_FIELD: a field the call needs is absent from the asset";
    case SC_ERROR_NO_SPHERES: return "SC_ERROR_NO_SPHERES: the asset has no spheres";
    case SC_ERROR_TOO_MANY_SPHERES: return "SC_ERROR_TOO_MANY_SPHERES: more than 65535 spheres";
    case SC_ERROR_TOO_MANY_CHAINS:
      return "SC_ERROR_TOO_MANY_CHAINS: more than 32 chains, or too many candidate pairs in them";
    case SC_ERROR_COUNT_MISMATCH: return "SC_ERROR_COUNT_MISMATCH: asset array lengths disagree (#S, #T, #V)";
    case SC_ERROR_INDEX_OUT_OF_RANGE:
      return "SC_ERROR_INDEX_OUT_OF_RANGE: a sphere, triangle, vertex or joint index is out of range";
    case SC_ERROR_OFFSETS: return "SC_ERROR_OFFSETS: surrounding_offsets or reach_offsets malformed";
    case SC_ERROR_NON_FINITE: return "SC_ERROR_NON_FINITE: NaN or infinite value in the asset";
    case SC_ERROR_RADIUS: return "SC_ERROR_RADIUS: a sphere radius is <= 0";
    case SC_ERROR_PIVOT_FRAME:
      return "SC_ERROR_PIVOT_FRAME: a pivot frame's mean distance is <= 0 or too small for its radius";
    case SC_ERROR_CHAIN_ORDER: return "SC_ERROR_CHAIN_ORDER: chain spheres not strictly ascending";
    case SC_ERROR_EXCLUDED_PAIRS: return "SC_ERROR_EXCLUDED_PAIRS: excluded pairs not a < b or not strictly ascending";
    case SC_ERROR_CONTACT_MARGIN: return "SC_ERROR_CONTACT_MARGIN: the asset's contact margin is negative";
    case SC_ERROR_SKIN_WEIGHTS:
      return "SC_ERROR_SKIN_WEIGHTS: a sphere's joint weights are negative, not finite or do not sum to 1";
    case SC_ERROR_REGIONS: return "SC_ERROR_REGIONS: the asset's regions are malformed";
    case SC_ERROR_BIND_POSE_TANGLED:
      return "SC_ERROR_BIND_POSE_TANGLED: the bind pose passes through itself beyond the narrow phase's budget";
    case SC_ERROR_CREASE_TOO_WIDE:
      return "SC_ERROR_CREASE_TOO_WIDE: the crease reaches too much of the bind surface from each vertex (a collapsed "
             "bind pose, or a mesh far denser than its crease)";
    default: return "unknown status";
  }
}

SC_API sc_status sc_model_create(const void* bytes, size_t size, uint32_t flags, sc_model** out) {
  if (out) *out = nullptr;
  if (!bytes || !out) return SC_ERROR_NULL_ARGUMENT;
  if ((flags & ~(SC_MODEL_NARROW_PHASE | SC_MODEL_NARROW_PHASE_REACH)) != 0 ||
      ((flags & SC_MODEL_NARROW_PHASE_REACH) && !(flags & SC_MODEL_NARROW_PHASE)))
    return SC_ERROR_INVALID_JOB;
  rt::AssetView view;
  if (const rt::Status s = rt::LoadAsset(bytes, size, &view); rt::Failed(s)) return C(s);
  sc_model* m = new (std::nothrow) sc_model;
  if (!m) return SC_ERROR_OUT_OF_MEMORY;
  m->view = view;
  rt::ModelOptions options;
  options.narrow_phase = (flags & SC_MODEL_NARROW_PHASE) != 0;
  options.narrow_phase_regions =
      (flags & SC_MODEL_NARROW_PHASE_REACH) ? rt::NarrowPhaseRegions::kReach : rt::NarrowPhaseRegions::kSurrounding;
  const rt::Status s = m->model.Init(view, options);
  if (rt::Failed(s)) {
    delete m;
    return C(s);
  }
  *out = m;
  return SC_OK;
}

SC_API void sc_model_destroy(sc_model* model) { delete model; }

SC_API sc_status sc_model_get_info(const sc_model* model, sc_model_info* info) {
  if (!model || !info) return SC_ERROR_NULL_ARGUMENT;
  const spherechain::schema::Asset& a = *model->view.asset;
  const bool crease = a.crease() > 0.0f;  // LoadAsset: > 0 only with bind_positions, triangles and weld_ids
  sc_model_info i{};
  i.sphere_count = model->view.sphere_count;
  i.vertex_count = model->view.vertex_count;
  i.triangle_count = model->view.triangle_count;
  i.chain_count = model->view.chain_count;
  i.joint_count = model->model.joint_count();
  i.region_count = rt::RegionCount(model->view);
  i.schema_version = a.schema_version();
  i.has_narrow_phase = model->model.narrow_phase() ? 1u : 0u;
  i.has_crease = crease ? 1u : 0u;
  i.contact_margin = model->model.contact_margin();
  i.crease = crease ? a.crease() : 0.0f;
  *info = i;
  return SC_OK;
}

SC_API sc_status sc_sphere_triangles(const sc_model* model, uint32_t sphere, const uint32_t** triangles,
                                     uint32_t* count) {
  if (triangles) *triangles = nullptr;
  if (count) *count = 0;
  if (!model || !triangles || !count) return SC_ERROR_NULL_ARGUMENT;
  if (sphere >= model->view.sphere_count) return SC_ERROR_INDEX_OUT_OF_RANGE;
  const rt::TriangleSpan span = rt::SurroundingTriangles(model->view, sphere);
  *triangles = span.count ? span.data : nullptr;
  *count = span.count;
  return SC_OK;
}

SC_API sc_status sc_bind_positions(const sc_model* model, const float** positions, uint32_t* vertex_count) {
  if (positions) *positions = nullptr;
  if (vertex_count) *vertex_count = 0;
  if (!model || !positions || !vertex_count) return SC_ERROR_NULL_ARGUMENT;
  const auto* bind = model->view.asset->bind_positions();
  if (!bind || bind->size() == 0) return SC_ERROR_MISSING_FIELD;  // LoadAsset: 3·#V when present
  *positions = bind->data();
  *vertex_count = model->view.vertex_count;
  return SC_OK;
}

SC_API sc_status sc_sphere_region(const sc_model* model, uint32_t sphere, uint32_t* region) {
  if (region) *region = UINT32_MAX;
  if (!model || !region) return SC_ERROR_NULL_ARGUMENT;
  if (sphere >= model->view.sphere_count) return SC_ERROR_INDEX_OUT_OF_RANGE;
  const auto* regions = model->view.asset->sphere_regions();
  if (!regions) return SC_ERROR_MISSING_FIELD;  // LoadAsset: #S entries when present
  *region = regions->Get(sphere);
  return SC_OK;
}

SC_API const char* sc_region_name(const sc_model* model, uint32_t region) {
  return model ? rt::RegionName(model->view, region) : "";
}

SC_API sc_status sc_workspace_create(const sc_model* model, sc_workspace** out) {
  if (out) *out = nullptr;
  if (!model || !out) return SC_ERROR_NULL_ARGUMENT;
  sc_workspace* w = new (std::nothrow) sc_workspace;
  if (!w) return SC_ERROR_OUT_OF_MEMORY;
  const rt::Status s = w->ws.Init(model->model);
  if (rt::Failed(s)) {
    delete w;
    return C(s);
  }
  *out = w;
  return SC_OK;
}

SC_API void sc_workspace_destroy(sc_workspace* workspace) { delete workspace; }

SC_API sc_status sc_workspace_spheres(const sc_workspace* workspace, float* xyzr, uint32_t capacity, uint32_t* count) {
  if (count) *count = 0;
  if (!workspace || !count || (!xyzr && capacity > 0)) return SC_ERROR_NULL_ARGUMENT;
  const rt::SphereArrays s = workspace->ws.spheres();
  const uint32_t n = s.count < capacity ? s.count : capacity;
  for (uint32_t i = 0; i < n; ++i) {
    xyzr[4 * size_t{i} + 0] = s.x[i];
    xyzr[4 * size_t{i} + 1] = s.y[i];
    xyzr[4 * size_t{i} + 2] = s.z[i];
    xyzr[4 * size_t{i} + 3] = s.r[i];
  }
  *count = s.count;
  return n < s.count ? SC_OK_TRUNCATED : SC_OK;
}

SC_API sc_status sc_refit_vertices(const sc_model* model, sc_workspace* workspace, const float* positions,
                                   uint32_t vertex_count, size_t stride_bytes) {
  if (!model || !workspace || !positions) return SC_ERROR_NULL_ARGUMENT;
  if (!workspace->ws.made_for(model->model)) return SC_ERROR_WORKSPACE_MODEL;
  if (!StrideFits(stride_bytes)) return SC_ERROR_STRIDE;
  rt::RefitJob job;
  job.model = &model->model;
  job.workspace = &workspace->ws;
  job.positions = {positions, vertex_count, static_cast<uint32_t>(stride_bytes)};
  job.mode = rt::RefitMode::kPivotFrame;
  return C(job.Run());
}

SC_API sc_status sc_refit_joints(const sc_model* model, sc_workspace* workspace, const float* joint_matrices,
                                 uint32_t joint_count) {
  if (!model || !workspace || !joint_matrices) return SC_ERROR_NULL_ARGUMENT;
  if (!workspace->ws.made_for(model->model)) return SC_ERROR_WORKSPACE_MODEL;
  rt::JointRefitJob job;
  job.model = &model->model;
  job.workspace = &workspace->ws;
  job.joint_matrices = joint_matrices;
  job.joint_count = joint_count;
  return C(job.Run());
}

SC_API uint32_t sc_detect_bound(const sc_model* model, sc_detect_method method) {
  if (!model || (method != SC_DETECT_M1 && method != SC_DETECT_M2)) return 0;
  return rt::DetectBound(model->view, method == SC_DETECT_M1 ? rt::DetectMethod::kM1 : rt::DetectMethod::kM2);
}

SC_API sc_status sc_detect(const sc_model* model, sc_workspace* workspace, sc_detect_method method, float margin,
                           sc_pair* pairs, uint32_t capacity, uint32_t* count) {
  if (count) *count = 0;
  if (!model || !workspace || !count || (!pairs && capacity > 0)) return SC_ERROR_NULL_ARGUMENT;
  if (!workspace->ws.made_for(model->model)) return SC_ERROR_WORKSPACE_MODEL;
  if (method != SC_DETECT_M1 && method != SC_DETECT_M2) return SC_ERROR_INVALID_JOB;
  uint32_t written = 0;
  rt::DetectStats stats;
  rt::DetectJob job;
  job.model = &model->model;
  job.workspace = &workspace->ws;
  job.method = method == SC_DETECT_M1 ? rt::DetectMethod::kM1 : rt::DetectMethod::kM2;
  job.output = reinterpret_cast<rt::Collision*>(pairs);
  job.capacity = capacity;
  job.count = &written;
  job.stats = &stats;
  job.margin = margin < 0.0f ? -1.0f : margin;  // < 0 (−inf too, as spherechain.h says): the asset's; NaN / +inf: kErrorInvalidJob
  const rt::Status s = job.Run();
  if (rt::Succeeded(s)) *count = stats.distinct_pairs;
  return C(s);
}

SC_API sc_status sc_fold_pairs(const sc_model* model, const sc_workspace* workspace, float closing, sc_pair* pairs,
                               uint32_t capacity, uint32_t* count) {
  if (count) *count = 0;
  if (!model || !workspace || !count || (!pairs && capacity > 0)) return SC_ERROR_NULL_ARGUMENT;
  if (!workspace->ws.made_for(model->model)) return SC_ERROR_WORKSPACE_MODEL;
  if (!model->model.narrow_phase()) return SC_ERROR_INVALID_JOB;
  uint32_t found = 0;
  const rt::Status s = rt::FoldPairs(*model->model.narrow_phase(), workspace->ws.spheres(), closing,
                                     reinterpret_cast<rt::Collision*>(pairs), capacity, &found);
  if (rt::Succeeded(s)) *count = found;
  return C(s);
}

SC_API sc_status sc_narrow_phase(const sc_model* model, sc_workspace* workspace, const float* positions,
                                 uint32_t vertex_count, size_t stride_bytes, const sc_narrow_phase_options* options,
                                 sc_contact* contacts, sc_contact_depth* depths, uint32_t capacity, uint32_t* count) {
  if (count) *count = 0;
  if (!model || !workspace || !positions || !count || (!contacts && capacity > 0)) return SC_ERROR_NULL_ARGUMENT;
  const sc_narrow_phase_options defaults{};
  const sc_narrow_phase_options& o = options ? *options : defaults;
  if (!o.sphere_pairs && o.sphere_pair_count > 0) return SC_ERROR_NULL_ARGUMENT;
  if (!workspace->ws.made_for(model->model)) return SC_ERROR_WORKSPACE_MODEL;
  if (!model->model.narrow_phase()) return SC_ERROR_INVALID_JOB;
  if (!StrideFits(stride_bytes)) return SC_ERROR_STRIDE;
  rt::Exclusions exclusions;
  switch (o.exclusions) {
    case SC_EXCLUSIONS_ASSET: exclusions = rt::Exclusions::kAsset; break;
    case SC_EXCLUSIONS_NONE: exclusions = rt::Exclusions::kNone; break;
    case SC_EXCLUSIONS_CREASE: exclusions = rt::Exclusions::kCrease; break;
    default: return SC_ERROR_INVALID_JOB;
  }
  uint32_t written = 0;
  rt::NarrowPhaseStats stats;
  rt::NarrowPhaseJob job;
  job.model = model->model.narrow_phase();
  job.workspace = workspace->ws.narrow_phase();
  job.positions = {positions, vertex_count, static_cast<uint32_t>(stride_bytes)};
  job.exclusions = exclusions;
  job.crease = o.crease;
  job.sphere_pairs = reinterpret_cast<const rt::Collision*>(o.sphere_pairs);
  job.sphere_pair_count = o.sphere_pairs ? o.sphere_pair_count : 0;
  job.joint_matrices = o.joint_matrices;
  job.joint_count = o.joint_matrices ? o.joint_count : 0;
  job.output = reinterpret_cast<rt::TriangleContact*>(contacts);
  job.capacity = capacity;
  job.depths =
      (exclusions == rt::Exclusions::kCrease && capacity > 0) ? reinterpret_cast<rt::ContactDepth*>(depths) : nullptr;
  job.count = &written;
  job.stats = &stats;
  const rt::Status s = job.Run();
  if (rt::Succeeded(s)) *count = stats.contacts;
  return C(s);
}

}  // extern "C"
