// Placeholder: the PLY/OBJ/XYZ readers and writers land with the foundation IO work.
#include "linesurf/io/model_io.h"

#include "linesurf/core/error.h"

namespace linesurf {

HybridModel readModel(const std::filesystem::path& path) { throwBadInput(path.string(), "", "reader not implemented yet"); }
TriangleMesh readMesh(const std::filesystem::path& path) { throwBadInput(path.string(), "", "reader not implemented yet"); }
bool fileHoldsMesh(const std::filesystem::path& path) { throwBadInput(path.string(), "", "reader not implemented yet"); }
void writeModel(const std::filesystem::path& path, const HybridModel&, const WriteOptions&) { throwBadInput(path.string(), "", "writer not implemented yet"); }
void writeMesh(const std::filesystem::path& path, const TriangleMesh&, const WriteOptions&) { throwBadInput(path.string(), "", "writer not implemented yet"); }

}  // namespace linesurf
