// The game-character formats read through assimp (import.h kSupportedExtensions: zae, iqm, smd,
// md5mesh, ms3d, b3d) on Debian's assimp-testmodels, what the bake makes of each, and the confinement
// of assimp's file access to the input's folder.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "spherechain/baker/bake.h"
#include "spherechain/import/import.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::baker;
namespace fs = std::filesystem;

TEST_CASE("import formats: every character format of assimp-testmodels imports, with its skin where it has one") {
  struct Case {
    const char* rel;
    const char* format;
    bool skinned;
  };
  // human.zae and mrfixit.iqm come without bones through assimp 5.2 (static meshes); the SMD and MD5
  // files carry a skeleton.
  test::SomeInputs inputs;
  for (const Case& c : {Case{"Collada/human.zae", "zae", false}, Case{"IQM/mrfixit.iqm", "iqm", false},
                        Case{"SMD/WusonSMD.smd", "smd", true}, Case{"B3D/WusonBlitz.b3d", "b3d", false},
                        Case{"MS3D/Wuson.ms3d", "ms3d", false}, Case{"MD5/SimpleCube.md5mesh", "md5mesh", true}}) {
    CAPTURE(c.rel);
    const std::string path = test::AssimpModel(c.rel);
    if (!inputs.Found(path)) continue;
    auto r = ImportMesh(path);
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
    CHECK(r->source_format == c.format);
    CHECK(r->triangle_count() > 0);
    CHECK(r->vertex_count() > 0);
    if (c.skinned) {
      REQUIRE(r->skin.has_value());
      CHECK(!r->skin->joints.empty());
      CHECK(r->skin->weight_offsets.size() == r->vertex_count() + 1);
    }
  }
}

TEST_CASE("import formats: a Blender file stands along +Z (Blender's world axis, which assimp keeps)") {
  const std::string path = test::AssimpModel("BLEND/HUMAN.blend");
  if (!test::Require(path)) return;
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->up_axis == UpAxis::kZ);
  // Known answer: the body's extent along z (its height) is the largest, about 2.3 times its width.
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < r->positions.size(); ++i)
    lo[i % 3] = std::min(lo[i % 3], r->positions[i]), hi[i % 3] = std::max(hi[i % 3], r->positions[i]);
  CHECK(hi[2] - lo[2] > 2.0f * (hi[0] - lo[0]));
  CHECK(hi[2] - lo[2] > 5.0f * (hi[1] - lo[1]));
}

// "heavy": three real bakes (the ASan half of CI skips it; it runs once, in the normal suite).
TEST_CASE("import formats (heavy): the three humans bake, the creatures and the cube are refused with the reason") {
  test::SomeInputs inputs;
  for (const char* rel : {"Collada/human.zae", "IQM/mrfixit.iqm", "BLEND/HUMAN.blend"}) {
    CAPTURE(rel);
    const std::string path = test::AssimpModel(rel);
    if (!inputs.Found(path)) continue;
    auto r = Bake(path, BakeConfig{});
    REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
    CHECK(r->fit.spheres.size() <= 128);
    CHECK(r->chains.size() == 6);
    CHECK(r->unassigned_triangles == 0);
    CHECK(r->segmentation.method == "geometry");  // no skin: segmented from the shape alone
    CHECK(!r->centre_weights.has_value());       // and no joint refit
  }
  // Not standing bodies, and no creature either (the any-skeleton path names why: no rig, one bone).
  const std::pair<const char*, const char*> refused[] = {
      {"SMD/WusonSMD.smd", "no recognisable limbs: the skin uses 1 bone (root)"},
      {"B3D/WusonBlitz.b3d", "the mesh has no skin"},
      {"MS3D/Wuson.ms3d", "the mesh has no skin"},
      {"MD5/SimpleCube.md5mesh", "segment (skeleton): "}};
  for (const auto& [rel, why] : refused) {
    CAPTURE(rel);
    const std::string path = test::AssimpModel(rel);
    if (!inputs.Found(path)) continue;
    auto r = Bake(path, BakeConfig{});
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("not a standing body") != std::string::npos);
    CHECK_MESSAGE(r.error().message.find(why) != std::string::npos, r.error().message);
  }
}

TEST_CASE("import formats: assimp reads nothing outside the input's folder (an MD5 animation linked from outside)") {
  const std::string cube = test::AssimpModel("MD5/SimpleCube.md5mesh");
  if (!test::Require(cube)) return;
  const fs::path root = fs::temp_directory_path() / ("spherechain_import_formats." + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "model");
  fs::create_directories(root / "elsewhere");
  fs::copy_file(cube, root / "model" / "cube.md5mesh");
  // The MD5 importer looks for <name>.md5anim beside the mesh; this one is a link to a file outside.
  std::ofstream(root / "elsewhere" / "secret.md5anim") << "MD5Version 10\n";
  fs::create_symlink(root / "elsewhere" / "secret.md5anim", root / "model" / "cube.md5anim");
  std::vector<std::string> warnings;
  Context ctx;
  ctx.sink = [&](Context::Level level, const std::string& m) {
    if (level == Context::Level::kWarn) warnings.push_back(m);
  };
  auto r = ImportMesh((root / "model" / "cube.md5mesh").string(), ImportOptions{}, &ctx);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));  // the mesh itself is inside: it imports
  bool refused = false;
  for (const std::string& w : warnings)
    refused = refused || (w.find("cube.md5anim") != std::string::npos && w.find("outside the input's folder") != std::string::npos);
  CHECK_MESSAGE(refused, "expected a warning that cube.md5anim (a link out of the folder) was refused");
  CHECK(r->clips.empty());
  fs::remove_all(root);
}
