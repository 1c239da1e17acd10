#pragma once
#include <pybind11/pybind11.h>

namespace linesurf::python {

/// read, write, geometry, normals, prepare, the extractions, verify, render, compare, threads.
void bindFunctions(pybind11::module_& m);

}  // namespace linesurf::python
