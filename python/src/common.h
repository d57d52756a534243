// spherechain Python module — what the binding files share: the exceptions, the NumPy C API, the asset's
// bytes shared by everything that reads them, and the record dtypes.
#pragma once

#include <pybind11/pybind11.h>

// The NumPy C API (PyArray_*): the per-frame calls read an array's pointer, shape and strides through its
// macros, with no Python object made. One translation unit (module.cpp) imports it; the others see it.
#define PY_ARRAY_UNIQUE_SYMBOL spherechain_python_ARRAY_API
#ifndef SPHERECHAIN_PYTHON_IMPORT_ARRAY
#define NO_IMPORT_ARRAY
#endif
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include <memory>
#include <string>

#include "spherechain/import/file_io.h"
#include "spherechain/import/types.h"
#include "spherechain/runtime/status.h"

namespace spherechain::python {

namespace py = pybind11;

// ---- exceptions -----------------------------------------------------------------------------------
/// The module's exception classes (created at import, module.cpp): spherechain.Error (base),
/// StatusError(Error, ValueError) with .status (the runtime status name, "kErrorVertexCount") and .code (its
/// value), OfflineError(Error) with .code ("config", "io", ... — import::ToString) and .message, and its
/// BakeError and EvaluateError.
struct ExceptionClasses {
  PyObject* error = nullptr;
  PyObject* status_error = nullptr;
  PyObject* offline_error = nullptr;
  PyObject* bake_error = nullptr;
  PyObject* evaluate_error = nullptr;
};
ExceptionClasses& Exceptions();

/// Text for Python from C++ bytes that are mostly UTF-8 but may not be (a path's undecodable bytes, a name from a
/// file): invalid bytes become `\xNN` escapes (backslashreplace), so a message never raises UnicodeDecodeError
/// and always prints.
py::str Text(const std::string& bytes);
/// Raises `type` (an OSError class) with Text(message).
[[noreturn]] void ThrowOsError(PyObject* type, const std::string& message);

/// The status name alone: "kErrorVertexCount" (the part of runtime::ToString before its ':').
std::string StatusName(runtime::Status status);
/// Raises spherechain.StatusError: message "<ToString(status)>" followed by " (<context>)" when given.
[[noreturn]] void ThrowStatus(runtime::Status status, const std::string& context = {});
/// Raises `cls` (an OfflineError) with .code = import::ToString(error.code), .message = error.message and the
/// text `text` (what the CLI prints after "error: ").
[[noreturn]] void ThrowOffline(PyObject* cls, const import::Error& error, const std::string& text);
/// Raises ValueError(message).
[[noreturn]] void ThrowValue(const std::string& message);
/// `o` as a str, or TypeError ("`what`: expected a str, got T").
std::string StrArg(py::handle o, const char* what);
/// `o` as a double (a float, an int, anything with __float__ or __index__), or TypeError naming `what`.
double RealArg(py::handle o, const char* what);

/// Makes `cls.__new__` (already set on the class) the only way to a new instance: the type's tp_new calls
/// it, so that `pybind11_object.__new__(cls)` and `object.__new__(cls)` are refused by Python ("is not safe")
/// instead of allocating an instance whose storage was never constructed (pybind11 gives such an instance
/// raw storage, which its methods would read: a crash). pybind11's own casts allocate without tp_new.
void SealNew(py::handle cls);
/// Sets `cls.__new__` to one that raises TypeError "spherechain.<name> cannot be made directly: <how>", and
/// seals it (SealNew). For the classes the module makes itself (Asset, Workspace).
void RefuseBareNew(py::handle cls, const char* name, const char* how);

/// Releases the GIL for a scope (Py_BEGIN_ALLOW_THREADS as RAII): the per-frame calls' lighter form of
/// py::gil_scoped_release (~30 ns less a call). Nothing touching Python objects may run inside.
class NoGil {
 public:
  NoGil() : state_(PyEval_SaveThread()) {}
  ~NoGil() { PyEval_RestoreThread(state_); }
  NoGil(const NoGil&) = delete;
  NoGil& operator=(const NoGil&) = delete;

 private:
  PyThreadState* state_;
};

// ---- the asset's bytes ----------------------------------------------------------------------------
/// A verified .sphc in aligned memory (import::LoadedAsset). Shared by the Asset object, every Model and
/// Workspace made from it and every array viewing it, so the bytes live as long as the last of them.
struct AssetData {
  import::LoadedAsset loaded;
  const runtime::AssetView& view() const { return loaded.view; }
};
using AssetPtr = std::shared_ptr<const AssetData>;

/// spherechain.Asset: the shared bytes (null once closed), where they came from, and a bake's report.
struct PyAsset {
  AssetPtr data;            ///< null after close()
  std::string path;         ///< the file it was loaded from or last saved to; empty for one in memory only
  std::string report_json;  ///< a baked asset's report (baker::MakeBakeReport), empty otherwise
  /// The bytes, or StatusError kErrorNullArgument when the asset was closed.
  const AssetPtr& Get() const;
};

void RegisterAsset(py::module_& m);    // asset.cpp: Asset, load, bake, evaluate
void RegisterRuntime(py::module_& m);  // runtime.cpp: Model, Workspace

// ---- NumPy helpers --------------------------------------------------------------------------------
/// The record dtypes (module.cpp builds them at import and checks their layout against the runtime's
/// structs): PAIR_DTYPE = runtime::Collision, CONTACT_DTYPE = TriangleContact + ContactDepth.
PyArray_Descr* PairDtype();
PyArray_Descr* ContactDtype();
/// "float64 (100, 3), strides (24, 8)": what an array is, for messages.
std::string DescribeArray(PyObject* object);
/// A read-only array of `nd` dimensions over `data` (dtype `type_num`, C-contiguous), which keeps `owner`
/// alive (the asset's bytes) for as long as it exists.
py::object ReadOnlyView(const AssetPtr& owner, const void* data, int type_num, int nd, const npy_intp* shape);

}  // namespace spherechain::python
