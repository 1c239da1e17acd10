#pragma once
/// The one budget of a command: the largest amount of memory and of output it may use, estimated
/// before the work starts (CLI: --max-mb; the same object bounds every command). A command adds
/// up what it will hold at once (image buffers, models, neighbour lists) and what it will write,
/// and asks require() before the work; an estimate over the budget is refused (BadParameter, exit
/// 1 in the CLI) naming the option that drives it. Estimates are upper bounds of the order of the
/// real figure, not exact sizes.
#include <cstddef>
#include <string>
#include <string_view>

namespace linesurf {

class Budget {
 public:
  /// `megabytes` (MiB) must be finite and > 0; `name` is how a message names the budget itself
  /// ("--max-mb" in the CLI, "max_mb" in Python).
  explicit Budget(double megabytes = 4096, std::string name = "--max-mb");
  double megabytes() const { return megabytes_; }
  double bytes() const { return megabytes_ * 1024.0 * 1024.0; }
  const std::string& name() const { return name_; }
  bool allows(double bytes) const { return bytes <= this->bytes(); }  ///< false for NaN
  /// Throws Error (BadParameter) "OPTION: WHAT needs about X MiB, more than --max-mb N (raise
  /// --max-mb to allow it)" when `bytes` exceeds the budget.
  void require(std::string_view option, double bytes, std::string_view what) const;

 private:
  double megabytes_;
  std::string name_;
};

/// Bytes of the buffers for one rendered view of width x height: colour, depth, alpha and normal
/// images (16 bytes a pixel each) and `layers` fragment layers of the Z3 buffer.
double renderViewBytes(int width, int height, int layers);
/// Bytes of one w x h image written as PNG, taken as the uncompressed 8-bit RGBA size (an upper
/// bound of what the encoder writes, plus its headers).
double pngFileBytes(int width, int height);
/// Bytes of a model file with `points` points and `segments` segments: per primitive a row of
/// every standard property (binary PLY), or about 50 characters a point as text (.xyz, ASCII PLY).
double modelFileBytes(size_t points, size_t segments, bool text);
/// Working memory of the §6.1 geometry of `points` points with k neighbours (neighbour lists,
/// normals, radii, kd-tree, the model itself).
double pointGeometryBytes(size_t points, int k);

}  // namespace linesurf
