// spherechain Python module — the offline side: Asset, load(), bake(), evaluate(). Each calls the library
// function the CLI calls (baker::ApplyBakeOptions + Bake, import::LoadAssetFile, evaluate::DescribeAsset,
// playback::ImportMeshForAsset + OpenAnimation + evaluate::Evaluate), so Python and the CLI give the same
// bytes, JSON and error messages. Long calls release the GIL.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <mutex>
#include <optional>
#include <vector>

#include "common.h"
#include "spherechain/baker/bake.h"
#include "spherechain/evaluate/evaluate.h"
#include "spherechain/evaluate/inspect.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/character.h"

namespace spherechain::python {

namespace fs = std::filesystem;

const AssetPtr& PyAsset::Get() const {
  if (!data) ThrowStatus(runtime::Status::kErrorNullArgument, "the asset is closed");
  return data;
}

namespace {

// ---- logging: the libraries' log lines, collected while the GIL is released, then given to Python's
// logging module (logger "spherechain") --------------------------------------------------------------
struct LogLines {
  std::mutex mutex;
  std::vector<std::pair<import::Context::Level, std::string>> lines;

  import::Context MakeContext() {
    import::Context ctx;
    ctx.sink = [this](import::Context::Level level, const std::string& message) {
      std::lock_guard<std::mutex> lock(mutex);
      lines.emplace_back(level, message);
    };
    return ctx;
  }
  void Emit() {  // with the GIL
    if (lines.empty()) return;
    py::object logger = py::module_::import("logging").attr("getLogger")("spherechain");
    for (const auto& [level, message] : lines) {
      const int py_level = level == import::Context::Level::kWarn ? 30 : level == import::Context::Level::kInfo ? 20 : 10;
      logger.attr("log")(py_level, "%s", Text(message));  // a path in it may not be UTF-8
    }
    lines.clear();
  }
};

// Strings the verifier let through may hold invalid UTF-8 (a bit flip in Asset.generator): replaced, not thrown.
py::object JsonToPython(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

// A path argument (str, bytes or os.PathLike) as the file system's bytes (os.fsencode: a str in the file system
// encoding, undecodable bytes kept as they were); TypeError for anything else.
// A NUL inside is refused (ValueError, as Python's open()): the file system would stop at it, and another file
// than the one named would be read or written.
std::string PathString(const py::handle& path) {
  std::string bytes = py::bytes(py::module_::import("os").attr("fsencode")(path)).cast<std::string>();
  if (bytes.find('\0') != std::string::npos)
    throw py::value_error("path " + std::string(py::str(py::repr(path))) + ": embedded null byte");
  return bytes;
}
// A path as Python shows it (os.fsdecode of its bytes).
py::object PathObject(const std::string& path) { return py::module_::import("os").attr("fsdecode")(py::bytes(path)); }

AssetPtr LoadOrThrow(const std::function<import::Status(import::LoadedAsset*)>& load) {
  auto data = std::make_shared<AssetData>();
  import::Status s = import::Ok{};
  {
    py::gil_scoped_release release;
    s = load(&data->loaded);
  }
  if (s.ok()) return data;
  if (runtime::Failed(data->loaded.status)) ThrowStatus(data->loaded.status, s.error().message);
  // kIo: no such file, a folder, unreadable, too large.
  ThrowOsError(s.error().message.find(": no such file") != std::string::npos ? PyExc_FileNotFoundError : PyExc_OSError,
               s.error().message);
}

PyAsset Load(const py::object& source) {
  PyAsset asset;
  if (PyObject_CheckBuffer(source.ptr())) {
    py::buffer_info b = py::buffer(source).request();
    bool contiguous = true;  // C order: each dimension's stride the product of the later ones
    for (py::ssize_t d = b.ndim - 1, step = b.itemsize; d >= 0; step *= b.shape[size_t(d)], --d)
      contiguous = contiguous && (b.shape[size_t(d)] <= 1 || b.strides[size_t(d)] == step);
    if (!contiguous) ThrowValue("load(): a bytes-like source must be C-contiguous, got " + DescribeArray(source.ptr()));
    const auto* bytes = static_cast<const uint8_t*>(b.ptr);
    const size_t size = size_t(b.size) * size_t(b.itemsize);
    asset.data = LoadOrThrow([&](import::LoadedAsset* out) { return import::LoadAssetBytes(bytes, size, "bytes", out); });
    return asset;
  }
  asset.path = PathString(source);
  asset.data = LoadOrThrow([&](import::LoadedAsset* out) { return import::LoadAssetFile(asset.path, out); });
  return asset;
}

// ---- bake -----------------------------------------------------------------------------------------
PyAsset Bake(const py::object& path, const py::object& config, std::optional<std::string> regions,
             std::optional<std::string> segmentation, const py::object& region_map, std::optional<std::string> vertices,
             const py::object& rig, std::optional<double> disk_step, bool force, bool skin_weights) {
  PyObject* error_class = Exceptions().bake_error;
  auto fail = [&](const import::Error& e) {
    ThrowOffline(error_class, e, import::ToString(e));
  };
  const std::string input = PathString(path);
  // The configuration: a file (as `bake --config`), a mapping (its JSON), or the defaults.
  baker::BakeConfig bake_config;
  if (!config.is_none()) {
    const bool mapping = py::isinstance(config, py::module_::import("collections.abc").attr("Mapping"));
    std::string text;
    if (mapping) {
      // numpy scalars (np.float64(0.01), np.int64(64)) as the Python numbers they hold (.item()).
      const py::cpp_function plain([](py::handle value) -> py::object {
        if (py::hasattr(value, "item")) return value.attr("item")();
        throw py::type_error(std::string(py::str(py::type::handle_of(value).attr("__name__"))) + " is not a JSON value");
      });
      try {
        text = py::str(py::module_::import("json").attr("dumps")(py::dict(config), py::arg("default") = plain));
      } catch (const py::error_already_set& e) {
        if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError)) throw;
        // The exception's own message (e.what() appends pybind11's traceback of json.dumps).
        fail(import::MakeError(import::Error::Code::kConfig, "the config dict: " + std::string(py::str(e.value()))));
      }
    }
    import::Result<baker::BakeConfig> parsed =
        mapping ? baker::ParseBakeConfig(text, "the config dict") : baker::LoadBakeConfig(PathString(config));
    if (!parsed.ok()) fail(parsed.error());
    bake_config = std::move(parsed).value();
  }
  baker::BakeOptions options;
  options.regions = regions.value_or("");
  options.segmentation = segmentation.value_or("");
  options.vertices = vertices.value_or("");
  if (!region_map.is_none()) options.region_map = PathString(region_map);
  if (!rig.is_none()) options.rig = PathString(rig);
  options.disk_step = disk_step.value_or(0.0);
  options.force = force;
  options.skin_weights = skin_weights;
  if (auto s = baker::ApplyBakeOptions(options, &bake_config); !s.ok()) fail(s.error());

  LogLines log;
  std::optional<import::Error> error;
  PyAsset asset;
  {
    py::gil_scoped_release release;
    import::Context ctx = log.MakeContext();
    auto result = baker::Bake(input, bake_config, &ctx);
    if (result.ok()) {
      const baker::BakeResult& r = result.value();
      auto data = std::make_shared<AssetData>();
      if (auto s = import::LoadAssetBytes(r.asset.data(), r.asset.size(), "the baked asset", &data->loaded); !s.ok())
        error = import::MakeError(import::Error::Code::kInternal, s.error().message);
      asset.data = std::move(data);
      // A name from the file that is not UTF-8 (a part's, a bone's) replaced, as the CLI writes the report.
      asset.report_json =
          baker::MakeBakeReport(r, bake_config, ctx).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    } else {
      error = result.error();
    }
  }
  log.Emit();
  if (error) fail(*error);
  return asset;
}

// ---- evaluate -------------------------------------------------------------------------------------
py::object Evaluate(const PyAsset& asset, const py::object& mesh_path, std::optional<std::string> clip, const py::object& frames,
                    const py::object& morph, const py::object& poses_dir, const py::object& rig, double margin,
                    double crease, const std::string& refit, const std::string& regions, bool coverage,
                    const py::object& sweep_margin, const py::object& png) {
  PyObject* error_class = Exceptions().evaluate_error;
  auto fail = [&](const import::Error& e) { ThrowOffline(error_class, e, e.message); };
  const AssetPtr data = asset.Get();
  if (regions != "asset" && regions != "paper")
    fail(import::MakeError(import::Error::Code::kConfig, "regions: '" + regions + "' is not one of asset, paper"));

  evaluate::EvaluateOptions options;
  std::string sweep;
  if (py::isinstance<py::str>(sweep_margin)) {
    sweep = sweep_margin.cast<std::string>();
  } else if (!sweep_margin.is_none()) {
    for (const py::handle& m : sweep_margin) {
      char text[40];
      std::snprintf(text, sizeof text, "%.17g", RealArg(m, "sweep_margin"));
      sweep += (sweep.empty() ? "" : ",") + std::string(text);
    }
  }
  if (auto s = evaluate::ParseSweepMargins(sweep, &options.sweep_margins_rel); !s.ok()) fail(s.error());
  options.asset_name = asset.path.empty() ? "(in memory)" : asset.path;
  options.mesh_name = PathString(mesh_path);
  options.margin_rel = margin;
  options.crease_rel = crease;
  options.refit = refit;
  options.paper_regions = regions == "paper";
  options.coverage = coverage;
  if (!png.is_none()) options.png_path = PathString(png);

  playback::AnimationRequest request;
  request.mesh_name = options.mesh_name;
  request.clip = clip.value_or("");
  // Any integer (an int, numpy's, anything with __index__): out of [1, kMaxFrames] a config error, as
  // OpenAnimation says it, instead of pybind11's TypeError for what does not fit 32 bits.
  {
    const py::int_ count = py::reinterpret_steal<py::int_>(PyNumber_Index(frames.ptr()));
    if (!count) throw py::error_already_set();
    int overflow = 0;
    const long long n = PyLong_AsLongLongAndOverflow(count.ptr(), &overflow);
    if (overflow != 0 || n < 1 || n > playback::kMaxFrames)
      fail(import::MakeError(import::Error::Code::kConfig, "frames: " + std::string(py::repr(count)) + " is not in [1, " +
                                                               std::to_string(playback::kMaxFrames) + "]"));
    request.frames = static_cast<uint32_t>(n);
  }
  if (py::isinstance<py::bool_>(morph)) {
    request.use_morph = morph.cast<bool>();
  } else if (py::isinstance<py::str>(morph) || py::isinstance<py::bytes>(morph) || py::hasattr(morph, "__fspath__")) {
    request.use_morph = true;  // one pose file, name or folder
    request.morph.push_back(PathString(morph));
  } else if (!morph.is_none()) {
    if (!py::isinstance<py::iterable>(morph))
      throw py::type_error("morph: expected True, a path or a list of paths, got " +
                           std::string(py::str(py::type::handle_of(morph).attr("__name__"))));
    request.use_morph = true;
    for (const py::handle& p : morph) request.morph.push_back(PathString(p));
  }
  const std::string explicit_poses = poses_dir.is_none() ? "" : PathString(poses_dir);
  const std::string rig_path = rig.is_none() ? "" : PathString(rig);
  // Where the outputs go, before any frame (as the CLI): no output over an input, no missing folder.
  if (!options.png_path.empty()) {
    const std::string asset_path = asset.path;
    if (const std::string clash = import::OutputsClash(
            {{"png", &options.png_path}}, {{"asset", &asset_path}, {"mesh", &options.mesh_name}, {"rig", &rig_path}},
            playback::PoseInputFiles(request.morph, explicit_poses));
        !clash.empty())
      fail(import::MakeError(import::Error::Code::kConfig, clash));
    if (const std::string why = import::OutputPathProblem(options.png_path); !why.empty())
      fail(import::MakeError(import::Error::Code::kIo, why));
  }
  // Default key poses: the package's data/ (installed beside the module), else the source tree's.
  const fs::path module_file = PathString(py::module_::import("spherechain._spherechain").attr("__file__"));
  const std::vector<std::string> data_dirs = {(module_file.parent_path() / "data").string(), SPHERECHAIN_SOURCE_DATA_DIR};

  LogLines log;
  std::optional<import::Error> error;
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    import::Context ctx = log.MakeContext();
    import::Mesh mesh;
    import::Status s = playback::ImportMeshForAsset(data->view(), options.asset_name, options.mesh_name, rig_path, &mesh, &ctx);
    if (s.ok()) {
      request.poses_dir = !explicit_poses.empty()
                              ? explicit_poses
                              : playback::FindPosesDir(playback::DefaultPoseCharacter(mesh, options.mesh_name), data_dirs);
      auto animation = playback::OpenAnimation(mesh, request);
      if (!animation.ok()) {
        error = animation.error();
      } else {
        auto result = evaluate::Evaluate(data->view(), mesh, animation.value(), options, &ctx);
        if (result.ok()) report = std::move(result.value().report);
        else error = result.error();
      }
    } else {
      error = s.error();
    }
  }
  log.Emit();
  if (error) fail(*error);
  return JsonToPython(report);
}

}  // namespace

void RegisterAsset(py::module_& m) {
  py::class_<PyAsset>(m, "Asset", R"doc(
A verified .sphc sphere-chain asset in memory (made by bake() or load()).

The bytes are checked by the runtime loader when the asset is made and shared by every Model, Workspace and
array made from it: they stay alive until the last of those goes, whatever close() does. Lengths are in the
source units of the character the asset was baked from, in its model space (bind pose).
)doc")
      .def("save", [](PyAsset& self, const py::object& path) {
             const AssetPtr data = self.Get();  // a reference of its own: close() on another thread while
                                                // the GIL is released must not free the bytes being written
             const std::string p = PathString(path);
             import::Status s = import::Ok{};
             {
               py::gil_scoped_release release;
               s = import::WriteFileAtomic(p, data->loaded.bytes(), data->loaded.size);
             }
             if (!s.ok()) {
               ThrowOsError(PyExc_OSError, s.error().message);
             }
             self.path = p;
           }, py::arg("path"), R"doc(
Writes the asset's bytes to `path` (str, bytes — the file system's bytes — or os.PathLike) atomically: a temporary file in the same folder,
renamed over `path`, so a failure leaves no partial file. Afterwards `path` is the asset's `path`.
Raises OSError (folder missing, not writable); StatusError kErrorNullArgument on a closed asset.
)doc")
      .def("info", [](const PyAsset& self) { return JsonToPython(evaluate::DescribeAsset(self.Get()->view())); }, R"doc(
What the asset holds, as a dict: exactly what `spherechain inspect --json` prints (schema version, counts,
units, up axis, fingerprint, parts, regions, chains, excluded pairs, joint refit, accuracy, margins,
coverage, forced findings). Fields an older schema lacks are absent or None.
)doc")
      .def("to_bytes", [](const PyAsset& self) {
             const AssetPtr& data = self.Get();
             return py::bytes(reinterpret_cast<const char*>(data->loaded.bytes()), data->loaded.size);
           }, "The .sphc file's bytes (a copy), as save() writes them.")
      .def("close", [](PyAsset& self) { self.data.reset(); }, R"doc(
Drops this object's reference to the bytes. Models and Workspaces made from it keep working (they hold
their own reference); every later use of this Asset's bytes raises StatusError kErrorNullArgument (path,
report, closed and repr still answer).
)doc")
      .def_property_readonly("closed", [](const PyAsset& self) { return !self.data; }, "True after close().")
      .def("__enter__", [](PyAsset& self) -> PyAsset& { return self; }, py::return_value_policy::reference)
      .def("__exit__", [](PyAsset& self, const py::args&) { self.data.reset(); })
      .def_property_readonly("path", [](const PyAsset& self) -> py::object {
             return self.path.empty() ? py::object(py::none()) : PathObject(self.path);
           }, "The file the asset was loaded from or last saved to; None for one only in memory.")
      .def_property_readonly("report", [](const PyAsset& self) -> py::object {
             return self.report_json.empty() ? py::object(py::none()) : JsonToPython(nlohmann::json::parse(self.report_json));
           }, "A baked asset's bake report (what `bake --report` writes: counts, regions, chains, accuracy, "
              "plausibility, timings_ms) as a dict; None for a loaded asset.")
      .def_property_readonly("schema_version", [](const PyAsset& self) { return self.Get()->view().asset->schema_version(); },
                             "Asset.schema_version (runtime kMinSchemaVersion..kSchemaVersion).")
      .def_property_readonly("sphere_count", [](const PyAsset& self) { return self.Get()->view().sphere_count; }, "#S.")
      .def_property_readonly("vertex_count", [](const PyAsset& self) { return self.Get()->view().vertex_count; },
                             "#V: the rows refit() and narrow_phase() positions must have.")
      .def_property_readonly("triangle_count", [](const PyAsset& self) { return self.Get()->view().triangle_count; }, "#T.")
      .def_property_readonly("chain_count", [](const PyAsset& self) { return self.Get()->view().chain_count; }, "Chains.")
      .def_property_readonly("joint_count", [](const PyAsset& self) { return self.Get()->view().asset->joint_count(); },
                             "#J: the matrices refit_joints() takes; 0 without joint weights (unrigged or old asset).")
      .def_property_readonly("region_names", [](const PyAsset& self) {
             const runtime::AssetView& v = self.Get()->view();
             py::list names;  // Text: a name the verifier let through may not be UTF-8 (a bit flip)
             for (uint32_t k = 0; k < runtime::RegionCount(v); ++k) names.append(Text(runtime::RegionName(v, k)));
             return names;
           }, "Names of the region values sphere_regions and triangle_regions hold (list of str, index = value).")
      .def_property_readonly("bind_spheres", [](const PyAsset& self) -> py::object {
             const AssetPtr& data = self.Get();
             static_assert(sizeof(spherechain::schema::Sphere) == 4 * sizeof(float));
             const npy_intp shape[2] = {npy_intp(data->view().sphere_count), 4};
             return ReadOnlyView(data, data->view().asset->spheres()->data(), NPY_FLOAT32, 2, shape);
           }, R"doc(
The bind-pose spheres (Asset.spheres): numpy.ndarray float32, shape (#S, 4), rows (x, y, z, r) in source
units, model space. A read-only view of the asset's bytes (no copy); it keeps them alive.
)doc")
      .def_property_readonly("bind_positions", [](const PyAsset& self) -> py::object {
             const AssetPtr& data = self.Get();
             const auto* v = data->view().asset->bind_positions();
             if (!v) return py::none();
             const npy_intp shape[2] = {npy_intp(v->size() / 3), 3};
             return ReadOnlyView(data, v->data(), NPY_FLOAT32, 2, shape);
           }, R"doc(
The vertex buffer as baked (Asset.bind_positions): numpy.ndarray float32, shape (#V, 3), source units, model
space, bind pose — positions refit() accepts. A read-only view of the asset's bytes; None for an asset baked
before the crease rule.
)doc")
      .def_property_readonly("sphere_regions", [](const PyAsset& self) -> py::object {
             const AssetPtr& data = self.Get();
             const auto* v = data->view().asset->sphere_regions();
             if (!v) return py::none();
             const npy_intp shape[1] = {npy_intp(v->size())};
             return ReadOnlyView(data, v->data(), NPY_UINT8, 1, shape);
           }, "Region of each sphere: numpy.ndarray uint8, shape (#S,), values index region_names. A read-only "
              "view of the asset's bytes; None when the asset has none.")
      .def_property_readonly("triangle_regions", [](const PyAsset& self) -> py::object {
             const AssetPtr& data = self.Get();
             const auto* v = data->view().asset->triangle_regions();
             if (!v) return py::none();
             const npy_intp shape[1] = {npy_intp(v->size())};
             return ReadOnlyView(data, v->data(), NPY_UINT8, 1, shape);
           }, "Region of each triangle of the source mesh: numpy.ndarray uint8, shape (#T,), values index "
              "region_names. A read-only view of the asset's bytes; None when the asset has none.")
      .def("__repr__", [](const PyAsset& self) {
        if (!self.data) return std::string("<spherechain.Asset (closed)>");
        const runtime::AssetView& v = self.data->view();
        return "<spherechain.Asset " + (self.path.empty() ? std::string("(in memory)") : std::string(py::repr(PathObject(self.path)))) + ": " +
               std::to_string(v.sphere_count) + " spheres, " + std::to_string(v.vertex_count) + " vertices, " +
               std::to_string(v.triangle_count) + " triangles>";
      });

  m.def("load", &Load, py::arg("source"), R"doc(
Loads a .sphc asset and verifies it with the runtime loader (runtime LoadAsset: identifier, version, every
offset, count and index).

source: a path (str or os.PathLike), or the file's contents (bytes, bytearray, memoryview, a C-contiguous
numpy array, read as its raw bytes: copied once into aligned memory). A bytes object is always the contents,
never a path (unlike save(), bake() and evaluate(), whose paths may be bytes): pass a bytes path as
os.fsdecode(path) or a pathlib.Path.
Raises StatusError with the loader's status (kErrorIdentifier, kErrorVersionTooOld, kErrorCorrupt, ...) when
the bytes are not a loadable asset; FileNotFoundError / OSError when the file cannot be read.
)doc");

  m.def("bake", &Bake, py::arg("path"), py::arg("config") = py::none(), py::kw_only(), py::arg("regions") = py::none(),
        py::arg("segmentation") = py::none(), py::arg("region_map") = py::none(), py::arg("vertices") = py::none(),
        py::arg("rig") = py::none(), py::arg("disk_step") = py::none(), py::arg("force") = false,
        py::arg("skin_weights") = false, R"doc(
Bakes a character file into an Asset: what `spherechain bake PATH -o OUT.sphc` writes, byte for byte, for
the same input, configuration and options (the same library calls). Releases the GIL; the libraries' log
lines go to the logging module's "spherechain" logger.

path: the character (.gltf/.glb, .obj, .fbx, .dae, .x, .blend, ...): str, bytes or os.PathLike (as every path
argument of bake() and evaluate(): bytes are the file system's bytes).
config: None (defaults), a dict of configuration keys (as a `--config` JSON file: "regions", "max_spheres",
    "fit", "chains", ... — docs/guide.md; numpy scalars are taken as the numbers they hold), or the path of
    such a JSON file.
regions: "extended" or "paper" (`--regions`); segmentation: "auto", "rig", "geometry", "skeleton", "map";
region_map: path of a JSON region map; vertices: "joined" or "source" (assimp formats); rig: a MakeHuman
.mhskel; disk_step: the torso disk step in source units (> 0); force: write the asset although a
plausibility check fails (`--force`); skin_weights: also write the skin weights per vertex for the narrow
phase's joint-matrix cull (`--skin-weights`). Each one given overrides the configuration's key.
Raises BakeError (.code, .message; str() is what the CLI prints after "error: ").
)doc");

  m.def("evaluate", &Evaluate, py::arg("asset"), py::arg("mesh"), py::arg("clip") = py::none(), py::arg("frames") = 40,
        py::kw_only(), py::arg("morph") = py::none(), py::arg("poses_dir") = py::none(), py::arg("rig") = py::none(),
        py::arg("margin") = 0.01, py::arg("crease") = 0.03, py::arg("refit") = "frame", py::arg("regions") = "asset",
        py::arg("coverage") = true, py::arg("sweep_margin") = py::none(), py::arg("png") = py::none(), R"doc(
Measures the asset against the exact contacts of the deformed mesh, frame by frame, and returns what
`spherechain evaluate ASSET --mesh MESH --json OUT` writes, as a dict (per frame, margin sweep, summary).
Releases the GIL; slow (the exact truth: ~0.1 s a frame on 27k triangles, more with coverage).

asset: an Asset (its path names it in the report); mesh: the character it was baked from (checked by
fingerprint), str, bytes or os.PathLike (every path here: bytes are the file system's bytes).
clip: the clip to play (None: the first, or the morph through the default key poses when there is none);
frames: frames to play, an integer in [1, 1000000] (else EvaluateError config).
morph: True (the default key poses), a pose file / name / folder, or a list of them;
poses_dir: the folder of key poses; rig: a MakeHuman .mhskel.
margin: false-alarm distance, a fraction of the body height [0, 1); crease: the truth's bind distance, a
fraction of the height [0, 1]; refit: "frame", "paper" or "joints"; regions: "asset" or "paper";
coverage: measure coverage (the costly part); sweep_margin: None, "auto" or a list of margins (fractions of
the height); png: write the picture of the frame with the most missed contacts there (checked before any
frame: EvaluateError config when it names an input, io when its folder is missing or it is a folder).
Raises EvaluateError (.code, .message; str() is what the CLI prints after "error: ").
)doc");
  RefuseBareNew(m.attr("Asset"), "Asset", "use spherechain.load() or spherechain.bake()");
}

}  // namespace spherechain::python
