// RefitJob (§5.1) and BuildPivotFrame.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "runtime/asset_builder.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

struct Fixture {
  test::Mesh mesh;
  test::AlignedBytes bytes;
  AssetView view;
  test::Character ctx;
  explicit Fixture(bool crossing = true) {
    bytes = test::Serialize(test::TwoTubes(crossing, &mesh));
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    REQUIRE(ctx.Init(view) == Status::kOk);
  }
  Status Refit(const std::vector<float>& pos, RefitMode mode) {
    RefitJob job;
    job.model = &ctx.model;
    job.workspace = &ctx.ws;
    job.mode = mode;
    job.positions = {pos.data(), static_cast<uint32_t>(pos.size() / 3), 12};
    return job.Run();
  }
};

// Rotation of `angle` about unit axis (x, y, z), row-major.
void AxisAngle(float x, float y, float z, float angle, float R[9]) {
  const float c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const float m[9] = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y, t * x * y + s * z, t * y * y + c,
                      t * y * z - s * x, t * x * z - s * y, t * y * z + s * x, t * z * z + c};
  for (int i = 0; i < 9; ++i) R[i] = m[i];
}

}  // namespace

TEST_CASE("BuildPivotFrame gives a right-handed orthonormal frame and rejects collinear pivots") {
  const float p[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 1}, {1, 2, -1}};
  PivotFrameBasis f;
  REQUIRE(BuildPivotFrame(p, &f));
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const float dot = f.axes[a][0] * f.axes[b][0] + f.axes[a][1] * f.axes[b][1] + f.axes[a][2] * f.axes[b][2];
      CHECK(dot == doctest::Approx(a == b ? 1.0 : 0.0).epsilon(1e-6));
    }
  const float c[3] = {0.3f, -2.0f, 5.0f};
  float local[3], back[3];
  PivotFrameToLocal(f, c, local);
  PivotFrameToModel(f, local, back);
  for (int k = 0; k < 3; ++k) CHECK(back[k] == doctest::Approx(c[k]).epsilon(1e-5));
  const float line[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  CHECK_FALSE(BuildPivotFrame(line, &f));
}

TEST_CASE("Refit at the bind pose reproduces the bind spheres (both modes)") {
  Fixture fx;
  for (RefitMode mode : {RefitMode::kPaper, RefitMode::kPivotFrame}) {
    REQUIRE(fx.Refit(fx.mesh.positions, mode) == Status::kOk);
    const SphereArrays s = fx.ctx.ws.spheres();
    for (uint32_t i = 0; i < s.count; ++i) {
      const schema::Sphere* b = fx.view.asset->spheres()->Get(i);
      CHECK(s.x[i] == doctest::Approx(b->center().x()).epsilon(1e-5).scale(1));
      CHECK(s.y[i] == doctest::Approx(b->center().y()).epsilon(1e-5).scale(1));
      CHECK(s.z[i] == doctest::Approx(b->center().z()).epsilon(1e-5).scale(1));
      CHECK(s.r[i] == doctest::Approx(b->radius()).epsilon(1e-5));
    }
  }
}

TEST_CASE("kPivotFrame: a rigid motion of the mesh moves every sphere rigidly and keeps the pair set") {
  Fixture fx;
  std::vector<Collision> before(DetectBound(fx.view, DetectMethod::kM2)), after(before.size());
  uint32_t n_before = 0, n_after = 0;
  DetectJob det;
  det.model = &fx.ctx.model;
  det.workspace = &fx.ctx.ws;
  det.method = DetectMethod::kM2;
  det.output = before.data();
  det.capacity = static_cast<uint32_t>(before.size());
  det.count = &n_before;
  REQUIRE(fx.Refit(fx.mesh.positions, RefitMode::kPivotFrame) == Status::kOk);
  REQUIRE(det.Run() == Status::kOk);
  REQUIRE(n_before > 0);

  float R[9];
  const float inv = 1.0f / std::sqrt(14.0f);
  AxisAngle(1 * inv, 2 * inv, 3 * inv, 1.1f, R);
  const float t[3] = {5.0f, -3.0f, 2.5f};
  REQUIRE(fx.Refit(test::Transform(fx.mesh.positions, R, t), RefitMode::kPivotFrame) == Status::kOk);
  const SphereArrays s = fx.ctx.ws.spheres();
  for (uint32_t i = 0; i < s.count; ++i) {
    const schema::Sphere* b = fx.view.asset->spheres()->Get(i);
    const float c[3] = {b->center().x(), b->center().y(), b->center().z()};
    const float want[3] = {R[0] * c[0] + R[1] * c[1] + R[2] * c[2] + t[0], R[3] * c[0] + R[4] * c[1] + R[5] * c[2] + t[1],
                           R[6] * c[0] + R[7] * c[1] + R[8] * c[2] + t[2]};
    CAPTURE(i);
    CHECK(s.x[i] == doctest::Approx(want[0]).epsilon(1e-4).scale(1));
    CHECK(s.y[i] == doctest::Approx(want[1]).epsilon(1e-4).scale(1));
    CHECK(s.z[i] == doctest::Approx(want[2]).epsilon(1e-4).scale(1));
    CHECK(s.r[i] == doctest::Approx(b->radius()).epsilon(1e-4));
  }
  det.output = after.data();
  det.count = &n_after;
  REQUIRE(det.Run() == Status::kOk);
  REQUIRE(n_after == n_before);
  for (uint32_t k = 0; k < n_after; ++k) {
    CHECK(after[k].a == before[k].a);
    CHECK(after[k].b == before[k].b);
    CHECK(after[k].depth == doctest::Approx(before[k].depth).epsilon(1e-3));
  }
}

TEST_CASE("kPaper: a translation moves every sphere by the same vector, a rotation does not (documented)") {
  Fixture fx;
  float I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const float t[3] = {-1.5f, 7.0f, 0.25f};
  REQUIRE(fx.Refit(test::Transform(fx.mesh.positions, I, t), RefitMode::kPaper) == Status::kOk);
  SphereArrays s = fx.ctx.ws.spheres();
  for (uint32_t i = 0; i < s.count; ++i) {
    const schema::Sphere* b = fx.view.asset->spheres()->Get(i);
    CHECK(s.x[i] == doctest::Approx(b->center().x() + t[0]).epsilon(1e-5).scale(1));
    CHECK(s.y[i] == doctest::Approx(b->center().y() + t[1]).epsilon(1e-5).scale(1));
    CHECK(s.z[i] == doctest::Approx(b->center().z() + t[2]).epsilon(1e-5).scale(1));
    CHECK(s.r[i] == doctest::Approx(b->radius()).epsilon(1e-5));
  }
  // Rotation: kPaper keeps the bind offset unrotated, so at least one sphere ends off its rigid place.
  float R[9];
  AxisAngle(0, 0, 1, 1.0f, R);
  const float zero[3] = {0, 0, 0};
  REQUIRE(fx.Refit(test::Transform(fx.mesh.positions, R, zero), RefitMode::kPaper) == Status::kOk);
  s = fx.ctx.ws.spheres();
  float worst = 0;
  for (uint32_t i = 0; i < s.count; ++i) {
    const schema::Sphere* b = fx.view.asset->spheres()->Get(i);
    const float wx = R[0] * b->center().x() + R[1] * b->center().y(), wy = R[3] * b->center().x() + R[4] * b->center().y();
    worst = std::fmax(worst, std::hypot(s.x[i] - wx, s.y[i] - wy));
  }
  CHECK(worst > 0.1f);
}

TEST_CASE("Refit reads an interleaved vertex buffer through the stride") {
  Fixture fx;
  const uint32_t V = fx.mesh.vertex_count();
  std::vector<float> interleaved(size_t{V} * 8, -999.0f);  // xyz + normal + uv, 32-byte stride
  for (uint32_t i = 0; i < V; ++i)
    for (int k = 0; k < 3; ++k) interleaved[8 * i + k] = fx.mesh.positions[3 * i + k] + 1.0f;
  std::vector<float> packed = fx.mesh.positions;
  for (float& v : packed) v += 1.0f;
  REQUIRE(fx.Refit(packed, RefitMode::kPivotFrame) == Status::kOk);
  const std::vector<float> want_x(fx.ctx.ws.spheres().x, fx.ctx.ws.spheres().x + fx.ctx.model.sphere_count());
  const std::vector<float> want_r(fx.ctx.ws.spheres().r, fx.ctx.ws.spheres().r + fx.ctx.model.sphere_count());
  (void)fx.ctx.ws.ResetToBindPose(fx.ctx.model);
  RefitJob job;
  job.model = &fx.ctx.model;
  job.workspace = &fx.ctx.ws;
  job.positions = {interleaved.data(), V, 32};
  REQUIRE(job.Run() == Status::kOk);
  for (uint32_t i = 0; i < fx.ctx.model.sphere_count(); ++i) {
    CHECK(fx.ctx.ws.spheres().x[i] == want_x[i]);
    CHECK(fx.ctx.ws.spheres().r[i] == want_r[i]);
  }
}

TEST_CASE("RefitJob rejects bad arguments with the documented statuses") {
  Fixture fx;
  std::vector<float> pos = fx.mesh.positions;
  RefitJob job;
  CHECK(job.Run() == Status::kErrorNullArgument);
  job.model = &fx.ctx.model;
  job.workspace = &fx.ctx.ws;
  job.positions = {pos.data(), fx.mesh.vertex_count() - 1, 12};
  CHECK(job.Run() == Status::kErrorVertexCount);
  job.positions = {pos.data(), fx.mesh.vertex_count() + 1, 12};
  CHECK(job.Run() == Status::kErrorVertexCount);
  job.positions = {pos.data(), fx.mesh.vertex_count(), 8};
  CHECK(job.Run() == Status::kErrorStride);
  job.positions = {pos.data(), fx.mesh.vertex_count(), 14};
  CHECK(job.Run() == Status::kErrorStride);
  job.positions = {reinterpret_cast<const char*>(pos.data()) + 1, fx.mesh.vertex_count(), 12};
  CHECK(job.Run() == Status::kErrorAlignment);
  job.positions = {pos.data(), fx.mesh.vertex_count(), 12};
  job.mode = static_cast<RefitMode>(7);
  CHECK(job.Run() == Status::kErrorInvalidJob);
  CHECK_FALSE(job.Validate());
  job.mode = RefitMode::kPivotFrame;
  CHECK(job.Validate());
  test::Character empty;
  job.model = &empty.model;
  job.workspace = &empty.ws;
  CHECK(job.Run() == Status::kErrorInvalidJob);
}

TEST_CASE("RefitJob through a parallel_for hook equals the serial run") {
  Fixture fx;
  float R[9];
  AxisAngle(0, 1, 0, 0.7f, R);
  const float t[3] = {1, 2, 3};
  const std::vector<float> pos = test::Transform(fx.mesh.positions, R, t);
  REQUIRE(fx.Refit(pos, RefitMode::kPivotFrame) == Status::kOk);
  const std::vector<float> serial(fx.ctx.ws.spheres().z, fx.ctx.ws.spheres().z + fx.ctx.model.sphere_count());
  (void)fx.ctx.ws.ResetToBindPose(fx.ctx.model);
  for (uint32_t grain : {3u, 0xffffffffu}) {  // 0xffffffff: one task (its count once wrapped to 0 in 32 bits)
    CAPTURE(grain);
    (void)fx.ctx.ws.ResetToBindPose(fx.ctx.model);
    RefitJob job;
    job.model = &fx.ctx.model;
    job.workspace = &fx.ctx.ws;
    job.positions = {pos.data(), fx.mesh.vertex_count(), 12};
    job.parallel_grain = grain;
    int calls = 0;
    job.parallel_for.user = &calls;
    job.parallel_for.run = [](void* user, uint32_t count, ParallelFor::Task task, void* data) {
      ++*static_cast<int*>(user);
      for (uint32_t i = count; i-- > 0;) task(data, i, i + 1);  // reverse order, one index per task
    };
    REQUIRE(job.Run() == Status::kOk);
    CHECK(calls == 1);
    for (uint32_t i = 0; i < fx.ctx.model.sphere_count(); ++i) CHECK(fx.ctx.ws.spheres().z[i] == serial[i]);
  }
}
