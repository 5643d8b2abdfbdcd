// Pictures for people (features/Plot.h): the viridis table, the font, tick choice, pseudo-colour
// images with their colour bar and axes, montages, histograms, PNG output. The figures' text is
// antialiased, so these tests do not compare glyph pixels: they check the contract instead (data
// cells exactly the viridis colour of their value, the bar monotone, tick values, every label
// inked inside its box and nothing drawn where nothing belongs, sizes as documented).
//
// Set LTM_PLOT_SAMPLE=/some/file.png to have Montage.SampleForPeople also write its montage there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "features/Features.h"
#include "features/Plot.h"
#include "io/Image.h"
#include "tests/Preemption.h"

namespace fs = std::filesystem;
using ltm::Box;
using ltm::Image;
using ltm::Rgb;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::string kMinus = "\xE2\x88\x92";  // U+2212

int code(float v) { return static_cast<int>(std::lround(255.0 * v)); }

Rgb pixel(const Image& img, int row, int col) { return {img.at(row, col, 0), img.at(row, col, 1), img.at(row, col, 2)}; }

bool is_white(const Image& img, int row, int col) { return pixel(img, row, col) == ltm::kWhite; }

// The 8-bit codes of a pixel equal those of a colour (what Cairo draws is stored in 8 bits).
bool same_codes(const Rgb& a, const Rgb& b) {
    for (std::size_t k = 0; k < 3; ++k)
        if (code(a[k]) != code(b[k])) return false;
    return true;
}

// CIELAB L* of an sRGB colour (IEC 61966-2-1 decoding, D65 luminance weights, CIE 1976 L*).
double lightness(const Rgb& c) {
    auto linear = [](double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); };
    const double Y = 0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]);
    return Y > 216.0 / 24389.0 ? 116.0 * std::cbrt(Y) - 16.0 : Y * 24389.0 / 27.0;
}

std::vector<float> ramp(int w, int h) {
    std::vector<float> v(static_cast<std::size_t>(w * h));
    for (int k = 0; k < w * h; ++k) v[static_cast<std::size_t>(k)] = static_cast<float>(k) / static_cast<float>(w * h - 1);
    return v;
}

Box grown(const Box& b, double by) { return {b.x - by, b.y - by, b.w + 2 * by, b.h + 2 * by}; }

bool contains(const Box& b, int row, int col) {
    return col + 0.5 >= b.x && col + 0.5 <= b.x + b.w && row + 0.5 >= b.y && row + 0.5 <= b.y + b.h;
}

bool overlap(const Box& a, const Box& b) {
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

// Non-white pixels inside a box.
int ink(const Image& img, const Box& b) {
    int n = 0;
    for (int r = std::max(0, static_cast<int>(b.y)); r < std::min(img.height, static_cast<int>(std::ceil(b.y + b.h))); ++r)
        for (int c = std::max(0, static_cast<int>(b.x)); c < std::min(img.width, static_cast<int>(std::ceil(b.x + b.w))); ++c)
            n += !is_white(img, r, c);
    return n;
}

// Every label has ink inside its box (grown by a pixel of antialiasing); the boxes do not overlap
// each other or `blocks` (e.g. the image and the colour bar with their frames); the canvas'
// margin is white; and no ink lies outside the allowed boxes.
void expect_clean_figure(const Image& img, const std::vector<ltm::Label>& labels, const std::vector<Box>& blocks,
                         std::vector<Box> allowed) {
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const auto& l = labels[i];
        EXPECT_GT(ink(img, grown(l.box, 1)), 0) << "label '" << l.text << "' is not drawn";
        for (std::size_t j = i + 1; j < labels.size(); ++j)
            EXPECT_FALSE(overlap(l.box, labels[j].box)) << "'" << l.text << "' overlaps '" << labels[j].text << "'";
        for (const Box& b : blocks) EXPECT_FALSE(overlap(l.box, b)) << "'" << l.text << "' overlaps a block";
        allowed.push_back(grown(l.box, 1));
    }
    const int M = ltm::kPlotMargin;
    int in_margin = 0, stray = 0;
    for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) {
            if (is_white(img, r, c)) continue;
            if (r < M - 1 || c < M - 1 || r >= img.height - M + 1 || c >= img.width - M + 1) ++in_margin;
            bool ok = false;
            for (const Box& b : allowed) ok = ok || contains(b, r, c);
            stray += !ok;
        }
    EXPECT_EQ(in_margin, 0) << "ink in the white margin";
    EXPECT_EQ(stray, 0) << "ink outside every label, block and tick";
}

// The boxes a pseudo-colour figure may draw in besides its labels: the image and the bar with
// their frames and tick marks.
std::vector<Box> pseudo_colour_blocks(const ltm::PseudoColourLayout& L) {
    return {{L.image_x - 1.0, L.image_y - 1.0, L.image_w + 2.0, L.image_h + 2.0},
            {L.bar_x - 1.0, L.bar_y - 1.0, L.bar_w + 2.0, L.bar_h + 2.0}};
}
std::vector<Box> pseudo_colour_ink(const ltm::PseudoColourLayout& L) {
    const double t = ltm::kPlotTickLength;
    return {{L.image_x - 1.0 - t, L.image_y - 1.0, L.image_w + 2.0 + t, L.image_h + 2.0 + t},
            {L.bar_x - 1.0, L.bar_y - 1.0, L.bar_w + 2.0 + t, L.bar_h + 2.0}};
}

}  // namespace

// ---- colour map ----

TEST(Viridis, EndpointsAreThePublishedValues) {
    const auto& t = ltm::viridis_table();
    // #440154 and #FDE725 (van der Walt and Smith; matplotlib's viridis)
    EXPECT_EQ(code(t[0][0]), 0x44);
    EXPECT_EQ(code(t[0][1]), 0x01);
    EXPECT_EQ(code(t[0][2]), 0x54);
    EXPECT_EQ(code(t[255][0]), 0xFD);
    EXPECT_EQ(code(t[255][1]), 0xE7);
    EXPECT_EQ(code(t[255][2]), 0x25);
    EXPECT_EQ(ltm::viridis(0.0), t[0]);
    EXPECT_EQ(ltm::viridis(1.0), t[255]);
    EXPECT_EQ(ltm::viridis(-3.0), t[0]);
    EXPECT_EQ(ltm::viridis(7.0), t[255]);
    EXPECT_EQ(ltm::viridis(-std::numeric_limits<double>::infinity()), t[0]);
    EXPECT_EQ(ltm::viridis(std::numeric_limits<double>::infinity()), t[255]);
    // t = k / 255 lands on entry k (up to the rounding of k / 255: same 8-bit colour)
    for (int k = 0; k < 256; ++k) {
        const Rgb c = ltm::viridis(k / 255.0);
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(code(c[ch]), code(t[static_cast<std::size_t>(k)][ch])) << k;
    }
}

TEST(Viridis, LightnessIncreasesMonotonically) {
    const auto& t = ltm::viridis_table();
    for (std::size_t k = 1; k < t.size(); ++k) EXPECT_GT(lightness(t[k]), lightness(t[k - 1])) << "entry " << k;
    // between the entries too (interpolation stays monotone)
    double previous = lightness(ltm::viridis(0.0));
    for (int i = 1; i <= 4096; ++i) {
        const double L = lightness(ltm::viridis(i / 4096.0));
        EXPECT_GE(L, previous) << i;
        previous = L;
    }
    EXPECT_LT(lightness(t[0]), 20.0);   // dark purple ...
    EXPECT_GT(lightness(t[255]), 85.0); // ... to light yellow
}

TEST(Viridis, NanIsANeutralGreyTheMapNeverUses) {
    const Rgb nan = ltm::viridis(kNaN);
    EXPECT_EQ(nan, ltm::kNanColour);
    EXPECT_EQ(nan[0], nan[1]);
    EXPECT_EQ(nan[1], nan[2]);
    // every viridis entry has a clear hue: its channels spread by more than 25 codes (0.1)
    for (const Rgb& c : ltm::viridis_table()) {
        const float spread = std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]});
        EXPECT_GT(spread, 0.1f);
    }
    // ... and the grey is neither the background nor the text
    EXPECT_NE(nan, ltm::kWhite);
    EXPECT_NE(nan, ltm::kBlack);
}

// ---- font and text ----

TEST(Font, TheFontFileLoadsAndAMissingOneIsNamed) {
    EXPECT_NO_THROW(ltm::require_font());
    const std::string missing = "/nonexistent/fonts/DejaVuSans.ttf";
    try {
        ltm::require_font(missing);
        ADD_FAILURE() << "no error for a missing font file";
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(missing), std::string::npos) << m;
        EXPECT_NE(m.find("fonts-dejavu-core"), std::string::npos) << m;
        EXPECT_NE(m.find("missing"), std::string::npos) << m;
    }
    // a file that is not a font
    const fs::path junk = fs::temp_directory_path() / ("ltm_plot_font_" + std::to_string(::getpid()) + ".ttf");
    std::ofstream(junk) << "not a font\n";
    try {
        ltm::require_font(junk.string());
        ADD_FAILURE() << "no error for a file that is not a font";
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(junk.string()), std::string::npos) << m;
        EXPECT_NE(m.find("not a font"), std::string::npos) << m;
        EXPECT_NE(m.find("fonts-dejavu-core"), std::string::npos) << m;
    }
    fs::remove(junk);
}

TEST(Text, SizesFollowTheFont) {
    EXPECT_EQ(ltm::text_width("", 12), 0.0);
    EXPECT_GT(ltm::text_width("ab", 12), ltm::text_width("a", 12));
    // DejaVu Sans: ascent + descent = 1.164 em; digits are 0.636 em wide
    EXPECT_GE(ltm::text_height(12), 13);
    EXPECT_LE(ltm::text_height(12), 15);
    EXPECT_GE(ltm::text_height(24), 27);
    EXPECT_LE(ltm::text_height(24), 29);
    EXPECT_NEAR(ltm::text_width("0123456789", 20), 10 * 0.636 * 20, 10);
    EXPECT_NEAR(ltm::text_width("scatter", 24), 2 * ltm::text_width("scatter", 12), 3);
}

// ---- ticks ----

TEST(Ticks, HandDerivedCases) {
    using V = std::vector<double>;
    // [0, 1]: step 0.1 gives 11 ticks, 0.2 gives 6 (<= 6); with at most 5, 0.2's 6 are too many, 0.25 gives 5
    EXPECT_EQ(ltm::nice_ticks(0, 1, 6), (V{0, 0.2, 0.4, 0.6, 0.8, 1}));
    EXPECT_EQ(ltm::nice_ticks(0, 1, 5), (V{0, 0.25, 0.5, 0.75, 1}));
    EXPECT_EQ(ltm::nice_ticks(0, 1, 11), (V{0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1}));  // the doubles of the decimals
    // a 25 mm field of view: 2.5 gives 11 ticks, 5 gives 5
    EXPECT_EQ(ltm::nice_ticks(-12.5, 12.5, 9), (V{-10, -5, 0, 5, 10}));
    EXPECT_EQ(ltm::nice_ticks(-12.5, 12.5, 11), (V{-12.5, -10, -7.5, -5, -2.5, 0, 2.5, 5, 7.5, 10, 12.5}));
    // counts 21 .. 48: 2 gives 14, 2.5 gives 11, 5 gives 25 .. 45
    EXPECT_EQ(ltm::nice_ticks(21, 48, 9), (V{25, 30, 35, 40, 45}));
    // a symmetric range: exactly 0 in the middle
    const V sym = ltm::nice_ticks(-0.3, 0.3, 7);
    EXPECT_EQ(sym, (V{-0.3, -0.2, -0.1, 0, 0.1, 0.2, 0.3}));
    EXPECT_EQ(sym[3], 0.0);
    EXPECT_FALSE(std::signbit(sym[3]));
    // far from zero, narrow
    EXPECT_EQ(ltm::nice_ticks(1000, 1000.5, 6), (V{1000, 1000.1, 1000.2, 1000.3, 1000.4, 1000.5}));
    // large and small magnitudes
    EXPECT_EQ(ltm::nice_ticks(0, 3e6, 4), (V{0, 1e6, 2e6, 3e6}));
    EXPECT_EQ(ltm::nice_ticks(2e-5, 9e-5, 4), (V{2e-5, 4e-5, 6e-5, 8e-5}));
    // at most 2 on [0.1, 0.9]: 0.5 leaves only one tick, so the next smaller step (0.25) is used
    EXPECT_EQ(ltm::nice_ticks(0.1, 0.9, 2), (V{0.25, 0.5, 0.75}));
    // whole numbers: [0, 3] at most 8 would step by 0.5 (7 ticks); with whole steps, by 1
    EXPECT_EQ(ltm::nice_ticks(0, 3, 8), (V{0, 0.5, 1, 1.5, 2, 2.5, 3}));
    EXPECT_EQ(ltm::nice_ticks(0, 3, 8, true), (V{0, 1, 2, 3}));
    EXPECT_EQ(ltm::nice_ticks(0, 1, 2, true), (V{0, 1}));
    EXPECT_EQ(ltm::nice_ticks(21, 48, 30, true), (V{21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32, 33, 34, 35, 36, 37,
                                                    38, 39, 40, 41, 42, 43, 44, 45, 46, 47, 48}));
    // [3, 16] at most 6: 2 gives 7, 2.5 gives 5; whole steps skip 2.5, so 5 (3 ticks)
    EXPECT_EQ(ltm::nice_ticks(3, 16, 6), (V{5, 7.5, 10, 12.5, 15}));
    EXPECT_EQ(ltm::nice_ticks(3, 16, 6, true), (V{5, 10, 15}));
    // 25 is a whole step, 2.5 is not
    EXPECT_EQ(ltm::nice_ticks(0, 100, 5, true), (V{0, 25, 50, 75, 100}));
    EXPECT_EQ(ltm::nice_ticks(0, 10, 5, true), (V{0, 5, 10}));
    // one value
    EXPECT_EQ(ltm::nice_ticks(3, 3, 5), (V{3}));
    EXPECT_THROW(ltm::nice_ticks(1, 0, 5), std::invalid_argument);
    EXPECT_THROW(ltm::nice_ticks(0, std::numeric_limits<double>::infinity(), 5), std::invalid_argument);
    EXPECT_THROW(ltm::nice_ticks(kNaN, 1, 5), std::invalid_argument);
}

TEST(Ticks, AtMostTheRequestedNumberInsideTheRange) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-6, 6);
    for (int i = 0; i < 2000; ++i) {
        const double a = std::pow(10.0, u(rng)) * (i % 3 == 0 ? -1 : 1), b = a + std::pow(10.0, u(rng));
        const int n = 2 + i % 9;
        const auto t = ltm::nice_ticks(a, b, n);
        ASSERT_GE(t.size(), 2u) << a << " " << b << " " << n;
        if (n >= 5) {
            EXPECT_LE(static_cast<int>(t.size()), n) << a << " " << b << " " << n;
        }
        const double step = t[1] - t[0];
        for (std::size_t k = 0; k < t.size(); ++k) {
            EXPECT_GE(t[k], a - 1e-9 * step);
            EXPECT_LE(t[k], b + 1e-9 * step);
            if (k > 0) {
                EXPECT_NEAR(t[k] - t[k - 1], step, 1e-6 * step + 1e-15 * std::fabs(t[k]));  // + rounding of t
            }
        }
    }
}

TEST(Ticks, Labels) {
    using S = std::vector<std::string>;
    EXPECT_EQ(ltm::tick_labels({0, 0.25, 0.5, 0.75, 1}), (S{"0.00", "0.25", "0.50", "0.75", "1.00"}));
    EXPECT_EQ(ltm::tick_labels({-10, -5, 0, 5, 10}), (S{kMinus + "10", kMinus + "5", "0", "5", "10"}));
    EXPECT_EQ(ltm::tick_labels({25, 30, 35}), (S{"25", "30", "35"}));
    EXPECT_EQ(ltm::tick_labels({-0.3, 0, 0.3}), (S{kMinus + "0.3", "0.0", "0.3"}));
    EXPECT_EQ(ltm::tick_labels({1000, 1000.1, 1000.2}), (S{"1000.0", "1000.1", "1000.2"}));
    EXPECT_EQ(ltm::tick_labels({0, 1e6, 2e6}), (S{"0", "1e6", "2e6"}));
    EXPECT_EQ(ltm::tick_labels({0, 50000, 100000, 150000}), (S{"0", "50000", "100000", "150000"}));  // below 1e6: in full
    EXPECT_EQ(ltm::tick_labels({2e-5, 4e-5}), (S{"2e" + kMinus + "5", "4e" + kMinus + "5"}));
    EXPECT_EQ(ltm::tick_labels({1.5e6, 1.6e6}), (S{"1.5e6", "1.6e6"}));
    EXPECT_TRUE(ltm::tick_labels({}).empty());
}

TEST(Ticks, CompactValues) {
    EXPECT_EQ(ltm::format_tick(1000.0), "1e3");
    EXPECT_EQ(ltm::format_tick(2.5e-5), "2.5e-5");
    EXPECT_EQ(ltm::format_tick(-1.25e10), "-1.25e10");
    EXPECT_EQ(ltm::format_tick(0.5), "0.5");
    EXPECT_EQ(ltm::format_tick(123.456), "123");
    EXPECT_EQ(ltm::format_tick(0.0), "0");
    EXPECT_EQ(ltm::format_tick(1000.5, 5), "1000.5");
}

// ---- feature titles ----

TEST(FeatureTitles, EveryChannelHasTheUnitTheDocsGive) {
    for (const auto& name : ltm::feature_channel_names(true)) EXPECT_FALSE(ltm::feature_unit(name).empty()) << name;
    // docs/features.md
    EXPECT_EQ(ltm::feature_unit("BrightField"), "fraction");
    EXPECT_EQ(ltm::feature_unit("ScatterCount"), "count");
    EXPECT_EQ(ltm::feature_unit("ScatterWidth"), "index");
    EXPECT_EQ(ltm::feature_unit("ScatterDiameter"), "display pixels");
    EXPECT_EQ(ltm::feature_unit("EllipseAngle"), "degrees");
    EXPECT_EQ(ltm::feature_unit("RobustScatterDiameter"), "display pixels");
    EXPECT_EQ(ltm::feature_unit("MeanY"), "mm");
    EXPECT_EQ(ltm::feature_unit("Deflection"), "mm");
    EXPECT_EQ(ltm::feature_title("ScatterCount"), "ScatterCount (count)");
    EXPECT_EQ(ltm::feature_unit("Nonsense"), "");
    EXPECT_EQ(ltm::feature_title("Nonsense"), "Nonsense");
}

// ---- pseudo colour ----

TEST(PseudoColour, LayoutAsDocumented) {
    // 20 x 10 at s = 4, no title, no axes: the image frame's top-left corner at the margin
    const auto L = ltm::pseudo_colour_layout(ramp(20, 10), 20, 10, "", 0.0, 1.0, 4);
    const int M = ltm::kPlotMargin;
    // left: the image frame (1 pixel) is the leftmost thing drawn; top: the bar's top tick label,
    // centred on the top row's centre line, reaches th / 2 - 0.5 above the image
    const int th = ltm::text_height(ltm::kTickFontSize);
    EXPECT_EQ(L.image_x, M + 1);
    EXPECT_EQ(L.image_y, M - static_cast<int>(std::floor(0.5 - th / 2.0)));
    EXPECT_EQ(L.image_w, 80);
    EXPECT_EQ(L.image_h, 40);
    EXPECT_EQ(L.bar_x, L.image_x + 80 + ltm::kPlotBarGap);
    EXPECT_EQ(L.bar_y, L.image_y);
    EXPECT_EQ(L.bar_w, ltm::kPlotBarWidth);
    EXPECT_EQ(L.bar_h, ltm::kPlotMinBarHeight);  // max(40, 80)
    // bar ticks: at most (80 - 1) / 50 + 1 = 2 over [0, 1]: 0 and 1, at the centres of the end rows
    EXPECT_EQ(L.tick_values, (std::vector<double>{0, 1}));
    EXPECT_EQ(L.tick_labels, (std::vector<std::string>{"0", "1"}));
    EXPECT_DOUBLE_EQ(L.tick_rows[0], L.bar_y + 79.5);
    EXPECT_DOUBLE_EQ(L.tick_rows[1], L.bar_y + 0.5);
    EXPECT_TRUE(L.x_ticks.empty());
    EXPECT_TRUE(L.y_ticks.empty());
    // the canvas: the widest tick label's right edge (or the bar's frame) plus the margin, the
    // bottom label's lower half or the bar's frame plus the margin
    const double label_right = L.bar_x + L.bar_w + 1 + ltm::kPlotTickLength + ltm::kPlotTickLabelGap +
                               std::max(ltm::text_width("0", ltm::kTickFontSize), ltm::text_width("1", ltm::kTickFontSize));
    EXPECT_EQ(L.width, static_cast<int>(std::ceil(label_right)) + M);
    const double bottom = std::max(L.bar_y + L.bar_h + 1.0, L.tick_rows[0] + th / 2.0);
    EXPECT_EQ(L.height, static_cast<int>(std::ceil(bottom)) + M);
    const Image img = ltm::pseudo_colour(ramp(20, 10), 20, 10, "", 0.0, 1.0, 4);
    EXPECT_EQ(img.width, L.width);
    EXPECT_EQ(img.height, L.height);
    EXPECT_EQ(img.channels, 3);
}

TEST(PseudoColour, AxesInMillimetresOverTheFieldOfView) {
    // 100 x 100 camera pixels at s = 4 over a 25 x 25 mm field of view: at most 400 / 50 + 1 = 9
    // ticks: -10 .. 10 in steps of 5 mm; x = 0 is the image's middle column boundary, y = 10 mm
    // is (12.5 - 10) / 25 * 400 = 40 rows below the top (+y) edge.
    std::vector<float> v(100 * 100);
    for (int m = 0; m < 100; ++m)
        for (int n = 0; n < 100; ++n) v[static_cast<std::size_t>(m * 100 + n)] = static_cast<float>(n - m);
    const ltm::ImageExtent fov{25, 25};
    const auto L = ltm::pseudo_colour_layout(v, 100, 100, "ScatterCount (count)", kNaN, kNaN, 4, fov);
    EXPECT_EQ(L.x_ticks, (std::vector<double>{-10, -5, 0, 5, 10}));
    EXPECT_EQ(L.y_ticks, (std::vector<double>{-10, -5, 0, 5, 10}));
    ASSERT_EQ(L.x_tick_columns.size(), 5u);
    EXPECT_DOUBLE_EQ(L.x_tick_columns[0], L.image_x + 40.0);   // -10 mm
    EXPECT_DOUBLE_EQ(L.x_tick_columns[2], L.image_x + 200.0);  // 0 mm
    EXPECT_DOUBLE_EQ(L.y_tick_rows[4], L.image_y + 40.0);      // +10 mm near the top
    EXPECT_DOUBLE_EQ(L.y_tick_rows[0], L.image_y + 360.0);     // -10 mm near the bottom
    // the colour bar over [-99, 99], 400 rows: at most 399 / 50 + 1 = 8 ticks: step 20 gives 9, 25 gives 7
    EXPECT_EQ(L.lo, -99.0);
    EXPECT_EQ(L.hi, 99.0);
    EXPECT_EQ(L.tick_values, (std::vector<double>{-75, -50, -25, 0, 25, 50, 75}));
    EXPECT_DOUBLE_EQ(L.tick_rows[3], L.bar_y + 199.5 + 0.5);  // 0: (99 / 198) * 399 + 0.5, the middle of 400 rows
    EXPECT_DOUBLE_EQ(L.tick_rows[6], L.bar_y + 24.0 / 198.0 * 399.0 + 0.5);  // 75
    // the texts: title, 7 bar labels, 5 + 5 axis tick labels, "x (mm)", "y (mm)"
    std::vector<std::string> texts;
    for (const auto& l : L.labels) texts.push_back(l.text);
    EXPECT_EQ(L.labels.size(), 1u + 7 + 5 + 5 + 2);
    EXPECT_NE(std::find(texts.begin(), texts.end(), "x (mm)"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), "y (mm)"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), kMinus + "10"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), "ScatterCount (count)"), texts.end());
    for (const auto& l : L.labels) {
        if (l.text == "y (mm)") {
            EXPECT_TRUE(l.vertical);
            EXPECT_LT(l.box.x + l.box.w, L.image_x);
        } else {
            EXPECT_FALSE(l.vertical) << l.text;
        }
        if (l.text == "ScatterCount (count)") {
            EXPECT_NEAR(l.box.x + l.box.w / 2, L.image_x + 200.0, 0.5);  // centred over the image
            EXPECT_LE(l.box.y + l.box.h, L.image_y - 1 - ltm::kPlotTitleGap + 1e-9);
        }
        if (l.text == "x (mm)") {
            EXPECT_GT(l.box.y, L.image_y + L.image_h);
        }
    }

    const Image img = ltm::pseudo_colour(v, 100, 100, "ScatterCount (count)", kNaN, kNaN, 4, fov);
    ASSERT_EQ(img.width, L.width);
    ASSERT_EQ(img.height, L.height);
    expect_clean_figure(img, L.labels, pseudo_colour_blocks(L), pseudo_colour_ink(L));
    // the tick marks are drawn: below the frame at x = 0 mm, left of it at y = 10 mm, right of the bar at 0
    const int below = L.image_y + L.image_h + 2, left = L.image_x - 3;
    EXPECT_LT(lightness(pixel(img, below, L.image_x + 199)), 50);
    EXPECT_LT(lightness(pixel(img, L.image_y + 39, left)), 50);
    EXPECT_LT(lightness(pixel(img, L.bar_y + 199, L.bar_x + L.bar_w + 3)), 50);  // 0 on the row above the middle line
    EXPECT_TRUE(is_white(img, below, L.image_x + 180));  // and only there
}

TEST(PseudoColour, CellsAreExactlyTheViridisColourOfTheirValue) {
    const int w = 7, h = 5, s = 3;
    std::vector<float> v = ramp(w, h);
    v[8] = static_cast<float>(kNaN);
    v[9] = 5.0f;    // above hi: clamps to the top colour
    v[10] = -5.0f;  // below lo
    const double lo = 0.1, hi = 0.9;
    for (const ltm::ImageExtent fov : {ltm::ImageExtent{}, ltm::ImageExtent{7, 5}}) {
        const Image img = ltm::pseudo_colour(v, w, h, "cells", lo, hi, s, fov);
        const auto L = ltm::pseudo_colour_layout(v, w, h, "cells", lo, hi, s, fov);
        const int x0 = L.image_x, y0 = L.image_y;
        for (int m = 0; m < h; ++m)
            for (int n = 0; n < w; ++n) {
                const double value = v[static_cast<std::size_t>(m * w + n)];
                const Rgb expected = ltm::viridis((value - lo) / (hi - lo));
                for (int i = 0; i < s; ++i)
                    for (int j = 0; j < s; ++j)
                        EXPECT_EQ(pixel(img, y0 + m * s + i, x0 + n * s + j), expected) << m << " " << n;
            }
        EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 1 * s), ltm::kNanColour);            // k = 8
        EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 2 * s), ltm::viridis_table()[255]);  // k = 9
        EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 3 * s), ltm::viridis_table()[0]);    // k = 10
        // the frame just outside the cells, white beyond it
        EXPECT_TRUE(same_codes(pixel(img, y0 - 1, x0 + 5), ltm::kFrameColour));
        EXPECT_TRUE(same_codes(pixel(img, y0 + 5, x0 - 1), ltm::kFrameColour));
        EXPECT_TRUE(same_codes(pixel(img, y0 + h * s, x0 + 5), ltm::kFrameColour));
        EXPECT_TRUE(same_codes(pixel(img, y0 + 5, x0 + w * s), ltm::kFrameColour));
        EXPECT_TRUE(is_white(img, y0 - 2, x0 + 5));
        EXPECT_TRUE(is_white(img, y0 + 5, x0 + w * s + 1));
    }
}

// A montage marks each defect with a ring (study/Experiment.h): drawn over the data cells only,
// white within 1 output pixel of the circle, black between 1 and 2, the cells elsewhere untouched.
TEST(PseudoColour, RingsMarkSpotsOverTheCells) {
    const int w = 20, h = 16, s = 3;
    const std::vector<float> v = ramp(w, h);
    // A ring around data pixel (m, n) = (5, 7), radius 2 data pixels (6 output pixels), and one
    // reaching past the image's left edge (clipped: the frame and the axes stay as they are).
    const std::vector<ltm::Ring> rings = {{7.5, 5.5, 2.0}, {0.5, 12.5, 3.0}};
    const ltm::ImageExtent fov{20, 16};
    const Image plain = ltm::pseudo_colour(v, w, h, "", kNaN, kNaN, s, fov);
    const Image marked = ltm::pseudo_colour(v, w, h, "", kNaN, kNaN, s, fov, rings);
    const auto L = ltm::pseudo_colour_layout(v, w, h, "", kNaN, kNaN, s, fov);
    ASSERT_EQ(marked.width, plain.width);
    ASSERT_EQ(marked.height, plain.height);
    int white = 0, black = 0;
    for (int r = 0; r < plain.height; ++r)
        for (int c = 0; c < plain.width; ++c) {
            const bool inside = r >= L.image_y && r < L.image_y + L.image_h && c >= L.image_x && c < L.image_x + L.image_w;
            double off = 1e9;
            for (const ltm::Ring& g : rings)
                off = std::min(off, std::fabs(std::hypot(c + 0.5 - (L.image_x + g.x * s), r + 0.5 - (L.image_y + g.y * s)) -
                                              g.radius * s));
            if (inside && off <= 1.0) {
                EXPECT_EQ(pixel(marked, r, c), ltm::kWhite) << r << " " << c;
                ++white;
            } else if (inside && off <= 2.0) {
                EXPECT_EQ(pixel(marked, r, c), ltm::kBlack) << r << " " << c;
                ++black;
            } else {
                EXPECT_EQ(pixel(marked, r, c), pixel(plain, r, c)) << r << " " << c;
            }
        }
    // The first ring is whole: a circle of radius 6 output pixels, 2 wide in white and 2 in black
    // (about 2 pi 6 x 2 and 2 pi (6 +- 1.5) x 1 pixels).
    EXPECT_GT(white, 60);
    EXPECT_GT(black, 60);
    // The marked spot itself (the cell block of (5, 7)) keeps its colour.
    EXPECT_EQ(pixel(marked, L.image_y + 5 * s + 1, L.image_x + 7 * s + 1), pixel(plain, L.image_y + 5 * s + 1, L.image_x + 7 * s + 1));
}

TEST(PseudoColour, BarIsMonotoneFromHiOnTopToLoAtTheBottom) {
    const Image img = ltm::pseudo_colour(ramp(20, 30), 20, 30, "T", -2.0, 3.0, 4);
    const auto L = ltm::pseudo_colour_layout(ramp(20, 30), 20, 30, "T", -2.0, 3.0, 4);
    EXPECT_EQ(L.bar_h, 120);
    for (int r = 0; r < L.bar_h; ++r)
        for (int c = L.bar_x; c < L.bar_x + L.bar_w; ++c)
            ASSERT_EQ(pixel(img, L.bar_y + r, c), ltm::viridis(1.0 - r / 119.0)) << r;
    EXPECT_EQ(pixel(img, L.bar_y, L.bar_x), ltm::viridis_table()[255]);
    EXPECT_EQ(pixel(img, L.bar_y + 119, L.bar_x), ltm::viridis_table()[0]);
    // lightness rises row by row up the bar
    for (int r = 1; r < L.bar_h; ++r)
        EXPECT_LT(lightness(pixel(img, L.bar_y + r, L.bar_x + 5)), lightness(pixel(img, L.bar_y + r - 1, L.bar_x + 5)));
    // framed just outside
    EXPECT_TRUE(same_codes(pixel(img, L.bar_y - 1, L.bar_x + 5), ltm::kFrameColour));
    EXPECT_TRUE(same_codes(pixel(img, L.bar_y + L.bar_h, L.bar_x + 5), ltm::kFrameColour));
    EXPECT_TRUE(same_codes(pixel(img, L.bar_y + 50, L.bar_x - 1), ltm::kFrameColour));
    EXPECT_TRUE(same_codes(pixel(img, L.bar_y + 50, L.bar_x + L.bar_w), ltm::kFrameColour));
    // ticks over [-2, 3], at most 119 / 50 + 1 = 3: step 2 gives -2, 0, 2; each sits where the bar
    // shows its value's colour
    EXPECT_EQ(L.tick_values, (std::vector<double>{-2, 0, 2}));
    EXPECT_EQ(L.tick_labels, (std::vector<std::string>{kMinus + "2", "0", "2"}));
    for (std::size_t i = 0; i < L.tick_values.size(); ++i) {
        const int row = static_cast<int>(std::floor(L.tick_rows[i]));
        const double t_bar = 1.0 - (row - L.bar_y) / 119.0, t_value = (L.tick_values[i] + 2.0) / 5.0;
        EXPECT_NEAR(t_bar, t_value, 0.5 / 119.0 + 1e-12) << L.tick_values[i];
    }
    expect_clean_figure(img, L.labels, pseudo_colour_blocks(L), pseudo_colour_ink(L));
}

TEST(PseudoColour, FiguresAreCleanAtManySizes) {
    for (const int s : {1, 3, 4})
        for (const auto& size : {std::pair<int, int>{20, 10}, {100, 100}, {64, 48}, {5, 120}})
            for (const std::string title : {"", "Deflection (mm)", "a title much wider than the image it is over, surely"}) {
                const auto [w, h] = size;
                std::vector<float> v = ramp(w, h);
                for (auto& x : v) x = 1000 + 0.5f * x;
                const ltm::ImageExtent fov{w * 0.25, h * 0.25};
                const auto L = ltm::pseudo_colour_layout(v, w, h, title, kNaN, kNaN, s, fov);
                const Image img = ltm::pseudo_colour(v, w, h, title, kNaN, kNaN, s, fov);
                SCOPED_TRACE(std::to_string(w) + " x " + std::to_string(h) + " at " + std::to_string(s) + ", '" + title + "'");
                ASSERT_EQ(img.width, L.width);
                ASSERT_EQ(img.height, L.height);
                expect_clean_figure(img, L.labels, pseudo_colour_blocks(L), pseudo_colour_ink(L));
                // bar labels tell neighbours apart
                for (std::size_t i = 1; i < L.tick_labels.size(); ++i) EXPECT_NE(L.tick_labels[i], L.tick_labels[i - 1]);
            }
}

TEST(PseudoColour, WholeNumbersGetWholeNumberTicks) {
    // a mask with values 0 .. 3 on a 160-row bar: at most 159 / 50 + 1 = 4 ticks; 0.5 would give
    // 7, 1 gives 4
    std::vector<float> mask(40 * 40, 0.0f);
    mask[5] = 1, mask[50] = 2, mask[500] = 3;
    const auto L = ltm::pseudo_colour_layout(mask, 40, 40, "mask", 0.0, 3.0, 4);
    EXPECT_EQ(L.tick_values, (std::vector<double>{0, 1, 2, 3}));
    // one value off a whole number: steps of 0.5 are allowed again (at most 4: 1 gives 4 too, so
    // the same ticks); a range off whole numbers likewise
    mask[7] = 0.5f;
    EXPECT_EQ(ltm::pseudo_colour_layout(mask, 40, 40, "mask", 0.0, 3.0, 4).tick_values, (std::vector<double>{0, 1, 2, 3}));
    EXPECT_EQ(ltm::pseudo_colour_layout(mask, 40, 40, "mask", 0.0, 1.5, 4).tick_values,
              (std::vector<double>{0, 0.5, 1, 1.5}));
    mask[7] = 0;
    EXPECT_EQ(ltm::pseudo_colour_layout(mask, 40, 40, "mask", 0.0, 1.0, 4).tick_values, (std::vector<double>{0, 1}));
    mask[7] = 0.25f;
    EXPECT_EQ(ltm::pseudo_colour_layout(mask, 40, 40, "mask", 0.0, 1.0, 4).tick_values,
              (std::vector<double>{0, 0.5, 1}));
}

TEST(PseudoColour, NanRangeUsesTheFiniteMinimumAndMaximum) {
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<float> v = {static_cast<float>(kNaN), 2.0f, 3.0f, 5.0f, inf, -inf};
    const auto L = ltm::pseudo_colour_layout(v, 3, 2, "", kNaN, kNaN, 1);
    EXPECT_EQ(L.lo, 2.0);
    EXPECT_EQ(L.hi, 5.0);
    const Image img = ltm::pseudo_colour(v, 3, 2, "", kNaN, kNaN, 1);
    const int x = L.image_x, y = L.image_y;
    EXPECT_EQ(pixel(img, y, x), ltm::kNanColour);
    EXPECT_EQ(pixel(img, y, x + 1), ltm::viridis_table()[0]);     // 2 = min
    EXPECT_EQ(pixel(img, y, x + 2), ltm::viridis(1.0 / 3.0));    // 3
    EXPECT_EQ(pixel(img, y + 1, x), ltm::viridis_table()[255]);   // 5 = max
    EXPECT_EQ(pixel(img, y + 1, x + 1), ltm::viridis_table()[255]);  // +inf clamps to the top
    EXPECT_EQ(pixel(img, y + 1, x + 2), ltm::viridis_table()[0]);    // -inf to the bottom

    // only one bound NaN: that one from the data
    EXPECT_EQ(ltm::colour_range(v, 0.0, kNaN), std::make_pair(0.0, 5.0));
    EXPECT_EQ(ltm::colour_range(v, kNaN, 4.0), std::make_pair(2.0, 4.0));
    // a constant image: widened by 1 around the value, drawn in the middle colour
    const std::vector<float> c(12, 7.0f);
    EXPECT_EQ(ltm::colour_range(c, kNaN, kNaN), std::make_pair(6.5, 7.5));
    const auto F = ltm::pseudo_colour_layout(c, 4, 3, "flat", kNaN, kNaN, 2);
    const Image flat = ltm::pseudo_colour(c, 4, 3, "flat", kNaN, kNaN, 2);
    EXPECT_EQ(pixel(flat, F.image_y, F.image_x), ltm::viridis(0.5));
    // at most 79 / 50 + 1 = 2 ticks: step 1 leaves only 7, so the next smaller step, 0.5
    EXPECT_EQ(F.tick_values, (std::vector<double>{6.5, 7, 7.5}));
    // equal explicit bounds are widened the same way; no finite value at all gives [0, 1]
    EXPECT_EQ(ltm::colour_range(c, 3.0, 3.0), std::make_pair(2.5, 3.5));
    EXPECT_EQ(ltm::colour_range(std::vector<float>(4, static_cast<float>(kNaN)), kNaN, kNaN), std::make_pair(0.0, 1.0));
}

TEST(PseudoColour, BadArguments) {
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 5, "", 0, 1, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour({}, 0, 0, "", 0, 1, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 0, 1, 0), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 1, 0, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 0, std::numeric_limits<double>::infinity(), 1),
                 std::invalid_argument);
    EXPECT_FALSE(ltm::ImageExtent{}.known());
    EXPECT_FALSE((ltm::ImageExtent{25, -1}.known()));
    EXPECT_TRUE((ltm::ImageExtent{25, 25}.known()));
}

// ---- montage ----

TEST(Montage, Dimensions) {
    auto solid = [](int w, int h, float v, int channels = 3) {
        Image img(w, h, channels);
        std::fill(img.data.begin(), img.data.end(), v);
        return img;
    };
    const std::vector<std::vector<Image>> cells = {
        {solid(50, 40, 0.2f), solid(30, 20, 0.4f), solid(60, 10, 0.6f)},
        {solid(10, 45, 0.8f), solid(20, 20, 0.25f, 1), Image()},
    };
    const std::vector<std::string> rows = {"A", "Row two"}, columns = {"x", "yy", "column three is long"};
    const std::string title = "Montage";
    const Image img = ltm::montage(cells, rows, columns, title);
    // by the documented formula
    const int M = ltm::kPlotMargin, lh = ltm::text_height(ltm::kLabelFontSize);
    auto w_of = [](const std::string& s, double size) { return static_cast<int>(std::ceil(ltm::text_width(s, size))); };
    const int sw = std::max(60, w_of(columns[2], ltm::kLabelFontSize));
    const int sh = std::max(45, w_of(rows[1], ltm::kLabelFontSize));
    const int T = ltm::text_height(ltm::kTitleFontSize) + ltm::kMontageLabelGap;
    const int C = lh + ltm::kMontageColumnGap, R = lh + ltm::kMontageLabelGap;
    EXPECT_GT(sw, 60);  // the long column label widens every slot
    EXPECT_EQ(img.width, std::max(M + R + 3 * sw + 2 * ltm::kMontageGap + M, M + w_of(title, ltm::kTitleFontSize) + M));
    EXPECT_EQ(img.height, M + T + C + 2 * sh + ltm::kMontageGap + M);
    EXPECT_EQ(img.channels, 3);
    // cell (0, 1), 30 x 20, centred in its slot, copied exactly
    const int sx = M + R + sw + ltm::kMontageGap, sy = M + T + C;
    const int cx = sx + (sw - 30) / 2, cy = sy + (sh - 20) / 2;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 30; ++j) ASSERT_EQ(pixel(img, cy + i, cx + j), (Rgb{0.4f, 0.4f, 0.4f}));
    EXPECT_TRUE(is_white(img, cy - 1, cx));
    EXPECT_TRUE(is_white(img, cy, cx - 1));
    EXPECT_TRUE(is_white(img, cy + 20, cx));
    EXPECT_TRUE(is_white(img, cy, cx + 30));
    // the grey (1-channel) cell (1, 1)
    const int gy = M + T + C + sh + ltm::kMontageGap + (sh - 20) / 2, gx = sx + (sw - 20) / 2;
    EXPECT_EQ(pixel(img, gy, gx), (Rgb{0.25f, 0.25f, 0.25f}));
    // the missing cell (1, 2) stays white
    const int mx = M + R + 2 * (sw + ltm::kMontageGap), my = M + T + C + sh + ltm::kMontageGap;
    for (int r = my; r < my + sh; ++r)
        for (int c = mx; c < mx + sw; ++c) ASSERT_TRUE(is_white(img, r, c));
    // labels are drawn where they belong: the title on top, column labels above the slots, row
    // labels in the strip left of them; the margin stays white
    EXPECT_GT(ink(img, {0.0, double(M), double(img.width), double(T - ltm::kMontageLabelGap)}), 0);
    for (int c = 0; c < 3; ++c)
        EXPECT_GT(ink(img, {double(M + R + c * (sw + ltm::kMontageGap)), double(M + T), double(sw), double(lh)}), 0) << c;
    for (int r = 0; r < 2; ++r)
        EXPECT_GT(ink(img, {double(M), double(sy + r * (sh + ltm::kMontageGap)), double(lh), double(sh)}), 0) << r;
    EXPECT_EQ(ink(img, {0, 0, double(img.width), M - 1.0}), 0);
    EXPECT_EQ(ink(img, {0, 0, M - 1.0, double(img.height)}), 0);
    EXPECT_EQ(ink(img, {0, img.height - M + 1.0, double(img.width), M - 1.0}), 0);
    EXPECT_EQ(ink(img, {img.width - M + 1.0, 0, M - 1.0, double(img.height)}), 0);

    // a single cell, no labels: the margin on each side
    const Image one = ltm::montage({{solid(10, 10, 0.5f)}}, {}, {}, "");
    EXPECT_EQ(one.width, 10 + 2 * M);
    EXPECT_EQ(one.height, 10 + 2 * M);
    EXPECT_EQ(pixel(one, M, M), (Rgb{0.5f, 0.5f, 0.5f}));
    EXPECT_TRUE(is_white(one, M - 1, M));
}

TEST(Montage, BadArguments) {
    const Image cell(4, 4, 3);
    EXPECT_THROW(ltm::montage({}, {}, {}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{cell, cell}}, {"a", "b"}, {}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{cell, cell}}, {}, {"a"}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{Image(4, 4, 2)}}, {}, {}, ""), std::invalid_argument);
}

TEST(Montage, SampleForPeople) {
    // Synthetic feature images of two defects, the way `experiment` would show them.
    const int w = 48, h = 40;
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 1.0);
    auto image = [&](double cx, double cy, double sx, double sy, double amp, double base, double sigma) {
        std::vector<float> v(static_cast<std::size_t>(w * h));
        for (int m = 0; m < h; ++m)
            for (int n = 0; n < w; ++n) {
                const double dx = (n + 0.5 - cx) / sx, dy = (m + 0.5 - cy) / sy;
                double x = base + amp * std::exp(-0.5 * (dx * dx + dy * dy)) + sigma * noise(rng);
                if ((n - 24) * (n - 24) + (m - 20) * (m - 20) > 21 * 21) x = kNaN;  // outside the lens
                v[static_cast<std::size_t>(m * w + n)] = static_cast<float>(x);
            }
        return v;
    };
    const ltm::ImageExtent fov{12, 10};
    std::vector<std::vector<Image>> cells(2);
    const auto a = image(20, 18, 3, 3, 40, 2, 1.5), b = image(28, 24, 12, 1.5, 25, 2, 1.5);
    cells[0].push_back(ltm::pseudo_colour(a, w, h, "", kNaN, kNaN, 5, fov));
    cells[0].push_back(ltm::pseudo_colour(b, w, h, "", kNaN, kNaN, 5, fov));
    cells[1].push_back(ltm::pseudo_colour(image(20, 18, 3, 3, -0.4, 0.92, 0.01), w, h, "", kNaN, kNaN, 5, fov));
    cells[1].push_back(ltm::pseudo_colour(image(28, 24, 12, 1.5, -0.2, 0.92, 0.01), w, h, "", kNaN, kNaN, 5, fov));
    const Image img = ltm::montage(cells, {"ScatterCount (count)", "BrightField (fraction)"}, {"bubble", "scratch"},
                                   "Synthetic defects: feature images");
    // the cells' data pixels survive the montage exactly: find cell (0, 0)'s first finite pixel
    const auto L = ltm::pseudo_colour_layout(a, w, h, "", kNaN, kNaN, 5, fov);
    const int M = ltm::kPlotMargin, lh = ltm::text_height(ltm::kLabelFontSize);
    const int x0 = M + lh + ltm::kMontageLabelGap, y0 = M + ltm::text_height(ltm::kTitleFontSize) + ltm::kMontageLabelGap +
                                                       lh + ltm::kMontageColumnGap;
    int cw = 0, ch = 0;
    for (const auto& row : cells)
        for (const Image& c : row) cw = std::max(cw, c.width), ch = std::max(ch, c.height);
    const int sh = std::max(ch, static_cast<int>(std::ceil(ltm::text_width("BrightField (fraction)", ltm::kLabelFontSize))));
    const int top = y0 + (sh - L.height) / 2, left = x0 + (cw - L.width) / 2;
    const std::size_t k = 20 * w + 24;  // the lens centre: finite
    ASSERT_FALSE(std::isnan(a[k]));
    EXPECT_EQ(pixel(img, top + L.image_y + 20 * 5 + 2, left + L.image_x + 24 * 5 + 2), ltm::viridis((a[k] - L.lo) / (L.hi - L.lo)));
    EXPECT_EQ(pixel(img, top + L.image_y, left + L.image_x), ltm::kNanColour);  // the corner: outside the lens
    if (const char* out = std::getenv("LTM_PLOT_SAMPLE")) ltm::write_png(out, img);
}

// ---- histogram ----

TEST(Histogram, CountsTicksAndBars) {
    // 3 bins over [1, 4]: [1, 2) holds 1, [2, 3) holds 2, [3, 4] holds 3 and 4
    const auto L = ltm::histogram_layout({1, 2, 2, 3, 3, 3, 4, kNaN}, 3, "sizes", "size (mm)", false, "defects");
    EXPECT_EQ(L.width, ltm::kHistogramWidth);
    EXPECT_EQ(L.height, ltm::kHistogramHeight);
    EXPECT_EQ(L.counts, (std::vector<long>{1, 2, 4}));
    // y: at most 8 ticks over [0, 4]: 0.5 gives 9, 1 gives 5
    EXPECT_EQ(L.y_ticks, (std::vector<double>{0, 1, 2, 3, 4}));
    EXPECT_EQ(L.y_max, 4.0);
    // x: at most 8 over [1, 4]: 0.5 gives 7
    EXPECT_EQ(L.x_ticks, (std::vector<double>{1, 1.5, 2, 2.5, 3, 3.5, 4}));
    EXPECT_DOUBLE_EQ(L.x_tick_columns[0], L.plot.x);
    EXPECT_DOUBLE_EQ(L.x_tick_columns[6], L.plot.x + L.plot.w);
    EXPECT_DOUBLE_EQ(L.x_tick_columns[2], L.plot.x + L.plot.w / 3);
    EXPECT_DOUBLE_EQ(L.y_tick_rows[0], L.plot.y + L.plot.h);
    EXPECT_DOUBLE_EQ(L.y_tick_rows[4], L.plot.y);
    ASSERT_EQ(L.bars.size(), 3u);
    EXPECT_DOUBLE_EQ(L.bars[2].h, L.plot.h);  // 4 of y_max 4
    EXPECT_DOUBLE_EQ(L.bars[0].h, L.plot.h / 4);
    EXPECT_DOUBLE_EQ(L.bars[1].x, L.plot.x + L.plot.w / 3);

    const Image img = ltm::histogram({1, 2, 2, 3, 3, 3, 4, kNaN}, 3, "sizes", "size (mm)", false, "defects");
    ASSERT_EQ(img.width, 640);
    ASSERT_EQ(img.height, 400);
    // bars in the map's colour, white above them
    const int col = static_cast<int>(L.bars[0].x + L.bars[0].w / 2);
    const Rgb bar = pixel(img, static_cast<int>(L.plot.y + L.plot.h - 5), col);
    EXPECT_FALSE(bar == ltm::kWhite);
    EXPECT_NEAR(bar[1], ltm::viridis(0.4)[1], 1.0 / 255);
    EXPECT_TRUE(is_white(img, static_cast<int>(L.plot.y + L.plot.h * 0.5), col));
    std::vector<Box> allowed = {{L.plot.x - 1 - ltm::kPlotTickLength, L.plot.y - 1, L.plot.w + 2 + ltm::kPlotTickLength,
                                 L.plot.h + 2 + ltm::kPlotTickLength}};
    expect_clean_figure(img, L.labels, {}, allowed);
    std::vector<std::string> texts;
    for (const auto& l : L.labels) texts.push_back(l.text);
    EXPECT_NE(std::find(texts.begin(), texts.end(), "size (mm)"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), "defects"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), "sizes"), texts.end());
    EXPECT_NE(std::find(texts.begin(), texts.end(), "2.5"), texts.end());
}

TEST(Histogram, YAxisReachesTheTallestBar) {
    // 13 equal values: one bin of 13; at most 8 ticks over [0, 13]: step 2 gives 0 .. 12, one more step
    const auto L = ltm::histogram_layout(std::vector<double>(13, 2.0), 20, "t", "x", false);
    EXPECT_EQ(L.counts, (std::vector<long>{13}));
    EXPECT_EQ(L.y_ticks, (std::vector<double>{0, 2, 4, 6, 8, 10, 12, 14}));
    EXPECT_EQ(L.y_max, 14.0);
    EXPECT_DOUBLE_EQ(L.lo, 1.5);
    EXPECT_DOUBLE_EQ(L.hi, 2.5);
    // small counts: every whole number, never 0.5
    const auto S = ltm::histogram_layout({1, 2}, 2, "t", "x", false);
    EXPECT_EQ(S.y_ticks, (std::vector<double>{0, 1}));
    // nothing at all: one empty bin, axes 0 .. 1
    const auto E = ltm::histogram_layout({}, 5, "t", "x", true);
    EXPECT_EQ(E.counts, (std::vector<long>{0}));
    EXPECT_NO_THROW(ltm::histogram({}, 5, "t", "x", true));
    EXPECT_THROW(ltm::histogram({1.0}, 0, "t", "x", false), std::invalid_argument);
}

TEST(Histogram, LogarithmicX) {
    // 0.01 .. 10: the powers of ten, at log10 positions
    const auto L = ltm::histogram_layout({0.01, 0.1, 1, 10, -3, 0}, 6, "t", "size (mm)", true);
    EXPECT_DOUBLE_EQ(L.lo, -2.0);
    EXPECT_DOUBLE_EQ(L.hi, 1.0);
    EXPECT_EQ(L.x_ticks, (std::vector<double>{0.01, 0.1, 1, 10}));
    EXPECT_DOUBLE_EQ(L.x_tick_columns[2], L.plot.x + L.plot.w * 2.0 / 3.0);
    long total = 0;
    for (long c : L.counts) total += c;
    EXPECT_EQ(total, 4);  // -3 and 0 have no logarithm
    // within one decade and no power of ten: 1, 2, 5 times one (0.2), too few: nice ticks of the values
    const auto N = ltm::histogram_layout({0.15, 0.4}, 4, "t", "x", true);
    EXPECT_EQ(N.x_ticks, (std::vector<double>{0.15, 0.2, 0.25, 0.3, 0.35, 0.4}));
    // two decades' worth of 1, 2, 5
    const auto D = ltm::histogram_layout({0.15, 0.9}, 4, "t", "x", true);
    EXPECT_EQ(D.x_ticks, (std::vector<double>{0.2, 0.5}));
    const Image img = ltm::histogram({0.01, 0.1, 1, 10}, 6, "t", "size (mm)", true);
    const auto I = ltm::histogram_layout({0.01, 0.1, 1, 10}, 6, "t", "size (mm)", true);
    std::vector<Box> allowed = {{I.plot.x - 1 - ltm::kPlotTickLength, I.plot.y - 1, I.plot.w + 2 + ltm::kPlotTickLength,
                                 I.plot.h + 2 + ltm::kPlotTickLength}};
    expect_clean_figure(img, I.labels, {}, allowed);
}

// ---- PNG ----

// The PNG's codes are png_code of pseudo_colour's float picture, pixel for pixel: the PNG path
// paints the cells itself, row by row, reusing a cell's code along a run of equal values, so the
// values hold runs (of numbers, of NaNs with different bits, of +-inf) as well as a ramp, and are
// drawn at a pixel scale of 1 and of 4.
TEST(PseudoColourPng, ReadableAndTheSameCodes) {
    const fs::path dir = fs::temp_directory_path() / ("ltm_plot_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string file = (dir / "ramp.png").string();
    std::vector<float> v = ramp(20, 10);
    v[3] = static_cast<float>(kNaN);
    for (int k = 40; k < 47; ++k) v[static_cast<std::size_t>(k)] = 0.25f;          // a run across cells
    for (int k = 59; k < 62; ++k) v[static_cast<std::size_t>(k)] = 0.75f;          // a run across a row's end
    v[80] = std::numeric_limits<float>::infinity();
    v[81] = std::numeric_limits<float>::infinity();
    v[82] = -std::numeric_limits<float>::infinity();
    const std::uint32_t nan_bits[2] = {0x7FC00001u, 0xFFC00000u};                // NaNs of other bits
    std::memcpy(&v[90], &nan_bits[0], sizeof(float));
    std::memcpy(&v[91], &nan_bits[1], sizeof(float));
    v[92] = v[91];
    for (const int scale : {4, 1}) {
        SCOPED_TRACE("pixel scale " + std::to_string(scale));
        ltm::write_pseudo_colour_png(file, v, 20, 10, "T", 0.0, 1.0, scale, {5, 2.5});
        const Image back = ltm::read_image(file);
        const Image expected = ltm::pseudo_colour(v, 20, 10, "T", 0.0, 1.0, scale, {5, 2.5});
        const auto L = ltm::pseudo_colour_layout(v, 20, 10, "T", 0.0, 1.0, scale, {5, 2.5});
        EXPECT_EQ(back.width, L.width);
        EXPECT_EQ(back.height, L.height);
        ASSERT_EQ(back.channels, 3);
        ASSERT_EQ(back.data.size(), expected.data.size());
        for (std::size_t i = 0; i < back.data.size(); ++i) ASSERT_EQ(code(back.data[i]), code(expected.data[i])) << i;
        // a data cell's stored code is the viridis colour's; NaN's is kNanColour's, +-inf the ends'
        const auto cell = [&](int k, int c) {
            return code(back.at(L.image_y + (k / 20) * scale, L.image_x + (k % 20) * scale + scale - 1, c));
        };
        for (int c = 0; c < 3; ++c) {
            const auto i = static_cast<std::size_t>(c);
            EXPECT_EQ(cell(5, c), code(ltm::viridis(v[5])[i]));
            EXPECT_EQ(cell(46, c), code(ltm::viridis(0.25)[i]));
            EXPECT_EQ(cell(60, c), code(ltm::viridis(0.75)[i]));
            EXPECT_EQ(cell(81, c), code(ltm::viridis(1.0)[i]));
            EXPECT_EQ(cell(82, c), code(ltm::viridis(0.0)[i]));
            for (const int k : {3, 90, 91, 92}) EXPECT_EQ(cell(k, c), code(ltm::kNanColour[i])) << k;
        }
    }
    fs::remove_all(dir);
}

namespace {

// Writes the preview of v (w x h cells over [lo, hi], no title or axes, pixel scale 1) into a
// fresh folder named after `tag` and expects its PNG to hold pseudo_colour's codes, pixel for pixel.
void expect_preview_codes_are_pseudo_colours(const std::vector<float>& v, int w, int h, double lo, double hi,
                                             const std::string& tag) {
    const fs::path dir = fs::temp_directory_path() / ("ltm_plot_" + tag + "_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string file = (dir / (tag + ".png")).string();
    ltm::write_pseudo_colour_png(file, v, w, h, "", lo, hi, 1, {});
    const Image back = ltm::read_image(file);
    const Image expected = ltm::pseudo_colour(v, w, h, "", lo, hi, 1, {});
    ASSERT_EQ(back.data.size(), expected.data.size());
    for (std::size_t i = 0; i < back.data.size(); ++i) ASSERT_EQ(code(back.data[i]), code(expected.data[i])) << i;
    fs::remove_all(dir);
}

}  // namespace

// Over [0, 255] the cells' colours land on every entry of the map (whole values: f = 0, and
// f = 1 at the top), halfway between entries, and just off them: the PNG path's inlined viridis
// must give the codes of viridis() itself, which returns the entries as they are there.
TEST(PseudoColourPng, EveryEntryOfTheMapAndBetweenAsViridisGivesThem) {
    std::vector<float> v;
    for (int k = 0; k < 256; ++k)
        for (const float d : {0.0f, 0.5f, 1e-3f, -1e-3f}) v.push_back(static_cast<float>(k) + d);
    const int w = 64, h = static_cast<int>(v.size()) / w;
    expect_preview_codes_are_pseudo_colours(v, w, h, 0.0, 255.0, "entries");
}

// A picture of kPreviewTableCells cells takes its colours from the table of buckets
// (features/Plot.cpp): every value of [0, 1] must still get viridis()'s codes. The values: both
// ends of every bucket of 2^-14 (b / 2^14 and the float just below (b + 1) / 2^14, where a
// bucket's word is decided), 1, values beyond both ends, NaN, infinities, the rest uniform.
TEST(PseudoColourPng, LargePicturesGiveViridisCodesThroughTheTable) {
    const int w = 512, h = 256;
    ASSERT_GE(static_cast<long long>(w) * h, ltm::kPreviewTableCells);
    std::vector<float> v;
    constexpr int kBuckets = 1 << 14;
    for (int b = 0; b < kBuckets; ++b) {
        v.push_back(static_cast<float>(b) / kBuckets);
        v.push_back(std::nextafter(static_cast<float>(b + 1) / kBuckets, 0.0f));
    }
    for (const float x : {1.0f, -0.5f, 1.5f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()})
        v.push_back(x);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    while (v.size() < static_cast<std::size_t>(w) * h) v.push_back(unit(rng));
    expect_preview_codes_are_pseudo_colours(v, w, h, 0.0, 1.0, "table");
}

namespace {

// A line plot is kLinePlotWidth x kLinePlotHeight, draws its series in their colours (the point
// markers are filled squares of exactly that colour), skips what a log axis cannot show, and
// refuses a series whose x and y differ in length.
TEST(LinePlot, SizeColoursAndBadSeries) {
    ltm::Series a;
    a.name = "a";
    a.x = {1, 10, 100};
    a.y = {1, 0.1, 0.01};
    a.colour = {1.0f, 0.0f, 0.0f};
    ltm::Series b;
    b.name = "b";
    b.x = {1, 10, 100};
    b.y = {0.0, NAN, 5};  // 0 and NaN cannot be drawn on a log axis
    b.colour = {0.0f, 0.0f, 1.0f};
    b.dashed = true;
    const ltm::Image img = ltm::line_plot({a, b}, "title", "K", "error", true, true);
    EXPECT_EQ(img.width, ltm::kLinePlotWidth);
    EXPECT_EQ(img.height, ltm::kLinePlotHeight);
    int red = 0, blue = 0;
    for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) {
            red += img.at(r, c, 0) == 1.0f && img.at(r, c, 1) == 0.0f && img.at(r, c, 2) == 0.0f;
            blue += img.at(r, c, 0) == 0.0f && img.at(r, c, 1) == 0.0f && img.at(r, c, 2) == 1.0f;
        }
    EXPECT_GT(red, 3);   // three markers and the lines between them
    EXPECT_GT(blue, 0);  // one marker, the legend's sample
    b.y.pop_back();
    EXPECT_THROW(ltm::line_plot({b}, "", "x", "y", false, false), std::invalid_argument);
}

}  // namespace

// ---- figures from many threads ----

// Runs body(t, j) on thread t for j = t, t + 1, ..., `threads` threads at once, until `seconds` have passed,
// each thread paused at random instructions every few hundred microseconds (tests/Preemption.h);
// body returns false for a result unlike the one drawn alone. Bounded by time, not by a count,
// so that it weighs the same under the sanitizers.
void from_many_threads(int threads, double seconds, const std::function<bool(int, int)>& body) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    std::vector<std::vector<int>> mismatches(static_cast<std::size_t>(threads));
    std::vector<long> done(static_cast<std::size_t>(threads), 0);
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            const ltm::test::ScopedPreemption preempt(std::chrono::microseconds(300 + 7 * t), std::chrono::microseconds(30));
            for (int j = t; std::chrono::steady_clock::now() < end; ++j) {
                ++done[static_cast<std::size_t>(t)];
                if (!body(t, j)) mismatches[static_cast<std::size_t>(t)].push_back(j);
            }
        });
    for (auto& th : pool) th.join();
    for (int t = 0; t < threads; ++t) {
        EXPECT_GT(done[static_cast<std::size_t>(t)], 0) << "thread " << t << " did nothing";
        EXPECT_TRUE(mismatches[static_cast<std::size_t>(t)].empty())
            << "thread " << t << ": " << mismatches[static_cast<std::size_t>(t)].size()
            << " results unlike the same drawn alone, the first at j = " << mismatches[static_cast<std::size_t>(t)][0];
    }
}

// More threads than cores, so that the scheduler interleaves them too.
int many_threads() { return std::max(16, 8 * static_cast<int>(std::thread::hardware_concurrency())); }

// The previews of a render are drawn in parallel (app/FeatureOutputs.cpp), and a dataset draws
// them for many samples at once: text must be measured and drawn from any number of threads at
// the same time, with the results of one thread alone. Here eight threads measure a glyph at two
// sizes in turn, so that the font at one size is released by one thread while another takes it up
// again. Text through Cairo's font API failed this in 10 runs of 10 on a 2-core machine, each
// within 0.4-2 s: Cairo 1.16 aborts in cairo_scaled_font_destroy ("Assertion
// `! scaled_font->cache_frozen' failed"), the race features/Plot.cpp's Font comment describes,
// which aborted about one render in a thousand.
TEST(PlotThreads, TextMeasuredFromManyThreadsAtOnceIsTheSameAsAlone) {
    const double alone[2] = {ltm::text_width("x", 10), ltm::text_width("x", 11)};
    from_many_threads(8, 4.0, [&](int, int j) { return ltm::text_width("x", 10 + j % 2) == alone[j % 2]; });
}

// Whole figures (titles, tick and axis labels, vertical labels) drawn from many threads at once
// are the same pictures as drawn alone, pixel for pixel.
TEST(PlotThreads, FiguresDrawnFromManyThreadsAtOnceAreTheSameAsDrawnAlone) {
    const auto draw = [](int i) {
        const std::string title = "ScatterWidth " + std::to_string(i);
        if (i % 2 == 0) return ltm::pseudo_colour(ramp(12, 9), 12, 9, title, 0.0, 1.0, 1 + i % 3);
        std::vector<double> v;
        for (int k = 0; k <= i % 17; ++k) v.push_back(0.1 * k * k);
        return ltm::histogram(v, 1 + i % 7, title, "size (mm)", false);
    };
    constexpr int kFigures = 12;
    std::vector<Image> alone;
    for (int i = 0; i < kFigures; ++i) alone.push_back(draw(i));
    from_many_threads(many_threads(), 2.0, [&](int, int j) {
        const Image f = draw(j % kFigures);
        const Image& a = alone[static_cast<std::size_t>(j % kFigures)];
        return f.width == a.width && f.height == a.height && f.data == a.data;
    });
}

// The previews as a render writes them in parallel (app/FeatureOutputs.cpp): PNG files drawn in a
// thread's own picture memory, deflated with the thread's own igzip state and written atomically;
// written from many threads at once they are the same bytes as written alone. Pictures below and
// above kPreviewTableCells cells, so both colour paths run.
TEST(PlotThreads, PreviewPngsWrittenFromManyThreadsAtOnceAreTheSameBytes) {
    const fs::path dir = fs::temp_directory_path() / ("ltm_plot_threads_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const auto write = [&](int i, const std::string& name) {
        const int w = i % 2 ? 400 : 30, h = i % 2 ? 350 : 20;  // 140000 cells (the table) or 600
        const fs::path file = dir / name;
        ltm::write_pseudo_colour_png(file.string(), ramp(w, h), w, h, "BrightField " + std::to_string(i), 0.0, 1.0,
                                     1 + i % 2, {5, 2.5});
        std::ifstream in(file, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    constexpr int kPreviews = 4;
    std::vector<std::string> alone;
    for (int i = 0; i < kPreviews; ++i) alone.push_back(write(i, "alone-" + std::to_string(i) + ".png"));
    from_many_threads(many_threads(), 2.0, [&](int t, int j) {
        const int i = j % kPreviews;
        return write(i, "thread-" + std::to_string(t) + ".png") == alone[static_cast<std::size_t>(i)];
    });
    fs::remove_all(dir);
}
