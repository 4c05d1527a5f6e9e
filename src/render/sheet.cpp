// Contact sheets (a grid of labelled panels) and the heat-map legend.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "lodkit/render.h"

namespace lod {

namespace {

constexpr uint8_t black[3] = {20, 20, 20};

void fill(Image& image, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h, const uint8_t rgb[3]) {
  for (uint32_t y = y0; y < std::min(y0 + h, image.height); ++y)
    for (uint32_t x = x0; x < std::min(x0 + w, image.width); ++x) {
      uint8_t* p = &image.rgba[(size_t(y) * image.width + x) * 4];
      p[0] = rgb[0], p[1] = rgb[1], p[2] = rgb[2], p[3] = 255;
    }
}

// sRGB bytes of a linear colour, as the GL framebuffer encodes it.
uint8_t srgb_byte(float linear) {
  const double c = std::clamp(double(linear), 0.0, 1.0);
  const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
  return uint8_t(std::lround(s * 255));
}

// `text` cut back by whole UTF-8 characters and ended with an ellipsis, as long as fits `width`.
std::string ellipsized(const Font& font, std::string text, uint32_t size, int width) {
  static const std::string dots = "\u2026";
  while (!text.empty() && font.width(text + dots, size) > width) {
    while (!text.empty() && (uint8_t(text.back()) & 0xC0) == 0x80) text.pop_back();  // continuation bytes
    if (!text.empty()) text.pop_back();                                             // and the lead byte
  }
  return text + dots;
}

// Greedy word wrap of `text` into lines no wider than `width` pixels at `size`; a word wider than
// that on its own is cut (ellipsized).
std::vector<std::string> wrap(const Font& font, const std::string& text, uint32_t size, int width) {
  std::vector<std::string> words, lines;
  for (size_t i = 0; i < text.size();) {
    const size_t end = std::min(text.find(' ', i), text.size());
    if (end > i) words.push_back(text.substr(i, end - i));
    i = end + 1;
  }
  for (const std::string& word : words) {
    if (!lines.empty() && font.width(lines.back() + ' ' + word, size) <= width) {
      lines.back() += ' ' + word;
    } else {
      lines.push_back(font.width(word, size) <= width ? word : ellipsized(font, word, size, width));
    }
  }
  return lines;
}

}  // namespace

SheetLayout sheet_layout(uint32_t panels, const SheetOptions& options) {
  if (panels == 0) throw_usage("contact sheet: no panels");
  if (options.width == 0 || options.height == 0) throw_usage("contact sheet: the size must be at least 1x1");
  SheetLayout l;
  l.columns = options.columns ? std::min(options.columns, panels) : uint32_t(std::ceil(std::sqrt(double(panels))));
  l.rows = (panels + l.columns - 1) / l.columns;
  const uint32_t cell_height = options.height / l.rows;
  l.label_size = options.label_size ? options.label_size : std::clamp(cell_height / 16, 10u, 28u);
  l.label_height = l.label_size * 2;
  l.panel_width = options.width / l.columns;
  if (l.panel_width == 0 || cell_height <= l.label_height)
    throw_usage("contact sheet: " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " is too small for " + std::to_string(panels) + " labelled panels");
  l.panel_height = cell_height - l.label_height;
  return l;
}

Image contact_sheet(std::span<const Image> panels, std::span<const std::string> labels, const SheetOptions& options,
                    const Font& font) {
  if (labels.size() != panels.size()) throw_usage("contact sheet: one label per panel");
  const SheetLayout l = sheet_layout(uint32_t(panels.size()), options);
  Image sheet;
  sheet.width = options.width;
  sheet.height = options.height;
  sheet.rgba.assign(size_t(sheet.width) * sheet.height * 4, 255);
  // One type size for every label: the layout's, or smaller until the longest fits its panel on one
  // line; below 8 pixels, the labels wrap onto the lines the strip holds instead (at the largest size
  // down to 6 where they all fit, the last line kept ellipsized where they do not), so a label
  // never runs into its neighbour's cell.
  const int room = std::max(1, int(l.panel_width) - int(l.label_size));
  const auto advance = [&](uint32_t size) { return font.line_height(size); };  // baseline to baseline
  uint32_t size = l.label_size;
  const auto fits_one_line = [&] {
    return std::all_of(labels.begin(), labels.end(), [&](const std::string& label) { return font.width(label, size) <= room; });
  };
  while (size > 8 && !fits_one_line()) --size;
  std::vector<std::vector<std::string>> lines(labels.size());
  const auto wrap_all = [&] {
    size_t most = 1;
    for (size_t i = 0; i < labels.size(); ++i) most = std::max(most, (lines[i] = wrap(font, labels[i], size, room)).size());
    return most;
  };
  if (!fits_one_line()) {
    for (size = std::min(l.label_size, 8u);; --size)
      if (int(wrap_all()) * advance(size) <= int(l.label_height) || size == 6) break;
    const size_t most = size_t(std::max(1, int(l.label_height) / advance(size)));
    for (std::vector<std::string>& label : lines)
      if (label.size() > most) {
        label.resize(most);
        label.back() = ellipsized(font, label.back(), size, room);
      }
  } else {
    for (size_t i = 0; i < labels.size(); ++i) lines[i] = {labels[i]};
  }
  for (size_t i = 0; i < panels.size(); ++i) {
    const Image& panel = panels[i];
    if (panel.width != l.panel_width || panel.height != l.panel_height)
      throw_usage("contact sheet: panel " + std::to_string(i) + " is " + std::to_string(panel.width) + "x" +
                  std::to_string(panel.height) + ", the layout wants " + std::to_string(l.panel_width) + "x" +
                  std::to_string(l.panel_height));
    const uint32_t x0 = uint32_t(i % l.columns) * l.panel_width;
    const uint32_t y0 = uint32_t(i / l.columns) * (l.panel_height + l.label_height);
    for (uint32_t y = 0; y < panel.height; ++y)
      std::memcpy(&sheet.rgba[(size_t(y0 + y) * sheet.width + x0) * 4], &panel.rgba[size_t(y) * panel.width * 4],
                  size_t(panel.width) * 4);
    // The label centred in the strip under the panel: one line with its baseline a third of the way
    // up, or the block of lines centred.
    const int strip = int(y0 + l.panel_height);
    const int top = strip + (int(l.label_height) - int(lines[i].size()) * advance(size)) / 2;
    for (size_t k = 0; k < lines[i].size(); ++k) {
      const int text_width = font.width(lines[i][k], size);
      const int x = int(x0) + std::max(0, (int(l.panel_width) - text_width) / 2);
      const int baseline = lines[i].size() == 1 ? strip + int(l.label_height) - int(l.label_height) / 3
                                                : top + int(k) * advance(size) + font.ascent(size);
      font.draw(sheet, x, baseline, lines[i][k], size, black);
    }
  }
  // Hairlines between the cells.
  const uint8_t grey[3] = {200, 200, 200};
  for (uint32_t c = 1; c < l.columns; ++c) fill(sheet, c * l.panel_width, 0, 1, sheet.height, grey);
  for (uint32_t r = 1; r < l.rows; ++r) fill(sheet, 0, r * (l.panel_height + l.label_height), sheet.width, 1, grey);
  return sheet;
}

void draw_heat_legend(Image& image, const Font& font, const std::string& low, const std::string& high) {
  const uint32_t size = std::clamp(image.height / 40, 10u, 24u);
  const uint32_t bar_width = std::min(image.width / 3, 24 * size), bar_height = size;
  const uint32_t margin = size;
  if (image.width < bar_width + 2 * margin || image.height < bar_height + 3 * margin + size) return;  // no room
  const uint32_t x0 = margin, y0 = image.height - margin - bar_height;
  for (uint32_t x = 0; x < bar_width; ++x) {
    const float4 c = heat_color(bar_width > 1 ? float(x) / float(bar_width - 1) : 0.0f);
    const uint8_t rgb[3] = {srgb_byte(c.x), srgb_byte(c.y), srgb_byte(c.z)};
    fill(image, x0 + x, y0, 1, bar_height, rgb);
  }
  const int baseline = int(y0) - int(size) / 3;
  font.draw(image, int(x0), baseline, low, size, black);
  font.draw(image, int(x0 + bar_width) - font.width(high, size), baseline, high, size, black);
}

}  // namespace lod
