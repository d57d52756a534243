// playback/animation + playback/morph: clip sampling, linear blend skinning, the paper's Bézier morph between
// key poses (§5.1) and readable pose files.
#include <doctest/doctest.h>

#include <filesystem>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "spherechain/import/import.h"
#include "spherechain/playback/animation.h"
#include "spherechain/playback/morph.h"
#include "test_data.h"

namespace {

namespace sb = spherechain::playback;

/// Largest |a_i − b_i|.
float MaxDiff(const std::vector<float>& a, const std::vector<float>& b) {
  REQUIRE(a.size() == b.size());
  float m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

/// Largest extent of the positions over the three axes.
float Size(const std::vector<float>& p) {
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < p.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], p[i]);
    hi[i % 3] = std::max(hi[i % 3], p[i]);
  }
  return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
}

/// Two bones: "root" at the origin, "child" with its head at (0, 1, 0). Vertex 0 (0, 0.5, 0) follows
/// the root, vertices 1 (0, 2, 0) and 2 (1, 1, 0) follow the child, vertex 3 (0, 1, 1) is split 50/50.
sb::Mesh TwoBoneMesh() {
  sb::Mesh m;
  m.positions = {0, 0.5f, 0, 0, 2, 0, 1, 1, 0, 0, 1, 1};
  m.indices = {0, 1, 2, 1, 2, 3};
  sb::Skin s;
  s.nodes.resize(2);
  s.nodes[0].name = "root";
  s.nodes[1].name = "child";
  s.nodes[1].parent = 0;
  s.nodes[1].translation = {0, 1, 0};
  s.joints.resize(2);
  s.joints[0].node = 0;
  s.joints[1].node = 1;
  s.joints[1].inverse_bind[13] = -1.0f;  // translate(0, −1, 0), column-major
  s.weight_offsets = {0, 1, 2, 3, 5};
  s.weight_joints = {0, 1, 1, 0, 1};
  s.weights = {1, 1, 1, 0.5f, 0.5f};
  s.source = "test";
  m.skin = s;
  return m;
}

std::vector<float> Skinned(const sb::Mesh& mesh, const std::vector<sb::Transform>& locals) {
  std::vector<float> out(mesh.positions.size());
  sb::SkinningScratch scratch;
  const sb::Status s = sb::SkinLocals(mesh, locals, &scratch, out.data(), out.size());
  REQUIRE_MESSAGE(s.ok(), (s.ok() ? "" : s.error().message));
  return out;
}

/// Imports `path` and checks that skinning at the rest pose (rest locals, and a clip with no channels)
/// gives back Mesh::positions, and that every clip samples to finite positions of a sane size.
void CheckRestPoseReproducesBind(const std::string& path, float tolerance_rel) {
  auto r = spherechain::import::ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  const sb::Mesh& mesh = r.value();
  REQUIRE(mesh.skin.has_value());
  const float size = Size(mesh.positions);
  std::vector<sb::Transform> rest;
  sb::RestLocals(*mesh.skin, &rest);
  const std::vector<float> at_rest = Skinned(mesh, rest);
  CHECK(MaxDiff(at_rest, mesh.positions) <= tolerance_rel * size);

  sb::Clip empty;
  empty.name = "rest";
  std::vector<float> out(mesh.positions.size());
  sb::SkinningScratch scratch;
  REQUIRE(sb::SkinClip(mesh, empty, 0.0f, &scratch, out.data(), out.size()).ok());
  CHECK(MaxDiff(out, mesh.positions) <= tolerance_rel * size);

  REQUIRE_FALSE(mesh.clips.empty());
  for (const sb::Clip& clip : mesh.clips) {
    for (float u : {0.0f, 0.37f, 1.0f}) {
      const sb::Status s = sb::SkinClip(mesh, clip, u * clip.duration_s, &scratch, out.data(), out.size());
      REQUIRE_MESSAGE(s.ok(), (s.ok() ? "" : s.error().message));
      CHECK(std::all_of(out.begin(), out.end(), [](float v) { return std::isfinite(v); }));
      // An animated body keeps roughly its size (no exploded or collapsed skinning).
      CHECK(Size(out) > 0.5f * size);
      CHECK(Size(out) < 2.0f * size);
    }
  }
}

}  // namespace

TEST_CASE("animation: CesiumMan skinned at the rest pose reproduces the bind positions") {
  const std::string path = spherechain::test::SharedData("gltf/CesiumMan.gltf");
  if (!spherechain::test::Require(path)) return;
  CheckRestPoseReproducesBind(path, 1e-4f);
}

TEST_CASE("animation: BCN_Epileptic skinned at the rest pose reproduces the bind positions") {
  const std::string path = spherechain::test::AssimpModel("X/BCN_Epileptic.X");
  if (!spherechain::test::Require(path)) return;
  CheckRestPoseReproducesBind(path, 1e-4f);
}

TEST_CASE("animation: two-bone skin, child rotated 90 degrees, moves the child's vertices exactly") {
  const sb::Mesh mesh = TwoBoneMesh();
  std::vector<sb::Transform> locals;
  sb::RestLocals(*mesh.skin, &locals);
  CHECK(MaxDiff(Skinned(mesh, locals), mesh.positions) == 0.0f);

  // +90° about +Z at the child's head (0, 1, 0): (0, 2, 0) → (−1, 1, 0); (1, 1, 0) → (0, 2, 0);
  // the 50/50 vertex (0, 1, 1) lies on the axis through the head: it stays.
  locals[1].rotation = sb::QuatFromAxisAngle({0, 0, 1}, 90.0f);
  const std::vector<float> out = Skinned(mesh, locals);
  const std::vector<float> expected = {0, 0.5f, 0, -1, 1, 0, 0, 2, 0, 0, 1, 1};
  CHECK(MaxDiff(out, expected) < 1e-6f);

  // The same through a clip: linear rotation keys 0° at t=0 and 90° at t=2; step keys hold.
  sb::Clip clip;
  clip.name = "bend";
  clip.duration_s = 2.0f;
  sb::Channel ch;
  ch.node = 1;
  ch.path = sb::Channel::Path::kRotation;
  ch.times = {0.0f, 2.0f};
  const sb::Quat q90 = sb::QuatFromAxisAngle({0, 0, 1}, 90.0f);
  ch.values = {0, 0, 0, 1, q90[0], q90[1], q90[2], q90[3]};
  clip.channels.push_back(ch);
  std::vector<float> buf(mesh.positions.size());
  sb::SkinningScratch scratch;
  REQUIRE(sb::SkinClip(mesh, clip, 2.0f, &scratch, buf.data(), buf.size()).ok());
  CHECK(MaxDiff(buf, expected) < 1e-6f);
  REQUIRE(sb::SkinClip(mesh, clip, 1.0f, &scratch, buf.data(), buf.size()).ok());  // 45° (slerp)
  const float c = std::sqrt(0.5f);
  CHECK(buf[3] == doctest::Approx(-c).epsilon(1e-6));
  CHECK(buf[4] == doctest::Approx(1 + c).epsilon(1e-6));
  clip.channels[0].interpolation = sb::Channel::Interpolation::kStep;
  REQUIRE(sb::SkinClip(mesh, clip, 1.9f, &scratch, buf.data(), buf.size()).ok());  // holds the 0° key
  CHECK(MaxDiff(buf, mesh.positions) < 1e-6f);

  // Wrong buffer size and a bad channel are errors, not crashes.
  CHECK_FALSE(sb::SkinClip(mesh, clip, 0.0f, &scratch, buf.data(), buf.size() - 1).ok());
  clip.channels[0].node = 7;
  const sb::Status bad = sb::SkinClip(mesh, clip, 0.0f, &scratch, buf.data(), buf.size());
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("out of range") != std::string::npos);
}

TEST_CASE("animation: morph schedule reaches every key at its mid frame and starts at rest") {
  for (uint32_t k = 0; k < 5; ++k) {
    CHECK(sb::MorphKeyFrame(k, 40, 5) == 8 * k + 4);
    auto f = sb::MorphFrameAt(8 * k + 4, 40, 5);
    REQUIRE(f.ok());
    CHECK(f->key == k);
    CHECK(f->t == 0.5f);
    auto r = sb::MorphFrameAt(8 * k, 40, 5);
    REQUIRE(r.ok());
    CHECK(r->t == 0.0f);
  }
  // Uneven split (23 frames, 3 keys: 8, 8, 7 frames) and odd segments still hit t = ½.
  for (uint32_t k = 0; k < 3; ++k) {
    auto f = sb::MorphFrameAt(sb::MorphKeyFrame(k, 23, 3), 23, 3);
    REQUIRE(f.ok());
    CHECK(f->key == k);
    CHECK(f->t == 0.5f);
  }
  CHECK_FALSE(sb::MorphFrameAt(0, 5, 3).ok());   // too few frames
  CHECK_FALSE(sb::MorphFrameAt(40, 40, 5).ok());  // out of range
  CHECK_FALSE(sb::MorphFrameAt(0, 40, 0).ok());   // no keys

  // de Casteljau with P0 = P2 = 1, C = q² is q^(4t(1−t)), also beyond 90°.
  const sb::Quat one{0, 0, 0, 1};
  for (float deg : {30.0f, 120.0f, 170.0f}) {
    const sb::Quat q = sb::QuatFromAxisAngle({1, 2, 3}, deg);
    const sb::Quat c = sb::QuatMultiply(q, q);
    for (float t : {0.0f, 0.1f, 0.25f, 0.5f, 0.8f}) {
      const sb::Quat b = sb::QuadraticBezierRotation(one, c, one, t);
      const sb::Quat expect = sb::QuatFromAxisAngle({1, 2, 3}, deg * 4 * t * (1 - t));
      for (int i = 0; i < 4; ++i) CHECK(b[i] == doctest::Approx(expect[i]).epsilon(1e-5));
    }
  }
}

TEST_CASE("animation: morph of the two-bone skin is the rest pose at frame 0 and the key at its mid frame") {
  const sb::Mesh mesh = TwoBoneMesh();
  auto key = sb::ParsePose(R"({"name": "bend", "rotations": {"child": {"axis": [0, 0, 1], "degrees": 90}}})",
                           *mesh.skin, "bend.json");
  REQUIRE(key.ok());
  const std::vector<sb::Pose> keys = {key.value(), key.value()};
  std::vector<float> out(mesh.positions.size()), posed(mesh.positions.size());
  sb::SkinningScratch scratch;
  REQUIRE(sb::SkinMorphFrame(mesh, keys, 0, 8, &scratch, out.data(), out.size()).ok());
  CHECK(MaxDiff(out, mesh.positions) == 0.0f);
  REQUIRE(sb::SkinPose(mesh, keys[1], &scratch, posed.data(), posed.size()).ok());
  REQUIRE(sb::SkinMorphFrame(mesh, keys, sb::MorphKeyFrame(1, 8, 2), 8, &scratch, out.data(), out.size()).ok());
  CHECK(MaxDiff(out, posed) == 0.0f);
  CHECK(MaxDiff(out, {0, 0.5f, 0, -1, 1, 0, 0, 2, 0, 0, 1, 1}) < 1e-6f);
  // Frame 1 (t = ¼): 90°·4·¼·¾ = 67.5°.
  REQUIRE(sb::SkinMorphFrame(mesh, keys, 1, 8, &scratch, out.data(), out.size()).ok());
  const float a = 67.5f * 3.14159265f / 180.0f;
  CHECK(out[3] == doctest::Approx(-std::sin(a)).epsilon(1e-5));
  CHECK(out[4] == doctest::Approx(1 + std::cos(a)).epsilon(1e-5));

  // A key of a half turn (the most a pose may give): the excursion sweeps 0 → 135° → 180° → 135° → 0, as
  // below it (slerp toward C = rest·δ² = −rest has no arc: it used to stay at rest but for the key frame).
  auto half_turn = sb::ParsePose(R"({"name": "fold", "rotations": {"child": {"axis": [0, 0, 1], "degrees": 180}}})",
                                 *mesh.skin, "fold.json");
  REQUIRE(half_turn.ok());
  const std::vector<sb::Pose> folds = {half_turn.value(), half_turn.value()};
  for (uint32_t f : {1u, 3u}) {  // t = ¼ and ¾: 180°·4·¼·¾ = 135°
    REQUIRE(sb::SkinMorphFrame(mesh, folds, f, 8, &scratch, out.data(), out.size()).ok());
    const float b = 135.0f * 3.14159265f / 180.0f;
    CHECK(out[3] == doctest::Approx(-std::sin(b)).epsilon(1e-5));
    CHECK(out[4] == doctest::Approx(1 + std::cos(b)).epsilon(1e-5));
  }
}

TEST_CASE("animation: MakeHuman morph hits each key pose exactly at its mid frame, rest at frame 0") {
  const std::string obj = spherechain::test::SharedData("makehuman/base.obj");
  if (!spherechain::test::Require(obj)) return;
  const std::string poses_dir = spherechain::test::SourceFile("data/poses/makehuman");
  REQUIRE(std::filesystem::exists(poses_dir));
  auto r = spherechain::import::ImportMesh(obj);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  const sb::Mesh& mesh = r.value();
  REQUIRE(mesh.skin.has_value());
  auto keys = sb::LoadPoseFolder(poses_dir, *mesh.skin);
  REQUIRE_MESSAGE(keys.ok(), (keys.ok() ? "" : keys.error().message));
  CHECK(keys->size() == 5);
  const uint32_t frames = 40, n = static_cast<uint32_t>(keys->size());
  std::vector<float> out(mesh.positions.size()), posed(mesh.positions.size());
  sb::SkinningScratch scratch;
  REQUIRE(sb::SkinMorphFrame(mesh, keys.value(), 0, frames, &scratch, out.data(), out.size()).ok());
  CHECK(MaxDiff(out, mesh.positions) < 1e-4f);  // dm; float rounding of M_j ≈ identity
  std::vector<sb::Transform> rest;
  sb::RestLocals(*mesh.skin, &rest);
  CHECK(MaxDiff(out, Skinned(mesh, rest)) == 0.0f);
  for (uint32_t k = 0; k < n; ++k) {
    INFO("key pose " << keys.value()[k].name);
    REQUIRE(sb::SkinPose(mesh, keys.value()[k], &scratch, posed.data(), posed.size()).ok());
    REQUIRE(sb::SkinMorphFrame(mesh, keys.value(), sb::MorphKeyFrame(k, frames, n), frames, &scratch, out.data(),
                               out.size())
                .ok());
    CHECK(MaxDiff(out, posed) == 0.0f);
    CHECK(MaxDiff(posed, mesh.positions) > 1.0f);  // the key pose really moves the body (dm)
    // The excursion's first frame is the rest pose again.
    REQUIRE(sb::SkinMorphFrame(mesh, keys.value(), sb::MorphKeyFrame(k, frames, n) - frames / n / 2, frames, &scratch,
                               out.data(), out.size())
                .ok());
    CHECK(MaxDiff(out, Skinned(mesh, rest)) == 0.0f);
  }
}

TEST_CASE("animation: a pose file with an unknown bone or a bad axis is a clear error") {
  const sb::Mesh mesh = TwoBoneMesh();
  auto err = [&](const std::string& json) {
    auto p = sb::ParsePose(json, *mesh.skin, "poses/bad.json");
    REQUIRE_FALSE(p.ok());
    CHECK(p.error().code == sb::Error::Code::kConfig);
    CHECK(p.error().message.find("poses/bad.json") != std::string::npos);
    return p.error().message;
  };
  std::string m = err(R"({"rotations": {"upperarm01.L": {"axis": [1, 0, 0], "degrees": 30}}})");
  CHECK(m.find("unknown bone 'upperarm01.L'") != std::string::npos);
  m = err(R"({"rotations": {"child": {"axis": [0, 0, 0], "degrees": 30}}})");
  CHECK(m.find("'child'") != std::string::npos);
  CHECK(m.find("zero length") != std::string::npos);
  m = err(R"({"rotations": {"child": {"axis": [1, 0], "degrees": 30}}})");
  CHECK(m.find("\"axis\" must be an array of 3 numbers") != std::string::npos);
  m = err(R"({"rotations": {"child": {"axis": [1, "up", 0], "degrees": 30}}})");
  CHECK(m.find("not a finite number") != std::string::npos);
  // Finite as a double, infinite as the float it is kept in: refused (it became a rotation that did nothing).
  m = err(R"({"rotations": {"child": {"axis": [0, 1e39, 0], "degrees": 30}}})");
  CHECK(m.find("\"axis\" component 1 is not a finite number as a 32-bit float") != std::string::npos);
  m = err(R"({"rotations": {"child": {"axis": [0, 1, 0], "degrees": 181}}})");
  CHECK(m.find("within [-180, 180]") != std::string::npos);
  m = err(R"({"rotations": {"child": {"axis": [1, 0, 0]}}})");
  CHECK(m.find("\"degrees\"") != std::string::npos);
  err(R"({"name": "no rotations"})");
  err("{ not json");
  // A good one parses, with the file stem as default name.
  auto ok = sb::ParsePose(R"({"rotations": {"child": {"axis": [0, 0, 2], "degrees": -45}}})", *mesh.skin,
                          "poses/lean.json");
  REQUIRE(ok.ok());
  CHECK(ok->name == "lean");
  REQUIRE(ok->rotations.size() == 1);
  CHECK(ok->rotations[0].node == 1);
  CHECK(ok->rotations[0].rotation[2] == doctest::Approx(-std::sin(22.5 * 3.14159265358979 / 180)));
  // A missing file is kIo, naming it.
  auto missing = sb::LoadPose("/nonexistent/pose.json", *mesh.skin);
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().code == sb::Error::Code::kIo);
}
