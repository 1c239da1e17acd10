#include "linesurf/io/image_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
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

uint32_t crc32(const unsigned char* p, size_t n, uint32_t c = 0xFFFFFFFFu) {
  static const auto table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
      t[i] = c;
    }
    return t;
  }();
  for (size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return c;
}
uint32_t be32(const unsigned char* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }
void putBe32(std::string& s, uint32_t v) {
  for (int k = 3; k >= 0; --k) s += char((v >> (8 * k)) & 0xFF);
}

bool isPng(const std::string& bytes) { return bytes.size() >= 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n", 8) == 0; }

/// What the PNG checks found: the palette's chunk and size when the image is indexed with a
/// palette too short for its bit depth (so an index can point past its end).
struct PngLayout {
  size_t plteOffset = 0, plteLength = 0;  ///< the PLTE chunk (offset of its length field)
  bool shortPalette = false;
};

/// The chunk structure and every chunk's CRC, which stb_image does not check: a corrupt file is
/// refused instead of being decoded into wrong pixels.
PngLayout checkPngChunks(const std::string& bytes, const std::string& name) {
  PngLayout out;
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  size_t pos = 8;
  int colourType = -1, bitDepth = 0;
  while (true) {
    if (pos + 12 > bytes.size()) throwBadInput(name, fmt::format("byte {}", pos), "truncated PNG (no IEND chunk)");
    const uint32_t len = be32(b + pos);
    const std::string type(bytes, pos + 4, 4);
    const std::string printableType = oneLine(type);
    if (len > bytes.size() - pos - 12)
      throwBadInput(name, fmt::format("byte {}", pos), "truncated PNG (chunk '" + printableType + "' runs past the end)");
    const uint32_t crc = ~crc32(b + pos + 4, size_t(len) + 4);
    if (crc != be32(b + pos + 8 + len))
      throwBadInput(name, fmt::format("byte {}", pos), "PNG chunk '" + printableType + "' has a bad CRC (the file is corrupt)");
    if (type == "IHDR" && len >= 13) {
      bitDepth = b[pos + 8 + 8];
      colourType = b[pos + 8 + 9];
    } else if (type == "PLTE") {
      out.plteOffset = pos;
      out.plteLength = len;
    } else if (type == "IEND") {
      break;
    }
    pos += size_t(len) + 12;
  }
  if (colourType == 3 && out.plteLength > 0 && bitDepth >= 1 && bitDepth <= 8)
    out.shortPalette = out.plteLength / 3 < (size_t(1) << bitDepth);
  return out;
}

/// `bytes` with its palette extended to 256 entries of `fill`.
std::string withFullPalette(const std::string& bytes, const PngLayout& l, unsigned char fill) {
  std::string data = bytes.substr(l.plteOffset + 4, 4 + l.plteLength);  // "PLTE" + entries
  data.append(768 - l.plteLength, char(fill));
  std::string chunk;
  putBe32(chunk, 768);
  chunk += data;
  putBe32(chunk, ~crc32(reinterpret_cast<const unsigned char*>(data.data()), data.size()));
  return bytes.substr(0, l.plteOffset) + chunk + bytes.substr(l.plteOffset + 12 + l.plteLength);
}

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
  PngLayout png;
  if (isPng(bytes)) png = checkPngChunks(bytes, name);
  unsigned char* data = nullptr;
  if (png.shortPalette) {
    // An index past the palette's end: stb_image would read whatever follows its palette. Decode
    // with the palette padded in black and in white: a pixel that differs used such an index.
    const std::string black = withFullPalette(bytes, png, 0), white = withFullPalette(bytes, png, 255);
    data = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(black.data()), int(black.size()), &w, &h, &n, 4);
    if (data) {
      int w2 = 0, h2 = 0, n2 = 0;
      unsigned char* other =
          stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(white.data()), int(white.size()), &w2, &h2, &n2, 4);
      const bool same = other && w2 == w && h2 == h && std::memcmp(data, other, size_t(w) * h * 4) == 0;
      if (other) stbi_image_free(other);
      if (!same) {
        stbi_image_free(data);
        throwBadInput(name, "", fmt::format("a pixel's palette index is past the palette's {} colours", png.plteLength / 3));
      }
    }
  } else {
    data = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), int(bytes.size()), &w, &h, &n, 4);
  }
  if (!data) throwBadInput(name, "", std::string("cannot read image: ") + stbi_failure_reason());
  Image img(w, h);
  for (size_t i = 0; i < size_t(w) * h; ++i)
    for (int c = 0; c < 4; ++c) img.pixels[i][c] = data[i * 4 + c] / 255.0f;
  stbi_image_free(data);
  return img;
}

}  // namespace linesurf
