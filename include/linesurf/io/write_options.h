#pragma once
/// How a model file is written (io/model_io.h); its own header so that the per-format writers
/// behind model_io.h need not include it back.
namespace linesurf {

enum class PlyEncoding { BinaryLittleEndian, Ascii };

struct WriteOptions {
  PlyEncoding encoding = PlyEncoding::BinaryLittleEndian;
};

}  // namespace linesurf
