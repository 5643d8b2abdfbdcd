#pragma once
// Pictures for people: feature images in a perceptually uniform colour map with a labelled colour
// bar and axes in mm, montages of such pictures in a labelled grid, and histograms. Lines and
// text are drawn with Cairo (antialiased), text as the outlines of DejaVu Sans's glyphs, read from
// its file through FreeType (kFontFile; no fontconfig lookup, so the machine's font configuration
// does not change a figure) and filled as paths, not through Cairo's text API. Figures may be
// drawn from any number of threads at once. Data pixels are not drawn by Cairo: they are written into the picture afterwards,
// exact and nearest-neighbour, so a preview stays a faithful picture of the data. Everything here
// produces an RGB Image (io/Image.h: 3 channels, values in [0, 1], row 0 on top) that write_png
// writes (atomically) as an 8-bit PNG; write_pseudo_colour_png draws the same picture straight
// in code values (Image8), the file byte for byte the same.
//
// Colour map: viridis (S. van der Walt and N. Smith, 2015; the 256-entry table of matplotlib's
// _cm_listed.py, released under CC0), perceptually uniform in CAM02-UCS and monotone in lightness,
// so equal steps in value look like equal steps in colour, and it reads in grey-scale print and
// for the common forms of colour blindness. Its first entry is #440154 (dark purple), its last
// #FDE725 (yellow). NaN values are drawn in a neutral grey (kNanColour), which viridis never
// contains (every entry has a clear hue), so missing data cannot be mistaken for a value.
//
// Layout constants below are in output pixels; font sizes are the em size in pixels.
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
constexpr Rgb kFrameColour = {0.25f, 0.25f, 0.25f}; // frames, axes and tick marks

// ---- text ----

// The one font every figure uses (Debian package fonts-dejavu-core), read directly from this file.
constexpr const char* kFontFile = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

constexpr double kTitleFontSize = 15;  // figure titles
constexpr double kLabelFontSize = 13;  // axis labels, montage row and column labels
constexpr double kTickFontSize = 12;   // tick labels

// Loads `path` with FreeType; throws std::runtime_error naming the path (and the Debian package
// fonts-dejavu-core) if it is missing or not a font. Every drawing function below calls it for
// kFontFile (once per process; the face is then kept).
void require_font(const std::string& path = kFontFile);

// A text's box at a font size: width = its advance (the sum of its glyphs' advances, each rounded
// to whole pixels), height = the font's ascent and descent, each rounded up to whole pixels (the
// same for every text of that size: a line). A label drawn in a
// box has its baseline `ascent` below the box's top; its ink stays inside the box (up to the
// antialiasing fringe of about a pixel at the left and right ends).
double text_width(const std::string& text, double size);
int text_height(double size);

// A rectangle in output pixels: top-left corner (x, y), width w, height h.
struct Box {
    double x = 0, y = 0, w = 0, h = 0;
};

// A text as a figure draws it: in `box`, horizontal, or turned 90 degrees counter-clockwise
// (vertical: reads bottom to top; box.w is then the line height and box.h the text's width).
struct Label {
    std::string text;
    double size = kTickFontSize;
    bool vertical = false;
    Box box;
};

// ---- ticks ----

// Tick values for an axis over [lo, hi]: every multiple k * step in [lo, hi] (ends included, to
// 1e-9 of a step), step = m * 10^e with m in {1, 2, 2.5, 5}: the smallest such step that gives
// at most max_ticks ticks (max_ticks < 2 counts as 2; if that step gives fewer than 2 ticks, the
// next smaller one); with whole_steps only whole-number steps (1, 2, 5, 10, 20, 25, ...: for
// counts, indices, masks). Values are k * m * 10^e computed so that decimal ticks are the
// doubles nearest to them (0.3, not 0.30000000000000004), and 0 is exactly 0. lo > hi, or a
// non-finite bound, is std::invalid_argument; lo == hi gives that one value.
// Examples: [0, 1] at most 6: 0, 0.2, 0.4, 0.6, 0.8, 1; at most 5: 0, 0.25, 0.5, 0.75, 1;
// [-12.5, 12.5] at most 9: -10, -5, 0, 5, 10; [3, 16] at most 6: 5, 7.5, 10, 12.5, 15, with
// whole steps 5, 10, 15.
std::vector<double> nice_ticks(double lo, double hi, int max_ticks, bool whole_steps = false);

// Labels for ticks from nice_ticks (evenly spaced): fixed-point with just the decimals the
// spacing needs ("0.00", "0.25", "0.50"; "25000"), or, when the largest magnitude is >= 1e6 or
// the spacing < 1e-4, format_tick with enough digits to tell neighbours apart ("1.5e6").
// Negative values get a real minus sign (U+2212, "−10").
std::vector<std::string> tick_labels(const std::vector<double>& ticks);

// Compact value labels: printf "%.3g" (significant_digits, clamped to 1 - 17), with the exponent
// shortened: 1e+03 -> 1e3, 2.5e-05 -> 2.5e-5; hyphen-minus signs.
std::string format_tick(double value, int significant_digits = 3);

// ---- pseudo-colour image with a colour bar ----

// The part of the focus plane an image covers, in mm, centred on the optical axis (a camera's
// `size`, docs/scene-format.md): column 0's left edge is x = -width/2, the last column's right
// edge +width/2; row 0's top edge is y = +height/2 (the +y edge, docs/conventions.md), the last
// row's bottom edge -height/2. width or height <= 0 (the default) means unknown: no axes.
struct ImageExtent {
    double width = 0, height = 0;
    bool known() const;
};

constexpr int kPlotMargin = 10;        // white border on every side of everything drawn
constexpr int kPlotTitleGap = 8;       // between the title's box and the image's frame
constexpr int kPlotBarGap = 16;        // between the image and the colour bar
constexpr int kPlotBarWidth = 14;      // the colour bar
constexpr int kPlotTickLength = 4;     // tick marks, outside the frame
constexpr int kPlotTickLabelGap = 4;   // between a tick mark's end and its label's box
constexpr int kPlotAxisLabelGap = 4;   // between the tick labels and the axis label ("x (mm)")
constexpr int kPlotMinBarHeight = 80;  // the colour bar is at least this tall
constexpr int kPlotTickSpacing = 50;   // an axis of length n gets at most n / 50 + 1 ticks

// Where pseudo_colour puts things, in output pixels (s = pixel_scale):
//   image        image_w = width * s by image_h = height * s; data pixel (m, n) fills the s x s
//                block at (image_x + n s, image_y + m s). Framed by a 1-pixel kFrameColour line
//                just outside it.
//   axis ticks   on any axis n pixels long: nice_ticks with at most n / kPlotTickSpacing + 1, fewer
//                while neighbouring labels would come closer than kPlotTickLabelGap; if even 2
//                are too close, only the ticks whose labels clear the last one kept are kept.
//   axes         (only when the extent is known) ticks in mm over the extent below the frame (x)
//                and left of it (y), kPlotTickLength long, labels centred under / beside them
//                kPlotTickLabelGap further out, and the axis labels "x (mm)" centred below the x
//                tick labels and "y (mm)" (vertical) left of the y tick labels, kPlotAxisLabelGap
//                further out. x tick at value v: column image_x + (v + width_mm / 2) / width_mm *
//                image_w; y tick: row image_y + (height_mm / 2 - v) / height_mm * image_h.
//   colour bar   kPlotBarWidth by bar_h = max(image_h, kPlotMinBarHeight) at bar_x = image_x +
//                image_w + kPlotBarGap, bar_y = image_y, framed like the image; bar row r shows
//                t = 1 - r / (bar_h - 1): exactly the colour of hi on top, of lo at the bottom.
//                Ticks over [lo, hi] (the axis taken as bar_h - 1 long) right of it at row
//                bar_y + (hi - v) / (hi - lo) * (bar_h - 1) + 0.5 (the centre line of the row
//                showing v), labels vertically centred on them; whole-number steps when lo, hi
//                and every finite value are whole numbers (counts, indices, masks).
//   title        centred over the image, kPlotTitleGap above the frame and every other label
//                (none when empty).
// Everything drawn (the frames included) is then shifted so that its bounding box starts
// kPlotMargin from the top-left corner, and the canvas is that box plus kPlotMargin on every side.
struct PseudoColourLayout {
    int width = 0, height = 0;                    // the canvas
    int image_x = 0, image_y = 0, image_w = 0, image_h = 0;
    int bar_x = 0, bar_y = 0, bar_w = 0, bar_h = 0;
    double lo = 0, hi = 1;                        // the range the colours span
    std::vector<double> tick_values;              // the colour bar's, increasing
    std::vector<std::string> tick_labels;
    std::vector<double> tick_rows;                // the canvas row (y, at the tick's centre line) of each
    std::vector<double> x_ticks, y_ticks;         // mm, increasing (empty without an extent)
    std::vector<double> x_tick_columns, y_tick_rows;  // their canvas x / y
    std::vector<Label> labels;                    // every text drawn: title, tick labels, axis labels
};

// The value range pseudo_colour uses: lo and hi as given when finite; a NaN lo (hi) is replaced by
// the smallest (largest) finite value (NaN and +-inf pixels are ignored; with no finite value at
// all, 0 and 1). If the range is then empty (lo == hi, e.g. a constant image) it is widened by 1,
// to [lo - 0.5, hi + 0.5], so the bar is valid and the constant is drawn in the map's middle
// colour. lo > hi or an infinite bound is std::invalid_argument.
std::pair<double, double> colour_range(const std::vector<float>& values, double lo, double hi);

// The layout pseudo_colour draws (see above).
PseudoColourLayout pseudo_colour_layout(const std::vector<float>& values, int width, int height,
                                        const std::string& title, double lo, double hi, int pixel_scale,
                                        const ImageExtent& extent = {});

// A ring marking a spot of a pseudo-colour image (a defect in a montage): centred at (x, y), radius
// `radius`, all in data pixels with Contrast.h's coordinates (x along columns, y down the rows,
// data pixel (m, n) the unit square at (n, m)). Drawn by pseudo_colour over its data cells, in
// output pixels exactly (no antialiasing): those whose centre lies within 1 of the circle of
// radius radius * pixel_scale are white, those between 1 and 2 of it black, so the ring shows on
// every colour of the map (white on its dark end, black on its light end); clipped to the image.
struct Ring {
    double x = 0, y = 0, radius = 0;
};

// `values` (width x height, row-major, row 0 on top) drawn in viridis, each pixel as a
// pixel_scale x pixel_scale block (nearest, exactly viridis((v - lo) / (hi - lo)) with t clamped
// to [0, 1], so values beyond the range take the end colours; NaN exactly kNanColour), with the
// colour bar, the axes (if the extent is known) and the title (omitted when empty) as laid out
// above. lo / hi as colour_range. White background, black text. Bad sizes (values.size() !=
// width * height, width or height < 1, pixel_scale < 1, a scaled side beyond 32768) are
// std::invalid_argument. `rings` are drawn over the data cells (Ring).
Image pseudo_colour(const std::vector<float>& values, int width, int height, const std::string& title,
                    double lo, double hi, int pixel_scale, const ImageExtent& extent = {},
                    const std::vector<Ring>& rings = {});

// pseudo_colour written as an 8-bit RGB PNG (write_png: atomic): the same drawing in code values
// (Image8), so the file is the one write_png(pseudo_colour(...)) writes, without the float picture.
// With `group`, committed into it (io/AtomicFile.h's CommitGroup). From kPreviewTableCells cells on,
// the cells' colours come from a table of exact colours by bucket of the value (features/Plot.cpp
// says why it gives the same codes).
inline constexpr long long kPreviewTableCells = 1 << 17;
void write_pseudo_colour_png(const std::string& path, const std::vector<float>& values, int width, int height,
                             const std::string& title, double lo, double hi, int pixel_scale,
                             const ImageExtent& extent = {}, io::CommitGroup* group = nullptr);

// ---- montage ----

constexpr int kMontageGap = 8;          // between cells
constexpr int kMontageLabelGap = 8;     // between row labels and cells, and below the title
constexpr int kMontageColumnGap = 4;    // between column labels and cells

// A grid of images: cells[r][c] in row r, column c (rows may be ragged; a missing or empty cell is
// left white). 1-channel cells are copied as grey (NaN as kNanColour), 3-channel cells exactly as
// they are; other channel counts are std::invalid_argument. row_labels / column_labels must be
// empty or hold one label per row / column (else std::invalid_argument). Row labels are vertical
// (reading upwards) left of their row, centred on it; column labels above their column, centred;
// the title centred on top. Labels at kLabelFontSize, the title at kTitleFontSize. With
// M = kPlotMargin, cw / ch the widest / tallest cell, a slot sw = max(cw, widest column label)
// wide and sh = max(ch, longest row label) tall (cells centred in their slot on white; left / top
// get the smaller half of the padding), T = text_height(kTitleFontSize) + kMontageLabelGap (0
// without a title), C = text_height(kLabelFontSize) + kMontageColumnGap (0 without column labels),
// R = text_height(kLabelFontSize) + kMontageLabelGap (0 without row labels), and
// rows x columns slots (text widths rounded up):
//   width  = max(M + R + columns * sw + (columns - 1) * kMontageGap + M,  M + text_width(title) + M)
//   height = M + T + C + rows * sh + (rows - 1) * kMontageGap + M
// and slot (r, c) at x = M + R + c (sw + kMontageGap), y = M + T + C + r (sh + kMontageGap).
Image montage(const std::vector<std::vector<Image>>& cells, const std::vector<std::string>& row_labels,
              const std::vector<std::string>& column_labels, const std::string& title);

// ---- histogram ----

constexpr int kHistogramWidth = 640, kHistogramHeight = 400;

// Where histogram puts things, in output pixels: the plot box (the axes are 1-pixel lines just
// left of and below it), one bar per bin (bars[b] over bin b, left to right, bins equally wide;
// a count c reaches up to row plot.y + plot.h - c / y_max * plot.h), the ticks and every label.
// y: counts from 0 to y_max = the last y tick; the y ticks are nice_ticks over [0, largest count]
// (at most 8, whole-number steps), one step more if the largest count is above the last. x: nice_ticks over the bins' range (at most 8), or with log_x the
// powers of ten inside it (if fewer than 2: 1, 2 and 5 times powers of ten; if still fewer:
// nice_ticks of the values), placed at log10 of the value. Labels: the title centred on top
// (kTitleFontSize), tick labels under / left of their ticks (kTickFontSize), the x label centred
// below the x tick labels and the y label vertical at the left (kLabelFontSize). The plot box
// leaves room for all of them inside kPlotMargin.
struct HistogramLayout {
    int width = kHistogramWidth, height = kHistogramHeight;
    Box plot;
    double lo = 0, hi = 1;                    // the x range (log10 of the values with log_x)
    std::vector<long> counts;
    std::vector<Box> bars;
    double y_max = 1;
    std::vector<double> x_ticks, y_ticks;     // values (not log10), counts
    std::vector<double> x_tick_columns, y_tick_rows;
    std::vector<Label> labels;
};

// The histogram of `values` (non-finite ones ignored): `bins` equal bins over [min, max] of the
// values (log-spaced with log_x, values <= 0 then ignored), laid out as above, kHistogramWidth x
// kHistogramHeight pixels. A constant set draws one bin over [v - 0.5, v + 0.5], an empty one one
// empty bin over [0, 1] (both in log10 with log_x). bins < 1 is std::invalid_argument.
HistogramLayout histogram_layout(const std::vector<double>& values, int bins, const std::string& title,
                                 const std::string& x_label, bool log_x, const std::string& y_label = "count");
Image histogram(const std::vector<double>& values, int bins, const std::string& title, const std::string& x_label,
                bool log_x, const std::string& y_label = "count");

// ---- line plot ----

constexpr int kLinePlotWidth = 760, kLinePlotHeight = 420;
constexpr int kLegendSample = 24;  // the length of a legend's line sample
constexpr int kLegendGap = 6;      // between the sample and its name, and between the plot and the legend

// One curve: points (x[i], y[i]) joined in order; a point that cannot be drawn (non-finite, or
// <= 0 on a log axis) breaks the line there. Drawn in `colour`, solid, dashed or dotted.
struct Series {
    std::string name;
    std::vector<double> x, y;
    Rgb colour = kBlack;
    bool dashed = false;  // 5 on, 3 off
    bool dotted = false;  // 1 on, 3 off (dashed wins if both)
};

// Curves over common axes, kLinePlotWidth x kLinePlotHeight pixels: the axes span the drawable
// points of all series (widened by 1 around a single value, in log10 on a log axis), with ticks as
// histogram places them (log_x / log_y: powers of ten, else 1, 2, 5 times them); every point
// marked by a 3-pixel square; the legend (each series' line sample and name, in order) right of the
// plot box, the title on top, the axis labels below and left. std::invalid_argument if a series'
// x and y differ in length.
Image line_plot(const std::vector<Series>& series, const std::string& title, const std::string& x_label,
                const std::string& y_label, bool log_x, bool log_y);

// Colours for curves: viridis at evenly spaced points from 0 to 0.85 (its yellow end is too
// light on white), i of n.
Rgb series_colour(int i, int n);

}  // namespace ltm
