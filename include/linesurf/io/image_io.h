#pragma once
/// PNG output of rendered images and texture loading (stb_image / stb_image_write).
#include <filesystem>

#include "linesurf/core/image.h"

namespace linesurf {

/// Writes an 8-bit RGBA (or RGB when `withAlpha` is false) PNG; colour is clamped to [0,1]
/// and rounded. Written to a temporary file and renamed into place.
void writePng(const std::filesystem::path& path, const Image& image, bool withAlpha = true);
/// Largest image readImage decodes by default (pixels; 16 bytes each once decoded).
inline constexpr size_t kDefaultMaxImagePixels = size_t(1) << 26;  // 8192 x 8192

/// Width and height from an image file's header, without decoding it (BadInput on failure).
struct ImageInfo {
  int width = 0, height = 0;
};
ImageInfo readImageInfo(const std::filesystem::path& path);

/// Reads PNG/JPEG/BMP/TGA into linear-in-file RGBA floats in [0,1]; throws on failure. The
/// size the header declares is checked against `maxPixels` before anything is decoded.
Image readImage(const std::filesystem::path& path, size_t maxPixels = kDefaultMaxImagePixels);
/// 8-bit channels of an image as PNG stores them: clamped to [0, 1] (NaN -> 0) and rounded; `channels`
/// 3 (RGB) or 4 (RGBA), row-major from the top-left. `out` holds width * height * channels bytes.
void quantize8(const Image& image, int channels, unsigned char* out);
/// Encodes 8-bit RGBA into PNG bytes (used by writePng and tests).
std::vector<unsigned char> encodePng(const Image& image, bool withAlpha = true);

}  // namespace linesurf
