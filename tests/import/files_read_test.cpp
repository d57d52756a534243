// import: the files a read opened (Context::files_read, what `bake --depfile` lists) for every importer —
// glTF with its external buffer and image, an embedded glTF, OBJ, the MakeHuman rig, assimp formats — and the
// depfile text (MakeDepfile: Make's escaping of spaces, '#' and '$').
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "spherechain/import/file_io.h"
#include "spherechain/import/import.h"
#include "test_data.h"

namespace {

using spherechain::import::Context;
using spherechain::import::ImportMesh;
using spherechain::import::MakeDepfile;
namespace fs = std::filesystem;
namespace test = spherechain::test;

/// A folder of its own per process (ctest runs the cases in parallel), with Make's special characters in
/// its name.
struct FilesDir {
  fs::path dir;
  FilesDir() {
    dir = fs::temp_directory_path() / ("spherechain files read #1 $x." + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~FilesDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string Write(const std::string& rel, const std::string& bytes) const {
    std::ofstream(dir / rel, std::ios::binary) << bytes;
    return (dir / rel).string();
  }
};

/// One-triangle glTF: its buffer in `buffer_uri`, and an image `image_uri` (never decoded) when not empty.
std::string TriangleGltf(const std::string& buffer_uri, const std::string& image_uri = "") {
  std::string images = image_uri.empty() ? "" : R"(,"images":[{"uri":")" + image_uri + R"("}])";
  return R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"scene":0,"nodes":[{"mesh":0}],)"
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],)"
         R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":")" +
         buffer_uri + R"(","byteLength":36}])" + images + "}";
}

std::string TriangleBytes() {
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  return std::string(reinterpret_cast<const char*>(v), sizeof v);
}

/// The absolute, lexically normal form Context::RecordFileRead stores.
std::string Abs(const std::string& p) { return fs::absolute(p).lexically_normal().string(); }

std::vector<std::string> FilesRead(const std::string& path, const spherechain::import::ImportOptions& options = {}) {
  Context ctx;
  auto mesh = ImportMesh(path, options, &ctx);
  REQUIRE_MESSAGE(mesh.ok(), (mesh.ok() ? "" : mesh.error().message));
  return ctx.files_read;
}

}  // namespace

TEST_CASE("Files read: a glTF's external buffer and image, each once, absolute") {
  FilesDir d;
  d.Write("tri.bin", TriangleBytes());
  d.Write("skin.png", "not decoded, only read");
  const std::string gltf = d.Write("tri.gltf", TriangleGltf("tri.bin", "skin.png"));
  CHECK(FilesRead(gltf) == std::vector<std::string>{Abs(gltf), Abs(d.dir / "tri.bin"), Abs(d.dir / "skin.png")});

  // Relative paths are recorded absolute (against the current directory) and normal.
  const fs::path cwd = fs::current_path();
  fs::current_path(d.dir);
  const std::vector<std::string> rel = FilesRead("./tri.gltf");
  fs::current_path(cwd);
  CHECK(rel == std::vector<std::string>{Abs(d.dir / "tri.gltf"), Abs(d.dir / "tri.bin"), Abs(d.dir / "skin.png")});
}

TEST_CASE("Files read: a buffer refused for leaving the folder is not recorded; a failed import keeps what it read") {
  FilesDir d;
  fs::create_directories(d.dir / "sub");
  d.Write("data.bin", TriangleBytes());
  const std::string gltf = d.Write("sub/escape.gltf", TriangleGltf("../data.bin"));
  Context ctx;
  CHECK(!ImportMesh(gltf, {}, &ctx).ok());
  CHECK(ctx.files_read == std::vector<std::string>{Abs(gltf)});

  Context ctx2;
  const std::string truncated = d.Write("truncated.gltf", R"({"asset": {"version": "2.0"}, "meshes": [)");
  CHECK(!ImportMesh(truncated, {}, &ctx2).ok());
  CHECK(ctx2.files_read == std::vector<std::string>{Abs(truncated)});

  Context ctx3;
  CHECK(!ImportMesh((d.dir / "missing.obj").string(), {}, &ctx3).ok());
  CHECK(ctx3.files_read.empty());
}

TEST_CASE("Files read: an OBJ, and MakeHuman's base.obj with its rig and weights") {
  FilesDir d;
  const std::string obj = d.Write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CHECK(FilesRead(obj) == std::vector<std::string>{Abs(obj)});

  const std::string base = test::SharedData("makehuman/base.obj");
  if (!test::Require(base)) return;
  const fs::path mh = fs::path(base).parent_path();
  CHECK(FilesRead(base) ==
        std::vector<std::string>{Abs(base), Abs(mh / "default.mhskel"), Abs(mh / "default_weights.mhw")});
}

TEST_CASE("Files read: glTF files of the sample models (embedded CesiumMan; BoxTextured's .bin and .png)") {
  test::SomeInputs inputs;
  const std::string cesium = test::SharedData("gltf/CesiumMan.gltf");  // buffer and image are data: URIs
  if (inputs.Found(cesium)) CHECK(FilesRead(cesium) == std::vector<std::string>{Abs(cesium)});
  const std::string box = test::AssimpModel("glTF2/BoxTextured-glTF/BoxTextured.gltf");
  if (inputs.Found(box)) {
    const fs::path dir = fs::path(box).parent_path();
    CHECK(FilesRead(box) ==
          std::vector<std::string>{Abs(box), Abs(dir / "BoxTextured0.bin"), Abs(dir / "CesiumLogoFlat.png")});
  }
}

TEST_CASE("Files read: what assimp's importers open (X, Collada archive, IQM, Blender)") {
  test::SomeInputs inputs;
  // Each of these is one file: assimp opens the input (more than once: the result lists it once) and nothing
  // beside it (textures are named, not read).
  for (const char* rel : {"X/BCN_Epileptic.X", "X/Testwuson.X", "Collada/human.zae", "IQM/mrfixit.iqm", "BLEND/HUMAN.blend"}) {
    const std::string path = test::AssimpModel(rel);
    CAPTURE(path);
    if (!inputs.Found(path)) continue;
    CHECK(FilesRead(path) == std::vector<std::string>{Abs(path)});
  }
}

TEST_CASE("MakeDepfile: Make's rule and escaping (gcc -MD -MP)") {
  auto d = MakeDepfile("out/a.sphc", {"/in/man.gltf", "/in/man.bin"});
  REQUIRE(d.ok());
  CHECK(d.value() == "out/a.sphc: \\\n /in/man.gltf \\\n /in/man.bin\n\n/in/man.gltf:\n\n/in/man.bin:\n");

  // A space or tab: backslash (the backslashes before it doubled); '#': backslash; '$': doubled.
  auto e = MakeDepfile("my out/a.sphc", {"/a b/c#d/$e.gltf", "/x\\ y/t\tab.obj", "/back\\slash"});
  REQUIRE(e.ok());
  CHECK(e.value() == "my\\ out/a.sphc: \\\n /a\\ b/c\\#d/$$e.gltf \\\n /x\\\\\\ y/t\\\tab.obj \\\n /back\\slash\n"
                     "\n/a\\ b/c\\#d/$$e.gltf:\n\n/x\\\\\\ y/t\\\tab.obj:\n\n/back\\slash:\n");

  // No prerequisites: the rule alone.
  auto f = MakeDepfile("a.sphc", {});
  REQUIRE(f.ok());
  CHECK(f.value() == "a.sphc:\n");

  // A line break cannot be named; neither can an empty path.
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"/a\nb.gltf"}, std::vector<std::string>{"/a\rb"},
                                              std::vector<std::string>{""}}) {
    auto r = MakeDepfile("a.sphc", bad);
    REQUIRE(!r.ok());
    CHECK(r.error().code == spherechain::import::Error::Code::kIo);
  }
  CHECK(!MakeDepfile("a\nb.sphc", {"/x"}).ok());
}

TEST_CASE("Context::RecordFileRead: absolute, lexically normal, each path once in first-read order") {
  Context ctx;
  ctx.RecordFileRead("/a/b/../c.gltf");
  ctx.RecordFileRead("/a/./c.gltf");
  ctx.RecordFileRead("/a/c.bin");
  ctx.RecordFileRead("");
  ctx.RecordFileRead("rel.obj");
  CHECK(ctx.files_read == std::vector<std::string>{"/a/c.gltf", "/a/c.bin", Abs("rel.obj")});
}

TEST_CASE("Context::RecordFileRead: a '..' after a symbolic link to a folder leads to the link target's parent") {
  // real/deep holds nothing; lnk -> real/deep; so lnk/../ is real/, where the glTF and its buffer are. Dropping
  // `lnk/..` by the text named files that do not exist (the depfile) and let an output overwrite a file read.
  FilesDir d;
  fs::create_directories(d.dir / "real" / "deep");
  fs::create_directory_symlink("real/deep", d.dir / "lnk");
  d.Write("real/tri.bin", TriangleBytes());
  d.Write("real/tri.gltf", TriangleGltf("tri.bin"));
  const fs::path real = fs::canonical(d.dir / "real");
  CHECK(FilesRead((d.dir / "lnk" / ".." / "tri.gltf").string()) ==
        std::vector<std::string>{(real / "tri.gltf").string(), (real / "tri.bin").string()});
  // The clash check compares with what was read: a report onto the buffer is refused.
  const std::string report = (d.dir / "lnk" / ".." / "tri.bin").string();
  Context ctx;
  REQUIRE(ImportMesh((d.dir / "lnk" / ".." / "tri.gltf").string(), {}, &ctx).ok());
  const std::string clash = spherechain::import::OutputsClash({{"--report", &report}}, {}, ctx.files_read);
  CHECK(clash.find("is also an input") != std::string::npos);
}

TEST_CASE("OutputFiles::Write never writes through a link planted at its temporary's name") {
  FilesDir d;
  const std::string victim = d.Write("victim.txt", "keep me"), out = (d.dir / "out.json").string();
  // The next temporary of `out` is the one after this one (the process's count goes up by one a call).
  const std::string seen = spherechain::import::TemporaryPathFor(out);
  const size_t dot = seen.rfind('.');
  const std::string next = seen.substr(0, dot + 1) + std::to_string(std::stoull(seen.substr(dot + 1)) + 1);
  fs::create_symlink(victim, next);
  spherechain::import::OutputFiles files;
  REQUIRE(files.Write(out, std::string("new")).ok());
  REQUIRE(files.Commit().ok());
  std::ifstream a(victim), b(out);
  const std::string victim_text((std::istreambuf_iterator<char>(a)), {}), out_text((std::istreambuf_iterator<char>(b)), {});
  CHECK(victim_text == "keep me");
  CHECK(out_text == "new");
  CHECK_FALSE(fs::is_symlink(out));
  std::error_code ec;
  CHECK_FALSE(fs::exists(fs::symlink_status(next, ec)));
}
