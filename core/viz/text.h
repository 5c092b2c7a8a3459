// A built-in bitmap font, so charts and labelled pictures need no font files or libraries: one
// 5x8 glyph (7 rows above the baseline, 1 descender row) per printable ASCII character, drawn at
// integer scales. Anything else (control bytes, each non-ASCII UTF-8 code point) draws a box.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "core/image/image.h"

namespace hdr4d {

inline constexpr int kGlyphWidth = 5;     // inked columns of a glyph
inline constexpr int kGlyphHeight = 8;    // rows: 7 above the baseline, 1 for descenders
inline constexpr int kGlyphAdvance = 6;   // a glyph and one column of spacing
inline constexpr int kGlyphBaseline = 7;  // rows above the baseline

// Rows top to bottom; bit (kGlyphWidth - 1 - column) is set where a pixel is inked.
using GlyphRows = std::array<std::uint8_t, kGlyphHeight>;

// True for printable ASCII (32..126), the characters with a glyph of their own.
bool HasGlyph(char c);
// The glyph of `c`, or the box drawn for characters without one.
GlyphRows GlyphFor(char c);

// Characters as drawn: one per byte, except that a non-ASCII UTF-8 sequence counts (and draws
// a box) once.
int TextLength(std::string_view text);
// Width and height in pixels of `text` at `scale` (no trailing spacing column; 0 when empty).
int TextWidth(std::string_view text, int scale = 1);
int TextHeight(int scale = 1);

// Draws `text` with the top-left corner of its box at (x, y), each glyph pixel a scale x scale
// square in `rgb` (the first three channels; the image needs at least three). Clipped to the
// image; pixels outside [x, x + TextWidth) x [y, y + TextHeight) are never touched.
void DrawText(Image* image,
              int x,
              int y,
              std::string_view text,
              const std::array<float, 3>& rgb,
              int scale = 1);

// The same text turned 90 degrees counter-clockwise (reads bottom to top, as a vertical axis
// label): it fills [x, x + TextHeight) x [y, y + TextWidth), the first character at the bottom.
void DrawTextUp(Image* image,
                int x,
                int y,
                std::string_view text,
                const std::array<float, 3>& rgb,
                int scale = 1);

}  // namespace hdr4d
