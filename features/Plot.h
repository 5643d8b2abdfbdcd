#pragma once
// Pictures for people: feature images in a perceptually uniform colour map with a labelled colour
// bar, text from a built-in bitmap font (no font files, no external library), and montages of
// such pictures in a labelled grid. Everything here produces an RGB Image (io/Image.h: 3
// channels, values in [0, 1], row 0 on top) that write_png writes as an 8-bit PNG.
//
// Colour map: viridis (S. van der Walt and N. Smith, 2015; the 256-entry table of matplotlib's
// _cm_listed.py, released under CC0), perceptually uniform in CAM02-UCS and monotone in lightness,
// so equal steps in value look like equal steps in colour, and it reads in grey-scale print and
// for the common forms of colour blindness. Its first entry is #440154 (dark purple), its last
// #FDE725 (yellow). NaN values are drawn in a neutral grey (kNanColour), which viridis never
// contains (every entry has a clear hue), so missing data cannot be mistaken for a value.
//
// Font: 5 x 7 pixel glyphs (capitals and digits occupy rows 0 - 6) plus one descender row (row 7,
// for g j p q y , ; _), in a 6 x 10 pixel cell at scale 1 (one blank column between glyphs, two
// blank rows between lines). Printable ASCII (32 - 126) is covered; any other character (each
// UTF-8 sequence counts as one) is drawn as a box, so a missing glyph is visible, not silent.
//
// Layout constants below are in output pixels; labels use the font at kPlotTextScale.
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "io/Image.h"

namespace ltm {

using Rgb = std::array<float, 3>;

// ---- colour map ----

// The 256 viridis entries, sRGB values in [0, 1] (6 decimals, as published by matplotlib).
const std::array<Rgb, 256>& viridis_table();

// viridis at t in [0, 1] (clamped; -inf -> 0, +inf -> 1): linear interpolation between the 256
// entries at s = 255 t, so t = 0 and t = 1 give the first and last entries exactly. NaN gives
// kNanColour.
Rgb viridis(double t);

constexpr Rgb kNanColour = {0.6f, 0.6f, 0.6f};      // neutral grey (#999999)
constexpr Rgb kWhite = {1.0f, 1.0f, 1.0f};          // background
constexpr Rgb kBlack = {0.0f, 0.0f, 0.0f};          // text
constexpr Rgb kFrameColour = {0.25f, 0.25f, 0.25f}; // the colour bar's frame and tick marks

// ---- text ----

constexpr int kGlyphWidth = 5;    // pixels at scale 1
constexpr int kGlyphHeight = 8;   // 7 rows above the baseline + 1 descender row
constexpr int kGlyphAdvance = 6;  // glyph + 1 blank column
constexpr int kLineAdvance = 10;  // glyph + 2 blank rows ('\n' starts a new line)

// The box a text occupies at `scale` (each font pixel becomes scale x scale image pixels):
// width = (kGlyphAdvance * longest line - 1) * scale (0 for an empty text), height =
// (kLineAdvance * (lines - 1) + kGlyphHeight) * scale. Characters are counted as drawn (one per
// UTF-8 sequence).
int text_width(const std::string& text, int scale);
int text_height(const std::string& text, int scale);

// Draws `text` with the top-left corner of its box at column x, row y of an RGB image (channels
// == 3, else std::invalid_argument; scale >= 1, else std::invalid_argument). Only the glyphs'
// pixels are painted (the background is left as it is); pixels outside the image are clipped.
// Unknown characters are drawn as a box (the glyph cell's 5 x 7 outline).
void draw_text(Image& rgb, int x, int y, const std::string& text, int scale, Rgb colour);

// ---- pseudo-colour image with a colour bar ----

constexpr int kPlotTextScale = 2;     // labels: 10 x 14 pixel capitals, 12 pixel advance
constexpr int kPlotMargin = 8;        // white border on every side
constexpr int kPlotTitleGap = 8;      // between the title's box and the image
constexpr int kPlotBarGap = 12;       // between the image and the colour bar
constexpr int kPlotBarWidth = 16;     // the colour bar
constexpr int kPlotTickLength = 4;    // tick marks right of the bar
constexpr int kPlotTickLabelGap = 4;  // between a tick mark and its label
constexpr int kPlotMinBarHeight = 64; // room for 3 labels (16 pixels high each) with gaps
constexpr int kPlotFiveTickHeight = 100;  // bars at least this tall get 5 ticks, shorter ones 3

// Where pseudo_colour puts things (all in output pixels; boxes as x, y of the top-left corner,
// width, height). Given the text sizes T = text_height(title) (0 without a title) and
// L = the widest tick label, s = pixel_scale, H = max(height * s, kPlotMinBarHeight):
//   title box      at (M, M)
//   image          at (M, M + T + G_t), width * s by height * s (top-aligned in the H rows)
//   colour bar     at (M + width * s + G_b, same y), kPlotBarWidth by H, framed by a 1-pixel line
//                  just outside it
//   tick marks     from the bar's right edge, kPlotTickLength long; labels kPlotTickLabelGap
//                  further right, centred vertically on their tick (cap height 7 * scale)
//   canvas width   max(M + width * s + G_b + kPlotBarWidth + kPlotTickLength + kPlotTickLabelGap
//                      + L + M,  M + text_width(title) + M)
//   canvas height  M + T + G_t + H + P + M, P = 4 * kPlotTextScale (the bottom label's lower half)
// with M = kPlotMargin, G_t = kPlotTitleGap if there is a title (else 0), G_b = kPlotBarGap.
// For example a 20 x 10 image at s = 4 with title "T" and ticks 0, 0.5, 1: T = 16, L = 34,
// H = 64, canvas 166 x 112.
struct PseudoColourLayout {
    int width = 0, height = 0;                    // the canvas
    int image_x = 0, image_y = 0, image_w = 0, image_h = 0;
    int bar_x = 0, bar_y = 0, bar_w = 0, bar_h = 0;
    int title_x = 0, title_y = 0;
    double lo = 0, hi = 1;                        // the range the colours span
    std::vector<double> tick_values;              // top (hi) to bottom (lo)
    std::vector<std::string> tick_labels;
    std::vector<int> tick_rows;                   // the canvas row of each tick
};

// The value range pseudo_colour uses: lo and hi as given when finite; a NaN lo (hi) is replaced by
// the smallest (largest) finite value (NaN and +-inf pixels are ignored; with no finite value at
// all, 0 and 1). If the range is then empty (lo == hi, e.g. a constant image) it is widened by 1,
// to [lo - 0.5, hi + 0.5], so the bar is valid and the constant is drawn in the map's middle
// colour. lo > hi or an infinite bound is std::invalid_argument.
std::pair<double, double> colour_range(const std::vector<float>& values, double lo, double hi);

// Compact tick labels: printf "%.3g" (more significant digits, up to 9, only where needed to tell
// neighbouring ticks apart), with the exponent shortened: 1e+03 -> 1e3, 2.5e-05 -> 2.5e-5.
std::string format_tick(double value, int significant_digits = 3);

// The layout pseudo_colour draws (see above); ticks are evenly spaced from hi (top) to lo
// (bottom), 5 of them if the bar is at least kPlotFiveTickHeight tall, else 3.
PseudoColourLayout pseudo_colour_layout(const std::vector<float>& values, int width, int height,
                                        const std::string& title, double lo, double hi, int pixel_scale);

// `values` (width x height, row-major, row 0 on top) drawn in viridis, each pixel as a
// pixel_scale x pixel_scale block (nearest), value v at t = (v - lo) / (hi - lo) clamped to
// [0, 1] (so values beyond the range take the end colours), NaN in kNanColour; a vertical colour
// bar to the right (bar row r of H shows hi - (hi - lo) r / (H - 1): its top row is exactly the
// colour of hi, its bottom row that of lo) with tick labels, and the title above (omitted when
// empty). lo / hi as colour_range. White background, black text. Bad sizes
// (values.size() != width * height, width or height < 1, pixel_scale < 1) are
// std::invalid_argument.
Image pseudo_colour(const std::vector<float>& values, int width, int height, const std::string& title,
                    double lo, double hi, int pixel_scale);

// pseudo_colour written as an 8-bit RGB PNG (write_png: atomic).
void write_pseudo_colour_png(const std::string& path, const std::vector<float>& values, int width, int height,
                             const std::string& title, double lo, double hi, int pixel_scale);

// ---- montage ----

constexpr int kMontageGap = 8;          // between cells
constexpr int kMontageLabelGap = 8;     // between row labels and cells, and below the title
constexpr int kMontageColumnGap = 4;    // between column labels and cells

// A grid of images: cells[r][c] in row r, column c (rows may be ragged; a missing or empty cell is
// left white). Every cell slot has the same size: cw = the widest cell, ch = the tallest; a slot
// is max(cw, widest column label) wide and ch tall, and each image is centred in its slot on
// white (left / top get the smaller half of the padding). 1-channel cells are drawn as grey
// (NaN in kNanColour), 3-channel cells as they are; other channel counts are
// std::invalid_argument. row_labels / column_labels must be empty or hold one label per row /
// column (else std::invalid_argument); row labels sit left of their row, vertically centred,
// right-aligned; column labels above their column, centred; the title centred on top.
// With M = kPlotMargin, T = text_height(title) + kMontageLabelGap (0 without a title),
// C = text_height(any label) + kMontageColumnGap (0 without column labels),
// R = widest row label + kMontageLabelGap (0 without row labels), sw = slot width, and
// rows x columns slots:
//   width  = max(M + R + columns * sw + (columns - 1) * kMontageGap + M,  M + text_width(title) + M)
//   height = M + T + C + rows * ch + (rows - 1) * kMontageGap + M
// All text uses kPlotTextScale.
Image montage(const std::vector<std::vector<Image>>& cells, const std::vector<std::string>& row_labels,
              const std::vector<std::string>& column_labels, const std::string& title);

// ---- histogram ----

// A histogram of `values` (non-finite ones ignored): `bins` equal bins over [min, max] of the
// values (log-spaced with log_x, values <= 0 then ignored), bars in viridis' middle colour on a
// framed plot, the bin edges of the first, middle and last bins as x tick labels, the largest
// count on the y axis, the title above and the x label below. 640 x 400 pixels. An empty or
// constant set draws one bar. bins < 1 is std::invalid_argument.
Image histogram(const std::vector<double>& values, int bins, const std::string& title, const std::string& x_label,
                bool log_x);

}  // namespace ltm
