// rtlab-view — the overlay's text: a built-in 5x7 bitmap font drawn into an RGBA canvas on the
// host, which the viewer uploads as a texture. Lowercase prints as uppercase; characters the font
// lacks print as '?'.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rt::view {

struct Rgba {
    uint8_t r, g, b, a;
};

class TextCanvas {
  public:
    static constexpr int kCellWidth = 6, kCellHeight = 9;  // glyph 5x7 plus spacing
    static constexpr int kMargin = 3;                      // pixels around the text block

    // A canvas of cols x rows character cells (plus a margin) filled with `background`.
    TextCanvas(int cols, int rows, Rgba background);
    void text(int col, int row, const std::string& s, Rgba color);

    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<uint8_t>& rgba() const { return rgba_; }

  private:
    int width_, height_;
    std::vector<uint8_t> rgba_;
};

}  // namespace rt::view
