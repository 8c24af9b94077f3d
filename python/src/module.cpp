// The Python module sgd_icp._core: the library's errors as Python exceptions, and the parts of
// the module (bindings.hpp) in the order they are defined. The public names are re-exported by
// sgd_icp/__init__.py; sgd_icp/_core.pyi documents them for type checkers and IDEs.
#include <exception>
#include <string>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"

#ifndef SGDICP_VERSION
#define SGDICP_VERSION "0.0.0"
#endif

namespace sgdicp::python {
namespace {

// ---- exceptions: sgd_icp.Error and its subclasses, which are also ValueError / OSError

struct ExceptionTypes {
  PyObject* error = nullptr;
  PyObject* invalid_input = nullptr;
  PyObject* invalid_settings = nullptr;
  PyObject* format = nullptr;
  PyObject* io = nullptr;
};
ExceptionTypes exception_types;  // created once at import; the module holds the references

PyObject* new_exception(py::module_& m, const char* name, const char* doc, py::tuple bases) {
  const std::string qualified = std::string("sgd_icp.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), /*dict=*/nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::reinterpret_steal<py::object>(type));
  return type;
}

void bind_exceptions(py::module_& m) {
  const py::handle value_error = PyExc_ValueError;
  const py::handle os_error = PyExc_OSError;
  auto& t = exception_types;
  t.error = new_exception(m, "Error", "Base class of every error the sgd_icp library raises.",
                          py::make_tuple(py::handle(PyExc_Exception)));
  const py::handle error = t.error;
  t.invalid_input = new_exception(
      m, "InvalidInputError",
      "Input the method cannot work with: a wrong array shape or dtype, an empty or all-NaN "
      "cloud, fewer points than a mini-batch, a non-rigid initial transform. A ValueError.",
      py::make_tuple(error, value_error));
  t.invalid_settings = new_exception(
      m, "InvalidSettingsError", "A setting out of range or contradicting another. A ValueError.",
      py::make_tuple(error, value_error));
  t.format = new_exception(
      m, "FormatError",
      "A file whose content is not valid for its format; the message names the file and the "
      "line or byte where it broke. A ValueError.",
      py::make_tuple(error, value_error));
  t.io = new_exception(m, "IoError",
                       "A file that cannot be opened, read or written; the message names the "
                       "path and the system's reason. An OSError.",
                       py::make_tuple(error, os_error));

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidInputError& e) {
      PyErr_SetString(exception_types.invalid_input, e.what());
    } catch (const InvalidSettingsError& e) {
      PyErr_SetString(exception_types.invalid_settings, e.what());
    } catch (const FormatError& e) {
      PyErr_SetString(exception_types.format, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(exception_types.io, e.what());
    } catch (const Error& e) {
      PyErr_SetString(exception_types.error, e.what());
    }
  });
}

}  // namespace

void define_module(py::module_& m) {
  m.doc() = "SGD-ICP point-cloud registration (C++ core of the sgd_icp package).";
  m.attr("__version__") = SGDICP_VERSION;

  bind_exceptions(m);
  bind_settings(m);
  bind_preprocessing(m);
  bind_reference_index(m);
  bind_results(m);
  bind_registration(m);
  bind_io(m);
  bind_depth(m);
  bind_metrics(m);
  bind_odometry(m);
}

}  // namespace sgdicp::python

PYBIND11_MODULE(_core, m) {
  sgdicp::python::define_module(m);
}
