// spherechain evaluate — check.h: events against the exact truth, the policy, depths, the baseline, JUnit.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "spherechain/baker/bake.h"
#include "spherechain/baker/contacts.h"
#include "spherechain/evaluate/check.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/animation.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/runtime/crease.h"
#include "spherechain/runtime/narrow_phase.h"
#include "test_data.h"

namespace {

using namespace spherechain;
using evaluate::CheckPair;

struct Baked {
  baker::BakeResult result;
  runtime::AssetView view;
};

bool BakeIt(const std::string& path, Baked* out) {
  auto r = baker::Bake(path, baker::BakeConfig{});
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  out->result = std::move(r).value();
  return !runtime::Failed(runtime::LoadAsset(out->result.asset.data(), out->result.asset.size(), &out->view));
}

// The truth of one frame, from the mesh alone: every intersecting triangle pair (exact predicates, CGAL) that
// is not near on the welded bind surface within the asset's crease and does not intersect at bind pose, per
// region pair with its deepest ContactDepthOf.
std::map<CheckPair, float> TruthOf(const import::Mesh& mesh, const runtime::AssetView& view, const std::vector<float>& pos,
                                   const std::vector<uint32_t>& weld, runtime::CreaseGraph& graph,
                                   runtime::CreaseScratch& scratch, const std::set<baker::TrianglePair>& at_bind) {
  const uint32_t V = mesh.vertex_count();
  auto pairs = baker::ExactSelfIntersections(pos.data(), V, mesh.indices, weld);
  REQUIRE(pairs.ok());
  const auto* tr = view.asset->triangle_regions();
  std::map<CheckPair, float> out;
  for (const baker::TrianglePair& p : pairs.value()) {
    const uint32_t* ia = &mesh.indices[3 * size_t{p.a}];
    const uint32_t* ib = &mesh.indices[3 * size_t{p.b}];
    if (scratch.Near(graph, ia, ib, graph.crease()) || at_bind.count(p)) continue;
    const float* a[3] = {&pos[3 * ia[0]], &pos[3 * ia[1]], &pos[3 * ia[2]]};
    const float* b[3] = {&pos[3 * ib[0]], &pos[3 * ib[1]], &pos[3 * ib[2]]};
    runtime::ContactDepth d;
    runtime::ContactDepthOf(a, b, &d);
    const int ra = tr->Get(p.a), rb = tr->Get(p.b);
    float& deepest = out[{std::min(ra, rb), std::max(ra, rb)}];
    deepest = std::max(deepest, d.depth);
  }
  return out;
}

// Every frame of every clip: a region pair is in an event covering the frame exactly when the truth has a
// contact of the pair there; each event's depth is the deepest of the truth over its frames.
void CheckAgainstTruth(const std::string& path, uint32_t max_frames_checked, bool key_times = false) {
  Baked b;
  REQUIRE(BakeIt(path, &b));
  const import::Mesh& mesh = b.result.mesh;
  evaluate::CheckOptions o;
  o.fps = 15;
  o.key_times = key_times;
  auto report = evaluate::CheckClips(b.view, mesh, o);
  REQUIRE_MESSAGE(report.ok(), (report.ok() ? "" : report.error().message));
  REQUIRE(report->clips.size() == mesh.clips.size());
  if (key_times)
    for (size_t c = 0; c < mesh.clips.size(); ++c) {
      std::set<float> keys;  // the clip's key times (the creature's are distinct to far more than 1e-6 s)
      for (const auto& ch : mesh.clips[c].channels) keys.insert(ch.times.begin(), ch.times.end());
      CHECK(report->clips[c].frames == keys.size());
    }

  const std::vector<uint32_t> weld = import::ComputeWeldIds(mesh.positions);
  runtime::CreaseGraph graph;
  runtime::CreaseScratch scratch;
  REQUIRE(graph.Init(mesh.positions.data(), mesh.vertex_count(), mesh.indices.data(), mesh.triangle_count(), weld.data(),
                     b.view.asset->crease()) == runtime::Status::kOk);
  REQUIRE(scratch.Init(graph) == runtime::Status::kOk);
  std::set<baker::TrianglePair> at_bind;
  {
    auto bind = baker::ExactSelfIntersections(mesh.positions.data(), mesh.vertex_count(), mesh.indices, weld);
    REQUIRE(bind.ok());
    at_bind.insert(bind->begin(), bind->end());
  }
  uint32_t frames_with_truth = 0;
  for (const evaluate::CheckClip& clip : report->clips) {
    std::map<const evaluate::CheckEvent*, float> deepest;  // the truth's deepest over each event's frames
    const uint32_t step = std::max(1u, clip.frames / max_frames_checked);
    for (uint32_t f = 0; f < clip.frames; f += step) {
      std::vector<float> pos;
      REQUIRE(evaluate::CheckFrame(mesh, o, clip, f, &pos).ok());
      const std::map<CheckPair, float> truth = TruthOf(mesh, b.view, pos, weld, graph, scratch, at_bind);
      frames_with_truth += !truth.empty();
      std::set<CheckPair> covered;
      for (const evaluate::CheckEvent& e : clip.events)
        if (e.first_frame <= f && f <= e.last_frame) {
          CAPTURE(clip.name);
          CAPTURE(f);
          CAPTURE(e.name);
          CHECK(covered.insert(e.regions).second);  // one event per pair and frame
          REQUIRE(truth.count(e.regions));
          deepest[&e] = std::max(deepest[&e], truth.at(e.regions));
        }
      for (const auto& [pair, d] : truth) {
        CAPTURE(f);
        CHECK_MESSAGE(covered.count(pair), "frame " << f << ": the truth's pair " << pair.first << "-" << pair.second
                                                    << " is in no event");
      }
    }
    if (step == 1)
      for (const evaluate::CheckEvent& e : clip.events) {
        CAPTURE(e.name);
        CHECK(e.depth == doctest::Approx(deepest[&e]).epsilon(1e-5));
        CHECK(e.failed == (double(e.depth) > report->max_depth));
        CHECK(e.deepest_frame >= e.first_frame);
        CHECK(e.deepest_frame <= e.last_frame);
        CHECK(!e.contacts.empty());
      }
  }
  CHECK(frames_with_truth > 0);  // the clips make contacts: the comparison compared something
}

}  // namespace

// "heavy": the exact truth of every frame (the ASan half of CI skips them; they run once, in the normal suite).
TEST_CASE("check (heavy): the creature's events are the exact truth's, frame by frame, with its depths") {
  const std::string path = spherechain::test::SourceFile("tests/data/creature/creature.gltf");
  REQUIRE(std::filesystem::exists(path));
  CheckAgainstTruth(path, 1000);
  CheckAgainstTruth(path, 1000, /*key_times=*/true);
}

TEST_CASE("check (heavy): CesiumMan's walk, events against the exact truth") {
  const std::string path = spherechain::test::SharedData("gltf/CesiumMan.gltf");
  if (!spherechain::test::Require(path)) return;
  CheckAgainstTruth(path, 1000);
}

// The creature baked and checked with the default options, once: doctest runs a case's body again from the top
// for each of its subcases (12 runs below), and the bake and the check are the same each time (24 s a run under
// ASan).
struct CheckedCreature {
  Baked b;
  evaluate::CheckReport report;
};

const CheckedCreature& Creature() {
  static std::unique_ptr<CheckedCreature> done;
  if (!done) {
    auto c = std::make_unique<CheckedCreature>();
    REQUIRE(BakeIt(spherechain::test::SourceFile("tests/data/creature/creature.gltf"), &c->b));
    auto report = evaluate::CheckClips(c->b.view, c->b.result.mesh, evaluate::CheckOptions{});
    REQUIRE(report.ok());
    c->report = std::move(report).value();
    done = std::move(c);  // the view keeps pointing into the same asset bytes
  }
  return *done;
}

TEST_CASE("check: policy, depths, baseline and JUnit on the creature") {
  const Baked& b = Creature().b;
  const import::Mesh& mesh = b.result.mesh;
  const double h = evaluate::BodyHeight(mesh);
  REQUIRE(h > 0);

  SUBCASE("depths") {
    CHECK(evaluate::ParseDepth("0.5", h, 0).value() == doctest::Approx(0.5));
    CHECK(evaluate::ParseDepth("2%", h, 0).value() == doctest::Approx(0.02 * h));
    CHECK(evaluate::ParseDepth("1cm", h, 1.0).value() == doctest::Approx(0.01));
    CHECK(evaluate::ParseDepth("5mm", h, 0.1).value() == doctest::Approx(0.05));  // decimetre units
    CHECK(!evaluate::ParseDepth("1cm", h, 0).ok());                               // units unknown
    CHECK(evaluate::ParseDepth("1e-3", h, 0).value() == doctest::Approx(0.001));
    CHECK(evaluate::ParseDepth("2 cm", h, 1.0).value() == doctest::Approx(0.02));  // a space before the unit
    // decimal only: std::stod would read hexadecimal (0x10 = 16 units), a sign, a leading space, "inf"
    for (const char* bad : {"", "-1", "0", "1parsec", "cm", "nan", "0x10", "0x1p-4m", "+1", " 1", "inf", "1e999"}) {
      CAPTURE(bad);
      CHECK(!evaluate::ParseDepth(bad, h, 1.0).ok());
    }
  }

  evaluate::CheckOptions o;  // the options Creature() checked with
  const evaluate::CheckReport& r = Creature().report;
  REQUIRE(r.clips.size() == 2);  // "cross" drives the fore legs through each other, "still" does not move
  const evaluate::CheckClip* cross = r.clips[0].name == "cross" ? &r.clips[0] : &r.clips[1];
  const evaluate::CheckClip* still = cross == &r.clips[0] ? &r.clips[1] : &r.clips[0];
  REQUIRE(cross->failed());
  CHECK(!still->failed());
  CHECK(still->events.empty());
  const evaluate::CheckEvent& legs = cross->events.front();
  CHECK(legs.name == "ForeLeg_L-ForeLeg_R");
  CHECK(legs.joints[0].rfind("ForeLeg_L", 0) == 0);
  CHECK(legs.joints[1].rfind("ForeLeg_R", 0) == 0);

  SUBCASE("policy: a deeper threshold for the pair, or the pair allowed, passes the clip") {
    evaluate::CheckOptions p = o;
    p.policy.pair_max_depth[legs.regions] = legs.depth * 1.01;
    auto r2 = evaluate::CheckClips(b.view, mesh, p);
    REQUIRE(r2.ok());
    CHECK(!r2->failed());
    p.policy.pair_max_depth.clear();
    p.policy.allow.push_back(legs.regions);
    r2 = evaluate::CheckClips(b.view, mesh, p);
    REQUIRE(r2.ok());
    CHECK(!r2->failed());
    CHECK(!r2->clips[0].events.empty());  // still listed
  }

  SUBCASE("policy file: names and symbols; an unknown region lists the regions") {
    const std::string dir = std::string(SPHERECHAIN_BINARY_DIR) + "/tests/check_policy";
    std::filesystem::create_directories(dir);
    REQUIRE(import::WriteFileAtomic(dir + "/ok.json", std::string(R"({"allow": ["ForeLeg_L-ForeLeg_R"],
        "max_depth": {"R0-R1": "2%"}, "default_max_depth": 0.5})")).ok());
    evaluate::CheckPolicy policy;
    REQUIRE(evaluate::LoadCheckPolicy(dir + "/ok.json", b.view, h, 0, &policy).ok());
    CHECK(policy.max_depth == doctest::Approx(0.5));
    CHECK(policy.Threshold(legs.regions) == std::numeric_limits<double>::infinity());
    CHECK(policy.Threshold({0, 1}) == doctest::Approx(0.02 * h));
    // A depth as a JSON number is model units, exactly (not rounded through text to six decimals).
    REQUIRE(import::WriteFileAtomic(dir + "/tiny.json", std::string(R"({"default_max_depth": 3e-7})")).ok());
    REQUIRE(evaluate::LoadCheckPolicy(dir + "/tiny.json", b.view, h, 0, &policy).ok());
    CHECK(policy.max_depth == 3e-7);
    REQUIRE(import::WriteFileAtomic(dir + "/bad.json", std::string(R"({"allow": ["Wing_L-ForeLeg_R"]})")).ok());
    auto s = evaluate::LoadCheckPolicy(dir + "/bad.json", b.view, h, 0, &policy);
    REQUIRE(!s.ok());
    CHECK(s.error().message.find("Wing_L-ForeLeg_R") != std::string::npos);
    CHECK(s.error().message.find("ForeLeg_L") != std::string::npos);  // the regions there are
    REQUIRE(import::WriteFileAtomic(dir + "/key.json", std::string(R"({"alow": []})")).ok());
    CHECK(!evaluate::LoadCheckPolicy(dir + "/key.json", b.view, h, 0, &policy).ok());
    // One pair under two spellings: refused, both named (else the winner would be the keys' sorted order).
    const auto symbol = [&](int r) { return "R" + std::to_string(r); };
    const std::string by_symbol = symbol(legs.regions.first) + "-" + symbol(legs.regions.second);
    REQUIRE(import::WriteFileAtomic(dir + "/twice.json", R"({"max_depth": {"ForeLeg_R-ForeLeg_L": "1%", ")" + by_symbol +
                                                             R"(": "20%"}})").ok());
    s = evaluate::LoadCheckPolicy(dir + "/twice.json", b.view, h, 0, &policy);
    REQUIRE(!s.ok());
    CHECK(s.error().code == import::Error::Code::kConfig);
    CHECK(s.error().message.find("twice") != std::string::npos);
    CHECK(s.error().message.find("\"ForeLeg_R-ForeLeg_L\"") != std::string::npos);
    CHECK(s.error().message.find("\"" + by_symbol + "\"") != std::string::npos);
  }

  SUBCASE("baseline: the same run is known; deeper fails; a vanished event is fixed; another character refused") {
    const nlohmann::json base = evaluate::CheckReportJson(r);
    evaluate::CheckReport again = r;
    REQUIRE(evaluate::ApplyBaseline(base, &again).ok());
    CHECK(!again.failed());
    for (const auto& c : again.clips)
      for (const auto& e : c.events) CHECK(e.baseline == (e.depth > again.max_depth ? "known" : e.baseline));

    evaluate::CheckReport deeper = r;
    for (auto& c : deeper.clips)
      for (auto& e : c.events) e.depth *= 1.2f;
    REQUIRE(evaluate::ApplyBaseline(base, &deeper).ok());
    CHECK(deeper.failed());

    nlohmann::json shallow = base;  // the baseline had no failing event: every failing one is new
    for (auto& c : shallow["clips"]) c["events"] = nlohmann::json::array();
    evaluate::CheckReport fresh = r;
    REQUIRE(evaluate::ApplyBaseline(shallow, &fresh).ok());
    CHECK(fresh.failed());

    evaluate::CheckReport fixed = r;  // this run is clean: the baseline's failures are fixed
    for (auto& c : fixed.clips) c.events.clear();
    REQUIRE(evaluate::ApplyBaseline(base, &fixed).ok());
    bool listed = false;
    for (const auto& c : fixed.clips) listed |= std::find(c.fixed.begin(), c.fixed.end(), legs.name) != c.fixed.end();
    CHECK(listed);

    nlohmann::json other = base;
    other["fingerprint"] = "0123456789abcdef";
    evaluate::CheckReport o2 = r;
    auto s = evaluate::ApplyBaseline(other, &o2);
    REQUIRE(!s.ok());
    CHECK(s.error().message.find("another character") != std::string::npos);
    CHECK(!evaluate::ApplyBaseline(nlohmann::json::object(), &o2).ok());
  }

  SUBCASE("baseline: a report written with a baseline is the next run's baseline (its known events stay known)") {
    evaluate::CheckReport second = r;
    REQUIRE(evaluate::ApplyBaseline(evaluate::CheckReportJson(r), &second).ok());
    REQUIRE(!second.failed());
    const nlohmann::json second_json = evaluate::CheckReportJson(second);  // known events: failed false
    evaluate::CheckReport third = r;
    REQUIRE(evaluate::ApplyBaseline(second_json, &third).ok());
    CHECK(!third.failed());
    for (const auto& c : third.clips)
      for (const auto& e : c.events)
        if (e.over_threshold) CHECK(e.baseline == "known");
  }

  SUBCASE("baseline: values of the wrong type are kConfig naming the problem, not an exception") {
    for (const char* bad : {R"({"depth": "0.03", "name": "x", "over_threshold": true})", R"(3)",
                            R"({"name": 7, "over_threshold": true})"}) {
      CAPTURE(bad);
      nlohmann::json j = evaluate::CheckReportJson(r);
      j["clips"][0]["events"] = nlohmann::json::array({nlohmann::json::parse(bad)});
      evaluate::CheckReport o3 = r;
      auto s = evaluate::ApplyBaseline(j, &o3);
      REQUIRE(!s.ok());
      CHECK(s.error().code == import::Error::Code::kConfig);
    }
  }

  SUBCASE("a picture's caption with & and < (a clip named \"Walk & Run\") is escaped in the SVG") {
    const std::string svg =
        playback::RenderFrameSvg(mesh, b.view, mesh.positions.data(), {}, {}, "Walk & Run <fast> 'x'", 200);
    CHECK(svg.find("Walk &amp; Run &lt;fast&gt; &apos;x&apos;") != std::string::npos);
    CHECK(svg.find("Walk & Run") == std::string::npos);
    CHECK(playback::XmlEscape(std::string("a\x01" "b\tc\nd")) == "ab\tc&#10;d");
  }

  SUBCASE("XmlEscape keeps well-formed UTF-8 and replaces every other byte by U+FFFD") {
    const std::string fffd = "\xEF\xBF\xBD";
    CHECK(playback::XmlEscape("F\xC3\xBC\xC3\x9F \xE2\x80\x93 \xF0\x9F\xA6\xB4") == "F\xC3\xBC\xC3\x9F \xE2\x80\x93 \xF0\x9F\xA6\xB4");
    CHECK(playback::XmlEscape("caf\xE9.gltf") == "caf" + fffd + ".gltf");            // Latin-1
    CHECK(playback::XmlEscape("\xC3") == fffd);                                         // a character cut short
    CHECK(playback::XmlEscape("\xC0\xAF") == fffd + fffd);                              // overlong '/'
    CHECK(playback::XmlEscape("\xED\xA0\x80") == fffd + fffd + fffd);                   // a surrogate
    CHECK(playback::XmlEscape("\xF4\x90\x80\x80") == fffd + fffd + fffd + fffd);       // above U+10FFFF
    CHECK(playback::XmlEscape("\xE2\x80<") == fffd + fffd + "&lt;");
  }

  SUBCASE("JUnit: long non-ASCII names are written whole, a path in another encoding as U+FFFD") {
    evaluate::CheckReport named = r;
    std::string joint = "ForeLeg_R_02_";
    for (int i = 0; i < 250; ++i) joint += "\xC3\xB6";  // ö: 513 bytes, over any line buffer of 512
    evaluate::CheckClip& c = named.clips[cross == &r.clips[0] ? 0 : 1];
    for (evaluate::CheckEvent& e : c.events) e.joints[1] = joint;
    named.mesh_name = "caf\xE9.gltf";
    const std::string x = evaluate::CheckReportJUnit(named);
    CHECK(x.find(joint) != std::string::npos);
    CHECK(x.find("caf\xEF\xBF\xBD.gltf") != std::string::npos);
    CHECK(x.find("caf\xE9") == std::string::npos);
  }

  SUBCASE("JUnit: one testcase per clip, a failure for the failing one naming its event") {
    const std::string x = evaluate::CheckReportJUnit(r);
    size_t cases = 0, failures = 0;
    for (size_t k = x.find("<testcase "); k != std::string::npos; k = x.find("<testcase ", k + 1)) ++cases;
    for (size_t k = x.find("<failure "); k != std::string::npos; k = x.find("<failure ", k + 1)) ++failures;
    CHECK(cases == 2);
    CHECK(failures == 1);
    CHECK(x.find("ForeLeg_L-ForeLeg_R frames") != std::string::npos);
  }

  SUBCASE("bad input") {
    evaluate::CheckOptions bad = o;
    bad.clips = {"gallop"};
    auto e = evaluate::CheckClips(b.view, mesh, bad);
    REQUIRE(!e.ok());
    CHECK(e.error().message.find("'cross'") != std::string::npos);  // lists the clips there are
    bad = o;
    bad.fps = 0;
    CHECK(!evaluate::CheckClips(b.view, mesh, bad).ok());
    bad = o;
    bad.max_frames = 3;
    CHECK(!evaluate::CheckClips(b.view, mesh, bad).ok());
    import::Mesh no_clips = mesh;
    no_clips.clips.clear();
    e = evaluate::CheckClips(b.view, no_clips, o);
    REQUIRE(!e.ok());
    CHECK(e.error().message.find("nothing to check") != std::string::npos);
    bad = o;
    bad.clips = {"cross", "still", "cross"};
    e = evaluate::CheckClips(b.view, mesh, bad);
    REQUIRE(!e.ok());
    CHECK(e.error().message.find("'cross' is asked for twice") != std::string::npos);
  }

  SUBCASE("the morph through key poses and a clip of the character named \"morph\" are two clips") {
    const std::string dir = std::string(SPHERECHAIN_BINARY_DIR) + "/tests/check_morph";
    std::filesystem::create_directories(dir);
    REQUIRE(import::WriteFileAtomic(dir + "/tail.json",
                                    std::string(R"({"name": "tail", "rotations": {"Tail01": {"axis": [0, 0, 1], "degrees": 5}}})"))
                .ok());
    import::Mesh renamed = mesh;  // the failing clip "cross" renamed "morph"
    for (import::Clip& clip : renamed.clips)
      if (clip.name == "cross") clip.name = "morph";
    evaluate::CheckOptions m = o;
    m.poses = {dir + "/tail.json"};
    auto both = evaluate::CheckClips(b.view, renamed, m);
    REQUIRE(both.ok());
    REQUIRE(both->clips.size() == 3);
    const evaluate::CheckClip& file_clip = both->clips[0];  // the character's order, then the morph
    CHECK(file_clip.name == "morph");
    CHECK(!file_clip.morph);
    CHECK(file_clip.failed());          // the crossing legs are played, not the key poses' morph
    CHECK(file_clip.frames == cross->frames);
    CHECK(both->clips[2].name == "morph (key poses)");
    CHECK(both->clips[2].morph);
    CHECK(!both->clips[2].failed());
    CHECK(both->failed());
    std::vector<float> positions;  // a picture's frame is the clip's own
    CHECK(evaluate::CheckFrame(renamed, m, file_clip, file_clip.frames - 1, &positions).ok());
    CHECK(!evaluate::CheckFrame(renamed, m, both->clips[2], m.morph_frames, &positions).ok());
    // Without a clip of that name the morph is "morph", and --clip morph names no clip of the file.
    auto plain = evaluate::CheckClips(b.view, mesh, m);
    REQUIRE(plain.ok());
    CHECK(plain->clips.back().name == "morph");
    CHECK(plain->clips.back().morph);
    m.clips = {"morph"};
    CHECK(!evaluate::CheckClips(b.view, mesh, m).ok());
    m.clips = {};
    m.morph_frames = 1;  // too few for one key pose: the message names check's option
    auto few = evaluate::CheckClips(b.view, mesh, m);
    REQUIRE(!few.ok());
    CHECK(few.error().message.rfind("--morph-frames 1 is too few", 0) == 0);
  }
}
