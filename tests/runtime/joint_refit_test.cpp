// JointRefitJob (schema v3): sphere centres by linear blend skinning of their bind centres.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "runtime/asset_builder.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

// Two tubes (16 spheres); sphere s follows joint s % 2 with weight w0 and joint 2 with 1 − w0.
struct Rig {
  test::Mesh mesh;
  test::AssetData data;
  test::AlignedBytes bytes;
  AssetView view;
  test::Character ctx;
  explicit Rig(float w0 = 1.0f, bool joints = true) {
    data = test::TwoTubes(true, &mesh);
    if (joints) {
      data.joint_count = 3;
      for (size_t s = 0; s < data.spheres.size(); ++s) {
        data.sphere_joints.insert(data.sphere_joints.end(), {uint16_t(s % 2), 2, 0, 0});
        data.sphere_joint_weights.insert(data.sphere_joint_weights.end(), {w0, 1.0f - w0, 0.0f, 0.0f});
      }
    }
    bytes = test::Serialize(data);
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
    REQUIRE(ctx.Init(view) == Status::kOk);
  }
  Status Run(const std::vector<float>& matrices, uint32_t count = 3) {
    JointRefitJob job;
    job.model = &ctx.model;
    job.workspace = &ctx.ws;
    job.joint_matrices = matrices.data();
    job.joint_count = count;
    return job.Run();
  }
};

std::vector<float> Identity(uint32_t joints) {
  std::vector<float> m(size_t{kJointMatrixFloats} * joints, 0.0f);
  for (uint32_t j = 0; j < joints; ++j)
    for (int d = 0; d < 3; ++d) m[12 * j + 5 * d] = 1.0f;
  return m;
}

// Rotation by `angle` about z, then translation t, as a 3×4 row-major matrix at joint j.
void SetRigid(std::vector<float>& m, uint32_t j, float angle, float tx, float ty, float tz) {
  const float c = std::cos(angle), s = std::sin(angle);
  const float rows[12] = {c, -s, 0, tx, s, c, 0, ty, 0, 0, 1, tz};
  for (int i = 0; i < 12; ++i) m[12 * j + i] = rows[i];
}

}  // namespace

TEST_CASE("joint refit: identity matrices give back the bind spheres") {
  Rig rig(0.6f);
  REQUIRE(rig.Run(Identity(3)) == Status::kOk);
  const SphereArrays sp = rig.ctx.ws.spheres();
  for (uint32_t s = 0; s < sp.count; ++s) {
    const auto& b = rig.data.spheres[s];
    CHECK(sp.x[s] == doctest::Approx(b.center().x()).epsilon(1e-6));
    CHECK(sp.y[s] == doctest::Approx(b.center().y()).epsilon(1e-6));
    CHECK(sp.z[s] == doctest::Approx(b.center().z()).epsilon(1e-6));
    CHECK(sp.r[s] == b.radius());
  }
}

TEST_CASE("joint refit: one rigid motion of every joint moves the spheres as the vertex refit does") {
  Rig rig(0.7f);
  std::vector<float> m = Identity(3);
  for (uint32_t j = 0; j < 3; ++j) SetRigid(m, j, 0.8f, 3.0f, -2.0f, 5.0f);
  REQUIRE(rig.Run(m) == Status::kOk);
  std::vector<float> jx, jy, jz, jr;
  const SphereArrays sp = rig.ctx.ws.spheres();
  jx.assign(sp.x, sp.x + sp.count);
  jy.assign(sp.y, sp.y + sp.count);
  jz.assign(sp.z, sp.z + sp.count);
  jr.assign(sp.r, sp.r + sp.count);
  // The same motion applied to the mesh, refitted from the vertices (exact under rigid motion).
  std::vector<float> moved(rig.mesh.positions.size());
  for (size_t v = 0; v < moved.size() / 3; ++v) {
    const float* p = &rig.mesh.positions[3 * v];
    for (int r = 0; r < 3; ++r) moved[3 * v + r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
  }
  RefitJob vertex;
  vertex.model = &rig.ctx.model;
  vertex.workspace = &rig.ctx.ws;
  vertex.positions = {moved.data(), static_cast<uint32_t>(moved.size() / 3), 12};
  REQUIRE(vertex.Run() == Status::kOk);
  const SphereArrays vp = rig.ctx.ws.spheres();
  for (uint32_t s = 0; s < vp.count; ++s) {
    CHECK(jx[s] == doctest::Approx(vp.x[s]).epsilon(1e-4));
    CHECK(jy[s] == doctest::Approx(vp.y[s]).epsilon(1e-4));
    CHECK(jz[s] == doctest::Approx(vp.z[s]).epsilon(1e-4));
    CHECK(jr[s] == doctest::Approx(vp.r[s]).epsilon(1e-4));
  }
}

TEST_CASE("joint refit: the blend of two joints moves a centre by the weighted sum of their motions") {
  Rig rig(0.75f);
  std::vector<float> m = Identity(3);
  SetRigid(m, 2, 0.0f, 4.0f, 0.0f, -8.0f);  // joint 2 translates; joints 0 and 1 stay
  REQUIRE(rig.Run(m) == Status::kOk);
  const SphereArrays sp = rig.ctx.ws.spheres();
  for (uint32_t s = 0; s < sp.count; ++s) {
    const auto& b = rig.data.spheres[s];
    CHECK(sp.x[s] == doctest::Approx(b.center().x() + 0.25f * 4.0f).epsilon(1e-5));
    CHECK(sp.y[s] == doctest::Approx(b.center().y()).epsilon(1e-5));
    CHECK(sp.z[s] == doctest::Approx(b.center().z() - 0.25f * 8.0f).epsilon(1e-5));
  }
}

TEST_CASE("joint refit: every influence count and weight pattern, bit for bit the documented blend") {
  // Per sphere 1–4 influences of 5 joints, some out of order, none after a zero (LoadAsset refuses those:
  // the blend stops at the first zero after influence 0); the model groups the spheres by influence count,
  // the output stays by sphere id.
  test::Mesh mesh;
  test::AssetData data = test::TwoTubes(true, &mesh);
  data.joint_count = 5;
  const float patterns[6][4] = {{1, 0, 0, 0}, {0.3f, 0.5f, 0.2f, 0}, {0.4f, 0.3f, 0.2f, 0.1f},
                                {0.7f, 0.3f, 0, 0}, {0.4f, 0.6f, 0, 0}, {0.25f, 0.25f, 0.25f, 0.25f}};
  for (size_t s = 0; s < data.spheres.size(); ++s) {
    const float* w = patterns[(s * 5) % 6];
    data.sphere_joints.insert(data.sphere_joints.end(), {uint16_t(s % 5), uint16_t((s + 1) % 5),
                                                         uint16_t((s + 3) % 5), uint16_t((s + 4) % 5)});
    data.sphere_joint_weights.insert(data.sphere_joint_weights.end(), {w[0], w[1], w[2], w[3]});
  }
  test::AlignedBytes bytes = test::Serialize(data);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
  test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  std::vector<float> m(12 * 5);
  for (size_t i = 0; i < m.size(); ++i) m[i] = std::sin(float(i) * 1.7f) * (i % 4 == 3 ? 5.0f : 1.0f);
  JointRefitJob job;
  job.model = &ctx.model;
  job.workspace = &ctx.ws;
  job.joint_matrices = m.data();
  job.joint_count = 5;
  REQUIRE(job.Run() == Status::kOk);
  const SphereArrays sp = ctx.ws.spheres();
  uint32_t same = 0;
  for (uint32_t s = 0; s < sp.count; ++s) {
    const uint16_t* js = &data.sphere_joints[4 * s];
    const float* ws = &data.sphere_joint_weights[4 * s];
    float blend[12];
    for (int e = 0; e < 12; ++e) blend[e] = ws[0] * m[12 * js[0] + e];
    for (int k = 1; k < 4 && ws[k] != 0.0f; ++k)
      for (int e = 0; e < 12; ++e) blend[e] = blend[e] + ws[k] * m[12 * js[k] + e];
    const auto& b = data.spheres[s];
    const float p[4] = {b.center().x(), b.center().y(), b.center().z(), 1.0f};
    float c[3];
    for (int row = 0; row < 3; ++row)
      c[row] = (blend[4 * row] * p[0] + blend[4 * row + 1] * p[1]) + (blend[4 * row + 2] * p[2] + blend[4 * row + 3] * p[3]);
    same += sp.x[s] == c[0] && sp.y[s] == c[1] && sp.z[s] == c[2] && sp.r[s] == b.radius();
  }
  CHECK(same == sp.count);
}

TEST_CASE("joint refit: column-major 4x4 matrices convert to the 3x4 row-major layout") {
  const float cm[16] = {1, 2, 3, 0, 4, 5, 6, 0, 7, 8, 9, 0, 10, 11, 12, 1};  // columns
  float rm[kJointMatrixFloats];
  JointMatrixFromColumnMajor(cm, rm);
  const float want[12] = {1, 4, 7, 10, 2, 5, 8, 11, 3, 6, 9, 12};
  for (int i = 0; i < 12; ++i) CHECK(rm[i] == want[i]);
}

TEST_CASE("joint refit: bad input gets its status and leaves the spheres untouched") {
  Rig rig(0.5f);
  std::vector<float> m = Identity(3);
  SetRigid(m, 0, 0.3f, 1, 2, 3);
  REQUIRE(rig.Run(m) == Status::kOk);
  const SphereArrays sp = rig.ctx.ws.spheres();
  const std::vector<float> before(sp.x, sp.x + sp.count);
  auto untouched = [&] {
    for (uint32_t s = 0; s < sp.count; ++s) CHECK(rig.ctx.ws.spheres().x[s] == before[s]);
  };
  std::vector<float> bad = m;
  bad[12 * 1 + 7] = std::numeric_limits<float>::quiet_NaN();  // joint 1: some spheres follow it
  CHECK(rig.Run(bad) == Status::kErrorNonFiniteJoints);
  untouched();
  bad = m;
  bad[12 * 2 + 0] = INFINITY;
  CHECK(rig.Run(bad) == Status::kErrorNonFiniteJoints);
  untouched();
  CHECK(rig.Run(m, 2) == Status::kErrorJointCount);
  CHECK(rig.Run(m, 4) == Status::kErrorJointCount);
  untouched();

  JointRefitJob job;
  job.model = &rig.ctx.model;
  job.workspace = &rig.ctx.ws;
  job.joint_count = 3;
  CHECK(job.Check() == Status::kErrorNullArgument);  // no matrices
  job.joint_matrices = m.data();
  CHECK(job.Validate());
  std::vector<char> raw(sizeof(float) * m.size() + 1);
  job.joint_matrices = reinterpret_cast<const float*>(raw.data() + 1);
  CHECK(job.Check() == Status::kErrorAlignment);
  job.joint_matrices = m.data();
  test::Character empty;
  job.model = &empty.model;
  job.workspace = &empty.ws;
  CHECK(job.Check() == Status::kErrorInvalidJob);
  // A workspace made for another asset's model (one tube: other sphere count): refused, nothing written.
  test::Mesh other_mesh;
  test::Tube tube;
  const test::AlignedBytes other = test::Serialize(test::MakeTubes({tube}, {}, &other_mesh));
  AssetView other_view;
  REQUIRE(LoadAsset(other.data(), other.size, &other_view) == Status::kOk);
  test::Character other_ctx;
  REQUIRE(other_ctx.Init(other_view) == Status::kOk);
  job.model = &rig.ctx.model;
  job.workspace = &other_ctx.ws;
  CHECK(job.Check() == Status::kErrorWorkspaceModel);
  CHECK(job.Run() == Status::kErrorWorkspaceModel);
  job.model = &other_ctx.model;  // its own model holds no joint weights
  CHECK(job.Check() == Status::kErrorMissingField);
  untouched();

  // An asset without joint weights (schema v1/v2, or a mesh without a skin): re-bake.
  Rig plain(1.0f, /*joints=*/false);
  CHECK(plain.Run(m) == Status::kErrorMissingField);
  CHECK(std::string(ToString(Status::kErrorNonFiniteJoints)).rfind("kErrorNonFiniteJoints", 0) == 0);
}
