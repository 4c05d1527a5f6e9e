// PNG round trips and rejection, fonts, contact sheets and the heat-map legend.
#include <gtest/gtest.h>

#include "lodkit/error.h"
#include "lodkit/render.h"
#include "test_support.h"

namespace lod {
namespace {

Image gradient(uint32_t w, uint32_t h) {
  Image image;
  image.width = w;
  image.height = h;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      image.rgba.insert(image.rgba.end(), {uint8_t(x * 7), uint8_t(y * 13), uint8_t(x ^ y), uint8_t(255 - x)});
  return image;
}

Image filled(uint32_t w, uint32_t h, uint8_t r, uint8_t g, uint8_t b) {
  Image image;
  image.width = w;
  image.height = h;
  for (size_t i = 0; i < size_t(w) * h; ++i) image.rgba.insert(image.rgba.end(), {r, g, b, 255});
  return image;
}

TEST(Png, RoundTripAndStableBytes) {
  const Image image = gradient(37, 23);
  const std::string png = encode_png(image);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png, encode_png(image));
  const Image back = decode_png(test::bytes_of(png), "mem.png");
  EXPECT_EQ(back.width, 37u);
  EXPECT_EQ(back.height, 23u);
  EXPECT_TRUE(back.rgba == image.rgba);
  test::TempDir dir;
  write_png(image, dir / "a.png");
  EXPECT_TRUE(read_png(dir / "a.png").rgba == image.rgba);
}

TEST(Png, RejectsBadInput) {
  for (const std::string& bytes : {std::string(), std::string("GIF89a......"), std::string("\x89PNG\r\n\x1a\n", 8) + "junk"}) {
    try {
      decode_png(test::bytes_of(bytes), "bad.png");
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input);
      EXPECT_EQ(std::string(e.what()).rfind("bad.png", 0), 0u) << e.what();
    }
  }
  Image wrong = gradient(4, 4);
  wrong.rgba.pop_back();
  EXPECT_THROW(encode_png(wrong), Error);
  EXPECT_THROW(read_png("/nonexistent/x.png"), Error);
}

TEST(Font, DrawsDarkPixelsWhereTheTextIs) {
  const Font font;
  Image image = filled(200, 40, 255, 255, 255);
  const uint8_t black[3] = {0, 0, 0};
  const int advance = font.draw(image, 10, 30, "LOD 12,345", 20, black);
  EXPECT_EQ(advance, font.width("LOD 12,345", 20));
  EXPECT_GT(advance, 60);
  EXPECT_LT(advance, 160);
  uint32_t dark = 0, dark_outside = 0;
  for (uint32_t y = 0; y < 40; ++y)
    for (uint32_t x = 0; x < 200; ++x) {
      const bool is_dark = image.pixel(x, y)[0] < 128;
      dark += is_dark;
      // Glyphs sit above the baseline (y 30) and right of the pen (x 10), within the advance.
      if (is_dark && (x < 10 || x > uint32_t(10 + advance) || y > 34 || y < 8)) ++dark_outside;
    }
  EXPECT_GT(dark, 100u);
  EXPECT_EQ(dark_outside, 0u);
  EXPECT_GT(font.width("WWW", 20), font.width("iii", 20));
}

TEST(Font, MissingFontNamesThePackage) {
  try {
    Font font("/nonexistent/font.ttf");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/font.ttf"), std::string::npos);
  }
}

TEST(ContactSheet, PanelsInAGridWithLabels) {
  const SheetOptions options{.width = 600, .height = 400};
  const SheetLayout layout = sheet_layout(3, options);
  EXPECT_EQ(layout.columns, 2u);
  EXPECT_EQ(layout.rows, 2u);
  EXPECT_EQ(layout.panel_width, 300u);
  EXPECT_EQ(layout.panel_height + layout.label_height, 200u);
  const Image panels[3] = {filled(layout.panel_width, layout.panel_height, 255, 0, 0),
                           filled(layout.panel_width, layout.panel_height, 0, 255, 0),
                           filled(layout.panel_width, layout.panel_height, 0, 0, 255)};
  const std::string labels[3] = {"LOD0", "LOD1", "LOD2"};
  const Font font;
  const Image sheet = contact_sheet(panels, labels, options, font);
  ASSERT_EQ(sheet.width, 600u);
  ASSERT_EQ(sheet.height, 400u);
  const uint8_t* p = sheet.pixel(150, 50);
  EXPECT_EQ(p[0], 255);
  EXPECT_EQ(p[1], 0);
  EXPECT_EQ(sheet.pixel(450, 50)[1], 255);
  EXPECT_EQ(sheet.pixel(150, 250)[2], 255);
  EXPECT_EQ(sheet.pixel(150, 250)[0], 0);
  EXPECT_EQ(sheet.pixel(450, 250)[0], 255);  // no fourth panel: white
  EXPECT_EQ(sheet.pixel(450, 250)[1], 255);
  // Each label strip holds dark text pixels.
  for (uint32_t cell = 0; cell < 3; ++cell) {
    const uint32_t x0 = (cell % 2) * 300, y0 = (cell / 2) * 200 + layout.panel_height;
    uint32_t dark = 0;
    for (uint32_t y = y0; y < y0 + layout.label_height; ++y)
      for (uint32_t x = x0; x < x0 + 300; ++x) dark += sheet.pixel(x, y)[0] < 100 && sheet.pixel(x, y)[1] < 100;
    EXPECT_GT(dark, 20u) << "label " << cell;
  }
  EXPECT_THROW(contact_sheet(std::span(panels, 2), std::span(labels, 3), options, font), Error);
  EXPECT_THROW(sheet_layout(0, options), Error);
  EXPECT_THROW(sheet_layout(100, {.width = 100, .height = 100}), Error);
}

// Labels too long for their panels at 8 pixels (4 panels in 320x240, 160 pixels wide) wrap onto the
// strip's lines, or are cut with an ellipsis, and never ink a neighbour's cell: every dark pixel
// lies in its own label's strip; the sentence takes two lines (two bands of inked rows), the
// single long word one.
TEST(ContactSheet, LongLabelsWrapInsideTheirCells) {
  const SheetOptions options{.width = 320, .height = 240};
  const SheetLayout layout = sheet_layout(4, options);
  ASSERT_EQ(layout.panel_width, 160u);
  const Image white = filled(layout.panel_width, layout.panel_height, 255, 255, 255);
  const Image panels[4] = {white, white, white, white};
  const std::string labels[4] = {"LOD0: 1,234,567 triangles x 12 instances, error 0.000123 (0.05%)", "",
                                 std::string(200, 'W'), ""};
  const Font font;
  ASSERT_GT(font.width(labels[0], 8), int(layout.panel_width));  // (too long for one line)
  const Image sheet = contact_sheet(panels, labels, options, font);
  const uint32_t cell_height = layout.panel_height + layout.label_height;
  std::vector<bool> inked_rows[4] = {std::vector<bool>(layout.label_height), std::vector<bool>(layout.label_height),
                                     std::vector<bool>(layout.label_height), std::vector<bool>(layout.label_height)};
  for (uint32_t y = 0; y < sheet.height; ++y)
    for (uint32_t x = 0; x < sheet.width; ++x) {
      if (sheet.pixel(x, y)[0] >= 150) continue;  // (the hairlines are grey 200)
      const uint32_t cell = (y / cell_height) * 2 + x / layout.panel_width, row = y % cell_height;
      ASSERT_TRUE(cell == 0 || cell == 2) << "ink at " << x << "," << y << " in cell " << cell;
      ASSERT_GE(row, layout.panel_height) << "ink at " << x << "," << y << " above the strip";
      inked_rows[cell][row - layout.panel_height] = true;
    }
  const auto bands = [](const std::vector<bool>& rows) {
    size_t count = 0;
    for (size_t r = 0; r < rows.size(); ++r) count += rows[r] && (r == 0 || !rows[r - 1]);
    return count;
  };
  EXPECT_EQ(bands(inked_rows[0]), 2u);
  EXPECT_EQ(bands(inked_rows[2]), 1u);
}

TEST(ContactSheet, HeatLegendRunsBlueToRed) {
  const Font font;
  Image image = filled(400, 300, 255, 255, 255);
  draw_heat_legend(image, font, "0", "max");
  // The bar's ends in the bottom-left corner: blue at the left, red at the right.
  int blue_x = -1, red_x = -1;
  const uint32_t row = 300 - 12;
  for (uint32_t x = 0; x < 400; ++x) {
    const uint8_t* p = image.pixel(x, row);
    if (p[0] == 0 && p[1] == 0 && p[2] == 255 && blue_x < 0) blue_x = int(x);
    if (p[0] == 255 && p[1] == 0 && p[2] == 0) red_x = int(x);
  }
  EXPECT_GE(blue_x, 0);
  EXPECT_GT(red_x, blue_x + 50);
}

}  // namespace
}  // namespace lod
