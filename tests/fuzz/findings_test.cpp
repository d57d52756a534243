// What fuzzing the importers and the bake configuration turned up (fuzz/README.md "Findings"), each as the
// smallest input that shows it and the documented failure it must get now: an error with the documented code
// and a message naming the problem — never a crash, a hang or an allocation the file does not pay for.
#include <doctest/doctest.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "spherechain/baker/fit.h"
#include "spherechain/baker/segment.h"
#include "spherechain/import/import.h"

#include "../../fuzz/bake_sequence.h"

namespace {

namespace fs = std::filesystem;
using spherechain::import::Error;
using spherechain::import::ImportMesh;
using spherechain::import::ImportOptions;

struct Dir {
  fs::path dir;
  Dir() {
    // One folder per process: ctest runs each test case as its own process, in parallel.
    dir = fs::temp_directory_path() / ("spherechain_fuzz_findings_test." + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "rig");
  }
  ~Dir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string Write(const std::string& rel, const std::string& bytes) const {
    std::ofstream(dir / rel, std::ios::binary) << bytes;
    return (dir / rel).string();
  }
};

std::string Nested(size_t depth) { return std::string(depth, '[') + std::string(depth, ']'); }

/// The bytes of a fuzzer's corpus file, fuzz/corpus/TARGET/NAME.
std::string CorpusFile(const std::string& target, const std::string& name) {
  std::ifstream in(fs::path(SPHERECHAIN_SOURCE_DIR) / "fuzz/corpus" / target / name, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A file of the assimp fuzzer's corpus (fuzz/corpus/import_assimp/NAME) as the file it stands for: its first
/// byte, which picks the fuzzer's format, dropped.
std::string AssimpCorpusFile(const std::string& name) {
  const std::string bytes = CorpusFile("import_assimp", name);
  REQUIRE_MESSAGE(bytes.size() > 1, name);
  return bytes.substr(1);
}

/// A glTF of one triangle (positions in data.bin beside it: 3 × float3, then 3 uint32 indices), with `extra`
/// spliced into the root object (accessor / bufferView overrides go in by replacing the defaults below).
struct Gltf {
  std::string position_accessor = R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"})";
  std::string index_accessor = R"({"bufferView":1,"componentType":5125,"count":3,"type":"SCALAR"})";
  std::string views = R"([{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12}])";
  std::string nodes = R"([{"mesh":0}])";
  std::string scene_nodes = "[0]";
  std::string extra;  // e.g. "\"extras\": ..., "
  std::string Json() const {
    return "{" + extra + R"("asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":)" + scene_nodes +
           R"(}],"nodes":)" + nodes + R"(,"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)" +
           R"("accessors":[)" + position_accessor + "," + index_accessor + R"(],"bufferViews":)" + views +
           R"(,"buffers":[{"uri":"data.bin","byteLength":48}]})";
  }
};

std::string TriangleBin() {
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t i[3] = {0, 1, 2};
  return std::string(reinterpret_cast<const char*>(v), sizeof v) + std::string(reinterpret_cast<const char*>(i), sizeof i);
}

/// Imports `gltf` (with data.bin beside it) and returns the error; FAILs when it imports.
Error ImportError(const Dir& d, const std::string& gltf, const ImportOptions& options = {}) {
  d.Write("data.bin", TriangleBin());
  auto r = ImportMesh(d.Write("in.gltf", gltf), options);
  REQUIRE_FALSE(r.ok());
  return r.error();
}

}  // namespace

TEST_CASE("Fuzz findings: the triangle glTF of these tests imports as is") {
  Dir d;
  d.Write("data.bin", TriangleBin());
  auto r = ImportMesh(d.Write("in.gltf", Gltf().Json()));
  REQUIRE(r.ok());
  CHECK(r->triangle_count() == 1);
}

TEST_CASE("Fuzz findings: a glTF nested deeper than 64 levels is refused before tinygltf recurses into it") {
  // tinygltf turns "extras" into its Value type by recursion: 30,000 levels overflowed the stack inside it.
  Dir d;
  Gltf g;
  g.extra = "\"extras\": " + Nested(30000) + ",";
  Error e = ImportError(d, g.Json());
  CHECK(e.code == Error::Code::kFormat);
  CHECK(e.message.find("nests deeper than 64 levels") != std::string::npos);
  // Brackets inside strings do not count, and 60 real levels are fine.
  g.extra = "\"extras\": [\"" + std::string(500, '[') + "\", " + Nested(60) + "],";
  d.Write("data.bin", TriangleBin());
  CHECK(ImportMesh(d.Write("ok.gltf", g.Json())).ok());
}

TEST_CASE("Fuzz findings: a GLB whose JSON chunk nests too deep is refused the same way") {
  Dir d;
  Gltf g;
  g.extra = "\"extras\": " + Nested(30000) + ",";
  std::string json = g.Json();
  json.resize((json.size() + 3) / 4 * 4, ' ');
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::string glb = "glTF" + u32(2) + u32(uint32_t(20 + json.size())) + u32(uint32_t(json.size())) + "JSON" + json;
  d.Write("data.bin", TriangleBin());
  auto r = ImportMesh(d.Write("in.glb", glb));
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("nests deeper than 64 levels") != std::string::npos);
}

TEST_CASE("Fuzz findings: glTF offsets and counts that overflow are kFormat, never a read outside the buffer") {
  Dir d;
  SUBCASE("a bufferView offset near 2^64 (offset + length wrapped round to pass the old check)") {
    Gltf g;
    g.views = R"([{"buffer":0,"byteOffset":18446744073709551600,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12}])";
    CHECK(ImportError(d, g.Json()).message.find("runs past its buffer") != std::string::npos);
  }
  SUBCASE("an accessor offset past its view") {
    Gltf g;
    g.position_accessor = R"({"bufferView":0,"byteOffset":18446744073709551600,"componentType":5126,"count":3,"type":"VEC3"})";
    CHECK(ImportError(d, g.Json()).message.find("run past their bufferView") != std::string::npos);
  }
  SUBCASE("a count of 2^60 elements in a 36-byte view: refused before the memory is taken") {
    Gltf g;
    g.position_accessor = R"({"bufferView":0,"componentType":5126,"count":1152921504606846976,"type":"VEC3"})";
    CHECK(ImportError(d, g.Json()).message.find("run past their bufferView") != std::string::npos);
  }
  SUBCASE("an accessor without a bufferView (zeros) of a billion elements") {
    Gltf g;
    g.position_accessor = R"({"componentType":5126,"count":1000000000,"type":"VEC3"})";
    const Error e = ImportError(d, g.Json());
    CHECK(e.code == Error::Code::kFormat);
    CHECK(e.message.find("elements without a bufferView, over the limit") != std::string::npos);
  }
  SUBCASE("a negative sparse count, float sparse indices") {
    Gltf g;
    g.position_accessor = R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","sparse":{"count":-5,)"
                          R"("indices":{"bufferView":1,"componentType":5125},"values":{"bufferView":0}}})";
    CHECK(ImportError(d, g.Json()).message.find("sparse count out of range") != std::string::npos);
    g.position_accessor = R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","sparse":{"count":1,)"
                          R"("indices":{"bufferView":0,"componentType":5126},"values":{"bufferView":0}}})";
    CHECK(ImportError(d, g.Json()).message.find("sparse indices are not unsigned integers") != std::string::npos);
  }
}

TEST_CASE("Fuzz findings: glTF indices that are not whole numbers in range are refused, not converted") {
  // Converting -1, 1.5, NaN or 1e30 from double to an unsigned integer is undefined behaviour (UBSan); float
  // indices are not glTF, but tinygltf reads them.
  Dir d;
  Gltf g;
  g.index_accessor = R"({"bufferView":1,"componentType":5126,"count":3,"type":"SCALAR"})";
  auto with_indices = [&](float a, float b, float c) {
    const float i[3] = {a, b, c};
    d.Write("data.bin", TriangleBin().substr(0, 36) + std::string(reinterpret_cast<const char*>(i), sizeof i));
    return ImportMesh(d.Write("in.gltf", g.Json()));
  };
  CHECK(with_indices(0, 1, 2).ok());  // whole numbers: read as vertex numbers
  for (const float bad : {-1.0f, 1.5f, std::numeric_limits<float>::quiet_NaN(), 1e30f}) {
    CAPTURE(bad);
    auto r = with_indices(bad, 1, 2);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().code == Error::Code::kFormat);
    CHECK(r.error().message.find("indices: index 0 is ") != std::string::npos);
    CHECK(r.error().message.find(", not a vertex number") != std::string::npos);
  }
}

TEST_CASE("Fuzz findings: a mesh instanced past ImportOptions::max_vertices is refused while importing") {
  Dir d;
  Gltf g;
  g.nodes = "[";
  g.scene_nodes = "[";
  for (int n = 0; n < 50; ++n) {
    g.nodes += std::string(n ? "," : "") + R"({"mesh":0})";
    g.scene_nodes += std::string(n ? "," : "") + std::to_string(n);
  }
  g.nodes += "]";
  g.scene_nodes += "]";
  ImportOptions o;
  o.max_vertices = 100;  // 50 instances × 3 vertices = 150
  const Error e = ImportError(d, g.Json(), o);
  CHECK(e.code == Error::Code::kInvalidMesh);
  CHECK(e.message.find("vertices, over the limit of 100") != std::string::npos);
  d.Write("data.bin", TriangleBin());
  CHECK(ImportMesh(d.Write("in.gltf", g.Json())).ok());  // the default limits: 150 vertices
}

TEST_CASE("Fuzz findings: a MakeHuman rig's deep value is named briefly, and its weights_file stays beside it") {
  Dir d;
  const std::string obj = d.Write("body.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ng body\nf 1 2 3\n");
  ImportOptions o;
  // nlohmann's dump() recursed once per level printing the bad entry: 30,000 levels overflowed the stack.
  o.rig_path = d.Write("rig/deep.mhskel", R"({"bones":{},"joints":{"j":[)" + Nested(30000) + "]}}");
  auto r = ImportMesh(obj, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CHECK(r.error().message.find("joint 'j' lists vertex an array of 1, the OBJ has 3") != std::string::npos);
  // A skeleton's weights_file is data: it may not lead out of the skeleton's folder.
  d.Write("secret.mhw", R"({"weights":{}})");
  o.rig_path = d.Write("rig/out.mhskel", R"({"bones":{"root":{"head":"h"}},"joints":{"h":[0]},"weights_file":"../secret.mhw"})");
  r = ImportMesh(obj, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CHECK(r.error().message.find("is outside the skeleton's folder") != std::string::npos);
  d.Write("rig/in.mhw", R"({"weights":{"root":[[0,1],[1,1],[2,1]]}})");
  o.rig_path = d.Write("rig/in.mhskel", R"({"bones":{"root":{"head":"h"}},"joints":{"h":[0]},"weights_file":"in.mhw"})");
  CHECK(ImportMesh(obj, o).ok());
}

TEST_CASE("Fuzz findings: a region map's deep entry is named briefly (kConfig), not printed whole") {
  Dir d;
  spherechain::import::Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  mesh.indices = {0, 1, 2};
  const std::string map = d.Write("map.json", R"({"triangle_regions":[)" + Nested(30000) + "]}");
  auto seg = spherechain::baker::SegmentByMap(mesh, map);
  REQUIRE_FALSE(seg.ok());
  CHECK(seg.error().code == Error::Code::kConfig);
  CHECK(seg.error().message.find("triangle_regions[0] = an array of 1 is not a region") != std::string::npos);
  // The configuration fuzzer's own input (fuzz/corpus/bake_config/: the configuration, a NUL, the region map of
  // the fixed body, FixedBodyPath()), whose map nests under vertex_regions.
  auto body = ImportMesh(spherechain::fuzz::FixedBodyPath());
  REQUIRE(body.ok());
  const std::string bytes = CorpusFile("bake_config", "crash_dump_deep_region_map.json");
  const size_t nul = bytes.find('\0');
  REQUIRE(nul != std::string::npos);
  auto found = spherechain::baker::SegmentByMap(body.value(), d.Write("found.json", bytes.substr(nul + 1)));
  REQUIRE_FALSE(found.ok());
  CHECK(found.error().code == Error::Code::kConfig);
  CAPTURE(found.error().message);
  CHECK(found.error().message.find("vertex_regions[0] = an array of 1 is not a region") != std::string::npos);
  CHECK(found.error().message.size() < 400);
}

TEST_CASE("Fuzz findings: GLBs that broke segmentation are refused with both segmentations' reasons (kSegmentation)") {
  // fuzz_import_gltf, each file as the fuzzer kept it (fuzz/corpus/import_gltf/): each imports, and the automatic
  // segmentation refuses it with the geometry's reason and then the skeleton's.
  struct Case {
    const char* file;
    const char* geometry;  // the geometric segmentation's reason
    const char* skeleton;  // the any-skeleton path's reason
  };
  const Case cases[] = {
      // The creature with its mesh's node among the joints and the bone tree's root left out: the trunk's top bone
      // is a root, and the surface of "the tree above the trunk" was read at index -1 (ASan, UBSan).
      {"crash_segment_skeleton_two_trees.glb", "the bottom of the mesh does not split into two legs",
       "no recognisable limbs: the trunk's bones (node0) dominate no triangle"},
      // 8·10^9 times wider than tall: the T-pose search converted its slab count to int (UBSan).
      {"crash_segment_geometry_slab_overflow.glb", "two arms were not found",
       "no recognisable limbs: the skin uses 2 bones (node0, node8)"},
      // Positions far from the origin against the mesh's size: the weld's cell keys overflowed int64 (UBSan).
      {"crash_weld_key_overflow.glb", "the bottom of the mesh does not split into two legs",
       "no recognisable limbs: the skin uses 1 bone (body)"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.file);
    auto mesh = ImportMesh((fs::path(SPHERECHAIN_SOURCE_DIR) / "fuzz/corpus/import_gltf" / c.file).string());
    REQUIRE_MESSAGE(mesh.ok(), (mesh.ok() ? "" : mesh.error().message));
    auto seg = spherechain::baker::Segment(mesh.value(), spherechain::baker::SegmentMethod::kAuto);
    REQUIRE_FALSE(seg.ok());
    const std::string& m = seg.error().message;
    CAPTURE(m);
    CHECK(seg.error().code == Error::Code::kSegmentation);
    CHECK(m.rfind("segment (geometry): not a standing body: ", 0) == 0);
    CHECK(m.find(c.geometry) != std::string::npos);
    CHECK(m.find(std::string("segment (skeleton): ") + c.skeleton) != std::string::npos);
  }
}

TEST_CASE("Fuzz findings: a PLY on which assimp never returns is stopped in its child process (kFormat)") {
  // fuzz_import_assimp: an ASCII PLY header followed by binary FBX bytes; assimp's PLY reader ran for minutes.
  const std::string file = AssimpCorpusFile("timeout_assimp_ply_loop.ply");
  Dir d;
  ImportOptions o;
  o.assimp_seconds = 2.0;
  const auto t0 = std::chrono::steady_clock::now();
  auto r = ImportMesh(d.Write("loop.ply", file), o);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CHECK(r.error().message.find("assimp did not finish reading it within 2 s (its process was stopped)") != std::string::npos);
  CHECK(took < 10.0);
}

TEST_CASE("Fuzz findings: a PLY on which assimp's reader crashes is a kFormat error naming the signal") {
  // fuzz_import_assimp: a 134-byte ASCII PLY with a mangled property line; assimp's PLY reader dereferences
  // null (SIGSEGV inside libassimp). In its child process the crash ends the child only.
  const std::string file = AssimpCorpusFile("crash_assimp_ply_segv.ply");
  Dir d;
  auto r = ImportMesh(d.Write("crash.ply", file));
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CAPTURE(r.error().message);
  CHECK(r.error().message.find("the assimp importer's process died reading it (signal 11") != std::string::npos);
  CHECK(r.error().message.find("crash.ply") != std::string::npos);
}

TEST_CASE("Fuzz findings: assimp in its child process gives the same mesh, skin and clips as in this one") {
  // Every assimp seed of the fuzz corpus (the first byte picks the format), and BCN_Epileptic (skinned, a clip).
  // Also crash_child_*: fuzz_import_assimp, 30 November, an 83-byte SMD (one bone, a triangle, no weights) whose
  // empty weight list, decoded from the child's answer, passed a null data() to memcpy (UBSan: null pointer
  // argument; this case aborts under the ASan + UBSan suite without the fix). It must cross whole.
  std::vector<std::pair<std::string, std::string>> files;  // (name, bytes)
  const char* formats[] = {"fbx", "dae", "x", "blend", "3ds", "ply", "stl", "iqm", "smd", "md5mesh", "ms3d", "b3d"};
  for (const auto& e : fs::directory_iterator(fs::path(SPHERECHAIN_SOURCE_DIR) / "fuzz/corpus/import_assimp")) {
    std::ifstream in(e.path(), std::ios::binary);
    const std::string b{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string name = e.path().filename().string();
    if (b.size() > 1 && (name.rfind("assimp_", 0) == 0 || name.rfind("crash_child_", 0) == 0))
      files.emplace_back(std::string("in.") + formats[uint8_t(b[0]) % 12], b.substr(1));
  }
  const fs::path bcn = fs::path(SPHERECHAIN_ASSIMP_MODELS_DIR) / "X/BCN_Epileptic.X";
  if (fs::exists(bcn)) {
    std::ifstream in(bcn, std::ios::binary);
    files.emplace_back("bcn.x", std::string{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()});
  }
  REQUIRE(files.size() >= 20);
  Dir d;
  size_t compared = 0;
  for (const auto& [name, bytes] : files) {
    CAPTURE(name);
    const std::string path = d.Write(name, bytes);
    ImportOptions here;
    here.isolate_assimp = false;
    spherechain::import::Context ctx_child, ctx_here;
    auto a = ImportMesh(path, {}, &ctx_child);
    auto b = ImportMesh(path, here, &ctx_here);
    REQUIRE(a.ok() == b.ok());
    CHECK(ctx_child.files_read == ctx_here.files_read);
    if (!a.ok()) {
      CHECK(a.error().message == b.error().message);
      continue;
    }
    ++compared;
    CHECK(a->positions == b->positions);
    CHECK(a->indices == b->indices);
    CHECK(a->parts.size() == b->parts.size());
    CHECK(a->up_axis == b->up_axis);
    CHECK(a->units == b->units);
    CHECK(a->vertex_contract == b->vertex_contract);
    CHECK(a->source_vertex_count == b->source_vertex_count);
    CHECK(a->joined_vertex_count == b->joined_vertex_count);
    REQUIRE(a->skin.has_value() == b->skin.has_value());
    if (a->skin) {
      CHECK(a->skin->nodes.size() == b->skin->nodes.size());
      for (size_t n = 0; n < a->skin->nodes.size(); ++n) CHECK(a->skin->nodes[n].name == b->skin->nodes[n].name);
      CHECK(a->skin->weights == b->skin->weights);
      CHECK(a->skin->weight_joints == b->skin->weight_joints);
      CHECK(a->skin->joints.size() == b->skin->joints.size());
    }
    REQUIRE(a->clips.size() == b->clips.size());
    for (size_t c = 0; c < a->clips.size(); ++c) {
      CHECK(a->clips[c].name == b->clips[c].name);
      REQUIRE(a->clips[c].channels.size() == b->clips[c].channels.size());
      for (size_t k = 0; k < a->clips[c].channels.size(); ++k) CHECK(a->clips[c].channels[k].values == b->clips[c].channels[k].values);
    }
  }
  CHECK(compared >= 20);
}

TEST_CASE("Fuzz findings: a body lying down is fitted within the bipeds' voxel budget, not on millions of voxels") {
  // fuzz_import_assimp: a 228-triangle ASCII STL, segmented as a T-pose biped whose trunk lies horizontal. A
  // biped's voxels scale with its height, which for this body is its thickness: at the default 1/200 it has
  // 3.1 million interior voxels (MakeHuman 95,000) and its fit took 6 minutes. Bipeds now get a budget too,
  // FitParams::kBipedVoxelFactor × cover_max_voxels; here scaled down (voxels 1/20 of the height, a budget of
  // 4 × 500) so that the test is quick: about 3,000 voxels at that size, voxelised coarser under 2,000.
  const std::string file = AssimpCorpusFile("slow_fit_lying_body.stl");
  Dir d;
  auto mesh = ImportMesh(d.Write("lying.stl", file));
  REQUIRE(mesh.ok());
  auto seg = spherechain::baker::Segment(mesh.value(), spherechain::baker::SegmentMethod::kAuto);
  REQUIRE(seg.ok());
  REQUIRE(seg->layout.paper);  // segmented as a biped: the layout the budget used to skip
  spherechain::baker::FitParams p;
  p.cover_voxel_rel = 0.05;
  p.cover_max_voxels = 500;
  p.max_spheres = 32;
  std::vector<std::string> lines;
  spherechain::import::Context ctx;
  ctx.sink = [&](spherechain::import::Context::Level, const std::string& m) { lines.push_back(m); };
  auto fit = spherechain::baker::FitSpheres(mesh.value(), seg.value(), p, &ctx);
  REQUIRE(fit.ok());
  CHECK_FALSE(fit->spheres.empty());
  const uint32_t budget = uint32_t(p.cover_max_voxels) * spherechain::baker::FitParams::kBipedVoxelFactor;
  bool over = false;
  long fitted_voxels = -1;
  for (const std::string& m : lines) {
    CAPTURE(m);
    over = over || m.find("over the budget " + std::to_string(budget) + " (cover_max_voxels × ") != std::string::npos;
    if (const size_t at = m.find(" candidates over "); at != std::string::npos) fitted_voxels = std::stol(m.substr(at + 17));
  }
  CHECK(over);  // voxelised again, coarser
  CHECK(fitted_voxels > 0);
  CHECK(fitted_voxels <= long(budget));
}
