// playback::Play on a synthetic rigged character with known answers: two tubes (tests/runtime/asset_builder.h),
// tube B on its own joint, a clip that lowers it onto tube A. The bind pose and the early frames report no
// pair, the last frame reports exactly the A-B sphere pairs that overlap, the refit spheres of B move
// rigidly with it, and the documented errors come back.
#include <doctest/doctest.h>

#include <cmath>
#include <set>

#include "playback/rig.h"
#include "spherechain/playback/play.h"
#include "spherechain/playback/session.h"

namespace sc = spherechain;

namespace {

using sc::test::Rig;
using sc::test::MakeRig;

sc::playback::Animation Open(const Rig& r, uint32_t frames) {
  sc::playback::AnimationRequest req;
  req.mesh_name = "tubes";
  req.frames = frames;
  auto a = sc::playback::OpenAnimation(r.mesh, req);
  REQUIRE_MESSAGE(a.ok(), (a.ok() ? "" : a.error().message));
  return a.value();
}

}  // namespace

TEST_CASE("play: tube B lowered onto tube A collides only in the last frame, with the expected pairs") {
  Rig r;
  MakeRig(&r);
  const sc::playback::Animation anim = Open(r, 4);  // t = 0, .25, .5, .75: B at z = 10, 7, 4, 1
  CHECK(anim.clip == &r.mesh.clips[0]);
  sc::playback::PlayOptions o;
  o.repeat = 1;
  o.keep_spheres = true;
  o.narrow_phase = false;
  uint32_t calls = 0;
  o.on_frame = [&](uint32_t f, const std::vector<float>& positions, const std::vector<float>* joints) {
    CHECK(f == calls++);
    CHECK(positions.size() == r.mesh.positions.size());
    CHECK(joints == nullptr);  // the synthetic asset holds no centre joint weights
    return sc::import::Status(sc::import::Ok{});
  };
  auto played = sc::playback::Play(r.mesh, r.view, anim, o);
  REQUIRE_MESSAGE(played.ok(), (played.ok() ? "" : played.error().message));
  const sc::playback::PlayReport& rep = played.value();
  CHECK(calls == 4);
  CHECK(rep.sphere_count == 16);
  CHECK(rep.bind.label == "bind");
  CHECK(rep.bind.pairs.empty());
  REQUIRE(rep.frames.size() == 4);
  for (uint32_t f = 0; f < 3; ++f) CHECK(rep.frames[f].pairs.empty());
  CHECK(rep.frames[3].label == "t=0.750s");
  // Known answer for the last frame: B's spheres 9 units lower; every A-B pair whose spheres overlap.
  std::set<std::pair<int, int>> expected, got;
  for (int a = 0; a < 8; ++a)
    for (int b = 8; b < 16; ++b) {
      const auto& sa = r.data.spheres[a];
      const auto& sb = r.data.spheres[b];
      const float dx = sa.center().x() - sb.center().x(), dy = sa.center().y() - sb.center().y(),
                  dz = sa.center().z() - (sb.center().z() - 9.0f);
      if (dx * dx + dy * dy + dz * dz < (sa.radius() + sb.radius()) * (sa.radius() + sb.radius())) expected.emplace(a, b);
    }
  REQUIRE(!expected.empty());
  for (const auto& c : rep.frames[3].pairs) got.emplace(c.a, c.b);
  CHECK(got == expected);
  CHECK(rep.frames[3].m2.distinct_pairs == expected.size());
  CHECK(rep.summary.frames == 4);
  CHECK(rep.summary.frames_with_pairs == 1);
  CHECK(rep.summary.max_pairs_m2 == expected.size());
  // The spheres follow the tubes rigidly: A's stay, B's move down by 9 (pivot-frame refit of a translation).
  const std::vector<float>& s3 = rep.frames[3].spheres;
  REQUIRE(s3.size() == 16 * 4);
  for (int s = 0; s < 16; ++s) {
    const auto& b = r.data.spheres[s];
    CHECK(s3[4 * s] == doctest::Approx(b.center().x()).epsilon(1e-4));
    CHECK(s3[4 * s + 2] == doctest::Approx(b.center().z() - (s < 8 ? 0.0f : 9.0f)).epsilon(1e-4));
    CHECK(s3[4 * s + 3] == doctest::Approx(b.radius()).epsilon(1e-4));
  }
  CHECK(rep.frames[0].tracking_max < 1e-4);
  CHECK(sc::playback::RegionPairsText(rep.frames[0].regions) == "-");
}

TEST_CASE("play: documented errors — joint refit without weights, a bad narrow_behind_margin, wrong mesh, on_frame's error") {
  Rig r;
  MakeRig(&r);
  const sc::playback::Animation anim = Open(r, 4);
  sc::playback::PlayOptions o;
  o.repeat = 1;
  o.refit = sc::playback::PlayRefit::kJoints;
  auto a = sc::playback::Play(r.mesh, r.view, anim, o);
  REQUIRE(!a.ok());
  CHECK(a.error().code == sc::import::Error::Code::kConfig);
  CHECK(a.error().message.find("no joint weights") != std::string::npos);

  o.refit = sc::playback::PlayRefit::kPivotFrame;
  for (float bad : {-1.0f, std::nanf(""), INFINITY}) {  // the narrow phase behind M2's pairs: a margin scale >= 0
    o.narrow_phase = true;
    o.narrow_behind_margin = bad;
    auto e = sc::playback::Play(r.mesh, r.view, anim, o);
    REQUIRE(!e.ok());
    CHECK(e.error().code == sc::import::Error::Code::kConfig);
    CHECK(e.error().message.find("narrow_behind_margin") != std::string::npos);
  }
  for (float bad : {-1.0f, std::nanf(""), INFINITY}) {  // the folds' closing behind M2's pairs: finite, >= 0
    sc::playback::Session session;
    sc::playback::SessionOptions so;
    so.narrow = sc::playback::SessionNarrow::kBehindM2;
    so.fold_closing = bad;
    auto e = session.Init(r.view, r.mesh, so);
    REQUIRE(!e.ok());
    CHECK(e.error().code == sc::import::Error::Code::kConfig);
    CHECK(e.error().message.find("fold_closing") != std::string::npos);
    CHECK_FALSE(session.initialized());
  }
  o.narrow_phase = false;
  o.narrow_behind_margin = 0.0f;
  sc::import::Mesh shorter = r.mesh;
  shorter.positions.resize(shorter.positions.size() - 3);
  auto b = sc::playback::Play(shorter, r.view, anim, o);
  REQUIRE(!b.ok());
  CHECK(b.error().code == sc::import::Error::Code::kConfig);

  o.on_frame = [](uint32_t f, const std::vector<float>&, const std::vector<float>*) -> sc::import::Status {
    if (f == 2) return sc::import::MakeError(sc::import::Error::Code::kIo, "disk full");
    return sc::import::Ok{};
  };
  auto c = sc::playback::Play(r.mesh, r.view, anim, o);
  REQUIRE(!c.ok());
  CHECK(c.error().message == "disk full");

  sc::playback::AnimationRequest req;
  req.mesh_name = "tubes";
  req.clip = "lower";
  req.morph = {"x.json"};
  CHECK(!sc::playback::OpenAnimation(r.mesh, req).ok());
  req.morph.clear();
  req.frames = 0;
  CHECK(!sc::playback::OpenAnimation(r.mesh, req).ok());
  req.frames = 4;
  req.clip = "walk";
  auto d = sc::playback::OpenAnimation(r.mesh, req);
  REQUIRE(!d.ok());
  CHECK(d.error().message.find("(clips: 'lower')") != std::string::npos);
}
