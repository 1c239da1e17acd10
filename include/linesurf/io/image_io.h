#pragma once
/// PNG output of rendered images and texture loading (stb_image / stb_image_write).
#include <filesystem>

#include "linesurf/core/image.h"

namespace linesurf {

/// Writes an 8-bit RGBA (or RGB when `withAlpha` is false) PNG; colour is clamped to [0,1]
/// and rounded. Written to a temporary file and renamed into place.
void writePng(const std::filesystem::path& path, const Image& image, bool withAlpha = true);
/// Reads PNG/JPEG/BMP/TGA into linear-in-file RGBA floats in [0,1]; throws on failure.
Image readImage(const std::filesystem::path& path);
/// Encodes 8-bit RGBA into PNG bytes (used by writePng and tests).
std::vector<unsigned char> encodePng(const Image& image, bool withAlpha = true);

}  // namespace linesurf
