// spherechain Python module — the per-frame side: Model (runtime::Model, and the narrow phase's model built on
// first use) and Workspace (runtime::Workspace + its output buffers). The per-frame calls read the NumPy
// array's pointer, shape and strides through the C API (no copy, no Python object made), run the runtime's
// job with the GIL released and raise StatusError on a failed status. Nothing in the runtime allocates per
// call; returning a new array allocates in Python (the `out=` forms do not).
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::python {

namespace {

using runtime::Status;

// What every character of one asset shares: the runtime's Model, and the narrow phase's models (surrounding
// regions, reach regions), each built on first use (NarrowPhaseModel::Init is slow with the crease rule) under
// a once_flag, so Workspaces on several threads may ask at once.
struct ModelData {
  AssetPtr asset;
  runtime::Model model;
  uint32_t bound[2] = {0, 0};  // DetectBound for M1, M2
  runtime::NarrowPhaseModel narrow[2];
  Status narrow_status[2] = {Status::kOk, Status::kOk};
  std::once_flag narrow_once[2];

  // Call without the GIL.
  Status Narrow(int kind, const runtime::NarrowPhaseModel** out) {
    std::call_once(narrow_once[kind], [&] {
      narrow_status[kind] = narrow[kind].Init(
          asset->view(), kind == 0 ? runtime::NarrowPhaseRegions::kSurrounding : runtime::NarrowPhaseRegions::kReach);
    });
    *out = &narrow[kind];
    return narrow_status[kind];
  }
};
using ModelPtr = std::shared_ptr<ModelData>;

struct PyModel {
  ModelPtr data;
};

// One character: its spheres and scratch, and the buffers its calls write into. One call at a time (the GIL
// is released while the runtime runs: `busy` refuses a second thread instead of racing).
struct PyWorkspace {
  ModelPtr model;
  runtime::Workspace ws;
  std::vector<runtime::Collision> pairs;  // detect()'s records: up to 4,096 at first, grown to a frame's count
  // narrow_phase()'s copy of the caller's `pairs` (never fewer than 1 record, so an empty list is not null):
  // the job checks the pairs' indices and then reads them again while the GIL is released, so it must read
  // memory no other Python thread can change in between.
  std::vector<runtime::Collision> narrow_pairs;
  runtime::NarrowPhaseWorkspace narrow[2];
  std::vector<runtime::TriangleContact> contacts;
  std::vector<runtime::ContactDepth> depths;
  std::atomic<bool> busy{false};
};

class Exclusive {
 public:
  explicit Exclusive(PyWorkspace& w) : busy_(w.busy) {
    if (busy_.exchange(true, std::memory_order_acquire))
      throw std::runtime_error("spherechain.Workspace: another thread is using this workspace (one call at a time "
                               "per workspace: make one workspace per thread from the shared Model)");
  }
  ~Exclusive() { busy_.store(false, std::memory_order_release); }
  Exclusive(const Exclusive&) = delete;
  Exclusive& operator=(const Exclusive&) = delete;

 private:
  std::atomic<bool>& busy_;
};

runtime::DetectMethod MethodOf(const std::string& method) {
  if (method == "m1") return runtime::DetectMethod::kM1;
  if (method == "m2") return runtime::DetectMethod::kM2;
  ThrowValue("method: expected \"m1\" or \"m2\", got \"" + method + "\"");
}

// The strided positions view of a (#V, 3) float32 array: any row stride, x y z contiguous in a row.
runtime::PositionsView PositionsOf(PyObject* object, uint32_t vertex_count) {
  auto expected = [&] {
    return "positions: expected a numpy.ndarray of float32, shape (" + std::to_string(vertex_count) +
           ", 3), x y z contiguous in a row (strides[1] == 4, a row stride of at least 12 bytes, a multiple of 4); got " + DescribeArray(object);
  };
  if (!PyArray_Check(object)) ThrowValue(expected());
  auto* a = reinterpret_cast<PyArrayObject*>(object);
  if (PyArray_TYPE(a) != NPY_FLOAT32 || !PyArray_ISNOTSWAPPED(a) || PyArray_NDIM(a) != 2 || PyArray_DIM(a, 1) != 3)
    ThrowValue(expected());
  runtime::PositionsView view;
  if (PyArray_DIM(a, 0) == 0) {  // no rows: strides mean nothing; the runtime says kErrorVertexCount
    view.data = PyArray_DATA(a);
    return view;
  }
  if (PyArray_STRIDE(a, 1) != npy_intp(sizeof(float)) || PyArray_STRIDE(a, 0) < 0 ||
      PyArray_STRIDE(a, 0) > npy_intp(std::numeric_limits<uint32_t>::max()))
    ThrowValue(expected());
  view.data = PyArray_DATA(a);
  // More rows than a uint32 holds: the runtime's kErrorVertexCount, as for any other wrong count.
  view.count = PyArray_DIM(a, 0) > npy_intp(std::numeric_limits<uint32_t>::max()) ? 0 : uint32_t(PyArray_DIM(a, 0));
  view.stride_bytes = uint32_t(PyArray_STRIDE(a, 0));
  return view;
}

// The runtime's status as StatusError, with what the job was given when it is about the input.
[[noreturn]] void ThrowJob(Status s, const char* job, PyObject* positions, uint32_t vertex_count) {
  std::string context = job;
  if (s == Status::kErrorVertexCount)
    context += ": positions have " + std::to_string(PyArray_DIM(reinterpret_cast<PyArrayObject*>(positions), 0)) +
               " rows, the asset " + std::to_string(vertex_count) + " vertices";
  else if (s == Status::kErrorStride)
    context += ": row stride " + std::to_string(PyArray_STRIDE(reinterpret_cast<PyArrayObject*>(positions), 0)) +
               " bytes (>= 12, a multiple of 4)";
  else if (s == Status::kErrorAlignment)
    context += ": positions not 4-byte aligned";
  ThrowStatus(s, context);
}

// True when every current sphere is finite: x − x is 0 for a finite value and NaN for a NaN or an infinity,
// and NaN survives the sums. ~40 ns for 128 spheres.
bool SpheresFinite(const runtime::SphereArrays& s) {
  uint32_t i = 0;
  bool finite = true;
#if defined(__SSE2__)
  __m128 acc = _mm_setzero_ps();
  for (; i + 4 <= s.count; i += 4) {
    const __m128 x = _mm_loadu_ps(s.x + i), y = _mm_loadu_ps(s.y + i), z = _mm_loadu_ps(s.z + i), r = _mm_loadu_ps(s.r + i);
    acc = _mm_add_ps(acc, _mm_add_ps(_mm_add_ps(_mm_sub_ps(x, x), _mm_sub_ps(y, y)), _mm_add_ps(_mm_sub_ps(z, z), _mm_sub_ps(r, r))));
  }
  finite = _mm_movemask_ps(_mm_cmpunord_ps(acc, acc)) == 0;
#endif
  for (; i < s.count; ++i)
    finite = finite && std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && std::isfinite(s.z[i]) && std::isfinite(s.r[i]);
  return finite;
}

// A 1-D, C-contiguous array of `dtype` or an equivalent one (same fields at the same offsets), its data at the
// runtime struct's alignment (its records written or read in place as those structs).
PyArrayObject* RecordArrayOf(PyObject* object, PyArray_Descr* dtype, bool writable, const char* what) {
  if (PyArray_CheckExact(object)) {  // the usual case first: an array of this very dtype object (align=True:
                                     // NumPy's aligned flag is then the struct's alignment)
    auto* a = reinterpret_cast<PyArrayObject*>(object);
    if (PyArray_DESCR(a) == dtype && PyArray_NDIM(a) == 1 && PyArray_IS_C_CONTIGUOUS(a) && PyArray_ISALIGNED(a) &&
        (!writable || PyArray_ISWRITEABLE(a)))
      return a;
  }
  const char* name = dtype == PairDtype() ? "PAIR_DTYPE" : "CONTACT_DTYPE";
  auto* a = reinterpret_cast<PyArrayObject*>(object);
  if (!PyArray_Check(object) || !PyArray_EquivTypes(PyArray_DESCR(a), dtype) || PyArray_NDIM(a) != 1 ||
      !PyArray_IS_C_CONTIGUOUS(a) || (writable && !PyArray_ISWRITEABLE(a)))
    ThrowValue(std::string(what) + ": expected a one-dimensional, C-contiguous" + (writable ? ", writable" : "") +
               " numpy.ndarray of dtype spherechain." + name + "; got " + DescribeArray(object));
  // An equivalent dtype may be packed (align=False: NumPy then calls any address aligned), so the address
  // itself is checked against the struct's alignment.
  const size_t alignment = dtype == PairDtype() ? alignof(runtime::Collision) : alignof(runtime::TriangleContact);
  if (reinterpret_cast<uintptr_t>(PyArray_DATA(a)) % alignment != 0)
    ThrowValue(std::string(what) + ": the records' data must be aligned to " + std::to_string(alignment) +
               " bytes (spherechain." + name + "'s alignment; the runtime reads and writes them in place), got an "
               "address " + std::to_string(reinterpret_cast<uintptr_t>(PyArray_DATA(a)) % alignment) +
               " bytes past it (numpy.frombuffer with an offset?): copy it, numpy.array(" + what + ", dtype=spherechain." +
               name + ")");
  return a;
}

// The (#J, 3, 4) float32 joint matrices (refit_joints(), narrow_phase(matrices=)): C-contiguous and aligned,
// else ValueError naming the layout. `count`: the matrices given (0 past uint32: the runtime's kErrorJointCount).
const float* JointMatricesOf(PyObject* object, uint32_t joints, uint32_t* count) {
  auto* a = reinterpret_cast<PyArrayObject*>(object);
  if (!PyArray_Check(object) || PyArray_TYPE(a) != NPY_FLOAT32 || !PyArray_ISNOTSWAPPED(a) || PyArray_NDIM(a) != 3 ||
      PyArray_DIM(a, 1) != 3 || PyArray_DIM(a, 2) != 4 || !PyArray_IS_C_CONTIGUOUS(a) || !PyArray_ISALIGNED(a))
    ThrowValue("matrices: expected an aligned, C-contiguous numpy.ndarray of float32, shape (" + std::to_string(joints) +
               ", 3, 4) (per joint the top three rows of its skinning matrix, row-major); got " + DescribeArray(object) +
               (PyArray_Check(object) && !PyArray_ISALIGNED(a) ? " at an address not aligned to 4 bytes" : ""));
  *count = PyArray_DIM(a, 0) > npy_intp(std::numeric_limits<uint32_t>::max()) ? 0 : uint32_t(PyArray_DIM(a, 0));
  return static_cast<const float*>(PyArray_DATA(a));
}

// A new array of `count` records of `dtype` (uninitialised).
PyArrayObject* NewRecords(PyArray_Descr* dtype, npy_intp count) {
  Py_INCREF(dtype);  // PyArray_NewFromDescr steals it
  PyObject* a = PyArray_NewFromDescr(&PyArray_Type, dtype, 1, &count, nullptr, nullptr, 0, nullptr);
  if (!a) throw py::error_already_set();
  return reinterpret_cast<PyArrayObject*>(a);
}

// A length the runtime takes as a float32: finite there and >= 0 (NaN, inf and a double past FLT_MAX, which
// would become inf, are ValueError naming `what`: never a runtime status that blames something else).
float LengthOf(double v, const char* what, const char* alternative) {
  if (!(v >= 0.0 && v <= double(std::numeric_limits<float>::max())))
    ThrowValue(std::string(what) + ": " + py::repr(py::float_(v)).cast<std::string>() +
               " must be a finite number >= 0 (source units, float32: at most 3.4e38)" + alternative);
  return static_cast<float>(v);
}

float MarginOf(PyObject* value, const char* what) {
  if (!value || value == Py_None) return -1.0f;  // the asset's
  return LengthOf(RealArg(value, what), what, ", or None for the asset's");
}

// ---- the per-frame methods' calling convention ----------------------------------------------------------
// refit, refit_joints and detect are plain CPython methods (METH_FASTCALL | METH_KEYWORDS) on the Workspace
// type, not pybind11 functions: pybind11's general dispatcher (overloads, casters, default objects) cost a
// large part of a refit's own time (docs/performance.md#python). The rest of the API goes through pybind11.

// The PyWorkspace inside a Workspace instance (the method descriptor has checked its type; the class is
// final, so its layout is pybind11's simple one).
PyWorkspace& Self(PyObject* self) {
  auto* inst = reinterpret_cast<py::detail::instance*>(self);
  // Constructed, not only allocated: pybind11 gives an instance made by __new__ alone raw storage on the
  // first cast of it.
  const bool made = inst->simple_layout ? inst->simple_holder_constructed : inst->get_value_and_holder().holder_constructed();
  void* value = inst->simple_layout ? inst->simple_value_holder[0] : inst->get_value_and_holder().value_ptr();
  if (!made || !value) throw py::type_error("spherechain.Workspace: not initialised (make one with Model.workspace())");
  return *static_cast<PyWorkspace*>(value);
}

// Fills `out[i]` (borrowed; null when not given) from the positional and keyword arguments of a
// METH_FASTCALL | METH_KEYWORDS call, by `names`; the first `required` must be given.
template <size_t N>
void ParseArgs(const char* function, const char* const (&names)[N], size_t required, PyObject* const* args,
               Py_ssize_t nargs, PyObject* kwnames, PyObject* (&out)[N]) {
  for (size_t i = 0; i < N; ++i) out[i] = nullptr;
  if (size_t(nargs) > N)
    throw py::type_error(std::string(function) + "() takes at most " + std::to_string(N) + " arguments (" +
                         std::to_string(nargs) + " given)");
  for (Py_ssize_t i = 0; i < nargs; ++i) out[i] = args[i];
  const Py_ssize_t nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
  for (Py_ssize_t k = 0; k < nkw; ++k) {
    PyObject* key = PyTuple_GET_ITEM(kwnames, k);
    size_t i = 0;
    while (i < N && PyUnicode_CompareWithASCIIString(key, names[i]) != 0) ++i;
    if (i == N)
      throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" +
                           py::str(key).cast<std::string>() + "'");
    if (out[i]) throw py::type_error(std::string(function) + "() got multiple values for argument '" + names[i] + "'");
    out[i] = args[nargs + k];
  }
  for (size_t i = 0; i < required; ++i)
    if (!out[i]) throw py::type_error(std::string(function) + "() missing required argument '" + names[i] + "'");
}

// Which of `choices` the str `value` is (null: `fallback`); ValueError naming them otherwise.
template <size_t N>
size_t ChoiceOf(PyObject* value, const char* what, const char* const (&choices)[N], size_t fallback) {
  if (!value || value == Py_None) return fallback;
  if (PyUnicode_Check(value))
    for (size_t i = 0; i < N; ++i)
      if (PyUnicode_CompareWithASCIIString(value, choices[i]) == 0) return i;
  std::string list;
  for (size_t i = 0; i < N; ++i) list += std::string(i ? ", " : "") + "\"" + choices[i] + "\"";
  ThrowValue(std::string(what) + ": expected one of " + list + ", got " + py::repr(value).cast<std::string>());
}

// Runs `body` and turns a C++ exception into the Python error it stands for (these functions are called by
// CPython directly, so nothing may escape).
template <class Fn>
PyObject* Guarded(Fn&& body) {
  try {
    return body();
  } catch (py::error_already_set& e) {
    e.restore();
  } catch (const py::builtin_exception& e) {
    e.set_error();
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
  }
  return nullptr;
}

// ---- Workspace calls ------------------------------------------------------------------------------
void Refit(PyWorkspace& self, py::handle positions, PyObject* mode) {
  Exclusive exclusive(self);
  runtime::RefitJob job;
  job.model = &self.model->model;
  job.workspace = &self.ws;
  job.positions = PositionsOf(positions.ptr(), self.model->model.vertex_count());
  static const char* const kModes[] = {"frame", "paper"};
  job.mode = ChoiceOf(mode, "mode", kModes, 0) == 0 ? runtime::RefitMode::kPivotFrame : runtime::RefitMode::kPaper;
  Status s;
  bool finite;
  {
    NoGil release;
    s = job.Run();
    finite = runtime::Succeeded(s) && SpheresFinite(self.ws.spheres());
  }
  if (runtime::Failed(s)) ThrowJob(s, "refit", positions.ptr(), self.model->model.vertex_count());
  if (!finite) {  // the rare failure: which cause, from the positions (a scan of them, only here)
    bool positions_finite = true;
    const auto* row = static_cast<const unsigned char*>(job.positions.data);
    for (uint32_t v = 0; v < job.positions.count && positions_finite; ++v, row += job.positions.stride_bytes) {
      float p[3];
      std::memcpy(p, row, sizeof p);
      positions_finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    }
    ThrowStatus(Status::kErrorNonFinitePositions,
                positions_finite
                    ? "refit: every position is finite, but so large that a sphere overflowed float32 (its centre or "
                      "radius is infinite or NaN); the workspace's spheres are not finite until the next refit"
                    : "refit: a position the refit reads (a corner of a sphere's pivot triangles) is NaN or infinite; "
                      "the workspace's spheres are not finite until the next refit");
  }
}

void RefitJoints(PyWorkspace& self, py::handle matrices) {
  Exclusive exclusive(self);
  const uint32_t joints = self.model->model.joint_count();
  runtime::JointRefitJob job;
  job.model = &self.model->model;
  job.workspace = &self.ws;
  job.joint_matrices = JointMatricesOf(matrices.ptr(), joints, &job.joint_count);
  Status s;
  {
    NoGil release;
    s = job.Run();
  }
  if (runtime::Failed(s)) {
    std::string context = "refit_joints";
    if (s == Status::kErrorJointCount)
      context += ": " + std::to_string(PyArray_DIM(reinterpret_cast<PyArrayObject*>(matrices.ptr()), 0)) +
                 " matrices, the asset " + std::to_string(joints) + " joints";
    ThrowStatus(s, context);
  }
}

PyObject* Detect(PyWorkspace& self, PyObject* method, PyObject* margin, PyObject* fold_margin, PyObject* out) {
  Exclusive exclusive(self);
  runtime::DetectStats stats;
  uint32_t count = 0;
  runtime::DetectJob job;
  job.model = &self.model->model;
  job.workspace = &self.ws;
  static const char* const kMethods[] = {"m1", "m2"};
  job.method = ChoiceOf(method, "method", kMethods, 0) == 0 ? runtime::DetectMethod::kM1 : runtime::DetectMethod::kM2;
  job.margin = MarginOf(margin, "margin");
  job.fold_margin = MarginOf(fold_margin, "fold_margin");
  job.count = &count;
  job.stats = &stats;
  PyArrayObject* into = nullptr;
  if (out && out != Py_None) {
    into = RecordArrayOf(out, PairDtype(), true, "out");
    job.output = static_cast<runtime::Collision*>(PyArray_DATA(into));
    job.capacity = uint32_t(std::min<npy_intp>(PyArray_DIM(into, 0), std::numeric_limits<uint32_t>::max()));
  } else {
    job.output = self.pairs.data();
    job.capacity = uint32_t(self.pairs.size());
  }
  Status s;
  {
    NoGil release;
    s = job.Run();
  }
  if (!into && s == Status::kOkTruncated) {  // more pairs than the buffer holds: grown to them, run again
    self.pairs.resize(stats.distinct_pairs);
    job.output = self.pairs.data();
    job.capacity = uint32_t(self.pairs.size());
    NoGil release;
    s = job.Run();
  }
  if (runtime::Failed(s)) ThrowStatus(s, "detect");
  if (into) return PyLong_FromUnsignedLong(stats.distinct_pairs);
  PyArrayObject* result = NewRecords(PairDtype(), count);
  if (count) std::memcpy(PyArray_DATA(result), self.pairs.data(), size_t(count) * sizeof(runtime::Collision));
  return reinterpret_cast<PyObject*>(result);
}

py::object FoldPairsOf(PyWorkspace& self, double closing_arg) {
  Exclusive exclusive(self);
  const float closing = LengthOf(closing_arg, "closing", "");
  const runtime::NarrowPhaseModel* model = nullptr;
  Status s;
  uint32_t count = 0;
  std::vector<runtime::Collision> out;
  {
    py::gil_scoped_release release;
    s = self.model->Narrow(0, &model);
    if (runtime::Succeeded(s)) {
      out.resize(model->fold_pair_count());
      s = runtime::FoldPairs(*model, self.ws.spheres(), closing, out.data(), uint32_t(out.size()), &count);
    }
  }
  if (runtime::Failed(s))
    ThrowStatus(s, s == Status::kErrorInvalidJob ? "fold_pairs: the asset has no crease rule (bake it again)"
                   : s == Status::kErrorMissingField
                       ? "fold_pairs: the asset has no triangles or weld ids (baked before the narrow phase)"
                       : "fold_pairs");
  PyArrayObject* result = NewRecords(PairDtype(), count);
  if (count) std::memcpy(PyArray_DATA(result), out.data(), size_t(count) * sizeof(runtime::Collision));
  return py::reinterpret_steal<py::object>(reinterpret_cast<PyObject*>(result));
}

py::object NarrowPhase(PyWorkspace& self, py::handle positions, const py::object& exclusions, const py::object& pairs,
                       const std::string& regions, const py::object& crease, const py::object& matrices) {
  Exclusive exclusive(self);
  int kind = 0;
  if (regions == "reach") kind = 1;
  else if (regions != "surrounding") ThrowValue("regions: expected \"surrounding\" or \"reach\", got \"" + regions + "\"");
  runtime::NarrowPhaseJob job;
  job.positions = PositionsOf(positions.ptr(), self.model->model.vertex_count());
  if (!pairs.is_none()) {
    // Copied, with the GIL held: the job checks the indices and reads them again without the GIL, and another
    // Python thread may change the caller's array in between (an index past #S then reads out of bounds).
    PyArrayObject* p = RecordArrayOf(pairs.ptr(), PairDtype(), false, "pairs");
    const size_t n = size_t(std::min<npy_intp>(PyArray_DIM(p, 0), std::numeric_limits<uint32_t>::max()));
    self.narrow_pairs.resize(std::max<size_t>(n, 1));  // at least one: an empty list is not "no list"
    if (n) std::memcpy(self.narrow_pairs.data(), PyArray_DATA(p), n * sizeof(runtime::Collision));
    job.sphere_pairs = self.narrow_pairs.data();
    job.sphere_pair_count = uint32_t(n);
  }
  std::string exclusion = exclusions.is_none() ? "" : StrArg(exclusions, "exclusions");
  if (!exclusion.empty() && exclusion != "crease" && exclusion != "asset" && exclusion != "none")
    ThrowValue("exclusions: expected \"crease\", \"asset\", \"none\" or None, got \"" + exclusion + "\"");
  if (!crease.is_none()) {
    const double c = RealArg(crease, "crease");
    if (!(c > 0.0 && c <= double(std::numeric_limits<float>::max())))
      ThrowValue("crease: " + std::to_string(c) + " must be a finite number > 0 (source units), or None for the asset's");
    job.crease = static_cast<float>(c);
  }
  if (!matrices.is_none())  // the joint-matrix cull: refit_joints()'s layout
    job.joint_matrices = JointMatricesOf(matrices.ptr(), self.model->model.joint_count(), &job.joint_count);

  runtime::NarrowPhaseStats stats;
  uint32_t count = 0;
  Status s;
  std::string where = "narrow_phase";
  {
    py::gil_scoped_release release;
    const runtime::NarrowPhaseModel* model = nullptr;
    s = self.model->Narrow(kind, &model);
    if (runtime::Failed(s))
      where = s == Status::kErrorMissingField
                  ? "narrow_phase: the asset has no triangles or weld ids (baked before the narrow phase)"
                  : "narrow_phase: the narrow phase's model (NarrowPhaseModel::Init)";
    if (runtime::Succeeded(s) && !self.narrow[kind].made_for(*model)) {
      s = self.narrow[kind].Init(*model);
      if (runtime::Failed(s)) where = "narrow_phase: NarrowPhaseWorkspace::Init";
    }
    if (runtime::Succeeded(s)) {
      // None: the skin's own definition when the asset carries it and every pair is searched, as `play
      // --narrow-phase` does; else the asset's exclusions.
      if (exclusion.empty()) exclusion = model->has_crease() && !job.sphere_pairs ? "crease" : "asset";
      job.exclusions = exclusion == "crease" ? runtime::Exclusions::kCrease
                       : exclusion == "none" ? runtime::Exclusions::kNone
                                             : runtime::Exclusions::kAsset;
      job.model = model;
      job.workspace = &self.narrow[kind];
      job.count = &count;
      job.stats = &stats;
      // The depths first: a failed allocation must never leave fewer depths than contacts (the job writes
      // a depth per contact slot).
      if (self.contacts.empty()) self.depths.resize(4096), self.contacts.resize(4096);
      for (;;) {  // grows the buffers on the rare frame that needs more (then a second run)
        job.output = self.contacts.data();
        job.capacity = uint32_t(self.contacts.size());
        job.depths = job.exclusions == runtime::Exclusions::kCrease ? self.depths.data() : nullptr;
        s = job.Run();
        if (s != Status::kOkTruncated) break;
        const size_t grown = size_t(stats.contacts) + stats.contacts / 4;
        self.depths.resize(grown);
        self.contacts.resize(grown);
      }
    }
  }
  if (runtime::Failed(s)) {
    if (s == Status::kErrorVertexCount || s == Status::kErrorStride || s == Status::kErrorAlignment)
      ThrowJob(s, "narrow_phase", positions.ptr(), self.model->model.vertex_count());
    std::string why;  // kErrorInvalidJob: which argument
    if (s == Status::kErrorInvalidJob) {
      const bool rule = job.exclusions == runtime::Exclusions::kCrease;
      if (!rule && job.crease != 0.0f) why = ": crease is for exclusions \"crease\" only";
      else if (!rule && job.joint_matrices) why = ": matrices are for exclusions \"crease\" only";
      else if (rule && job.model && job.crease != 0.0f && job.crease < job.model->crease())
        why = ": crease " + std::to_string(job.crease) + " is below the asset's " + std::to_string(job.model->crease()) +
              " (a job may widen the folds, not narrow them)";
    }
    ThrowStatus(s, where + why);
  }
  PyArrayObject* result = NewRecords(ContactDtype(), count);
  auto* o = static_cast<unsigned char*>(PyArray_DATA(result));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const runtime::ContactDepth no_depth = {nan, {nan, nan, nan}};
  for (uint32_t i = 0; i < count; ++i, o += sizeof(runtime::TriangleContact) + sizeof(runtime::ContactDepth)) {
    std::memcpy(o, &self.contacts[i], sizeof(runtime::TriangleContact));
    std::memcpy(o + sizeof(runtime::TriangleContact), job.depths ? &self.depths[i] : &no_depth, sizeof(runtime::ContactDepth));
  }
  return py::reinterpret_steal<py::object>(reinterpret_cast<PyObject*>(result));
}

py::object Spheres(PyWorkspace& self) {
  Exclusive exclusive(self);
  const runtime::SphereArrays s = self.ws.spheres();
  const npy_intp shape[2] = {npy_intp(s.count), 4};
  PyObject* a = PyArray_SimpleNew(2, const_cast<npy_intp*>(shape), NPY_FLOAT32);
  if (!a) throw py::error_already_set();
  auto* o = static_cast<float*>(PyArray_DATA(reinterpret_cast<PyArrayObject*>(a)));
  for (uint32_t i = 0; i < s.count; ++i) o[4 * i] = s.x[i], o[4 * i + 1] = s.y[i], o[4 * i + 2] = s.z[i], o[4 * i + 3] = s.r[i];
  return py::reinterpret_steal<py::object>(a);
}

// Model(asset): runtime::Model::Init of the asset's bytes (without the GIL) and its DetectBounds.
PyModel BuildModel(const PyAsset& asset) {
  auto data = std::make_shared<ModelData>();
  data->asset = asset.Get();
  Status s;
  {
    py::gil_scoped_release release;
    s = data->model.Init(data->asset->view());
  }
  if (runtime::Failed(s)) ThrowStatus(s, "Model::Init");
  data->bound[0] = runtime::DetectBound(data->asset->view(), runtime::DetectMethod::kM1);
  data->bound[1] = runtime::DetectBound(data->asset->view(), runtime::DetectMethod::kM2);
  return PyModel{std::move(data)};
}

std::unique_ptr<PyWorkspace> MakeWorkspace(const PyModel& model) {
  auto w = std::make_unique<PyWorkspace>();
  w->model = model.data;
  if (const Status s = w->ws.Init(model.data->model); runtime::Failed(s)) ThrowStatus(s, "Workspace::Init");
  // DetectBound is #S(#S−1)/2 records: 12 B × 2·10^9 for the format's largest assets. Most frames report far
  // fewer; Detect grows the buffer when one reports more.
  w->pairs.resize(std::max<size_t>(1, std::min<size_t>(4096, std::max(model.data->bound[0], model.data->bound[1]))));
  return w;
}

// bench/python_bench.py's C++ rows: the same jobs on the same workspace and arrays, timed in C++ the way
// bench/runtime_bench does (median over 5 rounds × frames of batches of `reps` calls, per call, µs; detect on
// each frame's spheres, refitted before its batch).
py::dict TimeJobs(PyWorkspace& self, const py::list& frames, const py::object& joint_frames, int reps) {
  Exclusive exclusive(self);
  self.pairs.resize(std::max<size_t>(1, std::max(self.model->bound[0], self.model->bound[1])));  // never truncated
  // The arrays are read without the GIL: a reference to each is held meanwhile, so another thread emptying the
  // caller's lists cannot free one.
  std::vector<py::object> keep;
  std::vector<runtime::PositionsView> views;
  for (const py::handle& f : frames) {
    views.push_back(PositionsOf(f.ptr(), self.model->model.vertex_count()));
    keep.push_back(py::reinterpret_borrow<py::object>(f));
  }
  std::vector<const float*> joints;
  if (!joint_frames.is_none())
    for (const py::handle& f : joint_frames) {
      uint32_t count = 0;
      joints.push_back(JointMatricesOf(f.ptr(), self.model->model.joint_count(), &count));
      if (count != self.model->model.joint_count()) ThrowValue("joint_frames: " + std::to_string(count) + " matrices, the asset " +
                                                              std::to_string(self.model->model.joint_count()) + " joints");
      keep.push_back(py::reinterpret_borrow<py::object>(f));
    }
  if (views.empty() || reps <= 0) ThrowValue("frames: at least one; reps > 0");
  runtime::RefitJob refit;
  refit.model = &self.model->model;
  refit.workspace = &self.ws;
  uint32_t count = 0;
  runtime::DetectJob detect;
  detect.model = &self.model->model;
  detect.workspace = &self.ws;
  detect.output = self.pairs.data();
  detect.capacity = uint32_t(self.pairs.size());
  detect.count = &count;
  volatile uint32_t sink = 0;
  auto median = [&](size_t frame_count, auto&& prepare, auto&& fn) {
    std::vector<double> samples;
    for (int round = 0; round < 5; ++round)
      for (size_t f = 0; f < frame_count; ++f) {
        prepare(f);
        const auto t0 = std::chrono::steady_clock::now();
        for (int r = 0; r < reps; ++r) fn(f);
        const auto t1 = std::chrono::steady_clock::now();
        samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count() / reps);
      }
    std::nth_element(samples.begin(), samples.begin() + samples.size() / 2, samples.end());
    return samples[samples.size() / 2];
  };
  auto nothing = [](size_t) {};
  auto refit_frame = [&](size_t f) {
    refit.positions = views[f];
    sink = sink + uint32_t(refit.Run());
  };
  double us[5] = {0, 0, 0, 0, -1};
  {
    py::gil_scoped_release release;
    us[0] = median(views.size(), nothing, refit_frame);
    for (int k = 0; k < 2; ++k) {
      detect.method = k == 0 ? runtime::DetectMethod::kM1 : runtime::DetectMethod::kM2;
      us[1 + k] = median(views.size(), refit_frame, [&](size_t) { sink = sink + uint32_t(detect.Run()) + count; });
    }
    detect.method = runtime::DetectMethod::kM1;
    us[3] = median(views.size(), nothing, [&](size_t f) {
      refit_frame(f);
      sink = sink + uint32_t(detect.Run()) + count;
    });
    if (!joints.empty()) {
      runtime::JointRefitJob jr;
      jr.model = &self.model->model;
      jr.workspace = &self.ws;
      jr.joint_count = self.model->model.joint_count();
      us[4] = median(joints.size(), nothing, [&](size_t f) {
        jr.joint_matrices = joints[f];
        sink = sink + uint32_t(jr.Run());
      });
    }
  }
  py::dict out;
  out["refit"] = us[0];
  out["detect_m1"] = us[1];
  out["detect_m2"] = us[2];
  out["refit_m1"] = us[3];
  if (us[4] >= 0) out["refit_joints"] = us[4];
  return out;
}

PyObject* RawRefit(PyObject* self, PyObject* const* args, Py_ssize_t nargs, PyObject* kwnames) {
  return Guarded([&] {
    static const char* const kNames[] = {"positions", "mode"};
    PyObject* a[2];
    ParseArgs("refit", kNames, 1, args, nargs, kwnames, a);
    Refit(Self(self), a[0], a[1]);
    Py_RETURN_NONE;
  });
}

PyObject* RawRefitJoints(PyObject* self, PyObject* const* args, Py_ssize_t nargs, PyObject* kwnames) {
  return Guarded([&] {
    static const char* const kNames[] = {"matrices"};
    PyObject* a[1];
    ParseArgs("refit_joints", kNames, 1, args, nargs, kwnames, a);
    RefitJoints(Self(self), a[0]);
    Py_RETURN_NONE;
  });
}

PyObject* RawDetect(PyObject* self, PyObject* const* args, Py_ssize_t nargs, PyObject* kwnames) {
  return Guarded([&] {
    static const char* const kNames[] = {"method", "margin", "fold_margin", "out"};
    PyObject* a[4];
    ParseArgs("detect", kNames, 0, args, nargs, kwnames, a);
    return Detect(Self(self), a[0], a[1], a[2], a[3]);
  });
}

}  // namespace

void RegisterRuntime(py::module_& m) {
  m.def("_time_jobs", &TimeJobs, py::arg("workspace"), py::arg("frames"), py::arg("joint_frames") = py::none(),
        py::arg("reps") = 200,
        "bench/python_bench.py's C++ row: RefitJob, DetectJob M1/M2 (and JointRefitJob) on `workspace` over the "
        "frames, timed in C++ as bench/runtime_bench does; a dict of µs per call.");
  py::class_<PyModel> model(m, "Model", py::is_final(), R"doc(
What every character of one asset shares (runtime::Model): built once from an Asset, immutable, shared by
any number of Workspaces and threads. Holds the asset's bytes alive. The narrow phase's model is built on
the first Workspace.narrow_phase() call that needs it (NarrowPhaseModel::Init: slow with the crease rule).
)doc");
  // Model(asset) builds the model in __new__, so that Model.__new__(Model) alone cannot leave an instance
  // whose storage was never constructed (pybind11 gives such an instance raw storage, which its methods would
  // read), and the type's tp_new is that __new__ (SealNew: no other __new__ reaches it). The __init__ that
  // follows is pybind11's, and it skips an instance already built.
  model.attr("__new__") = py::cpp_function([](py::handle, const PyAsset& asset) { return py::cast(BuildModel(asset)); },
                                           py::name("Model"), py::arg("cls"), py::arg("asset"));
  SealNew(model);
  model
      .def(py::init(&BuildModel), py::arg("asset"), "Builds the model of `asset` (an Asset). Raises StatusError (kErrorNullArgument for a "
                             "closed asset, kErrorOutOfMemory).")
      .def("workspace", &MakeWorkspace, R"doc(
A new Workspace: one character's spheres (at the bind pose) and scratch, and the buffers its calls write.
Allocates once (runtime Workspace::Init), and the narrow phase's scratch on its first use.
)doc")
      .def("detect_bound", [](const PyModel& self, const std::string& method) {
             return self.data->bound[MethodOf(method) == runtime::DetectMethod::kM1 ? 0 : 1];
           }, py::arg("method") = "m1",
           "Most pairs Workspace.detect(method) can report (runtime DetectBound): an `out` array this long is never "
           "truncated.")
      .def_property_readonly("sphere_count", [](const PyModel& self) { return self.data->model.sphere_count(); }, "#S.")
      .def_property_readonly("vertex_count", [](const PyModel& self) { return self.data->model.vertex_count(); },
                             "#V: the rows the positions must have.")
      .def_property_readonly("joint_count", [](const PyModel& self) { return self.data->model.joint_count(); },
                             "#J: the matrices refit_joints() takes; 0 when the asset has no joint weights.")
      .def_property_readonly("chain_count", [](const PyModel& self) { return self.data->model.chain_count(); }, "Chains.")
      .def_property_readonly("contact_margin", [](const PyModel& self) { return self.data->model.contact_margin(); },
                             "The asset's contact margin [source units]: what detect() grows every radius by by default.")
      .def_property_readonly("fold_margin", [](const PyModel& self) -> py::object {
             const float f = self.data->model.fold_margin();
             return f < 0.0f ? py::object(py::none()) : py::object(py::float_(f));
           }, "The asset's fold margin [source units] (pairs of one region), or None when it has none.");

  py::class_<PyWorkspace, std::unique_ptr<PyWorkspace>> workspace(m, "Workspace", py::is_final(), R"doc(
One character's state for a Model (runtime::Workspace): its current spheres and the scratch of the
per-frame calls. Made by Model.workspace(). One call at a time (a second thread gets RuntimeError): use one
Workspace per thread. Every call releases the GIL while the runtime runs.
)doc");
  RefuseBareNew(workspace, "Workspace", "use Model.workspace()");
  workspace
      .def("narrow_phase", &NarrowPhase, py::arg("positions"), py::arg("exclusions") = py::none(),
           py::arg("pairs") = py::none(), py::arg("regions") = "surrounding", py::arg("crease") = py::none(),
           py::arg("matrices") = py::none(), R"doc(
The exact triangle self-contacts of the deformed mesh (runtime NarrowPhaseJob).

positions: as refit() (float32 (#V, 3), strided rows).
exclusions: "crease" (the skin's own definition: every intersecting pair not near on the bind surface;
    needs an asset baked with the crease rule), "asset" (pairs of different spheres, not an excluded pair),
    "none" (any two spheres); None: "crease" when the asset has the rule and `pairs` is None, else "asset".
pairs: None (search every pair: the exact answer) or PAIR_DTYPE records to search behind: detect()'s, and
    with "crease" also fold_pairs()' (the restricted skin contacts: the pairs of 16-triangle patches whose
    triangles stand behind the two spheres of a listed pair, and the bind pose's own contacts). A 1-D,
    C-contiguous array of PAIR_DTYPE (or an equivalent dtype), its data 4-byte aligned; copied once per call
    (into the workspace's buffer: another thread may change the array meanwhile).
regions: "surrounding" or "reach" (the triangles behind a sphere; "reach" finds more behind `pairs`).
crease: the fold distance [source units] of a "crease" search (only there); None: the asset's.
matrices: None, or the skinning matrices that deformed `positions` (as refit_joints() takes them) for a
    "crease" search on an asset baked with skin_weights=True: neighbouring skin that moved nearly rigidly is
    skipped, the same contacts found. The positions must be that linear blend skinning of the bind pose.
Returns a new numpy.ndarray of dtype CONTACT_DTYPE: triangle_a, triangle_b (uint32, source triangle indices),
sphere_a, sphere_b (uint16 owners, 0xFFFF for an unassigned triangle), depth (float32, source units) and
direction (3 float32, unit) of the separating-axis push — NaN unless exclusions is "crease".
Raises TypeError (exclusions not a str, crease not a number), ValueError (a bad exclusions or regions word, a
crease not finite as a float32 or <= 0; positions not a float32 (#V, 3) array with strides[1] == 4 and a row
stride >= 0; pairs not a 1-D, C-contiguous PAIR_DTYPE array or not 4-byte aligned; matrices not an aligned,
C-contiguous float32 (#J, 3, 4) array), StatusError (kErrorVertexCount; kErrorAlignment: positions not 4-byte
aligned; kErrorStride: a row stride < 12 or not a multiple of 4; kErrorIndexOutOfRange: a pair with a >= b or
b >= #S; kErrorNonFinitePositions: a vertex of a surrounding region is NaN or inf; kErrorMissingField: an asset
without triangles or weld ids (baked before the narrow phase), "crease" on an asset without the rule, or
matrices on one without skin weights; kErrorJointCount; kErrorNonFiniteJoints;
kErrorInvalidJob: a crease or matrices with another exclusions, or a crease below the asset's;
kErrorBindPoseTangled: an asset whose bind pose passes through itself beyond the narrow phase's budget,
every call; kErrorCreaseTooWide: an asset whose crease reaches too much of its bind surface, every call; kErrorFrameTangled: positions that pass through themselves beyond the narrow phase's budget, no
pose of the character — uninitialised, collapsed or scrambled; the message says which; kErrorOutOfMemory).
Cost: the runtime's narrow phase (docs/performance.md); the first call builds the narrow phase's model and
scratch, and each call allocates the returned array.
)doc")
      .def("fold_pairs", &FoldPairsOf, py::arg("closing"), R"doc(
The proxy's folds (runtime FoldPairs): the sphere pairs detect() never reports (the asset's excluded
neighbours) whose centres are now closer than at bind pose by more than `closing` [source units, >= 0,
finite as a float32: at most 3.4e38], from the current spheres (the last refit). With detect()'s pairs they are what
narrow_phase(exclusions="crease", pairs=...) searches behind, as `play --narrow-behind` does with closing
2 x Model.contact_margin and detect("m2", margin=1.5 x it, fold_margin=the same). Returns a new numpy.ndarray of PAIR_DTYPE (a < b; depth rA + rB − |cA −
cB|; chains 0). Raises TypeError (closing not a number), ValueError (closing negative, NaN or not finite as a
float32), StatusError (kErrorInvalidJob: an asset without the crease rule; kErrorMissingField: an asset
without triangles or weld ids, baked before the narrow phase; kErrorBindPoseTangled: its bind pose passes
through itself beyond the narrow phase's budget; kErrorCreaseTooWide: its crease reaches too much of its bind
surface; kErrorOutOfMemory).
Cost: one distance per excluded pair; builds the narrow phase's model on first use.
)doc")
      .def("reset", [](PyWorkspace& self) {
             Exclusive exclusive(self);
             if (const Status s = self.ws.ResetToBindPose(self.model->model); runtime::Failed(s)) ThrowStatus(s, "reset");
           }, "Puts the spheres back at the bind pose.")
      .def_property_readonly("spheres", &Spheres, R"doc(
The current spheres: a new numpy.ndarray float32, shape (#S, 4), rows (x, y, z, r) [source units, the space
of the positions last refitted; the bind pose after reset()]. A copy (the runtime keeps them as four arrays).
)doc")
      .def_property_readonly("model", [](const PyWorkspace& self) { return PyModel{self.model}; },
                             "The Model this workspace was made for.");

  // The per-frame methods: plain CPython methods (see RawRefit), documented with a text signature.
  static const std::string refit_doc = std::string("refit($self, /, positions, mode='frame')\n--\n") + R"doc(
Refits the spheres to the deformed vertex positions (runtime RefitJob, paper §5.1), read in place.

positions: numpy.ndarray float32, shape (#V, 3) [source units, the asset's model space or any rigid motion
    of it]: x, y, z contiguous in a row (strides[1] == 4), any row stride of >= 12 bytes and a multiple of 4 —
    a C-contiguous array or a column slice of an interleaved vertex buffer (e.g. buffer[:, 0:3] of a (#V, 8)
    float32 array). No copy.
mode: "frame" (default: the pivot frame, exact under rigid motion) or "paper" (the paper's translation).
Raises ValueError (not such an array: dtype, shape and strides named), StatusError kErrorVertexCount (#V
wrong), kErrorAlignment (data not 4-byte aligned), kErrorStride (a row stride < 12 or not a multiple of 4),
kErrorNonFinitePositions (a position the refit reads is NaN or infinite, or finite positions so large that a
sphere overflows float32 — the message says which: the spheres are then not finite).
Cost: the runtime's refit and a finiteness check of the spheres; no allocation (docs/performance.md#python).
)doc";
  static const std::string refit_joints_doc = std::string("refit_joints($self, /, matrices)\n--\n") + R"doc(
Refits the spheres from the joint skinning matrices (runtime JointRefitJob): each centre skinned like a
vertex by its four joint weights, radii as baked.

matrices: numpy.ndarray float32, shape (#J, 3, 4), C-contiguous, 4-byte aligned: per joint the top three rows
    of its skinning matrix (joint's model transform × inverse bind), row-major, in the skin's joint order.
    Read in place.
Raises ValueError (not such an array: dtype, shape, order or alignment), StatusError kErrorJointCount (#J
wrong), kErrorMissingField (no joint weights in the asset), kErrorNonFiniteJoints (a matrix holds NaN or inf:
spheres untouched).
)doc";
  static const std::string detect_doc = std::string("detect($self, /, method='m1', margin=None, fold_margin=None, out=None)\n--\n") + R"doc(
The overlapping, non-adjacent sphere pairs of the current spheres (runtime DetectJob, paper §5.2).

method: "m1" (pairs within each chain) or "m2" (every pair).
margin, fold_margin: contact margins [source units, >= 0, finite as a float32: at most 3.4e38]; None: the
    asset's (Model.contact_margin, Model.fold_margin).
out: None — returns a new numpy.ndarray of dtype PAIR_DTYPE (a uint16, b uint16, depth float32 [source
    units: rA + rB − |cA − cB|], chains uint32 bitmask), one record per pair (allocates it; a frame with
    more pairs than the workspace has held, past 4,096, also grows the workspace's buffer and runs twice);
    or a writable, C-contiguous, 4-byte aligned 1-D array of PAIR_DTYPE (or an equivalent dtype) — the pairs are written into it and the call returns their total
    count n (an int; out[:min(n, len(out))] hold them; n > len(out) means truncated: size it with
    Model.detect_bound(method)). Order: runtime's (M1 by chain, M2 by (a, b)).
Raises TypeError (a margin not a number), ValueError (unknown method; a margin negative, NaN or not finite
as a float32; out not such an array), StatusError kErrorInvalidJob (a fold margin on an asset without one).
)doc";
  static PyMethodDef methods[] = {
      {"refit", reinterpret_cast<PyCFunction>(reinterpret_cast<void (*)()>(RawRefit)), METH_FASTCALL | METH_KEYWORDS,
       refit_doc.c_str()},
      {"refit_joints", reinterpret_cast<PyCFunction>(reinterpret_cast<void (*)()>(RawRefitJoints)),
       METH_FASTCALL | METH_KEYWORDS, refit_joints_doc.c_str()},
      {"detect", reinterpret_cast<PyCFunction>(reinterpret_cast<void (*)()>(RawDetect)), METH_FASTCALL | METH_KEYWORDS,
       detect_doc.c_str()},
  };
  for (PyMethodDef& def : methods) {
    PyObject* descriptor = PyDescr_NewMethod(reinterpret_cast<PyTypeObject*>(workspace.ptr()), &def);
    if (!descriptor) throw py::error_already_set();
    workspace.attr(def.ml_name) = py::reinterpret_steal<py::object>(descriptor);
  }
}

}  // namespace spherechain::python
