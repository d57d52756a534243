// The C API (spherechain/spherechain.h, library spherechain::c) against the C++ runtime it wraps, on the same
// inputs: spheres, pair records, contact records and depths equal bit for bit (memcmp), counts equal, statuses
// the same. Real assets: CesiumMan baked by the CLI (fixture c_api_asset: rigged, the crease rule, reach regions
// — vertex and joint refit, M1, M2, the narrow phase with the crease rule and behind the M2 pairs, on reach
// regions) and the golden v3 CesiumMan (joint refit, M1, M2). The C program tests/c_api/c_api_test.c covers the
// C side's error paths.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/runtime.h"
#include "spherechain/spherechain.h"
#include "test_data.h"

using namespace spherechain::runtime;

namespace {

std::string RealAsset() { return SPHERECHAIN_C_API_ASSET; }  // CesiumMan, baked by the fixture

// The C and the C++ side of one asset: a C model + workspace, a C++ Model + Workspace (+ narrow phase).
struct Both {
  spherechain::test::AlignedBytes bytes;  // 8-byte aligned
  AssetView view;
  Model model;
  Workspace ws;
  NarrowPhaseModel narrow;
  NarrowPhaseWorkspace narrow_ws;
  sc_model* c_model = nullptr;
  sc_workspace* c_ws = nullptr;

  Both(const std::string& path, uint32_t flags) {
    REQUIRE_MESSAGE(spherechain::test::ReadAlignedFile(path, &bytes), path);
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    REQUIRE(model.Init(view) == Status::kOk);
    REQUIRE(ws.Init(model) == Status::kOk);
    if (flags & SC_MODEL_NARROW_PHASE) {
      const auto regions =
          (flags & SC_MODEL_NARROW_PHASE_REACH) ? NarrowPhaseRegions::kReach : NarrowPhaseRegions::kSurrounding;
      REQUIRE(narrow.Init(view, regions) == Status::kOk);
      REQUIRE(narrow_ws.Init(narrow) == Status::kOk);
    }
    REQUIRE(sc_model_create(bytes.data(), bytes.size, flags, &c_model) == SC_OK);
    REQUIRE(sc_workspace_create(c_model, &c_ws) == SC_OK);
  }
  ~Both() {
    sc_workspace_destroy(c_ws);
    sc_model_destroy(c_model);
  }

  // The C workspace's spheres equal the C++ workspace's, bit for bit.
  void CheckSpheres() const {
    std::vector<float> c(4 * view.sphere_count);
    uint32_t count = 0;
    REQUIRE(sc_workspace_spheres(c_ws, c.data(), view.sphere_count, &count) == SC_OK);
    REQUIRE(count == view.sphere_count);
    const SphereArrays s = ws.spheres();
    std::vector<float> cpp(4 * view.sphere_count);
    for (uint32_t i = 0; i < view.sphere_count; ++i) {
      cpp[4 * i] = s.x[i];
      cpp[4 * i + 1] = s.y[i];
      cpp[4 * i + 2] = s.z[i];
      cpp[4 * i + 3] = s.r[i];
    }
    CHECK(std::memcmp(c.data(), cpp.data(), c.size() * sizeof(float)) == 0);
  }

  // sc_detect == DetectJob (asset fold margin), full buffer and truncated; returns the pairs.
  std::vector<Collision> CheckDetect(DetectMethod method, float margin) {
    const sc_detect_method c_method = method == DetectMethod::kM1 ? SC_DETECT_M1 : SC_DETECT_M2;
    const uint32_t bound = DetectBound(view, method);
    REQUIRE(sc_detect_bound(c_model, c_method) == bound);
    std::vector<Collision> cpp(bound);
    std::vector<sc_pair> c(bound);
    uint32_t n_cpp = 0, n_c = 0;
    DetectJob job;
    job.model = &model;
    job.workspace = &ws;
    job.method = method;
    job.margin = margin;
    job.output = cpp.data();
    job.capacity = bound;
    job.count = &n_cpp;
    REQUIRE(job.Run() == Status::kOk);
    REQUIRE(sc_detect(c_model, c_ws, c_method, margin, c.data(), bound, &n_c) == SC_OK);
    REQUIRE(n_c == n_cpp);
    CHECK(std::memcmp(c.data(), cpp.data(), n_c * sizeof(sc_pair)) == 0);
    if (n_cpp > 1) {  // truncated: C++ reports what it wrote, C the full count; the same first records
      const uint32_t half = n_cpp / 2;
      uint32_t w_cpp = 0, w_c = 0;
      job.capacity = half;
      job.count = &w_cpp;
      CHECK(job.Run() == Status::kOkTruncated);
      CHECK(sc_detect(c_model, c_ws, c_method, margin, c.data(), half, &w_c) == SC_OK_TRUNCATED);
      CHECK(w_cpp == half);
      CHECK(w_c == n_cpp);
      CHECK(std::memcmp(c.data(), cpp.data(), half * sizeof(sc_pair)) == 0);
    }
    cpp.resize(n_cpp);
    return cpp;
  }

  // sc_narrow_phase == NarrowPhaseJob (contacts and depths), full buffer; returns the count.
  uint32_t CheckNarrow(const std::vector<float>& positions, Exclusions exclusions, sc_exclusions c_exclusions,
                       const std::vector<Collision>* pairs, bool with_depths, const std::vector<float>* joints = nullptr) {
    const uint32_t capacity = 1u << 16;
    std::vector<TriangleContact> cpp(capacity);
    std::vector<ContactDepth> cpp_depths(capacity);
    std::vector<sc_contact> c(capacity);
    std::vector<sc_contact_depth> c_depths(capacity);
    uint32_t n_cpp = 0, n_c = 0;
    NarrowPhaseJob job;
    job.model = &narrow;
    job.workspace = &narrow_ws;
    job.positions = {positions.data(), view.vertex_count, 12};
    job.exclusions = exclusions;
    job.sphere_pairs = pairs ? pairs->data() : nullptr;
    job.sphere_pair_count = pairs ? static_cast<uint32_t>(pairs->size()) : 0;
    job.output = cpp.data();
    job.depths = with_depths ? cpp_depths.data() : nullptr;
    job.capacity = capacity;
    job.count = &n_cpp;
    if (joints) job.joint_matrices = joints->data(), job.joint_count = static_cast<uint32_t>(joints->size() / kJointMatrixFloats);
    REQUIRE(job.Run() == Status::kOk);
    sc_narrow_phase_options options{};
    options.exclusions = c_exclusions;
    if (joints) options.joint_matrices = joints->data(), options.joint_count = job.joint_count;
    options.sphere_pairs = pairs ? reinterpret_cast<const sc_pair*>(pairs->data()) : nullptr;
    options.sphere_pair_count = pairs ? static_cast<uint32_t>(pairs->size()) : 0;
    REQUIRE(sc_narrow_phase(c_model, c_ws, positions.data(), view.vertex_count, 12, &options, c.data(),
                            with_depths ? c_depths.data() : nullptr, capacity, &n_c) == SC_OK);
    REQUIRE(n_c == n_cpp);
    CHECK(std::memcmp(c.data(), cpp.data(), n_c * sizeof(sc_contact)) == 0);
    if (with_depths) CHECK(std::memcmp(c_depths.data(), cpp_depths.data(), n_c * sizeof(sc_contact_depth)) == 0);
    return n_c;
  }

  // sc_refit_joints == JointRefitJob on `matrices`.
  void CheckJoints(const std::vector<float>& matrices) {
    JointRefitJob job;
    job.model = &model;
    job.workspace = &ws;
    job.joint_matrices = matrices.data();
    job.joint_count = model.joint_count();
    REQUIRE(job.Run() == Status::kOk);
    REQUIRE(sc_refit_joints(c_model, c_ws, matrices.data(), model.joint_count()) == SC_OK);
    CheckSpheres();
  }
};

// The frame of the test: the vertices of the left arm's triangles (Asset.triangle_regions == 0) pushed 0.8 of
// the way from their centroid to the rest's, across the body (x and z; the assets are Y-up).
std::vector<float> ArmPushedIn(const AssetView& view, const float* bind) {
  std::vector<float> p(bind, bind + 3 * size_t{view.vertex_count});
  std::vector<uint8_t> arm(view.vertex_count, 0);
  const auto* regions = view.asset->triangle_regions();
  const auto* triangles = view.asset->triangles();
  for (uint32_t t = 0; t < view.triangle_count; ++t)
    if (regions->Get(t) == 0)
      for (int k = 0; k < 3; ++k) arm[triangles->Get(3 * t + k)] = 1;
  double sum[2][3] = {}, n[2] = {};
  for (uint32_t v = 0; v < view.vertex_count; ++v) {
    for (int k = 0; k < 3; ++k) sum[arm[v]][k] += p[3 * v + k];
    ++n[arm[v]];
  }
  for (uint32_t v = 0; v < view.vertex_count; ++v)
    if (arm[v])
      for (int k : {0, 2}) p[3 * v + k] -= static_cast<float>(0.8 * (sum[1][k] / n[1] - sum[0][k] / n[0]));
  return p;
}

// Skinning matrices of a small random pose: per joint a rotation of up to ~0.3 rad about a random axis and a
// translation of up to 2 % of `scale` (3×4 row-major, what both refits read).
std::vector<float> RandomPose(uint32_t joints, float scale, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> m(12 * size_t{joints});
  for (uint32_t j = 0; j < joints; ++j) {
    float axis[3] = {u(rng), u(rng), u(rng)};
    const float len = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]) + 1e-6f;
    for (float& a : axis) a /= len;
    const float angle = 0.3f * u(rng), c = std::cos(angle), s = std::sin(angle), t = 1 - c;
    const float x = axis[0], y = axis[1], z = axis[2];
    const float r[3][3] = {{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
                           {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
                           {t * x * z - s * y, t * y * z + s * x, t * z * z + c}};
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) m[12 * j + 4 * row + col] = r[row][col];
      m[12 * j + 4 * row + 3] = 0.02f * scale * u(rng);
    }
  }
  return m;
}

}  // namespace

TEST_CASE(
    "C API == C++ runtime on CesiumMan: vertex and joint refit, M1, M2, narrow phase (crease rule, behind the pairs)") {
  if (!spherechain::test::Require(RealAsset())) return;
  Both b(RealAsset(), SC_MODEL_NARROW_PHASE);
  const auto* bind_vec = b.view.asset->bind_positions();
  REQUIRE(bind_vec);
  const float* bind = bind_vec->data();
  const float* c_bind = nullptr;
  uint32_t c_vertices = 0;
  REQUIRE(sc_bind_positions(b.c_model, &c_bind, &c_vertices) == SC_OK);
  CHECK(c_bind == bind);
  CHECK(c_vertices == b.view.vertex_count);
  sc_model_info info{};
  REQUIRE(sc_model_get_info(b.c_model, &info) == SC_OK);
  CHECK(info.sphere_count == b.model.sphere_count());
  CHECK(info.vertex_count == b.narrow.vertex_count());
  CHECK(info.triangle_count == b.narrow.triangle_count());
  CHECK(info.chain_count == b.model.chain_count());
  CHECK(info.joint_count == b.model.joint_count());
  CHECK(info.region_count == RegionCount(b.view));
  CHECK(info.contact_margin == b.model.contact_margin());
  CHECK(info.has_crease == 1);
  CHECK(info.crease == b.narrow.crease());
  b.CheckSpheres();  // bind pose, as created

  const std::vector<float> bind_copy(bind, bind + 3 * size_t{b.view.vertex_count});
  const std::vector<float> pushed = ArmPushedIn(b.view, bind);
  uint32_t contacts_at_bind = 0, contacts_pushed = 0, pairs_pushed = 0;
  for (const std::vector<float>* frame : {&bind_copy, &pushed}) {
    RefitJob refit;
    refit.model = &b.model;
    refit.workspace = &b.ws;
    refit.positions = {frame->data(), b.view.vertex_count, 12};
    REQUIRE(refit.Run() == Status::kOk);
    REQUIRE(sc_refit_vertices(b.c_model, b.c_ws, frame->data(), b.view.vertex_count, 12) == SC_OK);
    b.CheckSpheres();
    for (float margin : {-1.0f, 0.0f, 0.02f}) {
      CAPTURE(margin);
      b.CheckDetect(DetectMethod::kM1, margin);
      b.CheckDetect(DetectMethod::kM2, margin);
    }
    const std::vector<Collision> m2 = b.CheckDetect(DetectMethod::kM2, -1.0f);
    {  // −inf is below 0 too: the asset's margin, as spherechain.h says (the C++ job refuses any non-finite one)
      std::vector<sc_pair> c(m2.size() + 1);
      uint32_t n = 0;
      CHECK(sc_detect(b.c_model, b.c_ws, SC_DETECT_M2, -INFINITY, c.data(), static_cast<uint32_t>(c.size()), &n) == SC_OK);
      CHECK(n == m2.size());
      CHECK(std::memcmp(c.data(), m2.data(), n * sizeof(sc_pair)) == 0);
    }
    const uint32_t crease = b.CheckNarrow(*frame, Exclusions::kCrease, SC_EXCLUSIONS_CREASE, nullptr, true);
    if (frame == &bind_copy) {  // the bind pose is the skin under identity matrices: the joint-matrix cull
      REQUIRE(b.narrow.has_joint_cull());
      std::vector<float> identity(size_t{b.narrow.joint_count()} * kJointMatrixFloats, 0.0f);
      for (size_t j = 0; j < b.narrow.joint_count(); ++j)
        for (int k = 0; k < 3; ++k) identity[j * kJointMatrixFloats + 5 * k] = 1.0f;
      CHECK(b.CheckNarrow(*frame, Exclusions::kCrease, SC_EXCLUSIONS_CREASE, nullptr, true, &identity) == crease);
      sc_narrow_phase_options options{};
      options.exclusions = SC_EXCLUSIONS_CREASE;
      options.joint_matrices = identity.data();
      options.joint_count = b.narrow.joint_count() + 1;
      uint32_t n = 0;
      CHECK(sc_narrow_phase(b.c_model, b.c_ws, frame->data(), b.view.vertex_count, 12, &options, nullptr, nullptr, 0,
                            &n) == SC_ERROR_JOINT_COUNT);
      options.joint_count = b.narrow.joint_count();
      identity[3] = NAN;
      CHECK(sc_narrow_phase(b.c_model, b.c_ws, frame->data(), b.view.vertex_count, 12, &options, nullptr, nullptr, 0,
                            &n) == SC_ERROR_NON_FINITE_JOINTS);
      options.exclusions = SC_EXCLUSIONS_ASSET;
      CHECK(sc_narrow_phase(b.c_model, b.c_ws, frame->data(), b.view.vertex_count, 12, &options, nullptr, nullptr, 0,
                            &n) == SC_ERROR_INVALID_JOB);
    }
    b.CheckNarrow(*frame, Exclusions::kAsset, SC_EXCLUSIONS_ASSET, nullptr, false);
    b.CheckNarrow(*frame, Exclusions::kAsset, SC_EXCLUSIONS_ASSET, &m2, false);
    b.CheckNarrow(*frame, Exclusions::kNone, SC_EXCLUSIONS_NONE, &m2, false);
    (frame == &pushed ? contacts_pushed : contacts_at_bind) = crease;
    if (frame == &pushed) pairs_pushed = static_cast<uint32_t>(m2.size());
  }
  MESSAGE("CesiumMan, left arm pushed in: " << pairs_pushed << " M2 pairs, " << contacts_pushed
                                            << " skin contacts (bind: " << contacts_at_bind << ")");
  CHECK(contacts_pushed > contacts_at_bind);  // the comparison compared something
  CHECK(pairs_pushed > 0);

  // The narrow phase's errors match the job's: a workspace of another C model, a bad pair.
  Both other(RealAsset(), 0);
  uint32_t count = 5;
  CHECK(sc_narrow_phase(b.c_model, other.c_ws, pushed.data(), b.view.vertex_count, 12, nullptr, nullptr, nullptr, 0,
                        &count) == SC_ERROR_WORKSPACE_MODEL);
  CHECK(count == 0);
  CHECK(sc_refit_vertices(b.c_model, other.c_ws, pushed.data(), b.view.vertex_count, 12) == SC_ERROR_WORKSPACE_MODEL);
  CHECK(sc_refit_vertices(other.c_model, b.c_ws, pushed.data(), b.view.vertex_count, 12) == SC_ERROR_WORKSPACE_MODEL);

  // Joint refit (CesiumMan's glTF skin): random poses.
  REQUIRE(b.model.joint_count() > 0);
  CHECK(info.joint_count == b.model.joint_count());
  std::mt19937 rng(0xC0FFEEu);
  for (int pose = 0; pose < 4; ++pose) {
    b.CheckJoints(RandomPose(b.model.joint_count(), 1.5f, rng));
    b.CheckDetect(DetectMethod::kM1, -1.0f);
    b.CheckDetect(DetectMethod::kM2, -1.0f);
  }
}

TEST_CASE("C API == C++ runtime on CesiumMan: narrow phase on reach regions behind the M2 pairs") {
  if (!spherechain::test::Require(RealAsset())) return;
  Both b(RealAsset(), SC_MODEL_NARROW_PHASE | SC_MODEL_NARROW_PHASE_REACH);
  REQUIRE(b.narrow.regions() == NarrowPhaseRegions::kReach);
  const std::vector<float> pushed = ArmPushedIn(b.view, b.view.asset->bind_positions()->data());
  RefitJob refit;
  refit.model = &b.model;
  refit.workspace = &b.ws;
  refit.positions = {pushed.data(), b.view.vertex_count, 12};
  REQUIRE(refit.Run() == Status::kOk);
  REQUIRE(sc_refit_vertices(b.c_model, b.c_ws, pushed.data(), b.view.vertex_count, 12) == SC_OK);
  const std::vector<Collision> m2 = b.CheckDetect(DetectMethod::kM2, -1.0f);
  CHECK(b.CheckNarrow(pushed, Exclusions::kAsset, SC_EXCLUSIONS_ASSET, &m2, false) > 0);
}

TEST_CASE("C API == C++ runtime on the golden v3 CesiumMan: joint refit, M1, M2") {
  Both b(spherechain::test::SourceFile("tests/data/golden/v3/cesium_man.sphc"), 0);
  REQUIRE(b.model.joint_count() > 0);
  std::mt19937 rng(0x5eedu);
  uint32_t pairs = 0;
  for (int pose = 0; pose < 8; ++pose) {
    b.CheckJoints(RandomPose(b.model.joint_count(), 1.8f, rng));
    pairs += static_cast<uint32_t>(b.CheckDetect(DetectMethod::kM1, 0.01f).size());
    b.CheckDetect(DetectMethod::kM2, 0.01f);
  }
  CHECK(pairs > 0);
}

TEST_CASE("C API: every status value and string mirrors runtime::Status") {
  uint32_t named = 0;
  for (uint32_t base : {0x0000'0000u, 0x8000'0000u})
    for (uint32_t v = base; v < base + 0x400u; ++v) {
      const bool cpp_known = std::string(ToString(static_cast<Status>(v))) != "unknown status";
      const std::string c = sc_status_string(v);
      CAPTURE(v);
      CHECK(cpp_known == (c != "unknown status"));
      if (cpp_known) {
        ++named;
        CHECK(c.rfind("SC_", 0) == 0);
        CHECK(SC_SUCCEEDED(v) == Succeeded(static_cast<Status>(v)));
      }
    }
  CHECK(named == 37);  // status.h's enumerators
}
