// The label's stroke font (issue 8): our own single-line glyphs, drawn for this library on a
// 4 x 6 unit grid (the cap height is 6 units; round shapes are octagons with 1-unit
// chamfers, which stay legible when the strokes are 0.35 mm wide on 2.5 mm letters).
// No outside font is copied. Parallel strokes are at least 2 units apart, so they stay
// separate up to a stroke width of height / 4.
//
// Encoding: each glyph is a string of strokes separated by spaces; a stroke is a run of
// points written as two digits "xy" (x right, y up); a stroke of one point is a dot.
#include "splintcore/label.h"

namespace splintcore {

namespace {

struct GlyphSource {
  char character;
  uint8_t width;
  const char* strokes;
};

// Sorted by character code (the lookup is a linear scan: 44 entries).
constexpr GlyphSource kGlyphs[] = {
    {' ', 2, ""},
    {'#', 4, "1115 3135 0242 0444"},
    {'(', 2, "26040220"},
    {')', 2, "06242200"},
    {'+', 4, "2125 0343"},
    {'-', 3, "0333"},
    {'.', 0, "00"},
    {'/', 3, "0036"},
    {'0', 4, "100105163645413010 1234"},
    {'1', 4, "152620 0040"},
    {'2', 4, "05163645440040"},
    {'3', 4, "0516364544334241301001 1333"},
    {'4', 4, "30360242"},
    {'5', 4, "460604344341301001"},
    {'6', 4, "4536160501103041423303"},
    {'7', 4, "064610"},
    {'8', 4, "133344453616050413 133342413010010213"},
    {'9', 4, "0110304145361605041343"},
    {':', 0, "01 04"},
    {'A', 4, "0004264440 0343"},
    {'B', 4, "00063645443303 3342413000"},
    {'C', 4, "4536160501103041"},
    {'D', 4, "00062644422000"},
    {'E', 4, "40000646 0333"},
    {'F', 4, "000646 0333"},
    {'G', 4, "45361605011030414323"},
    {'H', 4, "0006 4046 0343"},
    {'I', 2, "1016 0020 0626"},
    {'J', 4, "464130100102"},
    {'K', 4, "0006 4602 1340"},
    {'L', 4, "060040"},
    {'M', 4, "0006234640"},
    {'N', 4, "00064046"},
    {'O', 4, "100105163645413010"},
    {'P', 4, "00063645443303"},
    {'Q', 4, "100105163645413010 2240"},
    {'R', 4, "00063645443303 2340"},
    {'S', 4, "453616050413334241301001"},
    {'T', 4, "0646 2026"},
    {'U', 4, "060110304146"},
    {'V', 4, "062046"},
    {'W', 4, "0610243046"},
    {'X', 4, "0046 0640"},
    {'Y', 4, "062346 2320"},
    {'Z', 4, "06460040"},
    {'_', 4, "0040"},
};

constexpr char kCharacters[] = " #()+-./0123456789:ABCDEFGHIJKLMNOPQRSTUVWXYZ_";

static_assert(sizeof(kGlyphs) / sizeof(kGlyphs[0]) + 1 == sizeof(kCharacters),
              "every glyph is listed in kCharacters");

}  // namespace

const char* stroke_font_characters() { return kCharacters; }

bool stroke_font_glyph(char c, StrokeGlyph* out) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  const GlyphSource* source = nullptr;
  for (const GlyphSource& g : kGlyphs) {
    if (g.character == c) {
      source = &g;
      break;
    }
  }
  if (source == nullptr) return false;
  StrokeGlyph g;
  g.character = source->character;
  g.width = source->width;
  g.advance = static_cast<uint8_t>(source->width + kStrokeFontGap);
  // The table is constant and checked by the tests (tests/label/label_test.cpp): a malformed
  // entry is a programmer error.
  const char* p = source->strokes;
  while (*p != '\0') {
    if (*p == ' ') {
      ++p;
      continue;
    }
    SPLINTCORE_ASSERT(g.stroke_count < kStrokeGlyphMaxStrokes);
    while (*p != '\0' && *p != ' ') {
      SPLINTCORE_ASSERT(p[1] != '\0' && g.point_count < kStrokeGlyphMaxPoints);
      SPLINTCORE_ASSERT(p[0] >= '0' && p[0] <= '9' && p[1] >= '0' && p[1] <= '9');
      g.points[g.point_count].x = static_cast<int8_t>(p[0] - '0');
      g.points[g.point_count].y = static_cast<int8_t>(p[1] - '0');
      ++g.point_count;
      p += 2;
    }
    g.stroke_end[g.stroke_count++] = g.point_count;
  }
  *out = g;
  return true;
}

}  // namespace splintcore
