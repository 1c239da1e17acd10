#include "linesurf/io/image_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <string>

#include "linesurf/core/error.h"
#include "io/detail/readers.h"
#include "linesurf/io/atomic_file.h"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_NO_STDIO_WRITE_UNUSED
#include <stb_image.h>
#include <stb_image_write.h>

namespace linesurf {

void quantize8(const Image& image, int channels, unsigned char* out) {
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < channels; ++c) {
      float v = image.pixels[i][c];
      if (!(v >= 0)) v = 0;  // also maps NaN to 0
      out[i * channels + c] = (unsigned char)std::lround(std::min(v, 1.0f) * 255.0f);
    }
}

std::vector<unsigned char> encodePng(const Image& image, bool withAlpha) {
  const int channels = withAlpha ? 4 : 3;
  std::vector<unsigned char> raw(size_t(image.width) * image.height * channels);
  quantize8(image, channels, raw.data());
  std::vector<unsigned char> out;
  auto sink = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<unsigned char>*>(ctx);
    v->insert(v->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
  };
  if (image.width <= 0 || image.height <= 0 ||
      !stbi_write_png_to_func(sink, &out, image.width, image.height, channels, raw.data(), image.width * channels))
    throw Error(Error::Kind::Io, "<png>", "", "cannot encode an empty image");
  return out;
}

void writePng(const std::filesystem::path& path, const Image& image, bool withAlpha) {
  std::vector<unsigned char> bytes = encodePng(image, withAlpha);
  writeFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

namespace {
ImageInfo infoOf(const std::string& bytes, const std::string& name) {
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), int(std::min<size_t>(bytes.size(), INT_MAX)),
                             &w, &h, &n))
    throwBadInput(name, "", std::string("cannot read image: ") + stbi_failure_reason());
  if (w <= 0 || h <= 0) throwBadInput(name, "", "image has no pixels");
  return {w, h};
}
}  // namespace

ImageInfo readImageInfo(const std::filesystem::path& path) {
  // The header is within the first 64 KiB for every format stb_image reads.
  return infoOf(detail::readFileBytes(path, 1 << 16), path.string());
}

Image readImage(const std::filesystem::path& path, size_t maxPixels) {
  const std::string name = path.string();
  const std::string bytes = detail::readFileBytes(path);
  if (bytes.size() > size_t(INT_MAX)) throwBadInput(name, "", "image file larger than 2 GiB");
  const ImageInfo info = infoOf(bytes, name);
  if (double(info.width) * info.height > double(maxPixels))
    throwBadInput(name, "", fmt::format("image of {}x{} pixels is larger than the limit of {} pixels", info.width,
                                        info.height, maxPixels));
  int w = 0, h = 0, n = 0;
  unsigned char* data =
      stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), int(bytes.size()), &w, &h, &n, 4);
  if (!data) throwBadInput(name, "", std::string("cannot read image: ") + stbi_failure_reason());
  Image img(w, h);
  for (size_t i = 0; i < size_t(w) * h; ++i)
    for (int c = 0; c < 4; ++c) img.pixels[i][c] = data[i * 4 + c] / 255.0f;
  stbi_image_free(data);
  return img;
}

}  // namespace linesurf
