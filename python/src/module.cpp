// linesurf._linesurf: the Python binding (pybind11 + numpy). Arrays in and out (arrays.h), the
// Model and Mesh classes (model.cpp), the functions (functions.cpp) with keyword options named
// keywordName(field) of the library's option tables (options.h); library errors as ValueError
// (bad parameters) or linesurf.FileFormatError / OSError (bad files). The pure-Python package
// linesurf/__init__.py re-exports everything and builds the keyword signatures.
#include <pybind11/pybind11.h>

#include "functions.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "model.h"

namespace py = pybind11;
using namespace linesurf;

PYBIND11_MODULE(_linesurf, m) {
  m.doc() = "linesurf: surface modelling and rendering with line segments (numpy in and out).";

  // --- errors ---------------------------------------------------------------------------------
  static py::exception<Error> fileFormatError(m, "FileFormatError", PyExc_OSError);
  fileFormatError.doc() = "A malformed or unreadable input file (an OSError); the message is the CLI's one line "
                          "'PATH: WHERE: WHAT'.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const OptionError& e) {
      PyErr_SetString(PyExc_ValueError, pythonMessage(e).c_str());
    } catch (const Error& e) {
      if (e.kind() == Error::Kind::BadParameter) PyErr_SetString(PyExc_ValueError, e.what());
      else if (e.kind() == Error::Kind::BadInput) PyErr_SetString(fileFormatError.ptr(), e.what());
      else PyErr_SetString(PyExc_OSError, e.what());
    }
  });
  python::bindModel(m);
  python::bindFunctions(m);
}
