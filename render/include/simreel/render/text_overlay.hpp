#pragma once
/// @file text_overlay.hpp
/// Text drawn into an Image on the CPU with a built-in 5x7 bitmap font: frame numbers and
/// times on review videos and contact sheets. No font files, no GL.

#include <array>
#include <cstdint>
#include <string_view>

#include "simreel/render/image.hpp"

namespace simreel::render {

struct TextStyle {
  int scale = 2;  ///< each font pixel becomes scale x scale image pixels (>= 1)
  std::array<std::uint8_t, 4> color{255, 255, 255, 255};
  /// Drawn behind the text, with a margin of one font pixel; alpha 0 draws no box. The box is
  /// blended over the image with its alpha, so the picture stays visible behind a label.
  std::array<std::uint8_t, 4> background{0, 0, 0, 160};
};

/// Size in image pixels of `text` drawn with `style`, background margin included: each glyph
/// is 5x7 font pixels plus one of spacing.
struct TextExtent {
  int width = 0;
  int height = 0;
};
TextExtent measure_text(std::string_view text, const TextStyle& style);

/// Draws `text` with the top-left corner of its background box at (x, y) in image pixels,
/// clipped to the image. Digits, letters (lower case drawn as upper case) and
/// `. , : ; - + = / ( ) [ ] % _ ' " ! ? # * < > @ &` have glyphs; anything else draws as a box.
/// Text with `\n` continues on the next line.
void draw_text(Image& image, int x, int y, std::string_view text, const TextStyle& style);

}  // namespace simreel::render
