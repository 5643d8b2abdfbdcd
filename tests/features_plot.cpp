// Pictures for people (features/Plot.h): the viridis table, the bitmap font, pseudo-colour images
// with their colour bar, montages, PNG output.
//
// Set LTM_PLOT_SAMPLE=/some/file.png to have Montage.SampleForPeople also write its montage there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "io/Image.h"
#include "features/Plot.h"
#include "tests/Tolerances.h"

namespace fs = std::filesystem;
using ltm::Image;
using ltm::Rgb;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int code(float v) { return static_cast<int>(std::lround(255.0 * v)); }

Image white(int w, int h) {
    Image img(w, h, 3);
    std::fill(img.data.begin(), img.data.end(), 1.0f);
    return img;
}

Rgb pixel(const Image& img, int row, int col) { return {img.at(row, col, 0), img.at(row, col, 1), img.at(row, col, 2)}; }

bool is_white(const Image& img, int row, int col) { return pixel(img, row, col) == ltm::kWhite; }

// CIELAB L* of an sRGB colour (IEC 61966-2-1 decoding, D65 luminance weights, CIE 1976 L*).
double lightness(const Rgb& c) {
    auto linear = [](double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); };
    const double Y = 0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]);
    return Y > 216.0 / 24389.0 ? 116.0 * std::cbrt(Y) - 16.0 : Y * 24389.0 / 27.0;
}

// A character drawn alone at scale 1: its 5 x 8 cell as a string of '#' and '.'.
std::string glyph_bitmap(const std::string& ch) {
    Image img = white(ltm::kGlyphWidth, ltm::kGlyphHeight);
    ltm::draw_text(img, 0, 0, ch, 1, ltm::kBlack);
    std::string s;
    for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) s += is_white(img, r, c) ? '.' : '#';
    return s;
}

std::vector<float> ramp(int w, int h) {
    std::vector<float> v(static_cast<std::size_t>(w * h));
    for (int k = 0; k < w * h; ++k) v[static_cast<std::size_t>(k)] = static_cast<float>(k) / static_cast<float>(w * h - 1);
    return v;
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

// ---- text ----

TEST(Text, DrawsInsideItsBoxAndNowhereElse) {
    const std::string text = "Ab0.9-+eE %=:()/_gjpqy";
    const int x = 7, y = 11, scale = 2;
    const int w = ltm::text_width(text, scale), h = ltm::text_height(text, scale);
    EXPECT_EQ(w, (6 * static_cast<int>(text.size()) - 1) * scale);
    EXPECT_EQ(h, 8 * scale);
    Image img = white(w + 30, h + 25);
    ltm::draw_text(img, x, y, text, scale, ltm::kBlack);
    int inside = 0, outside = 0;
    for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) {
            const bool in_box = r >= y && r < y + h && c >= x && c < x + w;
            if (!is_white(img, r, c)) (in_box ? inside : outside) += 1;
        }
    EXPECT_GT(inside, 0);
    EXPECT_EQ(outside, 0);
    // the first and last columns and the descender row are used (the box is tight)
    auto column_used = [&](int c) {
        for (int r = y; r < y + h; ++r)
            if (!is_white(img, r, c)) return true;
        return false;
    };
    EXPECT_TRUE(column_used(x));
    EXPECT_TRUE(column_used(x + w - 1));
    bool descender = false;
    for (int c = x; c < x + w; ++c) descender = descender || !is_white(img, y + h - 1, c);
    EXPECT_TRUE(descender);
    // painted pixels have exactly the requested colour
    Image red = white(w, h);
    ltm::draw_text(red, 0, 0, text, scale, {1.0f, 0.0f, 0.0f});
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const Rgb p = pixel(red, r, c);
            EXPECT_TRUE(p == ltm::kWhite || p == (Rgb{1.0f, 0.0f, 0.0f}));
        }
}

TEST(Text, EveryRequiredCharacterHasItsOwnGlyph) {
    std::string required = "0123456789.-+eE %=:()/_";
    for (char c = 'A'; c <= 'Z'; ++c) required += c;
    for (char c = 'a'; c <= 'z'; ++c) required += c;
    const std::string box = glyph_bitmap("\x01");
    const std::string blank(static_cast<std::size_t>(ltm::kGlyphWidth * ltm::kGlyphHeight), '.');
    std::set<std::string> seen;
    for (const char c : required) {
        const std::string g = glyph_bitmap(std::string(1, c));
        if (c == ' ') {
            EXPECT_EQ(g, blank);
        } else {
            EXPECT_NE(g, blank) << "'" << c << "' draws nothing";
            EXPECT_NE(g, box) << "'" << c << "' has no glyph";
        }
        seen.insert(g);
    }
    std::set<char> unique(required.begin(), required.end());
    EXPECT_EQ(seen.size(), unique.size()) << "two characters share a glyph";
    // all of printable ASCII is covered
    for (int c = 33; c < 127; ++c) EXPECT_NE(glyph_bitmap(std::string(1, static_cast<char>(c))), box) << c;
}

TEST(Text, UnknownCharactersAreBoxes) {
    // the 5 x 7 outline: rows 0 and 6 full, the sides between, the descender row empty
    const std::string box = glyph_bitmap("\x01");
    EXPECT_EQ(box, "#####"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#####"
                   ".....");
    EXPECT_EQ(glyph_bitmap("\t"), box);
    // a UTF-8 sequence ("µ", 2 bytes; "€", 3 bytes) is one character, one box
    EXPECT_EQ(ltm::text_width("\xC2\xB5", 1), 5);
    EXPECT_EQ(ltm::text_width("\xE2\x82\xAC" "5", 1), 11);
    EXPECT_EQ(glyph_bitmap("\xC2\xB5"), box);
}

TEST(Text, SizesOfSeveralLines) {
    EXPECT_EQ(ltm::text_width("", 3), 0);
    EXPECT_EQ(ltm::text_height("", 3), 24);
    EXPECT_EQ(ltm::text_width("abc\nd", 1), 17);
    EXPECT_EQ(ltm::text_height("abc\nd", 1), 18);
    EXPECT_EQ(ltm::text_height("a\nb\nc", 2), (10 * 2 + 8) * 2);
}

TEST(Text, ClipsAtTheImageEdges) {
    Image img = white(20, 12);
    ltm::draw_text(img, -7, -5, "Wg", 2, ltm::kBlack);
    ltm::draw_text(img, 15, 9, "Wg", 2, ltm::kBlack);
    int painted = 0;
    for (int r = 0; r < img.height; ++r)
        for (int c = 0; c < img.width; ++c) painted += !is_white(img, r, c);
    EXPECT_GT(painted, 0);
}

TEST(Text, BadArguments) {
    Image gray(10, 10, 1);
    EXPECT_THROW(ltm::draw_text(gray, 0, 0, "a", 1, ltm::kBlack), std::invalid_argument);
    Image rgb = white(10, 10);
    EXPECT_THROW(ltm::draw_text(rgb, 0, 0, "a", 0, ltm::kBlack), std::invalid_argument);
    EXPECT_THROW(ltm::text_width("a", 0), std::invalid_argument);
}

// ---- pseudo colour ----

TEST(PseudoColour, SizeFollowsTheLayout) {
    // 20 x 10 at s = 4: image 80 x 40; bar H = max(40, 64) = 64 < 100: 3 ticks "1", "0.5", "0",
    // the widest (3 characters) (6 * 3 - 1) * 2 = 34 wide; title height 8 * 2 = 16.
    //   width  = 8 + 80 + 12 + 16 + 4 + 4 + 34 + 8 = 166
    //   height = 8 + 16 + 8 + 64 + 8 + 8 = 112
    {
        const Image img = ltm::pseudo_colour(ramp(20, 10), 20, 10, "T", 0.0, 1.0, 4);
        EXPECT_EQ(img.width, 166);
        EXPECT_EQ(img.height, 112);
        EXPECT_EQ(img.channels, 3);
    }
    // without a title the title row and its gap go: 112 - 16 - 8 = 88
    {
        const Image img = ltm::pseudo_colour(ramp(20, 10), 20, 10, "", 0.0, 1.0, 4);
        EXPECT_EQ(img.width, 166);
        EXPECT_EQ(img.height, 88);
    }
    // 30 x 30 at s = 4: image 120 x 120 >= 100: 5 ticks "1", "0.75", "0.5", "0.25", "0", the widest
    // (6 * 4 - 1) * 2 = 46; title "Scatter" (6 * 7 - 1) * 2 = 82 fits.
    //   width  = 8 + 120 + 12 + 16 + 4 + 4 + 46 + 8 = 218
    //   height = 8 + 16 + 8 + 120 + 8 + 8 = 168
    {
        const auto L = ltm::pseudo_colour_layout(ramp(30, 30), 30, 30, "Scatter", 0.0, 1.0, 4);
        EXPECT_EQ(L.tick_labels, (std::vector<std::string>{"1", "0.75", "0.5", "0.25", "0"}));
        const Image img = ltm::pseudo_colour(ramp(30, 30), 30, 30, "Scatter", 0.0, 1.0, 4);
        EXPECT_EQ(img.width, 218);
        EXPECT_EQ(img.height, 168);
    }
    // a title wider than the rest sets the width: 30 characters, 8 + (6 * 30 - 1) * 2 + 8 = 374
    {
        const std::string title(30, 'x');
        const Image img = ltm::pseudo_colour(ramp(20, 10), 20, 10, title, 0.0, 1.0, 1);
        EXPECT_EQ(img.width, 374);
        EXPECT_EQ(img.height, 112);
    }
}

TEST(PseudoColour, BarRunsFromHiOnTopToLoAtTheBottom) {
    const Image img = ltm::pseudo_colour(ramp(20, 10), 20, 10, "T", -2.0, 3.0, 4);
    const auto L = ltm::pseudo_colour_layout(ramp(20, 10), 20, 10, "T", -2.0, 3.0, 4);
    // the bar's place by the layout's constants: x = 8 + 80 + 12 = 100, y = 8 + 16 + 8 = 32
    EXPECT_EQ(L.bar_x, 100);
    EXPECT_EQ(L.bar_y, 32);
    EXPECT_EQ(L.bar_w, 16);
    EXPECT_EQ(L.bar_h, 64);
    for (int c = 100; c < 116; ++c) {
        EXPECT_EQ(pixel(img, 32, c), ltm::viridis(1.0));  // the colour map at hi
        EXPECT_EQ(pixel(img, 32, c), ltm::viridis_table()[255]);
        EXPECT_EQ(pixel(img, 32 + 63, c), ltm::viridis_table()[0]);  // ... and at lo
    }
    // lightness falls row by row down the bar
    for (int r = 33; r < 32 + 64; ++r) EXPECT_LT(lightness(pixel(img, r, 105)), lightness(pixel(img, r - 1, 105)));
    // the frame is just outside
    EXPECT_EQ(pixel(img, 31, 105), ltm::kFrameColour);
    EXPECT_EQ(pixel(img, 96, 105), ltm::kFrameColour);
    EXPECT_EQ(pixel(img, 50, 99), ltm::kFrameColour);
    EXPECT_EQ(pixel(img, 50, 116), ltm::kFrameColour);
    // ticks at the top and bottom rows, labelled with hi and lo
    EXPECT_EQ(L.tick_rows.front(), 32);
    EXPECT_EQ(L.tick_rows.back(), 95);
    EXPECT_EQ(L.tick_labels, (std::vector<std::string>{"3", "0.5", "-2"}));
    // the labels are drawn (black pixels) right of the ticks
    int black = 0;
    for (int r = 0; r < img.height; ++r)
        for (int c = 100 + 16 + 8; c < img.width; ++c) black += pixel(img, r, c) == ltm::kBlack;
    EXPECT_GT(black, 0);
}

TEST(PseudoColour, PixelsAreScaledNearestAndMapped) {
    const int w = 7, h = 5, s = 3;
    std::vector<float> v = ramp(w, h);
    v[8] = static_cast<float>(kNaN);
    v[9] = 5.0f;    // above hi: clamps to the top colour
    v[10] = -5.0f;  // below lo
    const double lo = 0.1, hi = 0.9;
    const Image img = ltm::pseudo_colour(v, w, h, "", lo, hi, s);
    const int x0 = 8, y0 = 8;  // no title: the image starts at the margin
    for (int m = 0; m < h; ++m)
        for (int n = 0; n < w; ++n) {
            const double value = v[static_cast<std::size_t>(m * w + n)];
            const Rgb expected = ltm::viridis((value - lo) / (hi - lo));
            for (int i = 0; i < s; ++i)
                for (int j = 0; j < s; ++j) EXPECT_EQ(pixel(img, y0 + m * s + i, x0 + n * s + j), expected) << m << " " << n;
        }
    EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 1 * s), ltm::kNanColour);                 // k = 8
    EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 2 * s), ltm::viridis_table()[255]);       // k = 9
    EXPECT_EQ(pixel(img, y0 + 1 * s, x0 + 3 * s), ltm::viridis_table()[0]);         // k = 10
    // white around the image
    EXPECT_TRUE(is_white(img, y0 - 1, x0));
    EXPECT_TRUE(is_white(img, y0, x0 - 1));
    EXPECT_TRUE(is_white(img, y0 + h * s, x0));
    EXPECT_TRUE(is_white(img, y0, x0 + w * s));
}

TEST(PseudoColour, NanRangeUsesTheFiniteMinimumAndMaximum) {
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<float> v = {static_cast<float>(kNaN), 2.0f, 3.0f, 5.0f, inf, -inf};
    const auto L = ltm::pseudo_colour_layout(v, 3, 2, "", kNaN, kNaN, 1);
    EXPECT_EQ(L.lo, 2.0);
    EXPECT_EQ(L.hi, 5.0);
    EXPECT_EQ(L.tick_labels.front(), "5");
    EXPECT_EQ(L.tick_labels.back(), "2");
    const Image img = ltm::pseudo_colour(v, 3, 2, "", kNaN, kNaN, 1);
    EXPECT_EQ(pixel(img, 8, 8), ltm::kNanColour);
    EXPECT_EQ(pixel(img, 8, 9), ltm::viridis_table()[0]);     // 2 = min
    EXPECT_EQ(pixel(img, 8, 10), ltm::viridis(1.0 / 3.0));    // 3
    EXPECT_EQ(pixel(img, 9, 8), ltm::viridis_table()[255]);   // 5 = max
    EXPECT_EQ(pixel(img, 9, 9), ltm::viridis_table()[255]);   // +inf clamps to the top
    EXPECT_EQ(pixel(img, 9, 10), ltm::viridis_table()[0]);    // -inf to the bottom

    // only one bound NaN: that one from the data
    EXPECT_EQ(ltm::colour_range(v, 0.0, kNaN), std::make_pair(0.0, 5.0));
    EXPECT_EQ(ltm::colour_range(v, kNaN, 4.0), std::make_pair(2.0, 4.0));
    // a constant image: widened by 1 around the value, drawn in the middle colour
    const std::vector<float> c(12, 7.0f);
    EXPECT_EQ(ltm::colour_range(c, kNaN, kNaN), std::make_pair(6.5, 7.5));
    const Image flat = ltm::pseudo_colour(c, 4, 3, "flat", kNaN, kNaN, 2);
    EXPECT_EQ(pixel(flat, 8 + 16 + 8, 8), ltm::viridis(0.5));
    EXPECT_EQ(ltm::pseudo_colour_layout(c, 4, 3, "flat", kNaN, kNaN, 2).tick_labels,
              (std::vector<std::string>{"7.5", "7", "6.5"}));
    // equal explicit bounds are widened the same way; no finite value at all gives [0, 1]
    EXPECT_EQ(ltm::colour_range(c, 3.0, 3.0), std::make_pair(2.5, 3.5));
    EXPECT_EQ(ltm::colour_range(std::vector<float>(4, static_cast<float>(kNaN)), kNaN, kNaN), std::make_pair(0.0, 1.0));
}

TEST(PseudoColour, CompactDistinctTickLabels) {
    EXPECT_EQ(ltm::format_tick(1000.0), "1e3");
    EXPECT_EQ(ltm::format_tick(2.5e-5), "2.5e-5");
    EXPECT_EQ(ltm::format_tick(-1.25e10), "-1.25e10");
    EXPECT_EQ(ltm::format_tick(0.5), "0.5");
    EXPECT_EQ(ltm::format_tick(123.456), "123");
    EXPECT_EQ(ltm::format_tick(0.0), "0");
    // a narrow range far from zero: more digits until neighbours differ
    const auto L = ltm::pseudo_colour_layout(ramp(10, 10), 10, 10, "", 1000.0, 1000.5, 10);
    ASSERT_EQ(L.tick_labels.size(), 5u);
    for (std::size_t i = 1; i < L.tick_labels.size(); ++i) EXPECT_NE(L.tick_labels[i], L.tick_labels[i - 1]);
    EXPECT_EQ(L.tick_labels.front(), "1000.5");
    EXPECT_EQ(L.tick_labels.back(), "1000");
    // a symmetric range has an exact zero in the middle, not a rounding residue
    const auto Z = ltm::pseudo_colour_layout(ramp(10, 10), 10, 10, "", -0.3, 0.3, 10);
    EXPECT_EQ(Z.tick_labels[2], "0");
}

TEST(PseudoColour, BadArguments) {
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 5, "", 0, 1, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour({}, 0, 0, "", 0, 1, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 0, 1, 0), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 1, 0, 1), std::invalid_argument);
    EXPECT_THROW(ltm::pseudo_colour(ramp(4, 4), 4, 4, "", 0, std::numeric_limits<double>::infinity(), 1),
                 std::invalid_argument);
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
    // cells: cw = 60, ch = 45; column labels "x" (10), "yy" (22), "column three" ((6 * 12 - 1) * 2
    // = 142): slot width sw = 142, label height 16 -> C = 16 + 4 = 20; row labels "A", "Row two"
    // ((6 * 7 - 1) * 2 = 82) -> R = 82 + 8 = 90; title "Montage" (82 wide) -> T = 16 + 8 = 24.
    //   width  = max(8 + 90 + 3 * 142 + 2 * 8 + 8, 8 + 82 + 8) = 548
    //   height = 8 + 24 + 20 + 2 * 45 + 8 + 8 = 158
    const Image img = ltm::montage(cells, {"A", "Row two"}, {"x", "yy", "column three"}, "Montage");
    EXPECT_EQ(img.width, 548);
    EXPECT_EQ(img.height, 158);
    EXPECT_EQ(img.channels, 3);
    // cell (0, 1), 30 x 20, centred in its 142 x 45 slot: slot at x = 8 + 90 + 150 = 248,
    // y = 8 + 24 + 20 = 52; padding left (142 - 30) / 2 = 56, top (45 - 20) / 2 = 12
    EXPECT_EQ(pixel(img, 64, 304), (Rgb{0.4f, 0.4f, 0.4f}));
    EXPECT_EQ(pixel(img, 64 + 19, 304 + 29), (Rgb{0.4f, 0.4f, 0.4f}));
    EXPECT_TRUE(is_white(img, 63, 304));
    EXPECT_TRUE(is_white(img, 64, 303));
    EXPECT_TRUE(is_white(img, 64 + 20, 304));
    EXPECT_TRUE(is_white(img, 64, 304 + 30));
    // the grey (1-channel) cell (1, 1): slot y = 52 + 45 + 8 = 105, top pad 12, left pad 61
    EXPECT_EQ(pixel(img, 117, 248 + 61), (Rgb{0.25f, 0.25f, 0.25f}));
    // the missing cell (1, 2) stays white
    for (int r = 105; r < 150; ++r)
        for (int c = 8 + 90 + 2 * 150; c < 8 + 90 + 2 * 150 + 142; ++c) ASSERT_TRUE(is_white(img, r, c));

    // a single cell, no labels: 8 + 10 + 8 each way
    const Image one = ltm::montage({{solid(10, 10, 0.5f)}}, {}, {}, "");
    EXPECT_EQ(one.width, 26);
    EXPECT_EQ(one.height, 26);
    EXPECT_EQ(pixel(one, 8, 8), (Rgb{0.5f, 0.5f, 0.5f}));
    EXPECT_TRUE(is_white(one, 7, 8));
}

TEST(Montage, BadArguments) {
    const Image cell(4, 4, 3);
    EXPECT_THROW(ltm::montage({}, {}, {}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{cell, cell}}, {"a", "b"}, {}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{cell, cell}}, {}, {"a"}, ""), std::invalid_argument);
    EXPECT_THROW(ltm::montage({{Image(4, 4, 2)}}, {}, {}, ""), std::invalid_argument);
}

TEST(Montage, SampleForPeople) {
    // Synthetic feature images of two defects, the way `render` would show them.
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
    std::vector<std::vector<Image>> cells(2);
    cells[0].push_back(ltm::pseudo_colour(image(20, 18, 3, 3, 40, 2, 1.5), w, h, "ScatterCount", kNaN, kNaN, 3));
    cells[0].push_back(ltm::pseudo_colour(image(20, 18, 3, 3, -0.4, 0.92, 0.01), w, h, "BrightField", kNaN, kNaN, 3));
    cells[1].push_back(ltm::pseudo_colour(image(28, 24, 12, 1.5, 25, 2, 1.5), w, h, "ScatterCount", kNaN, kNaN, 3));
    cells[1].push_back(ltm::pseudo_colour(image(28, 24, 12, 1.5, -0.2, 0.92, 0.01), w, h, "BrightField", kNaN, kNaN, 3));
    const Image img = ltm::montage(cells, {"bubble r=0.125", "scratch"}, {"scatter (count)", "bright field (1)"},
                                   "Synthetic defects: feature images");
    EXPECT_GT(img.width, 0);
    if (const char* out = std::getenv("LTM_PLOT_SAMPLE")) ltm::write_png(out, img);
}

// ---- PNG ----

TEST(PseudoColourPng, ReadableAndOfTheExpectedSize) {
    const fs::path dir = fs::temp_directory_path() / ("ltm_plot_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string file = (dir / "ramp.png").string();
    std::vector<float> v = ramp(20, 10);
    v[3] = static_cast<float>(kNaN);
    ltm::write_pseudo_colour_png(file, v, 20, 10, "T", 0.0, 1.0, 4);
    const Image back = ltm::read_image(file);
    const Image expected = ltm::pseudo_colour(v, 20, 10, "T", 0.0, 1.0, 4);
    EXPECT_EQ(back.width, 166);  // as in PseudoColour.SizeFollowsTheLayout
    EXPECT_EQ(back.height, 112);
    ASSERT_EQ(back.channels, 3);
    ASSERT_EQ(back.data.size(), expected.data.size());
    for (std::size_t i = 0; i < back.data.size(); ++i) ASSERT_EQ(code(back.data[i]), code(expected.data[i])) << i;
    fs::remove_all(dir);
}
