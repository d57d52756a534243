// Segmentation into the paper's five regions (R0 left arm, R1 right arm, R2 left leg, R3 right leg,
// R4 torso): synthetic bodies with known answers, the MakeHuman body by rig and by geometry, and the
// documented errors. Set SPHERECHAIN_SEGMENT_DEBUG_DIR=/tmp to get front/back PNG renders (needs
// ImageMagick `convert`); the library itself never writes or prints anything.
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>
#include <unistd.h>

#include "spherechain/import/import.h"
#include "spherechain/baker/plausibility.h"
#include "spherechain/baker/segment.h"
#include "synthetic_body.h"
#include "test_data.h"

namespace sc = spherechain::baker;
using spherechain::test::Require;
using spherechain::test::SharedData;

namespace {

using namespace spherechain::test;  // the synthetic body (synthetic_body.h)

// ---------------------------------------------------------------------------------------------------
// Private MakeHuman loader (base.obj group `body` + default_weights.mhw) so this test does not depend on
// the importer's OBJ path.
sc::Mesh LoadMakeHumanBody(bool with_rig) {
  sc::Mesh mesh;
  std::ifstream in(SharedData("makehuman/base.obj"));
  std::string line;
  bool in_body = false;
  std::vector<float> all;
  uint32_t max_v = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream s(line.substr(2));
      float x, y, z;
      s >> x >> y >> z;
      all.insert(all.end(), {x, y, z});
    } else if (line.rfind("g ", 0) == 0) {
      in_body = line == "g body";
    } else if (in_body && line.rfind("f ", 0) == 0) {
      std::istringstream s(line.substr(2));
      std::vector<uint32_t> f;
      std::string tok;
      while (s >> tok) f.push_back(uint32_t(std::stoul(tok.substr(0, tok.find('/')))) - 1);
      for (size_t k = 1; k + 1 < f.size(); ++k) mesh.indices.insert(mesh.indices.end(), {f[0], f[k], f[k + 1]});
      for (uint32_t v : f) max_v = std::max(max_v, v);
    }
  }
  mesh.positions.assign(all.begin(), all.begin() + 3 * (size_t(max_v) + 1));
  mesh.up_axis = sc::UpAxis::kY;
  mesh.source_format = "obj";
  if (!with_rig) return mesh;
  std::ifstream win(SharedData("makehuman/default_weights.mhw"));
  const nlohmann::json w = nlohmann::json::parse(win);
  sc::Skin skin;
  skin.source = "mhskel";
  std::vector<std::vector<std::pair<uint32_t, float>>> rows(mesh.vertex_count());
  for (const auto& [bone, list] : w["weights"].items()) {
    const uint32_t j = uint32_t(skin.joints.size());
    skin.nodes.push_back({bone});
    skin.joints.push_back({int32_t(j)});
    for (const auto& vw : list) {
      const uint32_t v = vw[0].get<uint32_t>();
      if (v < rows.size()) rows[v].emplace_back(j, vw[1].get<float>());
    }
  }
  skin.weight_offsets.push_back(0);
  for (auto& r : rows) {
    float sum = 0;
    for (auto& [j, x] : r) sum += x;
    for (auto& [j, x] : r) {
      skin.weight_joints.push_back(j);
      skin.weights.push_back(sum > 0 ? x / sum : 0.0f);
    }
    skin.weight_offsets.push_back(uint32_t(skin.weights.size()));
  }
  mesh.skin = std::move(skin);
  return mesh;
}

// ---------------------------------------------------------------------------------------------------
// Checks and debug output.

std::array<size_t, sc::kRegionCount> Counts(const sc::Segmentation& s) {
  std::array<size_t, sc::kRegionCount> n{};
  for (uint8_t r : s.triangle_regions) ++n.at(r);
  return n;
}

/// Number of connected pieces of each region (triangles sharing a vertex at the same position).
std::array<int, sc::kRegionCount> PieceCounts(const sc::Mesh& mesh, const sc::Segmentation& s) {
  std::map<std::array<float, 3>, uint32_t> weld;
  std::vector<uint32_t> rep(mesh.vertex_count());
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    rep[v] = weld.emplace(std::array<float, 3>{mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]}, v)
                 .first->second;
  const uint32_t nt = mesh.triangle_count();
  std::vector<uint32_t> parent(nt);
  std::iota(parent.begin(), parent.end(), 0u);
  std::function<uint32_t(uint32_t)> find = [&](uint32_t x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
  std::vector<std::array<int64_t, sc::kRegionCount>> seen(mesh.vertex_count());
  for (auto& a : seen) a.fill(-1);
  for (uint32_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      auto& slot = seen[rep[mesh.indices[3 * t + k]]][s.triangle_regions[t]];
      if (slot < 0) slot = t;
      else parent[find(uint32_t(slot))] = find(t);
    }
  std::array<int, sc::kRegionCount> n{};
  for (uint32_t t = 0; t < nt; ++t)
    if (find(t) == t) ++n[s.triangle_regions[t]];
  return n;
}

std::string Describe(const sc::Segmentation& s) {
  std::ostringstream o;
  if (!s.layout.paper) {  // a creature's (the any-skeleton path: Testwuson.X)
    o << s.method << ":";
    for (int r = 0; r < s.layout.count(); ++r)
      o << ' ' << s.layout.regions[size_t(r)].name << ' '
        << std::count(s.triangle_regions.begin(), s.triangle_regions.end(), uint8_t(r));
    return o.str();
  }
  const auto n = Counts(s);
  o << s.method << ": L-arm " << n[0] << ", R-arm " << n[1] << ", L-leg " << n[2] << ", R-leg " << n[3] << ", torso "
    << n[4];
  return o.str();
}

/// Front (looking along -forward) and back views side by side, z-buffered, coloured by region and
/// shaded by normal. Written as PPM, converted to PNG with ImageMagick when available.
void RenderDebug(const sc::Mesh& mesh, const sc::Segmentation& s, const std::string& name, int forward_axis = 2) {
  const char* dir = std::getenv("SPHERECHAIN_SEGMENT_DEBUG_DIR");
  if (!dir) return;
  const int W = 400, H = 700;
  std::vector<std::array<uint8_t, 3>> img(size_t(2 * W) * H, {255, 255, 255});
  const int side_axis = forward_axis == 2 ? 0 : 2;
  float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], mesh.positions[3 * v + d]), hi[d] = std::max(hi[d], mesh.positions[3 * v + d]);
  const int up = mesh.up_axis == sc::UpAxis::kZ ? 2 : 1;
  const float scale = 0.95f * std::min(W / std::max(1e-6f, hi[side_axis] - lo[side_axis]), H / std::max(1e-6f, hi[up] - lo[up]));
  static const uint8_t colour[5][3] = {{220, 40, 40}, {40, 90, 220}, {240, 170, 20}, {30, 170, 80}, {170, 170, 170}};
  for (int view = 0; view < 2; ++view) {
    std::vector<float> zbuf(size_t(W) * H, -1e30f);
    const float flip = view == 0 ? 1.0f : -1.0f;  // front: +forward towards the viewer
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      float sx[3], sy[3], sz[3];
      float p[3][3];
      for (int k = 0; k < 3; ++k) {
        for (int d = 0; d < 3; ++d) p[k][d] = mesh.positions[3 * mesh.indices[3 * t + k] + d];
        // front view: viewer at +forward; the character's left (+X for +Z forward) appears on the image right
        sx[k] = W / 2 + flip * (p[k][side_axis] - 0.5f * (lo[side_axis] + hi[side_axis])) * scale *
                            (forward_axis == 2 ? 1.0f : -1.0f);
        sy[k] = H - 10 - (p[k][up] - lo[up]) * scale;
        sz[k] = flip * p[k][forward_axis];
      }
      const float e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
      const float e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
      float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
      const float nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) + 1e-12f;
      const float shade = 0.45f + 0.55f * std::abs(n[forward_axis] / nl);
      const int x0 = std::max(0, int(std::floor(std::min({sx[0], sx[1], sx[2]})))),
                x1 = std::min(W - 1, int(std::ceil(std::max({sx[0], sx[1], sx[2]}))));
      const int y0 = std::max(0, int(std::floor(std::min({sy[0], sy[1], sy[2]})))),
                y1 = std::min(H - 1, int(std::ceil(std::max({sy[0], sy[1], sy[2]}))));
      const float den = (sy[1] - sy[2]) * (sx[0] - sx[2]) + (sx[2] - sx[1]) * (sy[0] - sy[2]);
      if (std::abs(den) < 1e-12f) continue;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const float a = ((sy[1] - sy[2]) * (x - sx[2]) + (sx[2] - sx[1]) * (y - sy[2])) / den;
          const float b = ((sy[2] - sy[0]) * (x - sx[2]) + (sx[0] - sx[2]) * (y - sy[2])) / den;
          const float c = 1 - a - b;
          if (a < 0 || b < 0 || c < 0) continue;
          const float z = a * sz[0] + b * sz[1] + c * sz[2];
          if (z <= zbuf[size_t(y) * W + x]) continue;
          zbuf[size_t(y) * W + x] = z;
          const uint8_t* col = colour[std::min<int>(s.triangle_regions[t], 4)];
          img[size_t(y) * 2 * W + view * W + x] = {uint8_t(col[0] * shade), uint8_t(col[1] * shade), uint8_t(col[2] * shade)};
        }
    }
  }
  const std::string base = std::string(dir) + "/seg_" + name;
  {
    std::ofstream out(base + ".ppm", std::ios::binary);
    out << "P6\n" << 2 * W << ' ' << H << "\n255\n";
    out.write(reinterpret_cast<const char*>(img.data()), std::streamsize(img.size() * 3));
  }
  const std::string cmd = "convert '" + base + ".ppm' '" + base + ".png' 2>/dev/null && rm -f '" + base + ".ppm'";
  if (std::system(cmd.c_str()) == 0) MESSAGE("debug render: " << base << ".png (left: front, right: back)");
}

/// Checks the synthetic body's known answer: every triangle well inside a limb (beyond 30% of the
/// capsule from its root) is in that limb's region; the head and chest are torso; ≥ 90% overall.
void CheckSynthetic(const SyntheticBody& body, const sc::Segmentation& s) {
  REQUIRE(s.triangle_regions.size() == body.mesh.triangle_count());
  size_t agree = 0, wrong_limb = 0, limb_total = 0;
  for (uint32_t t = 0; t < body.mesh.triangle_count(); ++t) {
    const Capsule& part = body.parts[size_t(body.part_of_triangle[t])];
    const uint8_t truth = static_cast<uint8_t>(part.region);
    agree += s.triangle_regions[t] == truth;
    if (part.region == sc::Region::kTorso || body.along_part[t] < 0.3) continue;
    ++limb_total;
    wrong_limb += s.triangle_regions[t] != truth;
  }
  const double fraction = double(agree) / double(body.mesh.triangle_count());
  MESSAGE(Describe(s) << "; agreement with the construction " << fraction << "; limb triangles checked "
                      << limb_total << ", wrong " << wrong_limb);
  CHECK(limb_total > 1000);
  CHECK(wrong_limb == 0);
  CHECK(fraction >= 0.9);
  const auto pieces = PieceCounts(body.mesh, s);
  for (int r = 0; r < 4; ++r) CHECK_MESSAGE(pieces[r] == 1, "region " << r << " has " << pieces[r] << " pieces");
}

}  // namespace

TEST_CASE("segment: synthetic A-pose body, geometry, known answer") {
  const SyntheticBody body = MakeSyntheticBody(false);
  auto seg = sc::SegmentByGeometry(body.mesh);
  REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
  MESSAGE(seg->notes);
  CheckSynthetic(body, seg.value());
  RenderDebug(body.mesh, seg.value(), "synthetic_apose");
}

TEST_CASE("segment: synthetic T-pose body, geometry, known answer") {
  const SyntheticBody body = MakeSyntheticBody(true);
  auto seg = sc::SegmentByGeometry(body.mesh);
  REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
  MESSAGE(seg->notes);
  CheckSynthetic(body, seg.value());
  RenderDebug(body.mesh, seg.value(), "synthetic_tpose");
}

TEST_CASE("segment: synthetic body facing +X, left/right from the feet not from a fixed axis") {
  for (bool t_pose : {false, true}) {
    CAPTURE(t_pose);
    const SyntheticBody body = MakeSyntheticBody(t_pose, 1);
    auto seg = sc::SegmentByGeometry(body.mesh);
    REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
    CheckSynthetic(body, seg.value());
  }
}

TEST_CASE("segment: MakeHuman body by geometry and by rig agree") {
  if (!Require(SharedData("makehuman/base.obj")) || !Require(SharedData("makehuman/default_weights.mhw"))) return;
  const sc::Mesh mesh = LoadMakeHumanBody(true);
  REQUIRE(mesh.vertex_count() == 13380);
  REQUIRE(mesh.triangle_count() == 26756);
  auto geo = sc::SegmentByGeometry(mesh);
  REQUIRE_MESSAGE(geo.ok(), (geo.ok() ? "" : geo.error().message));
  auto rig = sc::SegmentByRig(mesh);
  REQUIRE_MESSAGE(rig.ok(), (rig.ok() ? "" : rig.error().message));
  MESSAGE("geometry notes: " << geo->notes);
  MESSAGE("rig notes: " << rig->notes);
  for (const sc::Segmentation* s : {&geo.value(), &rig.value()}) {
    const auto pieces = PieceCounts(mesh, *s);
    for (int r = 0; r < 4; ++r) CHECK_MESSAGE(pieces[r] == 1, s->method << " region " << r << ": " << pieces[r] << " pieces");
    for (uint8_t r : s->triangle_regions) REQUIRE(r < sc::kRegionCount);
    // The character faces +Z, so its left arm (R0) lies at +X.
    double x_left = 0, x_right = 0;
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const double x = mesh.positions[3 * mesh.indices[3 * t]];
      if (s->triangle_regions[t] == 0) x_left += x;
      if (s->triangle_regions[t] == 1) x_right += x;
    }
    CHECK(x_left > 0);
    CHECK(x_right < 0);
  }
  const sc::SegmentationAgreement a = sc::CompareSegmentations(mesh, geo.value(), rig.value());
  MESSAGE(Describe(geo.value()) << "\n" << Describe(rig.value()) << "\nagreement: triangles " << a.triangle_fraction
                                << ", area " << a.area_fraction << ", IoU L-arm " << a.iou[0] << " R-arm " << a.iou[1]
                                << " L-leg " << a.iou[2] << " R-leg " << a.iou[3] << " torso " << a.iou[4]);
  CHECK(a.triangle_fraction >= 0.90);
  for (int r = 0; r < sc::kRegionCount; ++r) CHECK(a.iou[r] >= 0.75);
  RenderDebug(mesh, geo.value(), "makehuman_geometry");
  RenderDebug(mesh, rig.value(), "makehuman_rig");
}

TEST_CASE("segment: Auto picks the rig when recognised, geometry otherwise") {
  const SyntheticBody body = MakeSyntheticBody(false);
  auto seg = sc::Segment(body.mesh, sc::SegmentMethod::kAuto);
  REQUIRE(seg.ok());
  CHECK(seg->method == "geometry");
  sc::Mesh rigged = body.mesh;
  rigged.skin = sc::Skin{};
  rigged.skin->nodes = {{"spine"}};
  rigged.skin->joints = {{0}};
  rigged.skin->weight_offsets.assign(rigged.vertex_count() + 1, 0);
  auto only_spine = sc::SegmentByRig(rigged);
  REQUIRE_FALSE(only_spine.ok());
  CHECK(only_spine.error().code == sc::Error::Code::kSegmentation);
  CHECK(only_spine.error().message.find("left_arm") != std::string::npos);
  auto fallback = sc::Segment(rigged, sc::SegmentMethod::kAuto);
  REQUIRE(fallback.ok());
  CHECK(fallback->method == "geometry");
}

namespace {
void CheckRealCharacter(const std::string& path) {
  {
    CAPTURE(path);
    if (!Require(path)) return;
    auto mesh = sc::ImportMesh(path);
    if (!mesh.ok()) {
      MESSAGE("import failed (importer still in progress?): " << mesh.error().message);
      return;
    }
    auto rig = sc::SegmentByRig(mesh.value());
    REQUIRE_MESSAGE(rig.ok(), (rig.ok() ? "" : rig.error().message));
    MESSAGE(path << " rig: " << Describe(rig.value()) << " — " << rig->notes);
    const auto pieces = PieceCounts(mesh.value(), rig.value());
    for (int r = 0; r < 4; ++r) CHECK(pieces[r] == 1);
    const std::string name = std::filesystem::path(path).stem().string();
    RenderDebug(mesh.value(), rig.value(), name + "_rig");
    auto geo = sc::SegmentByGeometry(mesh.value());
    if (geo.ok()) {
      const auto a = sc::CompareSegmentations(mesh.value(), geo.value(), rig.value());
      MESSAGE(path << " geometry: " << Describe(geo.value()) << "; agreement with rig " << a.triangle_fraction
                   << " — " << geo->notes);
      RenderDebug(mesh.value(), geo.value(), name + "_geometry");
    } else {
      MESSAGE(path << " geometry: " << geo.error().message);
    }
  }
}
}  // namespace

TEST_CASE("segment: CesiumMan via ImportMesh, rig and geometry") { CheckRealCharacter(SharedData("gltf/CesiumMan.gltf")); }

TEST_CASE("segment: BCN_Epileptic via ImportMesh, rig and geometry") {
  CheckRealCharacter(spherechain::test::AssimpModel("X/BCN_Epileptic.X"));
}

TEST_CASE("segment: a cube and a sphere are not bodies") {
  sc::Mesh cube;
  cube.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  cube.indices = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  sc::Mesh sphere;
  const int n = 24;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j < 2 * n; ++j) {
      const double th = M_PI * i / n, ph = M_PI * j / n;
      sphere.positions.insert(sphere.positions.end(),
                              {float(std::sin(th) * std::cos(ph)), float(std::cos(th)), float(std::sin(th) * std::sin(ph))});
    }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < 2 * n; ++j) {
      const uint32_t a = i * 2 * n + j, b = i * 2 * n + (j + 1) % (2 * n), c = a + 2 * n, d = b + 2 * n;
      sphere.indices.insert(sphere.indices.end(), {a, c, b, b, c, d});
    }
  for (const sc::Mesh* m : {&cube, &sphere}) {
    auto seg = sc::SegmentByGeometry(*m);
    REQUIRE_FALSE(seg.ok());
    CHECK(seg.error().code == sc::Error::Code::kSegmentation);
    CHECK(seg.error().message.find("not a standing body") != std::string::npos);
    MESSAGE(seg.error().message);
    auto rig = sc::SegmentByRig(*m);
    REQUIRE_FALSE(rig.ok());
    CHECK(rig.error().code == sc::Error::Code::kSegmentation);
  }
}

TEST_CASE("segment: region map, wrong length and bad values are config errors") {
  const SyntheticBody body = MakeSyntheticBody(false);
  const sc::Mesh& mesh = body.mesh;
  const auto dir = std::filesystem::temp_directory_path();
  auto write = [&](const std::string& name, const nlohmann::json& j) {
    const std::string p = (dir / ("spherechain_segment_" + name + "." + std::to_string(::getpid()) + ".json")).string();
    std::ofstream(p) << j.dump();
    return p;
  };
  std::vector<int> tri(mesh.triangle_count());
  for (size_t t = 0; t < tri.size(); ++t) tri[t] = int(body.parts[size_t(body.part_of_triangle[t])].region);
  auto ok = sc::SegmentByMap(mesh, write("ok", {{"triangle_regions", tri}}));
  REQUIRE_MESSAGE(ok.ok(), (ok.ok() ? "" : ok.error().message));
  CHECK(ok->method == "map");
  CHECK(std::equal(tri.begin(), tri.end(), ok->triangle_regions.begin()));

  std::vector<int> short_map(tri.begin(), tri.end() - 1);
  auto bad_len = sc::SegmentByMap(mesh, write("short", {{"triangle_regions", short_map}}));
  REQUIRE_FALSE(bad_len.ok());
  CHECK(bad_len.error().code == sc::Error::Code::kConfig);
  CHECK(bad_len.error().message.find(std::to_string(mesh.triangle_count())) != std::string::npos);

  std::vector<int> verts(mesh.vertex_count() + 3, 4);
  auto bad_vlen = sc::SegmentByMap(mesh, write("vshort", {{"vertex_regions", verts}}));
  REQUIRE_FALSE(bad_vlen.ok());
  CHECK(bad_vlen.error().code == sc::Error::Code::kConfig);

  tri[7] = 5;
  auto bad_val = sc::SegmentByMap(mesh, write("badval", {{"triangle_regions", tri}}));
  REQUIRE_FALSE(bad_val.ok());
  CHECK(bad_val.error().code == sc::Error::Code::kConfig);

  auto missing = sc::SegmentByMap(mesh, (dir / "spherechain_segment_no_such_file.json").string());
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().code == sc::Error::Code::kIo);

  std::vector<int> vert_torso(mesh.vertex_count(), 4);
  auto by_vertex = sc::SegmentByMap(mesh, write("vok", {{"vertex_regions", vert_torso}}));
  REQUIRE(by_vertex.ok());
  CHECK(std::all_of(by_vertex->triangle_regions.begin(), by_vertex->triangle_regions.end(), [](uint8_t r) { return r == 4; }));
}

// ---------------------------------------------------------------------------------------------------
// Welded segmentation (issue 11): parts meeting at coincident positions are one body.

namespace {

/// `mesh` cut at the plane x = `centre` into two halves, the way a modeller's mirrored halves or an
/// exporter's per-material parts arrive: each triangle goes to the half of its centroid; the vertices of
/// the left half come first, then those of the right half, so every vertex used by both halves (the
/// seam) appears twice. Triangle order is kept, skin rows are copied. With `straddle`, the two copies of
/// each seam vertex are moved apart by 0.4 of the segmentation's weld tolerance (1e-6 of the bounding-box
/// diagonal) across a multiple of half that tolerance — positions a quantised weld key would split — and
/// `*nudged_original` gets the left copy's positions (the same body without the cut).
sc::Mesh SplitAtMidPlane(const sc::Mesh& mesh, double centre, bool straddle, sc::Mesh* nudged_original,
                         uint32_t* seam_count) {
  const uint32_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  std::vector<uint8_t> used(size_t(nv) * 2, 0);
  std::vector<uint8_t> side(nt);
  for (uint32_t t = 0; t < nt; ++t) {
    double x = 0;
    for (int k = 0; k < 3; ++k) x += mesh.positions[3 * size_t(mesh.indices[3 * t + k])] / 3.0;
    side[t] = x >= centre;
    for (int k = 0; k < 3; ++k) used[2 * size_t(mesh.indices[3 * t + k]) + side[t]] = 1;
  }
  std::vector<uint32_t> remap(size_t(nv) * 2, UINT32_MAX);
  sc::Mesh out;
  out.up_axis = mesh.up_axis;
  out.source_format = mesh.source_format;
  std::vector<uint32_t> origin;
  for (int s = 0; s < 2; ++s)
    for (uint32_t v = 0; v < nv; ++v)
      if (used[2 * size_t(v) + s]) {
        remap[2 * size_t(v) + s] = uint32_t(origin.size());
        origin.push_back(v);
      }
  for (uint32_t v : origin)
    for (int d = 0; d < 3; ++d) out.positions.push_back(mesh.positions[3 * size_t(v) + d]);
  for (uint32_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) out.indices.push_back(remap[2 * size_t(mesh.indices[3 * t + k]) + side[t]]);
  *nudged_original = mesh;
  *seam_count = 0;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (uint32_t v = 0; v < nv; ++v)
    for (int d = 0; d < 3; ++d)
      lo[d] = std::min(lo[d], double(mesh.positions[3 * v + d])), hi[d] = std::max(hi[d], double(mesh.positions[3 * v + d]));
  const double eps = 1e-6 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
  for (uint32_t v = 0; v < nv; ++v) {
    if (!used[2 * size_t(v)] || !used[2 * size_t(v) + 1]) continue;
    ++*seam_count;
    if (!straddle) continue;
    const double k = std::floor(mesh.positions[3 * size_t(v)] / eps);
    const float left = float((k + 0.3) * eps), right = float((k + 0.7) * eps);
    out.positions[3 * size_t(remap[2 * size_t(v)])] = left;
    out.positions[3 * size_t(remap[2 * size_t(v) + 1])] = right;
    nudged_original->positions[3 * size_t(v)] = left;
  }
  if (mesh.skin) {
    sc::Skin skin = *mesh.skin;
    skin.weight_offsets = {0};
    skin.weight_joints.clear();
    skin.weights.clear();
    for (uint32_t v : origin) {
      for (uint32_t w = mesh.skin->weight_offsets[v]; w < mesh.skin->weight_offsets[v + 1]; ++w) {
        skin.weight_joints.push_back(mesh.skin->weight_joints[w]);
        skin.weights.push_back(mesh.skin->weights[w]);
      }
      skin.weight_offsets.push_back(uint32_t(skin.weights.size()));
    }
    out.skin = std::move(skin);
  }
  return out;
}

size_t Differences(const sc::Segmentation& a, const sc::Segmentation& b) {
  size_t n = 0;
  for (size_t t = 0; t < a.triangle_regions.size(); ++t) n += a.triangle_regions[t] != b.triangle_regions.at(t);
  return n;
}

/// Known answer: the halves segment exactly like the body they were cut from (same region per triangle).
void CheckHalvesLikeWhole(const sc::Mesh& mesh, double centre, sc::SegmentMethod method, const std::string& what) {
  for (bool straddle : {false, true}) {
    CAPTURE(what);
    CAPTURE(straddle);
    sc::Mesh whole;
    uint32_t seam = 0;
    const sc::Mesh halves = SplitAtMidPlane(mesh, centre, straddle, &whole, &seam);
    MESSAGE(what << (straddle ? " (seam copies straddling a weld cell)" : " (seam copies bitwise equal)") << ": "
                 << whole.vertex_count() << " vertices -> " << halves.vertex_count() << " (" << seam
                 << " seam vertices twice)");
    CHECK(seam > 20);
    CHECK(halves.vertex_count() == whole.vertex_count() + seam);
    auto a = sc::Segment(whole, method);
    REQUIRE_MESSAGE(a.ok(), (a.ok() ? "" : a.error().message));
    auto b = sc::Segment(halves, method);
    REQUIRE_MESSAGE(b.ok(), (b.ok() ? "" : b.error().message));
    MESSAGE("whole:  " << Describe(a.value()) << "\nhalves: " << Describe(b.value()));
    CHECK(b->method == a->method);
    CHECK(Differences(a.value(), b.value()) == 0);
    if (straddle) continue;  // PieceCounts joins bitwise-equal positions only
    const auto pieces = PieceCounts(halves, b.value());
    for (int r = 0; r < 4; ++r) CHECK_MESSAGE(pieces[r] == 1, "region " << r << ": " << pieces[r] << " pieces");
  }
}

}  // namespace

TEST_CASE("segment: a synthetic body cut into two halves at the mid-plane segments like the whole (welded)") {
  const SyntheticBody body = MakeSyntheticBody(false);
  CheckHalvesLikeWhole(body.mesh, 0.0, sc::SegmentMethod::kGeometry, "synthetic A-pose");
}

TEST_CASE("segment (heavy): MakeHuman cut into mirrored halves segments like the whole, by rig and by geometry") {
  if (!Require(SharedData("makehuman/base.obj")) || !Require(SharedData("makehuman/default_weights.mhw"))) return;
  const sc::Mesh mesh = LoadMakeHumanBody(true);
  CheckHalvesLikeWhole(mesh, 0.0, sc::SegmentMethod::kRig, "MakeHuman rig");
  CheckHalvesLikeWhole(mesh, 0.0, sc::SegmentMethod::kGeometry, "MakeHuman geometry");
}

TEST_CASE("segment (heavy): every X file of assimp-testmodels segments the same read as a triangle soup (--vertices source) and joined") {
  const std::string dir = spherechain::test::AssimpModel("X");
  if (!Require(dir)) return;
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".x") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  CHECK(files.size() >= 5);
  int bodies = 0;
  for (const std::string& f : files) {
    CAPTURE(f);
    sc::ImportOptions source_opts, joined_opts;
    source_opts.vertices = sc::VertexContract::kSource;
    joined_opts.vertices = sc::VertexContract::kJoined;
    auto source = sc::ImportMesh(f, source_opts);
    auto joined = sc::ImportMesh(f, joined_opts);
    REQUIRE(source.ok() == joined.ok());
    if (!source.ok()) {
      MESSAGE(f << ": not imported either way: " << source.error().message);
      continue;
    }
    CHECK(source->triangle_count() == joined->triangle_count());
    for (sc::SegmentMethod m : {sc::SegmentMethod::kAuto, sc::SegmentMethod::kGeometry}) {
      auto a = sc::Segment(source.value(), m);
      auto b = sc::Segment(joined.value(), m);
      REQUIRE(a.ok() == b.ok());
      if (!a.ok()) {
        CHECK(a.error().message == b.error().message);
        MESSAGE(f << ": refused either way: " << a.error().message);
        continue;
      }
      ++bodies;
      MESSAGE(f << " (" << source->vertex_count() << " / " << joined->vertex_count() << " vertices): "
                << Describe(a.value()) << " | joined " << Describe(b.value()));
      CHECK(a->method == b->method);
      CHECK(Differences(a.value(), b.value()) == 0);
    }
  }
  CHECK(bodies >= 2);  // BCN_Epileptic by rig and by geometry at least
}

// ---------------------------------------------------------------------------------------------------
// Plausibility checks (plausibility.h, issue 11 "no silent wrong bake"): the synthetic body's own
// segmentation passes; each constructed wrong one fails with its code.

namespace {

bool Has(const std::vector<sc::PlausibilityFinding>& f, const std::string& code) {
  for (const auto& x : f)
    if (x.code == code) return true;
  return false;
}

std::string Codes(const std::vector<sc::PlausibilityFinding>& f) {
  std::string s;
  for (const auto& x : f) s += x.code + " (" + x.message + ") ";
  return s.empty() ? "none" : s;
}

/// The construction's segmentation: every triangle in the region of its capsule.
sc::Segmentation TruthOf(const SyntheticBody& body) {
  sc::Segmentation s;
  s.method = "map";
  for (int p : body.part_of_triangle) s.triangle_regions.push_back(uint8_t(body.parts[size_t(p)].region));
  return s;
}

}  // namespace

TEST_CASE("plausibility: the synthetic body's true segmentation passes every check") {
  for (bool t_pose : {false, true}) {
    const SyntheticBody body = MakeSyntheticBody(t_pose);
    const sc::Segmentation truth = TruthOf(body);
    sc::CoverageStats cov;
    cov.protrusion = 0.05;
    sc::SegmentationAgreement agree;
    agree.triangle_fraction = 0.9;
    const auto f = sc::CheckPlausibility(body.mesh, truth, &cov, &agree);
    CHECK_MESSAGE(f.empty(), (t_pose ? "T-pose: " : "A-pose: ") << Codes(f));
    auto geo = sc::SegmentByGeometry(body.mesh);
    REQUIRE(geo.ok());
    CHECK_MESSAGE(sc::CheckPlausibility(body.mesh, geo.value(), nullptr, nullptr).empty(),
                  Codes(sc::CheckPlausibility(body.mesh, geo.value(), nullptr, nullptr)));
  }
}

TEST_CASE("plausibility: constructed wrong segmentations fail with their code") {
  const SyntheticBody body = MakeSyntheticBody(false);
  const sc::Segmentation truth = TruthOf(body);
  const uint8_t kLeftArm = uint8_t(sc::Region::kLeftArm), kTorso = uint8_t(sc::Region::kTorso);
  auto part_region = [&](uint32_t t) { return body.parts[size_t(body.part_of_triangle[t])].region; };

  SUBCASE("PLAUS-LIMB-PIECES: the middle of the left arm given to the torso") {
    sc::Segmentation s = truth;
    for (uint32_t t = 0; t < s.triangle_regions.size(); ++t)
      if (s.triangle_regions[t] == kLeftArm && body.along_part[t] > 0.35 && body.along_part[t] < 0.65) s.triangle_regions[t] = kTorso;
    const auto f = sc::CheckPlausibility(body.mesh, s, nullptr, nullptr);
    CHECK_MESSAGE(Has(f, "PLAUS-LIMB-PIECES"), Codes(f));
  }
  SUBCASE("PLAUS-LIMB-DETACHED: the left arm's upper half labelled right arm") {
    sc::Segmentation s = truth;
    for (uint32_t t = 0; t < s.triangle_regions.size(); ++t)
      if (s.triangle_regions[t] == kLeftArm && body.along_part[t] < 0.5) s.triangle_regions[t] = uint8_t(sc::Region::kRightArm);
    const auto f = sc::CheckPlausibility(body.mesh, s, nullptr, nullptr);
    CHECK_MESSAGE(Has(f, "PLAUS-LIMB-DETACHED"), Codes(f));
  }
  SUBCASE("PLAUS-LIMB-BALANCE: only the left hand left in the left arm") {
    sc::Segmentation s = truth;
    for (uint32_t t = 0; t < s.triangle_regions.size(); ++t)
      if (s.triangle_regions[t] == kLeftArm && body.along_part[t] < 0.85) s.triangle_regions[t] = kTorso;
    const auto f = sc::CheckPlausibility(body.mesh, s, nullptr, nullptr);
    CHECK_MESSAGE(Has(f, "PLAUS-LIMB-BALANCE"), Codes(f));
    CHECK(!Has(f, "PLAUS-LIMB-PIECES"));
  }
  SUBCASE("PLAUS-HEAD-IN-LIMB: the head and neck put into the left arm (the issue's 45-degree character)") {
    sc::Segmentation s = truth;
    double top = -1e300;
    for (uint32_t v = 0; v < body.mesh.vertex_count(); ++v) top = std::max(top, double(body.mesh.positions[3 * v + 1]));
    for (uint32_t t = 0; t < s.triangle_regions.size(); ++t) {
      double y = 0;
      for (int k = 0; k < 3; ++k) y += body.mesh.positions[3 * body.mesh.indices[3 * t + k] + 1] / 3.0;
      if (part_region(t) == sc::Region::kTorso && y > top - 0.25) s.triangle_regions[t] = kLeftArm;
    }
    const auto f = sc::CheckPlausibility(body.mesh, s, nullptr, nullptr);
    CHECK_MESSAGE(Has(f, "PLAUS-HEAD-IN-LIMB"), Codes(f));
  }
  SUBCASE("PLAUS-TRUNK-AXIS: the body lying along X with Y still up") {
    sc::Mesh lying = body.mesh;
    for (uint32_t v = 0; v < lying.vertex_count(); ++v) {
      const float x = lying.positions[3 * v], y = lying.positions[3 * v + 1];
      lying.positions[3 * v] = y;  // -90 degrees about Z: the head points +X
      lying.positions[3 * v + 1] = -x;
    }
    const auto f = sc::CheckPlausibility(lying, truth, nullptr, nullptr);
    CHECK_MESSAGE(Has(f, "PLAUS-TRUNK-AXIS"), Codes(f));
  }
  SUBCASE("PLAUS-OUTSIDE and PLAUS-SEG-AGREE: bounds on the given measures") {
    sc::CoverageStats cov;
    cov.protrusion = 0.5;
    sc::SegmentationAgreement agree;
    agree.triangle_fraction = 0.3;
    const auto f = sc::CheckPlausibility(body.mesh, truth, &cov, &agree);
    CHECK(Has(f, "PLAUS-OUTSIDE"));
    CHECK(Has(f, "PLAUS-SEG-AGREE"));
    CHECK(f.size() == 2);
    cov.protrusion = 0.34;
    agree.triangle_fraction = 0.61;
    CHECK(sc::CheckPlausibility(body.mesh, truth, &cov, &agree).empty());
  }
}

TEST_CASE("plausibility (heavy): the real humans pass by rig, a non-human X file segmented by geometry does not") {
  struct Case {
    std::string path;
    sc::SegmentMethod method;
    bool plausible;
  };
  const std::vector<Case> cases = {
      {SharedData("gltf/CesiumMan.gltf"), sc::SegmentMethod::kRig, true},
      {spherechain::test::AssimpModel("X/BCN_Epileptic.X"), sc::SegmentMethod::kRig, true},
      {spherechain::test::AssimpModel("Collada/human.zae"), sc::SegmentMethod::kGeometry, true},
      {spherechain::test::AssimpModel("IQM/mrfixit.iqm"), sc::SegmentMethod::kGeometry, true},
      // A spaceship-like trueSpace scene the geometric method takes for a body: legs of 108 and 414 triangles.
      {spherechain::test::AssimpModel("X/fromtruespace_bin32.x"), sc::SegmentMethod::kGeometry, false},
  };
  spherechain::test::SomeInputs inputs;
  for (const Case& c : cases) {
    CAPTURE(c.path);
    if (!inputs.Found(c.path)) continue;
    auto mesh = sc::ImportMesh(c.path);
    REQUIRE_MESSAGE(mesh.ok(), (mesh.ok() ? "" : mesh.error().message));
    auto seg = sc::Segment(mesh.value(), c.method);
    REQUIRE_MESSAGE(seg.ok(), (seg.ok() ? "" : seg.error().message));
    const auto f = sc::CheckPlausibility(mesh.value(), seg.value(), nullptr, nullptr);
    MESSAGE(c.path << " (" << seg->method << "): " << Codes(f));
    CHECK(f.empty() == c.plausible);
  }
}
