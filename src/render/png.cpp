// PNG encoding and decoding through stb (Debian's libstb-dev). stb frames the PNG; its deflate is
// replaced by zlib's at level 9 for smaller files. Neither writes a timestamp, so an image always
// encodes to the same bytes.
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/render.h"

namespace {

// stb's hook for its deflate: returns malloc'ed bytes that stb frees with STBIW_FREE.
unsigned char* zlib_compress(unsigned char* data, int length, int* out_length, int /*quality*/) {
  uLongf size = compressBound(uLong(length));
  auto* out = static_cast<unsigned char*>(std::malloc(size));
  if (!out) return nullptr;
  if (compress2(out, &size, data, uLong(length), 9) != Z_OK) {
    std::free(out);
    return nullptr;
  }
  *out_length = int(size);
  return out;
}

}  // namespace

// Static linkage: TinyGLTF's library carries its own stb copy.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBIW_ZLIB_COMPRESS zlib_compress
#define STBI_WRITE_NO_STDIO
#include <stb/stb_image_write.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_NO_STDIO
#include <stb/stb_image.h>

namespace lod {

std::string encode_png(const Image& image) {
  if (image.width == 0 || image.height == 0 || image.rgba.size() != size_t(image.width) * image.height * 4)
    throw_usage("encode_png: the image is empty or its pixels do not match its size");
  if (image.width > 0x7fffffffu / 4 || image.height > 0x7fffffffu)
    throw_usage("encode_png: the image is too large");
  std::string out;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
  };
  if (!stbi_write_png_to_func(append, &out, int(image.width), int(image.height), 4, image.rgba.data(),
                              int(image.width * 4)))
    throw_internal("encode_png: out of memory");
  return out;
}

void write_png(const Image& image, const std::filesystem::path& path) { write_file_atomic(path, encode_png(image)); }

Image decode_png(std::span<const uint8_t> bytes, const std::string& name) {
  if (bytes.size() < 8 || std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) != 0)
    throw_bad_input_at_byte(name, 0, "not a PNG file (no PNG signature)");
  if (bytes.size() > size_t(0x7fffffff)) throw_bad_input(name, "too large for the PNG decoder");
  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load_from_memory(bytes.data(), int(bytes.size()), &width, &height, &channels, 4);
  if (!pixels) throw_bad_input(name, std::string("unreadable PNG: ") + stbi_failure_reason());
  Image image;
  image.width = uint32_t(width);
  image.height = uint32_t(height);
  image.rgba.assign(pixels, pixels + size_t(width) * size_t(height) * 4);
  stbi_image_free(pixels);
  return image;
}

Image read_png(const std::filesystem::path& path) {
  const FileBytes bytes = read_file_bytes(path);
  return decode_png(bytes, path.string());
}

}  // namespace lod
