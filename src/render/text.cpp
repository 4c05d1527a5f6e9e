// Labels: glyphs rasterised by FreeType from a TrueType font (DejaVu Sans from Debian by default) and
// blended into an image by their coverage.
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <string>

#include "lodkit/error.h"
#include "lodkit/render.h"

namespace lod {

struct Font::Face {
  FT_Library library = nullptr;
  FT_Face face = nullptr;
  ~Face() {
    if (face) FT_Done_Face(face);
    if (library) FT_Done_FreeType(library);
  }
};

namespace {

// The next code point of UTF-8 `text` at `i` (advancing it); U+FFFD for a malformed sequence.
uint32_t next_code_point(const std::string& text, size_t& i) {
  const auto byte = [&](size_t k) { return uint8_t(text[k]); };
  const uint8_t b = byte(i++);
  if (b < 0x80) return b;
  const int extra = b >= 0xF0 ? 3 : b >= 0xE0 ? 2 : b >= 0xC0 ? 1 : -1;
  if (extra < 0) return 0xFFFD;
  uint32_t cp = b & (0x3F >> extra);
  for (int k = 0; k < extra; ++k) {
    if (i >= text.size() || (byte(i) & 0xC0) != 0x80) return 0xFFFD;
    cp = (cp << 6) | (byte(i++) & 0x3F);
  }
  return cp;
}

// Walks the glyphs of `text` at `size` pixels, calling `glyph(pen_x)` with each one loaded in the
// face's glyph slot (rendered when `render`); returns the total advance.
template <typename Glyph>
int layout(FT_Face face, const std::string& text, uint32_t size, bool render, Glyph&& glyph) {
  if (size == 0) return 0;
  if (FT_Set_Pixel_Sizes(face, 0, size)) throw_internal("FreeType: cannot set the font size " + std::to_string(size));
  int pen = 0;
  FT_UInt previous = 0;
  for (size_t i = 0; i < text.size();) {
    const FT_UInt index = FT_Get_Char_Index(face, next_code_point(text, i));
    if (previous && index && FT_HAS_KERNING(face)) {
      FT_Vector kerning{};
      FT_Get_Kerning(face, previous, index, FT_KERNING_DEFAULT, &kerning);
      pen += int(kerning.x >> 6);
    }
    if (FT_Load_Glyph(face, index, render ? FT_LOAD_RENDER : FT_LOAD_DEFAULT)) continue;
    glyph(pen);
    pen += int(face->glyph->advance.x >> 6);
    previous = index;
  }
  return pen;
}

}  // namespace

std::filesystem::path Font::default_font_path() { return "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"; }

Font::Font(const std::filesystem::path& path) : face_(std::make_unique<Face>()) {
  if (FT_Init_FreeType(&face_->library)) throw_internal("FreeType: initialisation failed");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw_bad_input(path.string(), std::string("font not found") +
                                       (path == default_font_path() ? " (Debian package fonts-dejavu-core)" : ""));
  if (FT_New_Face(face_->library, path.c_str(), 0, &face_->face))
    throw_bad_input(path.string(), "not a font FreeType can read");
}

Font::~Font() = default;

int Font::width(const std::string& text, uint32_t size) const {
  return layout(face_->face, text, size, false, [](int) {});
}

namespace {

// The face's size metrics at `size` pixels per em (26.6 fixed point).
const FT_Size_Metrics& size_metrics(FT_Face face, uint32_t size) {
  if (FT_Set_Pixel_Sizes(face, 0, std::max(size, 1u))) throw_internal("FreeType: cannot set the font size " + std::to_string(size));
  return face->size->metrics;
}

}  // namespace

int Font::ascent(uint32_t size) const { return int((size_metrics(face_->face, size).ascender + 63) >> 6); }

int Font::line_height(uint32_t size) const {
  const FT_Size_Metrics& m = size_metrics(face_->face, size);
  return int((m.ascender - m.descender + 63) >> 6);
}

int Font::draw(Image& image, int x, int y, const std::string& text, uint32_t size, const uint8_t color[3]) const {
  const FT_Face face = face_->face;
  return layout(face, text, size, true, [&](int pen) {
    const FT_Bitmap& bitmap = face->glyph->bitmap;
    if (bitmap.pixel_mode != FT_PIXEL_MODE_GRAY) return;
    const int left = x + pen + face->glyph->bitmap_left, top = y - face->glyph->bitmap_top;
    for (unsigned r = 0; r < bitmap.rows; ++r) {
      const int py = top + int(r);
      if (py < 0 || py >= int(image.height)) continue;
      for (unsigned c = 0; c < bitmap.width; ++c) {
        const int px = left + int(c);
        if (px < 0 || px >= int(image.width)) continue;
        const unsigned coverage = bitmap.buffer[r * unsigned(bitmap.pitch) + c];
        uint8_t* p = &image.rgba[(size_t(py) * image.width + size_t(px)) * 4];
        for (int k = 0; k < 3; ++k) p[k] = uint8_t((p[k] * (255 - coverage) + color[k] * coverage + 127) / 255);
      }
    }
  });
}

}  // namespace lod
