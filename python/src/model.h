#pragma once
// The Model and Mesh classes of the module, and model arguments (a Model or an (N, 3) array).
#include <pybind11/pybind11.h>

#include "linesurf/core/model.h"

namespace linesurf::python {

namespace py = pybind11;

/// A model argument: a Model, or an (N, 3) array of points (copied into `owned`).
struct ModelArg {
  HybridModel owned;
  const HybridModel* model = nullptr;
  HybridModel& mutableCopy() {
    if (model != &owned) owned = *model, model = &owned;
    return owned;
  }
};
ModelArg modelArg(py::handle obj, const char* name = "model");

/// linesurf.Model and linesurf.Mesh.
void bindModel(py::module_& m);

}  // namespace linesurf::python
