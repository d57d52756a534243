// spherechain Python module (`spherechain._spherechain`, re-exported by the package `spherechain`): the
// exceptions, the record dtypes and the NumPy helpers; asset.cpp binds the offline side (Asset, load, bake,
// evaluate), runtime.cpp the per-frame side (Model, Workspace).
#define SPHERECHAIN_PYTHON_IMPORT_ARRAY
#include "common.h"

#include <cstddef>

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/narrow_phase.h"

namespace spherechain::python {

ExceptionClasses& Exceptions() {
  static ExceptionClasses classes;
  return classes;
}

std::string StatusName(runtime::Status status) {
  const std::string text = runtime::ToString(status);
  return text.substr(0, text.find(':'));
}

py::str Text(const std::string& bytes) {
  PyObject* text = PyUnicode_DecodeUTF8(bytes.data(), static_cast<Py_ssize_t>(bytes.size()), "backslashreplace");
  if (!text) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(text);
}

void ThrowOsError(PyObject* type, const std::string& message) {
  PyErr_SetObject(type, Text(message).ptr());
  throw py::error_already_set();
}

void ThrowStatus(runtime::Status status, const std::string& context) {
  std::string text = runtime::ToString(status);
  if (!context.empty()) text += " (" + context + ")";
  PyObject* cls = Exceptions().status_error;
  py::object exc = py::reinterpret_steal<py::object>(PyObject_CallOneArg(cls, Text(text).ptr()));
  if (!exc) throw py::error_already_set();
  exc.attr("status") = StatusName(status);
  exc.attr("code") = static_cast<uint32_t>(status);
  PyErr_SetObject(cls, exc.ptr());
  throw py::error_already_set();
}

void ThrowOffline(PyObject* cls, const import::Error& error, const std::string& text) {
  py::object exc = py::reinterpret_steal<py::object>(PyObject_CallOneArg(cls, Text(text).ptr()));
  if (!exc) throw py::error_already_set();
  exc.attr("code") = import::ToString(error.code);
  exc.attr("message") = Text(error.message);
  PyErr_SetObject(cls, exc.ptr());
  throw py::error_already_set();
}

void ThrowValue(const std::string& message) { throw py::value_error(message); }

std::string StrArg(py::handle o, const char* what) {
  if (!py::isinstance<py::str>(o))
    throw py::type_error(std::string(what) + ": expected a str, got " + std::string(py::str(py::type::handle_of(o).attr("__name__"))));
  return o.cast<std::string>();
}

double RealArg(py::handle o, const char* what) {
  const double v = PyFloat_AsDouble(o.ptr());  // a float, an int or anything with __float__ / __index__
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw py::type_error(std::string(what) + ": expected a number, got " + std::string(py::str(py::type::handle_of(o).attr("__name__"))));
  }
  return v;
}

namespace {
// A sealed type's tp_new: calls the `__new__` the type holds (the module's own: it refuses or builds).
PyObject* OwnNew(PyTypeObject* type, PyObject* args, PyObject* kwargs) {
  PyObject* fn = PyObject_GetAttrString(reinterpret_cast<PyObject*>(type), "__new__");
  if (!fn) return nullptr;
  PyObject* head = PyTuple_Pack(1, reinterpret_cast<PyObject*>(type));
  PyObject* full = head ? PySequence_Concat(head, args) : nullptr;
  PyObject* result = full ? PyObject_Call(fn, full, kwargs) : nullptr;
  Py_XDECREF(full);
  Py_XDECREF(head);
  Py_DECREF(fn);
  return result;
}
}  // namespace

void SealNew(py::handle cls) {
  auto* type = reinterpret_cast<PyTypeObject*>(cls.ptr());
  type->tp_new = &OwnNew;
  PyType_Modified(type);
}

void RefuseBareNew(py::handle cls, const char* name, const char* how) {
  const std::string message = std::string("spherechain.") + name + " cannot be made directly: " + how;
  cls.attr("__new__") = py::cpp_function([message](py::handle, const py::args&, const py::kwargs&) -> py::object {
    throw py::type_error(message);
  }, py::name("__new__"));
  SealNew(cls);
}

namespace {

PyArray_Descr* g_pair_dtype = nullptr;
PyArray_Descr* g_contact_dtype = nullptr;

// np.dtype(fields), checked against the C++ struct it mirrors: same size, each field at its offset.
PyArray_Descr* MakeDtype(const py::list& fields, size_t itemsize, const std::vector<std::pair<const char*, size_t>>& offsets) {
  // align=True: the records are read and written in place as the runtime's structs, so an array of this dtype
  // counts as aligned (PyArray_ISALIGNED) only at the structs' alignment (4), not at any byte.
  py::object dtype = py::module_::import("numpy").attr("dtype")(fields, py::arg("align") = true);
  if (dtype.attr("itemsize").cast<size_t>() != itemsize)
    throw std::runtime_error("spherechain: record dtype size does not match the runtime's struct");
  py::dict by_name = dtype.attr("fields");
  for (const auto& [name, offset] : offsets)
    if (py::tuple(by_name[name])[1].cast<size_t>() != offset)
      throw std::runtime_error(std::string("spherechain: record field '") + name + "' is not at the runtime's offset");
  return reinterpret_cast<PyArray_Descr*>(dtype.release().ptr());  // a reference kept for the process
}

PyObject* NewException(py::module_& m, const char* name, const char* doc, PyObject* bases) {
  const std::string qualified = std::string("spherechain.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases, nullptr);
  if (!cls) throw py::error_already_set();
  m.attr(name) = py::handle(cls);
  return cls;
}

}  // namespace

PyArray_Descr* PairDtype() { return g_pair_dtype; }
PyArray_Descr* ContactDtype() { return g_contact_dtype; }

std::string DescribeArray(PyObject* object) {
  if (!PyArray_Check(object)) return std::string("a ") + Py_TYPE(object)->tp_name + ", not a numpy.ndarray";
  py::handle a(object);
  return py::str(a.attr("dtype")).cast<std::string>() + " " + py::str(a.attr("shape")).cast<std::string>() +
         ", strides " + py::str(a.attr("strides")).cast<std::string>();
}

py::object ReadOnlyView(const AssetPtr& owner, const void* data, int type_num, int nd, const npy_intp* shape) {
  PyObject* array = PyArray_New(&PyArray_Type, nd, const_cast<npy_intp*>(shape), type_num, nullptr,
                                const_cast<void*>(data), 0, NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED, nullptr);
  if (!array) throw py::error_already_set();
  auto* keep = new AssetPtr(owner);
  PyObject* capsule = PyCapsule_New(keep, "spherechain.asset_bytes", [](PyObject* c) {
    delete static_cast<AssetPtr*>(PyCapsule_GetPointer(c, "spherechain.asset_bytes"));
  });
  if (!capsule) {
    delete keep;
    Py_DECREF(array);
    throw py::error_already_set();
  }
  if (PyArray_SetBaseObject(reinterpret_cast<PyArrayObject*>(array), capsule) < 0) {  // steals the capsule
    Py_DECREF(array);
    throw py::error_already_set();
  }
  return py::reinterpret_steal<py::object>(array);
}

}  // namespace spherechain::python

PYBIND11_MODULE(_spherechain, m) {
  using namespace spherechain::python;
  namespace rt = spherechain::runtime;
  if (_import_array() < 0) throw py::error_already_set();
  m.doc() = "spherechain's native module; use the package `spherechain`, which re-exports it.";

  ExceptionClasses& e = Exceptions();
  e.error = NewException(m, "Error", "Base class of every error spherechain raises (besides ValueError and TypeError "
                                     "for arguments of the wrong type, dtype or shape).", PyExc_Exception);
  py::tuple status_bases = py::make_tuple(py::handle(e.error), py::handle(PyExc_ValueError));
  e.status_error = NewException(
      m, "StatusError",
      "A runtime call failed: .status is the runtime status name ('kErrorVertexCount', 'kErrorCorrupt', ...) and "
      ".code its value (runtime/status.h); the message starts with the name. Also a ValueError: every status "
      "names a bad input (an asset that does not verify, positions of the wrong count, NaN positions, ...).",
      status_bases.ptr());
  e.offline_error = NewException(
      m, "OfflineError",
      "An offline tool failed: .code is the error code the CLI prints ('io', 'format', 'invalid-mesh', "
      "'segmentation', 'fit', 'config', 'internal', 'implausible') and .message the text.", e.error);
  e.bake_error = NewException(m, "BakeError",
                              "bake() failed. str(error) is what `spherechain bake` prints after 'error: ' "
                              "('<code>: <message>').", e.offline_error);
  e.evaluate_error = NewException(m, "EvaluateError",
                                  "evaluate() failed. str(error) is what `spherechain evaluate` prints after "
                                  "'error: '.", e.offline_error);

  py::list pair_fields;
  pair_fields.append(py::make_tuple("a", "<u2"));
  pair_fields.append(py::make_tuple("b", "<u2"));
  pair_fields.append(py::make_tuple("depth", "<f4"));
  pair_fields.append(py::make_tuple("chains", "<u4"));
  g_pair_dtype = MakeDtype(pair_fields, sizeof(rt::Collision),
                           {{"a", offsetof(rt::Collision, a)}, {"b", offsetof(rt::Collision, b)},
                            {"depth", offsetof(rt::Collision, depth)}, {"chains", offsetof(rt::Collision, chains)}});
  py::list contact_fields;
  contact_fields.append(py::make_tuple("triangle_a", "<u4"));
  contact_fields.append(py::make_tuple("triangle_b", "<u4"));
  contact_fields.append(py::make_tuple("sphere_a", "<u2"));
  contact_fields.append(py::make_tuple("sphere_b", "<u2"));
  contact_fields.append(py::make_tuple("depth", "<f4"));
  contact_fields.append(py::make_tuple("direction", "<f4", py::make_tuple(3)));
  g_contact_dtype = MakeDtype(contact_fields, sizeof(rt::TriangleContact) + sizeof(rt::ContactDepth),
                              {{"triangle_a", 0}, {"triangle_b", 4}, {"sphere_a", 8}, {"sphere_b", 10}, {"depth", 12},
                               {"direction", 16}});
  m.attr("PAIR_DTYPE") = py::handle(reinterpret_cast<PyObject*>(g_pair_dtype));
  m.attr("CONTACT_DTYPE") = py::handle(reinterpret_cast<PyObject*>(g_contact_dtype));
  m.attr("SCHEMA_VERSION") = rt::kSchemaVersion;
  m.attr("__version__") = SPHERECHAIN_VERSION;

  RegisterAsset(m);
  RegisterRuntime(m);
}
