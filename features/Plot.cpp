// Plot.h: viridis, pseudo-colour images with a colour bar and axes, montages, histograms; lines
// and text drawn with Cairo, the font loaded from its file through FreeType.
#include "features/Plot.h"

#include "io/Pages.h"

#include <cairo.h>
#include <ft2build.h>
#include FT_FREETYPE_H
#include FT_OUTLINE_H
#include <emmintrin.h>  // SSE2: colour_range
#include <tmmintrin.h>  // SSSE3: png_row_codes

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>
#include <shared_mutex>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <unordered_map>

namespace ltm {

namespace {

// viridis: matplotlib's _viridis_data (matplotlib/_cm_listed.py; S. van der Walt and N. Smith,
// https://bids.github.io/colormap/, CC0), 256 sRGB entries from #440154 to #FDE725.
const std::array<Rgb, 256> kViridis = {{
    {0.267004f, 0.004874f, 0.329415f}, {0.268510f, 0.009605f, 0.335427f}, {0.269944f, 0.014625f, 0.341379f},
    {0.271305f, 0.019942f, 0.347269f}, {0.272594f, 0.025563f, 0.353093f}, {0.273809f, 0.031497f, 0.358853f},
    {0.274952f, 0.037752f, 0.364543f}, {0.276022f, 0.044167f, 0.370164f}, {0.277018f, 0.050344f, 0.375715f},
    {0.277941f, 0.056324f, 0.381191f}, {0.278791f, 0.062145f, 0.386592f}, {0.279566f, 0.067836f, 0.391917f},
    {0.280267f, 0.073417f, 0.397163f}, {0.280894f, 0.078907f, 0.402329f}, {0.281446f, 0.084320f, 0.407414f},
    {0.281924f, 0.089666f, 0.412415f}, {0.282327f, 0.094955f, 0.417331f}, {0.282656f, 0.100196f, 0.422160f},
    {0.282910f, 0.105393f, 0.426902f}, {0.283091f, 0.110553f, 0.431554f}, {0.283197f, 0.115680f, 0.436115f},
    {0.283229f, 0.120777f, 0.440584f}, {0.283187f, 0.125848f, 0.444960f}, {0.283072f, 0.130895f, 0.449241f},
    {0.282884f, 0.135920f, 0.453427f}, {0.282623f, 0.140926f, 0.457517f}, {0.282290f, 0.145912f, 0.461510f},
    {0.281887f, 0.150881f, 0.465405f}, {0.281412f, 0.155834f, 0.469201f}, {0.280868f, 0.160771f, 0.472899f},
    {0.280255f, 0.165693f, 0.476498f}, {0.279574f, 0.170599f, 0.479997f}, {0.278826f, 0.175490f, 0.483397f},
    {0.278012f, 0.180367f, 0.486697f}, {0.277134f, 0.185228f, 0.489898f}, {0.276194f, 0.190074f, 0.493001f},
    {0.275191f, 0.194905f, 0.496005f}, {0.274128f, 0.199721f, 0.498911f}, {0.273006f, 0.204520f, 0.501721f},
    {0.271828f, 0.209303f, 0.504434f}, {0.270595f, 0.214069f, 0.507052f}, {0.269308f, 0.218818f, 0.509577f},
    {0.267968f, 0.223549f, 0.512008f}, {0.266580f, 0.228262f, 0.514349f}, {0.265145f, 0.232956f, 0.516599f},
    {0.263663f, 0.237631f, 0.518762f}, {0.262138f, 0.242286f, 0.520837f}, {0.260571f, 0.246922f, 0.522828f},
    {0.258965f, 0.251537f, 0.524736f}, {0.257322f, 0.256130f, 0.526563f}, {0.255645f, 0.260703f, 0.528312f},
    {0.253935f, 0.265254f, 0.529983f}, {0.252194f, 0.269783f, 0.531579f}, {0.250425f, 0.274290f, 0.533103f},
    {0.248629f, 0.278775f, 0.534556f}, {0.246811f, 0.283237f, 0.535941f}, {0.244972f, 0.287675f, 0.537260f},
    {0.243113f, 0.292092f, 0.538516f}, {0.241237f, 0.296485f, 0.539709f}, {0.239346f, 0.300855f, 0.540844f},
    {0.237441f, 0.305202f, 0.541921f}, {0.235526f, 0.309527f, 0.542944f}, {0.233603f, 0.313828f, 0.543914f},
    {0.231674f, 0.318106f, 0.544834f}, {0.229739f, 0.322361f, 0.545706f}, {0.227802f, 0.326594f, 0.546532f},
    {0.225863f, 0.330805f, 0.547314f}, {0.223925f, 0.334994f, 0.548053f}, {0.221989f, 0.339161f, 0.548752f},
    {0.220057f, 0.343307f, 0.549413f}, {0.218130f, 0.347432f, 0.550038f}, {0.216210f, 0.351535f, 0.550627f},
    {0.214298f, 0.355619f, 0.551184f}, {0.212395f, 0.359683f, 0.551710f}, {0.210503f, 0.363727f, 0.552206f},
    {0.208623f, 0.367752f, 0.552675f}, {0.206756f, 0.371758f, 0.553117f}, {0.204903f, 0.375746f, 0.553533f},
    {0.203063f, 0.379716f, 0.553925f}, {0.201239f, 0.383670f, 0.554294f}, {0.199430f, 0.387607f, 0.554642f},
    {0.197636f, 0.391528f, 0.554969f}, {0.195860f, 0.395433f, 0.555276f}, {0.194100f, 0.399323f, 0.555565f},
    {0.192357f, 0.403199f, 0.555836f}, {0.190631f, 0.407061f, 0.556089f}, {0.188923f, 0.410910f, 0.556326f},
    {0.187231f, 0.414746f, 0.556547f}, {0.185556f, 0.418570f, 0.556753f}, {0.183898f, 0.422383f, 0.556944f},
    {0.182256f, 0.426184f, 0.557120f}, {0.180629f, 0.429975f, 0.557282f}, {0.179019f, 0.433756f, 0.557430f},
    {0.177423f, 0.437527f, 0.557565f}, {0.175841f, 0.441290f, 0.557685f}, {0.174274f, 0.445044f, 0.557792f},
    {0.172719f, 0.448791f, 0.557885f}, {0.171176f, 0.452530f, 0.557965f}, {0.169646f, 0.456262f, 0.558030f},
    {0.168126f, 0.459988f, 0.558082f}, {0.166617f, 0.463708f, 0.558119f}, {0.165117f, 0.467423f, 0.558141f},
    {0.163625f, 0.471133f, 0.558148f}, {0.162142f, 0.474838f, 0.558140f}, {0.160665f, 0.478540f, 0.558115f},
    {0.159194f, 0.482237f, 0.558073f}, {0.157729f, 0.485932f, 0.558013f}, {0.156270f, 0.489624f, 0.557936f},
    {0.154815f, 0.493313f, 0.557840f}, {0.153364f, 0.497000f, 0.557724f}, {0.151918f, 0.500685f, 0.557587f},
    {0.150476f, 0.504369f, 0.557430f}, {0.149039f, 0.508051f, 0.557250f}, {0.147607f, 0.511733f, 0.557049f},
    {0.146180f, 0.515413f, 0.556823f}, {0.144759f, 0.519093f, 0.556572f}, {0.143343f, 0.522773f, 0.556295f},
    {0.141935f, 0.526453f, 0.555991f}, {0.140536f, 0.530132f, 0.555659f}, {0.139147f, 0.533812f, 0.555298f},
    {0.137770f, 0.537492f, 0.554906f}, {0.136408f, 0.541173f, 0.554483f}, {0.135066f, 0.544853f, 0.554029f},
    {0.133743f, 0.548535f, 0.553541f}, {0.132444f, 0.552216f, 0.553018f}, {0.131172f, 0.555899f, 0.552459f},
    {0.129933f, 0.559582f, 0.551864f}, {0.128729f, 0.563265f, 0.551229f}, {0.127568f, 0.566949f, 0.550556f},
    {0.126453f, 0.570633f, 0.549841f}, {0.125394f, 0.574318f, 0.549086f}, {0.124395f, 0.578002f, 0.548287f},
    {0.123463f, 0.581687f, 0.547445f}, {0.122606f, 0.585371f, 0.546557f}, {0.121831f, 0.589055f, 0.545623f},
    {0.121148f, 0.592739f, 0.544641f}, {0.120565f, 0.596422f, 0.543611f}, {0.120092f, 0.600104f, 0.542530f},
    {0.119738f, 0.603785f, 0.541400f}, {0.119512f, 0.607464f, 0.540218f}, {0.119423f, 0.611141f, 0.538982f},
    {0.119483f, 0.614817f, 0.537692f}, {0.119699f, 0.618490f, 0.536347f}, {0.120081f, 0.622161f, 0.534946f},
    {0.120638f, 0.625828f, 0.533488f}, {0.121380f, 0.629492f, 0.531973f}, {0.122312f, 0.633153f, 0.530398f},
    {0.123444f, 0.636809f, 0.528763f}, {0.124780f, 0.640461f, 0.527068f}, {0.126326f, 0.644107f, 0.525311f},
    {0.128087f, 0.647749f, 0.523491f}, {0.130067f, 0.651384f, 0.521608f}, {0.132268f, 0.655014f, 0.519661f},
    {0.134692f, 0.658636f, 0.517649f}, {0.137339f, 0.662252f, 0.515571f}, {0.140210f, 0.665859f, 0.513427f},
    {0.143303f, 0.669459f, 0.511215f}, {0.146616f, 0.673050f, 0.508936f}, {0.150148f, 0.676631f, 0.506589f},
    {0.153894f, 0.680203f, 0.504172f}, {0.157851f, 0.683765f, 0.501686f}, {0.162016f, 0.687316f, 0.499129f},
    {0.166383f, 0.690856f, 0.496502f}, {0.170948f, 0.694384f, 0.493803f}, {0.175707f, 0.697900f, 0.491033f},
    {0.180653f, 0.701402f, 0.488189f}, {0.185783f, 0.704891f, 0.485273f}, {0.191090f, 0.708366f, 0.482284f},
    {0.196571f, 0.711827f, 0.479221f}, {0.202219f, 0.715272f, 0.476084f}, {0.208030f, 0.718701f, 0.472873f},
    {0.214000f, 0.722114f, 0.469588f}, {0.220124f, 0.725509f, 0.466226f}, {0.226397f, 0.728888f, 0.462789f},
    {0.232815f, 0.732247f, 0.459277f}, {0.239374f, 0.735588f, 0.455688f}, {0.246070f, 0.738910f, 0.452024f},
    {0.252899f, 0.742211f, 0.448284f}, {0.259857f, 0.745492f, 0.444467f}, {0.266941f, 0.748751f, 0.440573f},
    {0.274149f, 0.751988f, 0.436601f}, {0.281477f, 0.755203f, 0.432552f}, {0.288921f, 0.758394f, 0.428426f},
    {0.296479f, 0.761561f, 0.424223f}, {0.304148f, 0.764704f, 0.419943f}, {0.311925f, 0.767822f, 0.415586f},
    {0.319809f, 0.770914f, 0.411152f}, {0.327796f, 0.773980f, 0.406640f}, {0.335885f, 0.777018f, 0.402049f},
    {0.344074f, 0.780029f, 0.397381f}, {0.352360f, 0.783011f, 0.392636f}, {0.360741f, 0.785964f, 0.387814f},
    {0.369214f, 0.788888f, 0.382914f}, {0.377779f, 0.791781f, 0.377939f}, {0.386433f, 0.794644f, 0.372886f},
    {0.395174f, 0.797475f, 0.367757f}, {0.404001f, 0.800275f, 0.362552f}, {0.412913f, 0.803041f, 0.357269f},
    {0.421908f, 0.805774f, 0.351910f}, {0.430983f, 0.808473f, 0.346476f}, {0.440137f, 0.811138f, 0.340967f},
    {0.449368f, 0.813768f, 0.335384f}, {0.458674f, 0.816363f, 0.329727f}, {0.468053f, 0.818921f, 0.323998f},
    {0.477504f, 0.821444f, 0.318195f}, {0.487026f, 0.823929f, 0.312321f}, {0.496615f, 0.826376f, 0.306377f},
    {0.506271f, 0.828786f, 0.300362f}, {0.515992f, 0.831158f, 0.294279f}, {0.525776f, 0.833491f, 0.288127f},
    {0.535621f, 0.835785f, 0.281908f}, {0.545524f, 0.838039f, 0.275626f}, {0.555484f, 0.840254f, 0.269281f},
    {0.565498f, 0.842430f, 0.262877f}, {0.575563f, 0.844566f, 0.256415f}, {0.585678f, 0.846661f, 0.249897f},
    {0.595839f, 0.848717f, 0.243329f}, {0.606045f, 0.850733f, 0.236712f}, {0.616293f, 0.852709f, 0.230052f},
    {0.626579f, 0.854645f, 0.223353f}, {0.636902f, 0.856542f, 0.216620f}, {0.647257f, 0.858400f, 0.209861f},
    {0.657642f, 0.860219f, 0.203082f}, {0.668054f, 0.861999f, 0.196293f}, {0.678489f, 0.863742f, 0.189503f},
    {0.688944f, 0.865448f, 0.182725f}, {0.699415f, 0.867117f, 0.175971f}, {0.709898f, 0.868751f, 0.169257f},
    {0.720391f, 0.870350f, 0.162603f}, {0.730889f, 0.871916f, 0.156029f}, {0.741388f, 0.873449f, 0.149561f},
    {0.751884f, 0.874951f, 0.143228f}, {0.762373f, 0.876424f, 0.137064f}, {0.772852f, 0.877868f, 0.131109f},
    {0.783315f, 0.879285f, 0.125405f}, {0.793760f, 0.880678f, 0.120005f}, {0.804182f, 0.882046f, 0.114965f},
    {0.814576f, 0.883393f, 0.110347f}, {0.824940f, 0.884720f, 0.106217f}, {0.835270f, 0.886029f, 0.102646f},
    {0.845561f, 0.887322f, 0.099702f}, {0.855810f, 0.888601f, 0.097452f}, {0.866013f, 0.889868f, 0.095953f},
    {0.876168f, 0.891125f, 0.095250f}, {0.886271f, 0.892374f, 0.095374f}, {0.896320f, 0.893616f, 0.096335f},
    {0.906311f, 0.894855f, 0.098125f}, {0.916242f, 0.896091f, 0.100717f}, {0.926106f, 0.897330f, 0.104071f},
    {0.935904f, 0.898570f, 0.108131f}, {0.945636f, 0.899815f, 0.112838f}, {0.955300f, 0.901065f, 0.118128f},
    {0.964894f, 0.902323f, 0.123941f}, {0.974417f, 0.903590f, 0.130215f}, {0.983868f, 0.904867f, 0.136897f},
    {0.993248f, 0.906157f, 0.143936f},
}};


// ---- the font ----

std::string font_error(const std::string& path, const std::string& why) {
    return "font file " + path + ": " + why +
           " (figures are drawn in DejaVu Sans read from this file; it comes with the Debian package "
           "fonts-dejavu-core: scripts/install-deps installs it)";
}

// Opens `path` as face 0; the caller owns the face.
FT_Face open_face(FT_Library library, const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error(font_error(path, "missing"));
    FT_Face face = nullptr;
    if (const FT_Error e = FT_New_Face(library, path.c_str(), 0, &face))
        throw std::runtime_error(font_error(path, "not a font FreeType can read (FreeType error " + std::to_string(e) + ")"));
    return face;
}

struct FreeTypeLibrary {
    FT_Library library = nullptr;
    FreeTypeLibrary() {
        if (FT_Init_FreeType(&library)) throw std::runtime_error("FreeType could not be initialised");
    }
    ~FreeTypeLibrary() { FT_Done_FreeType(library); }
    FreeTypeLibrary(const FreeTypeLibrary&) = delete;
    FreeTypeLibrary& operator=(const FreeTypeLibrary&) = delete;
};

// A point of a glyph's outline, in ems (x right, y up from the baseline, at the glyph's origin).
struct OutlinePoint {
    double x = 0, y = 0;
};

// One drawing step of an outline: move to, line to, or a cubic Bezier through two control points
// to an end point (TrueType's quadratic curves are raised to cubics exactly).
struct OutlineStep {
    enum Kind : std::uint8_t { Move, Line, Cubic } kind = Move;
    OutlinePoint c1, c2, to;  // c1, c2: control points of a Cubic
};

struct Glyph {
    double advance = 0;  // ems
    std::vector<OutlineStep> outline;
};

// Text is drawn as the font's glyph outlines, filled by Cairo like any other path: a Font holds
// them, read through FreeType from the font file, and text never goes through Cairo's own text
// API. That API keeps process-wide mutable state (a font face's scaled fonts in one font map,
// shared by every thread that draws at the same size), and Cairo 1.16 (Debian 12) races on it:
// cairo_scaled_font_destroy drops a reference before it takes the font map's lock and then
// asserts that the font's glyph cache is not frozen, while another thread may meanwhile have
// found the font in the map and frozen its cache to draw ("Assertion `! scaled_font->cache_frozen'
// failed", an abort in about one render in a thousand whose previews were drawn in parallel).
//
// Glyphs are read on first use and kept for the life of the process: a glyph, once in the table,
// never changes or moves (std::unordered_map keeps its elements in place), so drawing threads read
// it under a shared lock and use it after releasing that lock; the FreeType face is touched only
// under the exclusive lock, by the one thread adding a glyph. Outlines are unhinted, in font units
// scaled to ems (FT_LOAD_NO_SCALE); metrics are rounded to whole pixels as FreeType rounds a
// sized face's (advances to the nearest pixel, ascent and descent up), so that a label's baseline
// and the next glyph's origin fall on pixel boundaries.
class Font {
public:
    explicit Font(const std::string& path) : face_(open_face(library_.library, path)) {
        if (!FT_IS_SCALABLE(face_) || face_->units_per_EM == 0) {
            FT_Done_Face(face_);
            throw std::runtime_error(font_error(path, "not a scalable (outline) font"));
        }
        const double em = face_->units_per_EM;
        ascent_ = face_->ascender / em;
        descent_ = -face_->descender / em;
    }
    ~Font() { FT_Done_Face(face_); }
    Font(const Font&) = delete;
    Font& operator=(const Font&) = delete;

    // The whole-pixel ascent above the baseline and line height (ascent + descent) at `size`.
    int ascent(double size) const { return static_cast<int>(std::ceil(ascent_ * size)); }
    int line_height(double size) const { return ascent(size) + static_cast<int>(std::ceil(descent_ * size)); }

    // The advance of one glyph at `size`, whole pixels.
    static double advance(const Glyph& g, double size) { return std::round(g.advance * size); }

    // The glyphs of a UTF-8 text, in order (a malformed byte counts as U+FFFD; a character the
    // font lacks is its .notdef glyph, a box).
    std::vector<const Glyph*> glyphs(const std::string& text) {
        std::vector<const Glyph*> out;
        for (std::size_t i = 0; i < text.size();) out.push_back(&glyph(next_code_point(text, i)));
        return out;
    }

    double width(const std::string& text, double size) {
        double w = 0;
        for (const Glyph* g : glyphs(text)) w += advance(*g, size);
        return w;
    }

private:
    static char32_t next_code_point(const std::string& s, std::size_t& i) {
        const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
        const unsigned char b = byte(i);
        const int n = b < 0x80 ? 0 : (b >> 5) == 0x6 ? 1 : (b >> 4) == 0xE ? 2 : (b >> 3) == 0x1E ? 3 : -1;
        if (n < 0 || i + static_cast<std::size_t>(n) >= s.size()) {  // not a lead byte, or cut short
            ++i;
            return 0xFFFD;
        }
        char32_t c = n == 0 ? b : n == 1 ? (b & 0x1F) : n == 2 ? (b & 0x0F) : (b & 0x07);
        for (int k = 1; k <= n; ++k) {
            if ((byte(i + static_cast<std::size_t>(k)) & 0xC0) != 0x80) {
                ++i;
                return 0xFFFD;
            }
            c = (c << 6) | (byte(i + static_cast<std::size_t>(k)) & 0x3F);
        }
        i += static_cast<std::size_t>(n) + 1;
        return c;
    }

    const Glyph& glyph(char32_t c) {
        {
            std::shared_lock<std::shared_mutex> read(lock_);
            const auto it = glyphs_.find(c);
            if (it != glyphs_.end()) return it->second;
        }
        std::unique_lock<std::shared_mutex> write(lock_);
        const auto it = glyphs_.find(c);  // another thread may have added it meanwhile
        if (it != glyphs_.end()) return it->second;
        return glyphs_.emplace(c, load(c)).first->second;
    }

    // The outline and advance of the glyph for code point c (under the exclusive lock).
    Glyph load(char32_t c) {
        Glyph g;
        const FT_UInt index = FT_Get_Char_Index(face_, c);  // 0, .notdef, where the font lacks c
        if (FT_Load_Glyph(face_, index, FT_LOAD_NO_SCALE | FT_LOAD_NO_HINTING | FT_LOAD_NO_BITMAP) != 0 ||
            face_->glyph->format != FT_GLYPH_FORMAT_OUTLINE)
            return g;  // nothing to draw, no advance
        const double em = face_->units_per_EM;
        g.advance = face_->glyph->advance.x / em;
        struct Sink {
            Glyph& g;
            double em;
            OutlinePoint at;  // the current point
            OutlinePoint p(const FT_Vector* v) const { return {v->x / em, v->y / em}; }
        } sink{g, em, {}};
        FT_Outline_Funcs funcs{};
        funcs.move_to = [](const FT_Vector* to, void* u) {
            Sink& k = *static_cast<Sink*>(u);
            k.at = k.p(to);
            k.g.outline.push_back({OutlineStep::Move, {}, {}, k.at});
            return 0;
        };
        funcs.line_to = [](const FT_Vector* to, void* u) {
            Sink& k = *static_cast<Sink*>(u);
            k.at = k.p(to);
            k.g.outline.push_back({OutlineStep::Line, {}, {}, k.at});
            return 0;
        };
        // A quadratic Bezier (p0, q, p1) is the cubic (p0, p0 + 2/3 (q - p0), p1 + 2/3 (q - p1), p1).
        funcs.conic_to = [](const FT_Vector* control, const FT_Vector* to, void* u) {
            Sink& k = *static_cast<Sink*>(u);
            const OutlinePoint q = k.p(control), p1 = k.p(to), p0 = k.at;
            k.g.outline.push_back({OutlineStep::Cubic,
                                   {p0.x + 2.0 / 3.0 * (q.x - p0.x), p0.y + 2.0 / 3.0 * (q.y - p0.y)},
                                   {p1.x + 2.0 / 3.0 * (q.x - p1.x), p1.y + 2.0 / 3.0 * (q.y - p1.y)},
                                   p1});
            k.at = p1;
            return 0;
        };
        funcs.cubic_to = [](const FT_Vector* c1, const FT_Vector* c2, const FT_Vector* to, void* u) {
            Sink& k = *static_cast<Sink*>(u);
            k.at = k.p(to);
            k.g.outline.push_back({OutlineStep::Cubic, k.p(c1), k.p(c2), k.at});
            return 0;
        };
        if (FT_Outline_Decompose(&face_->glyph->outline, &funcs, &sink) != 0) g.outline.clear();
        return g;
    }

    FreeTypeLibrary library_;
    FT_Face face_ = nullptr;
    double ascent_ = 0, descent_ = 0;  // ems
    std::shared_mutex lock_;
    std::unordered_map<char32_t, Glyph> glyphs_;
};

// kFontFile's Font, made on first use and kept for the life of the process (never destroyed, so
// still reachable at exit: a function-local static pointer).
Font& font() {
    static Font* const f = new Font(kFontFile);
    return *f;
}

// ---- drawing ----

// A white RGB canvas with a Cairo context: antialiased lines, and text as filled glyph outlines
// (Font above: unhinted outlines, metrics rounded to whole pixels; nothing taken from the machine).
// Memory a caller keeps for pictures it draws again and again (the previews of every render):
// every page of a fresh picture costs a page fault, about 10 us on a virtual machine, which was a
// quarter of the default scene's write stage (perf). A Canvas given one draws into `surface`.
// Its pages are huge ones (io::Scratch): the first preview of each thread faults two instead of
// 700 small ones at the default scene's size.
struct PictureMemory {
    io::Scratch<std::uint32_t> surface;  // Cairo's RGB24 pixel words
};

// A picture as a Cairo surface holds it: each pixel a 32-bit word 0x00RRGGBB (CAIRO_FORMAT_RGB24,
// in native byte order), rows `stride` words apart. A preview's cells are painted straight into
// its Canvas's surface and its PNG rows read from there: no RGB copy of the picture is made.
struct SurfacePicture {
    int width = 0, height = 0;
    std::uint32_t* pixels = nullptr;
    std::size_t stride = 0;
};

// n pixels 0x00RRGGBB (CAIRO_FORMAT_RGB24) as 3n RGB code values.
// Four bytes stored a pixel, three advanced (the fourth is the next pixel's first), the last
// pixel byte by byte: a preview's rows are converted as they are deflated.
void rgb_codes(const std::uint32_t* row, int n, std::uint8_t* out) {
    for (int c = 0; c + 1 < n; ++c, out += 3) {
        const std::uint32_t p = row[c];
        const std::uint8_t rgbx[4] = {static_cast<std::uint8_t>(p >> 16), static_cast<std::uint8_t>(p >> 8),
                                      static_cast<std::uint8_t>(p), 0};
        std::memcpy(out, rgbx, 4);
    }
    if (n > 0) {
        const std::uint32_t p = row[n - 1];
        out[0] = static_cast<std::uint8_t>(p >> 16);
        out[1] = static_cast<std::uint8_t>(p >> 8);
        out[2] = static_cast<std::uint8_t>(p);
    }
}

// The same conversion for the PNG rows of a preview, 4 pixels a step with SSSE3's byte shuffle
// where the processor has it (every x86-64 processor since 2006; the scalar rgb_codes otherwise
// and for the last pixels): one byte at a time it takes a fifth of a preview's time (perf,
// bench_features' BM_WriteFile/file:4). Each step loads 16 bytes (4 words) and stores 16, of
// which the last 4 are the next step's: the loop stops while 6 pixels are left, so that no store
// passes the row's 3n bytes. tests/features_plot.cpp compares the PNG's pixels with
// pseudo_colour's, whose picture comes through rgb_codes.
#if defined(__x86_64__)
__attribute__((target("ssse3"))) void rgb_codes_ssse3(const std::uint32_t* row, int n, std::uint8_t* out) {
    // word k of the 16 bytes is bytes B, G, R, 0 (little-endian 0x00RRGGBB): R, G, B of each
    const __m128i order = _mm_setr_epi8(2, 1, 0, 6, 5, 4, 10, 9, 8, 14, 13, 12, -1, -1, -1, -1);
    int c = 0;
    for (; c + 6 <= n; c += 4, out += 12) {
        const __m128i words = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + c));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_shuffle_epi8(words, order));
    }
    rgb_codes(row + c, n - c, out);
}
#endif

void png_row_codes(const std::uint32_t* row, int n, std::uint8_t* out) {
#if defined(__x86_64__)
    static const bool ssse3 = __builtin_cpu_supports("ssse3");
    if (ssse3) {
        rgb_codes_ssse3(row, n, out);
        return;
    }
#endif
    rgb_codes(row, n, out);
}

class Canvas {
public:
    // memory (optional): where the surface's pixels live (Cairo's own allocation without it).
    Canvas(int width, int height, PictureMemory* memory = nullptr) : memory_(memory) {
        if (memory_) {
            const int stride = cairo_format_stride_for_width(CAIRO_FORMAT_RGB24, width);
            if (stride < 0)
                throw std::runtime_error("Cairo: cannot make a " + std::to_string(width) + " x " + std::to_string(height) +
                                         " canvas: the width is too large");
            // RGB24's stride is a multiple of 4 bytes: whole words.
            // Uncleared: the canvas is painted white below.
            words_ = memory_->surface.get(static_cast<std::size_t>(stride / 4) * static_cast<std::size_t>(height > 0 ? height : 0));
            surface_ = cairo_image_surface_create_for_data(reinterpret_cast<unsigned char*>(words_),
                                                           CAIRO_FORMAT_RGB24, width, height, stride);
        } else {
            surface_ = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
        }
        cr_ = cairo_create(surface_);
        if (cairo_status(cr_) != CAIRO_STATUS_SUCCESS) {
            const std::string why = cairo_status_to_string(cairo_status(cr_));
            cairo_destroy(cr_);
            cairo_surface_destroy(surface_);
            throw std::runtime_error("Cairo: cannot make a " + std::to_string(width) + " x " + std::to_string(height) +
                                     " canvas: " + why);
        }
        cairo_set_source_rgb(cr_, 1, 1, 1);
        cairo_paint(cr_);
        cairo_set_line_width(cr_, 1.0);
        cairo_set_line_cap(cr_, CAIRO_LINE_CAP_BUTT);
    }
    ~Canvas() {
        cairo_destroy(cr_);
        cairo_surface_destroy(surface_);
    }
    Canvas(const Canvas&) = delete;
    Canvas& operator=(const Canvas&) = delete;

    double width_of(const std::string& text, double size) { return font().width(text, size); }
    // ascent, line height (ascent + descent), whole pixels
    std::pair<double, int> line(double size) { return {font().ascent(size), font().line_height(size)}; }
    Label label(const std::string& text, double size, bool vertical = false) {
        Label l;
        l.text = text;
        l.size = size;
        l.vertical = vertical;
        const double w = width_of(text, size);
        const int h = line(size).second;
        l.box.w = vertical ? h : w;
        l.box.h = vertical ? w : h;
        return l;
    }

    // The label's glyph outlines as one path, filled with the non-zero winding rule (TrueType's),
    // antialiased: the pen starts at the box's left end on the baseline, `ascent` below its top
    // (for a vertical label the same in a frame turned a quarter turn counter-clockwise).
    void draw(const Label& l, const Rgb& colour = kBlack) {
        if (l.text.empty()) return;
        const double ascent = line(l.size).first;
        set_colour(colour);
        cairo_save(cr_);
        if (l.vertical) {
            cairo_translate(cr_, l.box.x + ascent, l.box.y + l.box.h);
            cairo_rotate(cr_, -std::acos(0.0));  // a quarter turn counter-clockwise
        } else {
            cairo_translate(cr_, l.box.x, l.box.y + ascent);
        }
        cairo_new_path(cr_);
        double pen = 0;
        const double s = l.size;
        for (const Glyph* g : font().glyphs(l.text)) {
            for (const OutlineStep& step : g->outline) {
                const double x = pen + step.to.x * s, y = -step.to.y * s;  // y up in the font, down here
                switch (step.kind) {
                case OutlineStep::Move: cairo_move_to(cr_, x, y); break;
                case OutlineStep::Line: cairo_line_to(cr_, x, y); break;
                case OutlineStep::Cubic:
                    cairo_curve_to(cr_, pen + step.c1.x * s, -step.c1.y * s, pen + step.c2.x * s, -step.c2.y * s, x, y);
                    break;
                }
            }
            pen += Font::advance(*g, s);
        }
        cairo_set_fill_rule(cr_, CAIRO_FILL_RULE_WINDING);
        cairo_fill(cr_);
        cairo_restore(cr_);
    }
    // dash: 0 solid, 1 dashed (5 on, 3 off), 2 dotted (1 on, 3 off).
    void segment(double x0, double y0, double x1, double y1, const Rgb& colour, int dash = 0) {
        set_colour(colour);
        if (dash) {
            const double pattern[] = {dash == 1 ? 5.0 : 1.0, 3.0};
            cairo_set_dash(cr_, pattern, 2, 0);
        }
        cairo_move_to(cr_, x0, y0);
        cairo_line_to(cr_, x1, y1);
        cairo_stroke(cr_);
        if (dash) cairo_set_dash(cr_, nullptr, 0, 0);
    }
    // A 1-pixel line just outside the w x h block at (x, y).
    void frame(int x, int y, int w, int h, const Rgb& colour) {
        set_colour(colour);
        cairo_rectangle(cr_, x - 0.5, y - 0.5, w + 1.0, h + 1.0);
        cairo_stroke(cr_);
    }
    void fill(const Box& b, const Rgb& colour) {
        set_colour(colour);
        cairo_rectangle(cr_, b.x, b.y, b.w, b.h);
        cairo_fill(cr_);
    }

    // The picture as drawn, in the surface's memory (a Canvas drawing into a PictureMemory only:
    // Cairo's own memory goes with the Canvas).
    SurfacePicture surface_picture() {
        if (!memory_) throw std::logic_error("Canvas: a surface picture of a canvas without its PictureMemory");
        cairo_surface_flush(surface_);
        SurfacePicture p;
        p.width = cairo_image_surface_get_width(surface_);
        p.height = cairo_image_surface_get_height(surface_);
        p.pixels = words_;  // the words Cairo drew into
        p.stride = static_cast<std::size_t>(cairo_image_surface_get_stride(surface_)) / 4;
        return p;
    }
    // The picture as drawn: its RGB code values.
    Image8 codes() {
        cairo_surface_flush(surface_);
        const int w = cairo_image_surface_get_width(surface_), h = cairo_image_surface_get_height(surface_);
        const int stride = cairo_image_surface_get_stride(surface_);
        const unsigned char* data = cairo_image_surface_get_data(surface_);
        Image8 img;
        img.width = w;
        img.height = h;
        img.channels = 3;
        img.data.resize(3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
        for (int r = 0; r < h; ++r)
            rgb_codes(reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(r) * stride), w,
                      img.data.data() + 3 * static_cast<std::size_t>(r) * static_cast<std::size_t>(w));
        return img;
    }
    // The picture as an RGB Image, each channel code / 255.
    Image image() {
        const Image8 c = codes();
        Image img(c.width, c.height, 3);
        for (std::size_t i = 0; i < c.data.size(); ++i) img.data[i] = static_cast<float>(c.data[i]) / 255.0f;
        return img;
    }

private:
    void set_colour(const Rgb& c) { cairo_set_source_rgb(cr_, c[0], c[1], c[2]); }
    PictureMemory* memory_ = nullptr;
    std::uint32_t* words_ = nullptr;  // the surface's pixels in memory_
    cairo_surface_t* surface_ = nullptr;
    cairo_t* cr_ = nullptr;
};

void fill_rect(Image& img, int x, int y, int w, int h, const Rgb& c) {
    const int r0 = std::max(y, 0), r1 = std::min(y + h, img.height);
    const int c0 = std::max(x, 0), c1 = std::min(x + w, img.width);
    for (int r = r0; r < r1; ++r)
        for (int col = c0; col < c1; ++col)
            for (int k = 0; k < 3; ++k) img.at(r, col, k) = c[static_cast<std::size_t>(k)];
}
// The same in a surface: png_code of each channel, what write_png would store for c, as the
// pixel word 0x00RRGGBB.
std::uint32_t pixel_word(const std::uint8_t code[3]) {
    return static_cast<std::uint32_t>(code[0]) << 16 | static_cast<std::uint32_t>(code[1]) << 8 | code[2];
}
void fill_rect(SurfacePicture& img, int x, int y, int w, int h, const Rgb& c) {
    const std::uint8_t code[3] = {png_code(c[0]), png_code(c[1]), png_code(c[2])};
    const std::uint32_t word = pixel_word(code);
    const int r0 = std::max(y, 0), r1 = std::min(y + h, img.height);
    const int c0 = std::max(x, 0), c1 = std::min(x + w, img.width);
    if (c0 >= c1) return;
    for (int r = r0; r < r1; ++r) std::fill(img.pixels + static_cast<std::size_t>(r) * img.stride + c0,
                                            img.pixels + static_cast<std::size_t>(r) * img.stride + c1, word);
}

// A pixel-crisp position for a 1-pixel line near coordinate v in [0, n]: the middle of the pixel
// v falls in, the pixel left of (above) v in the first half, so that 0 and n land on the frame
// lines just outside the block.
double crisp(double v, int n) { return v <= 0.5 * n ? std::ceil(v) - 0.5 : std::floor(v) + 0.5; }

// Replaces every hyphen-minus by a real minus sign (U+2212).
std::string with_minus_signs(const std::string& s) {
    std::string out;
    for (const char ch : s) {
        if (ch == '-') out += "\xE2\x88\x92";
        else out += ch;
    }
    return out;
}

// The bounding box of boxes (x0, y0, x1, y1).
struct Bounds {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    void add(const Box& b) {
        x0 = std::min(x0, b.x);
        y0 = std::min(y0, b.y);
        x1 = std::max(x1, b.x + b.w);
        y1 = std::max(y1, b.y + b.h);
    }
};

// Ticks over [lo, hi] on an axis `length` pixels long whose labels take extent(label) pixels
// along it (see Plot.h, "axis ticks").
struct AxisTicks {
    std::vector<double> values;
    std::vector<std::string> labels;
};

template <class Extent>
AxisTicks axis_ticks(double lo, double hi, double length, const Extent& extent, bool whole_steps = false) {
    auto position = [&](double v) { return hi > lo ? (v - lo) / (hi - lo) * length : 0.0; };
    auto apart = [&](double a, const std::string& la, double b, const std::string& lb) {
        return std::fabs(position(b) - position(a)) >= (extent(la) + extent(lb)) / 2 + kPlotTickLabelGap;
    };
    AxisTicks t;
    for (int n = static_cast<int>(length) / kPlotTickSpacing + 1; n >= 2; --n) {
        t.values = nice_ticks(lo, hi, n, whole_steps);
        t.labels = tick_labels(t.values);
        bool fits = true;
        for (std::size_t i = 1; i < t.values.size() && fits; ++i)
            fits = apart(t.values[i - 1], t.labels[i - 1], t.values[i], t.labels[i]);
        if (fits || n == 2) {
            if (fits) return t;
            break;
        }
    }
    // Still too close: keep a tick only where its label clears the last kept one.
    AxisTicks kept;
    for (std::size_t i = 0; i < t.values.size(); ++i)
        if (kept.values.empty() || apart(kept.values.back(), kept.labels.back(), t.values[i], t.labels[i])) {
            kept.values.push_back(t.values[i]);
            kept.labels.push_back(t.labels[i]);
        }
    return kept;
}

// Ticks of a plot axis over [lo, hi] (log10 of the values when log): linear, nice_ticks (at most
// 8); logarithmic, the powers of ten inside the range, else 1, 2 and 5 times powers of ten, else
// nice_ticks of the values, each placed at log10 of its value (Plot.h, histogram).
struct AxisValues {
    std::vector<double> ticks, positions;
    std::vector<std::string> labels;
};

AxisValues axis_values(double lo, double hi, bool log) {
    AxisValues a;
    if (log) {
        auto inside = [&](double value) { return std::log10(value) >= lo - 1e-9 && std::log10(value) <= hi + 1e-9; };
        for (const std::vector<double>& steps : {std::vector<double>{1}, std::vector<double>{1, 2, 5}}) {
            a.ticks.clear();
            for (int e = static_cast<int>(std::floor(lo)); e <= static_cast<int>(std::ceil(hi)); ++e)
                for (const double s : steps) {
                    const double t = e >= 0 ? s * std::pow(10.0, e) : s / std::pow(10.0, -e);
                    if (inside(t)) a.ticks.push_back(t);
                }
            if (a.ticks.size() >= 2) break;
        }
        if (a.ticks.size() < 2) a.ticks = nice_ticks(std::pow(10.0, lo), std::pow(10.0, hi), 6);
        for (const double t : a.ticks) {
            a.positions.push_back(std::log10(t));
            a.labels.push_back(with_minus_signs(format_tick(t, 3)));
        }
    } else {
        a.ticks = nice_ticks(lo, hi, 8);
        a.positions = a.ticks;
        a.labels = tick_labels(a.ticks);
    }
    return a;
}

void shift(Label& l, double dx, double dy) {
    l.box.x += dx;
    l.box.y += dy;
}

}  // namespace

// ---- colour map ----

const std::array<Rgb, 256>& viridis_table() { return kViridis; }

Rgb viridis(double t) {
    if (std::isnan(t)) return kNanColour;
    t = std::clamp(t, 0.0, 1.0);
    const double s = 255.0 * t;
    const int i = std::min(static_cast<int>(s), 254);
    const double f = s - i;  // in [0, 1]; exactly 1 only at t = 1
    if (f == 0.0) return kViridis[static_cast<std::size_t>(i)];
    if (f == 1.0) return kViridis[static_cast<std::size_t>(i + 1)];
    Rgb c;
    for (int k = 0; k < 3; ++k) {
        const double a = kViridis[static_cast<std::size_t>(i)][k], b = kViridis[static_cast<std::size_t>(i + 1)][k];
        c[k] = static_cast<float>(a + (b - a) * f);
    }
    return c;
}

// ---- text ----

void require_font(const std::string& path) {
    if (path == kFontFile) {
        font();
        return;
    }
    Font checked(path);
}

double text_width(const std::string& text, double size) { return font().width(text, size); }

int text_height(double size) { return font().line_height(size); }

// ---- ticks ----

std::vector<double> nice_ticks(double lo, double hi, int max_ticks, bool whole_steps) {
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
        throw std::invalid_argument("nice_ticks: the range [" + format_tick(lo, 9) + ", " + format_tick(hi, 9) +
                                    "] must be finite with lo <= hi");
    if (lo == hi) return {lo};
    const int n = std::max(2, max_ticks);
    auto pow10 = [](int e) {
        double p = 1;
        for (int i = 0; i < std::abs(e); ++i) p *= 10;
        return p;
    };
    // step = mantissa * 10^exponent with an integer mantissa (10, 20, 25, 50), so that tick
    // k * step is the integer k * mantissa scaled by an exact power of ten: one rounding.
    struct Step {
        long long mantissa;
        int exponent;
    };
    auto step_value = [&](const Step& s) {
        return s.exponent >= 0 ? s.mantissa * pow10(s.exponent) : s.mantissa / pow10(-s.exponent);
    };
    auto ticks_of = [&](const Step& s) {
        const double step = step_value(s);
        const double k0 = std::ceil(lo / step - 1e-9), k1 = std::floor(hi / step + 1e-9);
        std::vector<double> t;
        for (double k = k0; k <= k1; ++k) {
            const double km = k * static_cast<double>(s.mantissa);
            t.push_back(s.exponent >= 0 ? km * pow10(s.exponent) : km / pow10(-s.exponent));
        }
        return t;
    };
    auto count_of = [&](const Step& s) {
        const double step = step_value(s);
        return std::floor(hi / step + 1e-9) - std::ceil(lo / step - 1e-9) + 1;
    };
    // Start well below the spacing n ticks need (more than n ticks there) and grow.
    int e = static_cast<int>(std::floor(std::log10((hi - lo) / n))) - 2;
    Step previous{0, 0};
    for (;; ++e) {
        for (const long long m : {10LL, 20LL, 25LL, 50LL}) {
            const Step s{m, e};
            if (whole_steps && (e < -1 || (e == -1 && m == 25))) continue;  // steps below 1, and 2.5
            const double count = count_of(s);
            if (count <= n) return count >= 2 || previous.mantissa == 0 ? ticks_of(s) : ticks_of(previous);
            previous = s;
        }
    }
}

std::vector<std::string> tick_labels(const std::vector<double>& ticks) {
    std::vector<std::string> out;
    if (ticks.empty()) return out;
    double largest = 0, step = 0;
    for (const double t : ticks) largest = std::max(largest, std::fabs(t));
    if (ticks.size() > 1) step = std::fabs(ticks[1] - ticks[0]);
    char buf[64];
    if (largest >= 1e6 || (step > 0 && step < 1e-4)) {
        for (int digits = 1; digits <= 17; ++digits) {
            out.clear();
            for (const double t : ticks) out.push_back(format_tick(t, digits));
            bool distinct = true;
            for (std::size_t i = 1; i < out.size(); ++i) distinct = distinct && out[i] != out[i - 1];
            if (distinct) break;
        }
    } else {
        int decimals = 0;
        for (; decimals < 12; ++decimals) {
            const double scale = std::pow(10.0, decimals);
            bool exact = true;
            for (const double t : ticks) exact = exact && std::fabs(t * scale - std::round(t * scale)) < 1e-6;
            if (exact) break;
        }
        for (const double t : ticks) {
            std::snprintf(buf, sizeof buf, "%.*f", decimals, t == 0 ? 0.0 : t);
            out.emplace_back(buf);
        }
    }
    for (auto& s : out) s = with_minus_signs(s);
    return out;
}

std::string format_tick(double value, int significant_digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", std::clamp(significant_digits, 1, 17), value);
    std::string s = buf;
    const auto e = s.find('e');
    if (e == std::string::npos) return s;
    std::string mantissa = s.substr(0, e), exponent = s.substr(e + 1);
    std::string sign;
    if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) {
        if (exponent[0] == '-') sign = "-";
        exponent.erase(0, 1);
    }
    while (exponent.size() > 1 && exponent[0] == '0') exponent.erase(0, 1);
    return mantissa + "e" + sign + exponent;
}

// ---- pseudo colour ----

bool ImageExtent::known() const { return std::isfinite(width) && std::isfinite(height) && width > 0 && height > 0; }

std::pair<double, double> colour_range(const std::vector<float>& values, double lo, double hi) {
    if (std::isinf(lo) || std::isinf(hi)) throw std::invalid_argument("colour range: lo and hi must be finite or NaN");
    if (std::isnan(lo) || std::isnan(hi)) {
        // In float, branch-free (the smallest and largest float are the same numbers as doubles):
        // four running minima and maxima in SSE lanes (x86-64's baseline); a NaN or an infinity
        // stands in as +inf for the minimum and -inf for the maximum. A preview of 10^6 pixels
        // scans them all, which a scalar loop makes a tenth of the industrial scene's preview time.
        constexpr float kBig = std::numeric_limits<float>::max(), kInf = std::numeric_limits<float>::infinity();
        const std::size_t n = values.size(), whole = n - n % 4;
        const float* const p = values.data();
        const __m128 big = _mm_set1_ps(kBig), inf = _mm_set1_ps(kInf), minus_inf = _mm_set1_ps(-kInf);
        const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
        __m128 lane_mn = inf, lane_mx = minus_inf;
        for (std::size_t i = 0; i < whole; i += 4) {
            const __m128 v = _mm_loadu_ps(p + i);
            const __m128 finite = _mm_cmple_ps(_mm_and_ps(v, magnitude), big);  // false for NaN, +-inf
            lane_mn = _mm_min_ps(lane_mn, _mm_or_ps(_mm_and_ps(finite, v), _mm_andnot_ps(finite, inf)));
            lane_mx = _mm_max_ps(lane_mx, _mm_or_ps(_mm_and_ps(finite, v), _mm_andnot_ps(finite, minus_inf)));
        }
        float mns[4], mxs[4];
        _mm_storeu_ps(mns, lane_mn);
        _mm_storeu_ps(mxs, lane_mx);
        float fmn = std::min({mns[0], mns[1], mns[2], mns[3]}), fmx = std::max({mxs[0], mxs[1], mxs[2], mxs[3]});
        for (std::size_t i = whole; i < n; ++i)
            if (std::fabs(p[i]) <= kBig) fmn = std::min(fmn, p[i]), fmx = std::max(fmx, p[i]);
        double mn = fmn, mx = fmx;
        if (mn > mx) mn = 0, mx = 1;  // no finite value
        if (std::isnan(lo)) lo = mn;
        if (std::isnan(hi)) hi = mx;
    }
    if (lo > hi)
        throw std::invalid_argument("colour range: lo " + format_tick(lo, 9) + " > hi " + format_tick(hi, 9));
    if (lo == hi) lo -= 0.5, hi += 0.5;
    return {lo, hi};
}

namespace {
// Whether v is a whole number, or NaN or +-inf, without a call to floor (x86-64's baseline has
// no rounding instruction): a float of magnitude 2^23 or more is whole, and a smaller one is
// whole exactly when truncating it to an integer gives it back.
bool whole_or_not_finite(float v) {
    const float a = std::fabs(v);
    return !(a <= std::numeric_limits<float>::max()) || a >= 0x1p23f || static_cast<float>(static_cast<std::int32_t>(v)) == v;
}
}  // namespace

PseudoColourLayout pseudo_colour_layout(const std::vector<float>& values, int width, int height,
                                        const std::string& title, double lo, double hi, int pixel_scale,
                                        const ImageExtent& extent) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("pseudo_colour: image size " + std::to_string(width) + " x " +
                                    std::to_string(height) + " must be at least 1 x 1");
    if (values.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
        throw std::invalid_argument("pseudo_colour: " + std::to_string(values.size()) + " values for a " +
                                    std::to_string(width) + " x " + std::to_string(height) + " image");
    if (pixel_scale < 1) throw std::invalid_argument("pseudo_colour: pixel_scale must be >= 1, got " + std::to_string(pixel_scale));
    constexpr long long kMaxSide = 1 << 15;
    if (static_cast<long long>(width) * pixel_scale > kMaxSide || static_cast<long long>(height) * pixel_scale > kMaxSide)
        throw std::invalid_argument("pseudo_colour: the scaled image would exceed " + std::to_string(kMaxSide) + " pixels a side");

    PseudoColourLayout L;
    std::tie(L.lo, L.hi) = colour_range(values, lo, hi);
    Canvas meter(1, 1);
    const int th = meter.line(kTickFontSize).second;
    const int out = 1 + kPlotTickLength + kPlotTickLabelGap;  // from a block's edge to its tick labels

    // Everything relative to the image's top-left corner first; shifted into place at the end.
    L.image_w = width * pixel_scale;
    L.image_h = height * pixel_scale;
    L.bar_w = kPlotBarWidth;
    L.bar_h = std::max(L.image_h, kPlotMinBarHeight);
    L.bar_x = L.image_w + kPlotBarGap;
    Bounds bounds;
    bounds.add({-1.0, -1.0, L.image_w + 2.0, L.image_h + 2.0});
    bounds.add({L.bar_x - 1.0, -1.0, L.bar_w + 2.0, L.bar_h + 2.0});

    const auto along_y = [&](const std::string&) { return static_cast<double>(th); };
    const auto along_x = [&](const std::string& s) { return meter.width_of(s, kTickFontSize); };
    {
        // Whole numbers only (counts, indices, a mask) get whole-number ticks.
        bool whole = std::floor(L.lo) == L.lo && std::floor(L.hi) == L.hi;
        for (std::size_t k = 0; k < values.size() && whole; ++k) whole = whole_or_not_finite(values[k]);
        AxisTicks bar = axis_ticks(L.lo, L.hi, L.bar_h - 1.0, along_y, whole);
        L.tick_values = std::move(bar.values);
        L.tick_labels = std::move(bar.labels);
    }
    for (std::size_t i = 0; i < L.tick_values.size(); ++i) {
        const double row = (L.hi - L.tick_values[i]) / (L.hi - L.lo) * (L.bar_h - 1) + 0.5;
        L.tick_rows.push_back(row);
        Label l = meter.label(L.tick_labels[i], kTickFontSize);
        l.box.x = L.bar_x + L.bar_w + out;
        l.box.y = row - th / 2.0;
        L.labels.push_back(l);
    }

    if (extent.known()) {
        AxisTicks xt = axis_ticks(-extent.width / 2, extent.width / 2, L.image_w, along_x);
        AxisTicks yt = axis_ticks(-extent.height / 2, extent.height / 2, L.image_h, along_y);
        L.x_ticks = xt.values;
        L.y_ticks = yt.values;
        const auto& xl = xt.labels;
        const auto& yl = yt.labels;
        double below = L.image_h + out + th;  // the bottom of the x tick labels
        for (std::size_t i = 0; i < L.x_ticks.size(); ++i) {
            const double col = (L.x_ticks[i] + extent.width / 2) / extent.width * L.image_w;
            L.x_tick_columns.push_back(col);
            Label l = meter.label(xl[i], kTickFontSize);
            l.box.x = col - l.box.w / 2;
            l.box.y = L.image_h + out;
            L.labels.push_back(l);
        }
        double left = -out;  // the left edge of the y tick labels
        for (std::size_t i = 0; i < L.y_ticks.size(); ++i) {
            const double row = (extent.height / 2 - L.y_ticks[i]) / extent.height * L.image_h;
            L.y_tick_rows.push_back(row);
            Label l = meter.label(yl[i], kTickFontSize);
            l.box.x = -out - l.box.w;
            l.box.y = row - th / 2.0;
            left = std::min(left, l.box.x);
            L.labels.push_back(l);
        }
        Label x = meter.label("x (mm)", kLabelFontSize);
        x.box.x = L.image_w / 2.0 - x.box.w / 2;
        x.box.y = below + kPlotAxisLabelGap;
        L.labels.push_back(x);
        Label y = meter.label("y (mm)", kLabelFontSize, true);
        y.box.x = left - kPlotAxisLabelGap - y.box.w;
        y.box.y = L.image_h / 2.0 - y.box.h / 2;
        L.labels.push_back(y);
    }
    if (!title.empty()) {
        double top = -1;  // above the frame and every other label
        for (const Label& l : L.labels) top = std::min(top, l.box.y);
        Label t = meter.label(title, kTitleFontSize);
        t.box.x = L.image_w / 2.0 - t.box.w / 2;
        t.box.y = top - kPlotTitleGap - t.box.h;
        L.labels.push_back(t);
    }

    for (const Label& l : L.labels) bounds.add(l.box);
    const int dx = kPlotMargin - static_cast<int>(std::floor(bounds.x0));
    const int dy = kPlotMargin - static_cast<int>(std::floor(bounds.y0));
    L.width = static_cast<int>(std::ceil(bounds.x1)) + dx + kPlotMargin;
    L.height = static_cast<int>(std::ceil(bounds.y1)) + dy + kPlotMargin;
    L.image_x = dx;
    L.image_y = dy;
    L.bar_x += dx;
    L.bar_y = dy;
    for (auto& r : L.tick_rows) r += dy;
    for (auto& c : L.x_tick_columns) c += dx;
    for (auto& r : L.y_tick_rows) r += dy;
    for (auto& l : L.labels) shift(l, dx, dy);
    return L;
}

namespace {

// The data cells of pseudo_colour's picture: cell (m, n) is the pixel_scale x pixel_scale block at
// (image_x + n * pixel_scale, image_y + m * pixel_scale) in viridis((v - lo) / (hi - lo)); NaN
// stays NaN (kNanColour) and +-inf clamp to the ends.
void paint_cells(Image& img, const std::vector<float>& values, int width, int height, const PseudoColourLayout& L,
                 int pixel_scale) {
    const double range = L.hi - L.lo;
    for (int m = 0; m < height; ++m)
        for (int n = 0; n < width; ++n) {
            const double v = values[static_cast<std::size_t>(m) * static_cast<std::size_t>(width) + static_cast<std::size_t>(n)];
            fill_rect(img, L.image_x + n * pixel_scale, L.image_y + m * pixel_scale, pixel_scale, pixel_scale,
                      viridis((v - L.lo) / range));
        }
}

// viridis and png_code inlined, the same arithmetic, as one pixel word (pixel_word): t clamped,
// s = 255 t, entry i = min(floor s, 254), f = s - i, each channel float(a + (b - a) f) of entries
// i and i + 1 in double, then rounded to its code. (viridis returns entry i itself at f = 0 and
// entry i + 1 at f = 1: the formula gives the same floats there, since b - a and a + (b - a) are
// exact in double for floats in [0, 1].) t is not NaN.
struct ViridisEntry {
    double a[3], d[3];
};
const std::array<ViridisEntry, 255>& viridis_entries() {
    static const std::array<ViridisEntry, 255> entries = [] {
        std::array<ViridisEntry, 255> e{};
        for (std::size_t i = 0; i < 255; ++i)
            for (std::size_t k = 0; k < 3; ++k) {
                e[i].a[k] = kViridis[i][k];
                e[i].d[k] = static_cast<double>(kViridis[i + 1][k]) - static_cast<double>(kViridis[i][k]);
            }
        return e;
    }();
    return entries;
}
int viridis_entry(double t) { return std::min(static_cast<int>(255.0 * t), 254); }  // t in [0, 1]
std::uint32_t viridis_word(double t) {
    t = std::clamp(t, 0.0, 1.0);
    const double s = 255.0 * t;
    const int i = viridis_entry(t);
    const double f = s - i;
    const ViridisEntry& e = viridis_entries()[static_cast<std::size_t>(i)];
    std::uint8_t code[3];
    for (int k = 0; k < 3; ++k) code[k] = png_code(static_cast<float>(e.a[k] + e.d[k] * f));
    return pixel_word(code);
}

// viridis_word through a table of K = 2^14 buckets of t, for pictures of kPreviewTableCells cells
// or more (the industrial scene's previews: 10^6 cells each, whose words computed one by one take
// half of their time;
// building the table costs 2 (K + 1) words, a third of a millisecond, once per process).
//
// Why it is exact: bucket b holds every t in [b / K, (b + 1) / K) (t K is exact, K being a power
// of two, so b = floor(t K)), and each step of viridis_word is monotone in t while the entry i
// stays the same: s = 255 t and floor are, f = s - i is, d f and a + d f are (rounding keeps order,
// increasing for d >= 0, decreasing for d < 0), and so are the float conversion and png_code. So
// when both ends of a bucket, b / K and the largest double below (b + 1) / K, have the same entry
// and the same codes, every t between has them: the bucket holds that word. Otherwise (921 of the
// 16384 buckets, where a code or the entry changes) it holds kExact and the cell is computed.
// t = 1 has a bucket of its own. tests/features_plot.cpp checks both ends of every bucket.
class ViridisTable {
public:
    static constexpr int kBuckets = 1 << 14;
    static constexpr std::uint32_t kExact = 0xFFFFFFFFu;  // pixel words have a zero top byte

    ViridisTable() {
        for (int b = 0; b < kBuckets; ++b) {
            const double t0 = static_cast<double>(b) / kBuckets;
            const double t1 = std::nextafter(static_cast<double>(b + 1) / kBuckets, 0.0);
            const std::uint32_t w0 = viridis_word(t0), w1 = viridis_word(t1);
            words_[static_cast<std::size_t>(b)] = viridis_entry(t0) == viridis_entry(t1) && w0 == w1 ? w0 : kExact;
        }
        words_[kBuckets] = viridis_word(1.0);
    }
    // viridis_word(t) for t in [0, 1].
    std::uint32_t word(double t) const {
        const std::uint32_t w = words_[static_cast<std::size_t>(t * kBuckets)];
        return w != kExact ? w : viridis_word(t);
    }

private:
    std::array<std::uint32_t, kBuckets + 1> words_;
};

// The same cells in code values, the same codes as fill_rect's, computed row by row: a cell's code
// once (and once for a run of equal values: feature maps hold long runs of counts and zeros), put
// pixel_scale times across, and the finished pixel row copied pixel_scale - 1 times down. Cell by
// cell through fill_rect (one fill_rect and one viridis a pixel) the cells would take half of the
// industrial scene's preview time (perf: 17 previews of 1000 x 1000 cells).
void paint_cells(SurfacePicture& img, const std::vector<float>& values, int width, int height, const PseudoColourLayout& L,
                 int pixel_scale) {
    if (L.image_x < 0 || L.image_y < 0 || L.image_x + width * pixel_scale > img.width ||
        L.image_y + height * pixel_scale > img.height)
        throw std::logic_error("pseudo_colour: the image block lies outside its picture");
    const std::uint8_t nan_code[3] = {png_code(kNanColour[0]), png_code(kNanColour[1]), png_code(kNanColour[2])};
    const std::uint32_t nan_word = pixel_word(nan_code);
    const ViridisTable* table = nullptr;
    if (static_cast<std::int64_t>(width) * height >= kPreviewTableCells) {
        static const ViridisTable shared;
        table = &shared;
    }
    const double range = L.hi - L.lo;
    const auto word_of = [&](double t) {
        if (std::isnan(t)) return nan_word;  // NaN is kNanColour
        return table ? table->word(std::clamp(t, 0.0, 1.0)) : viridis_word(t);
    };
    const std::size_t row_bytes = sizeof(std::uint32_t) * static_cast<std::size_t>(width) * pixel_scale;
    for (int m = 0; m < height; ++m) {
        std::uint32_t* const row = img.pixels + static_cast<std::size_t>(L.image_y + m * pixel_scale) * img.stride +
                                   static_cast<std::size_t>(L.image_x);
        const float* const v = values.data() + static_cast<std::size_t>(m) * static_cast<std::size_t>(width);
        std::uint32_t word = 0;
        std::uint32_t* out = row;
        for (int n = 0; n < width; ++n) {
            // Equal bits, equal colour (NaN included, whose colour does not depend on its bits).
            if (n == 0 || std::memcmp(&v[n], &v[n - 1], sizeof(float)) != 0) word = word_of((v[n] - L.lo) / range);
            for (int s = 0; s < pixel_scale; ++s) *out++ = word;
        }
        for (int s = 1; s < pixel_scale; ++s) std::memcpy(row + static_cast<std::size_t>(s) * img.stride, row, row_bytes);
    }
}

// pseudo_colour's picture as a float Image or, for a PNG, straight in code values in the Canvas's
// surface (SurfacePicture, which needs `memory`): the same drawing, the same pixels (fill_rect
// and paint_cells store png_code of the colour that the Image holds).
template <class Picture>
Picture draw_pseudo_colour(const std::vector<float>& values, int width, int height, const std::string& title,
                           double lo, double hi, int pixel_scale, const ImageExtent& extent,
                           PictureMemory* memory = nullptr) {
    const PseudoColourLayout L = pseudo_colour_layout(values, width, height, title, lo, hi, pixel_scale, extent);
    Canvas canvas(L.width, L.height, memory);
    canvas.frame(L.image_x, L.image_y, L.image_w, L.image_h, kFrameColour);
    canvas.frame(L.bar_x, L.bar_y, L.bar_w, L.bar_h, kFrameColour);
    const double bar_right = L.bar_x + L.bar_w + 1;
    for (const double row : L.tick_rows) {
        const double y = crisp(row - L.bar_y, L.bar_h) + L.bar_y;
        canvas.segment(bar_right, y, bar_right + kPlotTickLength, y, kFrameColour);
    }
    const double image_bottom = L.image_y + L.image_h + 1, image_left = L.image_x - 1;
    for (const double col : L.x_tick_columns) {
        const double x = crisp(col - L.image_x, L.image_w) + L.image_x;
        canvas.segment(x, image_bottom, x, image_bottom + kPlotTickLength, kFrameColour);
    }
    for (const double row : L.y_tick_rows) {
        const double y = crisp(row - L.image_y, L.image_h) + L.image_y;
        canvas.segment(image_left, y, image_left - kPlotTickLength, y, kFrameColour);
    }
    for (const Label& l : L.labels) canvas.draw(l);
    Picture img;
    if constexpr (std::is_same_v<Picture, SurfacePicture>)
        img = canvas.surface_picture();  // the surface lives on in `memory` after the Canvas
    else
        img = canvas.image();

    // The data and the colour bar, exact: written into the picture, not drawn.
    paint_cells(img, values, width, height, L, pixel_scale);
    for (int r = 0; r < L.bar_h; ++r)
        fill_rect(img, L.bar_x, L.bar_y + r, L.bar_w, 1, viridis(1.0 - static_cast<double>(r) / (L.bar_h - 1)));
    return img;
}

}  // namespace

namespace {

// The rings of pseudo_colour (Plot.h, Ring), written into the picture over the data cells.
void paint_rings(Image& img, const PseudoColourLayout& L, int pixel_scale, const std::vector<Ring>& rings) {
    for (const Ring& ring : rings) {
        const double X = L.image_x + ring.x * pixel_scale, Y = L.image_y + ring.y * pixel_scale;
        const double R = ring.radius * pixel_scale;
        const int r0 = std::max(L.image_y, static_cast<int>(std::floor(Y - R - 3))),
                  r1 = std::min(L.image_y + L.image_h, static_cast<int>(std::ceil(Y + R + 3)));
        const int c0 = std::max(L.image_x, static_cast<int>(std::floor(X - R - 3))),
                  c1 = std::min(L.image_x + L.image_w, static_cast<int>(std::ceil(X + R + 3)));
        for (int i = r0; i < r1; ++i)
            for (int j = c0; j < c1; ++j) {
                const double off = std::fabs(std::hypot(j + 0.5 - X, i + 0.5 - Y) - R);
                if (off <= 1.0) fill_rect(img, j, i, 1, 1, kWhite);
                else if (off <= 2.0) fill_rect(img, j, i, 1, 1, kBlack);
            }
    }
}

}  // namespace

Image pseudo_colour(const std::vector<float>& values, int width, int height, const std::string& title,
                    double lo, double hi, int pixel_scale, const ImageExtent& extent, const std::vector<Ring>& rings) {
    Image img = draw_pseudo_colour<Image>(values, width, height, title, lo, hi, pixel_scale, extent);
    if (!rings.empty())
        paint_rings(img, pseudo_colour_layout(values, width, height, title, lo, hi, pixel_scale, extent), pixel_scale, rings);
    return img;
}

void write_pseudo_colour_png(const std::string& path, const std::vector<float>& values, int width, int height,
                             const std::string& title, double lo, double hi, int pixel_scale,
                             const ImageExtent& extent, io::CommitGroup* group) {
    thread_local PictureMemory memory;  // kept by the thread for its next preview
    const SurfacePicture picture =
        draw_pseudo_colour<SurfacePicture>(values, width, height, title, lo, hi, pixel_scale, extent, &memory);
    write_png_rows(path, picture.width, picture.height, 3, [&](int r, std::uint8_t* out) {
        png_row_codes(picture.pixels + static_cast<std::size_t>(r) * picture.stride, picture.width, out);
    }, group);

}

// ---- montage ----

Image montage(const std::vector<std::vector<Image>>& cells, const std::vector<std::string>& row_labels,
              const std::vector<std::string>& column_labels, const std::string& title) {
    const int rows = static_cast<int>(cells.size());
    int columns = 0;
    for (const auto& row : cells) columns = std::max(columns, static_cast<int>(row.size()));
    if (rows == 0 || columns == 0) throw std::invalid_argument("montage: no cells");
    if (!row_labels.empty() && static_cast<int>(row_labels.size()) != rows)
        throw std::invalid_argument("montage: " + std::to_string(row_labels.size()) + " row labels for " +
                                    std::to_string(rows) + " rows");
    if (!column_labels.empty() && static_cast<int>(column_labels.size()) != columns)
        throw std::invalid_argument("montage: " + std::to_string(column_labels.size()) + " column labels for " +
                                    std::to_string(columns) + " columns");
    int cw = 0, ch = 0;
    for (const auto& row : cells)
        for (const Image& c : row) {
            if (c.width > 0 && c.height > 0 && c.channels != 1 && c.channels != 3)
                throw std::invalid_argument("montage: cells must have 1 or 3 channels, got " + std::to_string(c.channels));
            if (c.width > 0 && c.height > 0) cw = std::max(cw, c.width), ch = std::max(ch, c.height);
        }

    Canvas meter(1, 1);
    const int M = kPlotMargin, lh = meter.line(kLabelFontSize).second;
    int sw = cw, sh = ch;
    for (const auto& s : column_labels) sw = std::max(sw, static_cast<int>(std::ceil(meter.width_of(s, kLabelFontSize))));
    for (const auto& s : row_labels) sh = std::max(sh, static_cast<int>(std::ceil(meter.width_of(s, kLabelFontSize))));
    const int T = title.empty() ? 0 : meter.line(kTitleFontSize).second + kMontageLabelGap;
    const int C = column_labels.empty() ? 0 : lh + kMontageColumnGap;
    const int R = row_labels.empty() ? 0 : lh + kMontageLabelGap;
    const int title_w = static_cast<int>(std::ceil(meter.width_of(title, kTitleFontSize)));
    const int W = std::max(M + R + columns * sw + (columns - 1) * kMontageGap + M, M + title_w + M);
    const int H = M + T + C + rows * sh + (rows - 1) * kMontageGap + M;

    Canvas canvas(W, H);
    const int x0 = M + R, y0 = M + T + C;
    for (int c = 0; c < static_cast<int>(column_labels.size()); ++c) {
        Label l = meter.label(column_labels[static_cast<std::size_t>(c)], kLabelFontSize);
        l.box.x = x0 + c * (sw + kMontageGap) + (sw - l.box.w) / 2;
        l.box.y = M + T;
        canvas.draw(l);
    }
    for (int r = 0; r < static_cast<int>(row_labels.size()); ++r) {
        Label l = meter.label(row_labels[static_cast<std::size_t>(r)], kLabelFontSize, true);
        l.box.x = M;
        l.box.y = y0 + r * (sh + kMontageGap) + (sh - l.box.h) / 2;
        canvas.draw(l);
    }
    if (!title.empty()) {
        Label l = meter.label(title, kTitleFontSize);
        l.box.x = (W - l.box.w) / 2;
        l.box.y = M;
        canvas.draw(l);
    }
    Image img = canvas.image();

    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < static_cast<int>(cells[static_cast<std::size_t>(r)].size()); ++c) {
            const Image& cell = cells[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
            if (cell.width <= 0 || cell.height <= 0) continue;
            const int cx = x0 + c * (sw + kMontageGap) + (sw - cell.width) / 2;
            const int cy = y0 + r * (sh + kMontageGap) + (sh - cell.height) / 2;
            for (int i = 0; i < cell.height; ++i)
                for (int j = 0; j < cell.width; ++j) {
                    Rgb px;
                    bool nan = false;
                    for (int k = 0; k < 3; ++k) {
                        px[static_cast<std::size_t>(k)] = cell.at(i, j, cell.channels == 1 ? 0 : k);
                        nan = nan || std::isnan(px[static_cast<std::size_t>(k)]);
                    }
                    fill_rect(img, cx + j, cy + i, 1, 1, nan ? kNanColour : px);
                }
        }
    return img;
}

// ---- histogram ----

HistogramLayout histogram_layout(const std::vector<double>& values, int bins, const std::string& title,
                                 const std::string& x_label, bool log_x, const std::string& y_label) {
    if (bins < 1) throw std::invalid_argument("histogram: bins must be >= 1");
    HistogramLayout L;
    std::vector<double> v;
    for (double x : values)
        if (std::isfinite(x) && (!log_x || x > 0)) v.push_back(log_x ? std::log10(x) : x);
    L.lo = v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
    L.hi = v.empty() ? 1.0 : *std::max_element(v.begin(), v.end());
    if (v.empty()) {
        bins = 1;
    } else if (!(L.hi > L.lo)) {
        L.lo -= 0.5;
        L.hi += 0.5;
        bins = 1;
    }
    L.counts.assign(static_cast<std::size_t>(bins), 0);
    for (double x : v)
        ++L.counts[static_cast<std::size_t>(std::min(bins - 1, static_cast<int>((x - L.lo) / (L.hi - L.lo) * bins)))];
    const long peak = *std::max_element(L.counts.begin(), L.counts.end());

    Canvas meter(1, 1);
    const int M = kPlotMargin, th = meter.line(kTickFontSize).second, lh = meter.line(kLabelFontSize).second;
    const int out = 1 + kPlotTickLength + kPlotTickLabelGap;

    // y: counts 0 .. y_max, whole numbers.
    L.y_ticks = nice_ticks(0, static_cast<double>(std::max(1L, peak)), 8, true);
    if (L.y_ticks.back() < peak) L.y_ticks.push_back(L.y_ticks.back() + (L.y_ticks[1] - L.y_ticks[0]));
    L.y_max = L.y_ticks.back();

    // x: the ticks' values, and where they sit in the (log10) range.
    const AxisValues ax = axis_values(L.lo, L.hi, log_x);
    L.x_ticks = ax.ticks;
    const std::vector<double>& positions = ax.positions;
    const std::vector<std::string>& x_text = ax.labels;
    const std::vector<std::string> y_text = tick_labels(L.y_ticks);

    double y_label_w = 0, x_label_w = 0;
    for (const auto& s : y_text) y_label_w = std::max(y_label_w, meter.width_of(s, kTickFontSize));
    for (const auto& s : x_text) x_label_w = std::max(x_label_w, meter.width_of(s, kTickFontSize));
    Label t = meter.label(title, kTitleFontSize);
    const double plot_left = M + lh + kPlotAxisLabelGap + std::ceil(y_label_w) + out;
    const double plot_right = L.width - M - std::ceil(x_label_w / 2);
    const double plot_top = M + t.box.h + kPlotTitleGap + std::ceil(th / 2.0);
    const double plot_bottom = L.height - M - lh - kPlotAxisLabelGap - th - out;
    L.plot = {plot_left, plot_top, plot_right - plot_left, plot_bottom - plot_top};

    t.box.x = (L.width - t.box.w) / 2;
    t.box.y = M;
    L.labels.push_back(t);
    for (std::size_t i = 0; i < L.x_ticks.size(); ++i) {
        const double col = L.plot.x + (positions[i] - L.lo) / (L.hi - L.lo) * L.plot.w;
        L.x_tick_columns.push_back(col);
        Label l = meter.label(x_text[i], kTickFontSize);
        l.box.x = col - l.box.w / 2;
        l.box.y = plot_bottom + out;
        L.labels.push_back(l);
    }
    for (std::size_t i = 0; i < L.y_ticks.size(); ++i) {
        const double row = plot_bottom - L.y_ticks[i] / L.y_max * L.plot.h;
        L.y_tick_rows.push_back(row);
        Label l = meter.label(y_text[i], kTickFontSize);
        l.box.x = plot_left - out - l.box.w;
        l.box.y = row - th / 2.0;
        L.labels.push_back(l);
    }
    Label xl = meter.label(x_label, kLabelFontSize);
    xl.box.x = L.plot.x + L.plot.w / 2 - xl.box.w / 2;
    xl.box.y = plot_bottom + out + th + kPlotAxisLabelGap;
    L.labels.push_back(xl);
    Label yl = meter.label(y_label, kLabelFontSize, true);
    yl.box.x = M;
    yl.box.y = L.plot.y + L.plot.h / 2 - yl.box.h / 2;
    L.labels.push_back(yl);

    const double bw = L.plot.w / bins;
    for (int b = 0; b < bins; ++b) {
        const double h = static_cast<double>(L.counts[static_cast<std::size_t>(b)]) / L.y_max * L.plot.h;
        L.bars.push_back({L.plot.x + b * bw, plot_bottom - h, bw, h});
    }
    return L;
}

Image histogram(const std::vector<double>& values, int bins, const std::string& title, const std::string& x_label,
                bool log_x, const std::string& y_label) {
    const HistogramLayout L = histogram_layout(values, bins, title, x_label, log_x, y_label);
    Canvas canvas(L.width, L.height);
    const Rgb bar = viridis(0.4);
    for (const Box& b : L.bars)
        if (b.h > 0) canvas.fill({b.x + 0.5, b.y, b.w - 1.0, b.h}, bar);  // a pixel of white between bars
    const double left = std::floor(L.plot.x) - 0.5, bottom = std::ceil(L.plot.y + L.plot.h) + 0.5;
    canvas.segment(left, bottom, L.plot.x + L.plot.w, bottom, kFrameColour);  // x axis
    canvas.segment(left, bottom, left, L.plot.y, kFrameColour);               // y axis
    for (const double col : L.x_tick_columns) {
        const double x = std::floor(col) + 0.5;
        canvas.segment(x, bottom, x, bottom + kPlotTickLength, kFrameColour);
    }
    for (const double row : L.y_tick_rows) {
        const double y = std::floor(row) + 0.5;
        canvas.segment(left, y, left - kPlotTickLength, y, kFrameColour);
    }
    for (const Label& l : L.labels) canvas.draw(l);
    return canvas.image();
}


// ---- line plot ----

Rgb series_colour(int i, int n) { return viridis(n > 1 ? 0.85 * i / (n - 1) : 0.0); }

Image line_plot(const std::vector<Series>& series, const std::string& title, const std::string& x_label,
                const std::string& y_label, bool log_x, bool log_y) {
    auto drawable = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && (!log_x || x > 0) && (!log_y || y > 0);
    };
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (const Series& s : series) {
        if (s.x.size() != s.y.size()) throw std::invalid_argument("line_plot: series '" + s.name + "' has x and y of different lengths");
        for (std::size_t i = 0; i < s.x.size(); ++i)
            if (drawable(s.x[i], s.y[i])) {
                const double x = log_x ? std::log10(s.x[i]) : s.x[i], y = log_y ? std::log10(s.y[i]) : s.y[i];
                xlo = std::min(xlo, x);
                xhi = std::max(xhi, x);
                ylo = std::min(ylo, y);
                yhi = std::max(yhi, y);
            }
    }
    if (!(xhi >= xlo)) xlo = 0, xhi = 1;
    if (!(yhi >= ylo)) ylo = 0, yhi = 1;
    if (!(xhi > xlo)) xlo -= 0.5, xhi += 0.5;
    if (!(yhi > ylo)) ylo -= 0.5, yhi += 0.5;
    const AxisValues ax = axis_values(xlo, xhi, log_x), ay = axis_values(ylo, yhi, log_y);

    Canvas canvas(kLinePlotWidth, kLinePlotHeight);
    const int M = kPlotMargin, th = canvas.line(kTickFontSize).second, lh = canvas.line(kLabelFontSize).second;
    const int out = 1 + kPlotTickLength + kPlotTickLabelGap;
    double y_label_w = 0, legend_w = 0;
    for (const auto& s : ay.labels) y_label_w = std::max(y_label_w, canvas.width_of(s, kTickFontSize));
    for (const Series& s : series) legend_w = std::max(legend_w, canvas.width_of(s.name, kTickFontSize));
    legend_w += kLegendSample + kLegendGap;
    Label t = canvas.label(title, kTitleFontSize);
    const double left = M + lh + kPlotAxisLabelGap + std::ceil(y_label_w) + out;
    const double right = kLinePlotWidth - M - std::ceil(legend_w) - 2 * kLegendGap;
    const double top = M + t.box.h + kPlotTitleGap + std::ceil(th / 2.0);
    const double bottom = kLinePlotHeight - M - lh - kPlotAxisLabelGap - th - out;
    auto col = [&](double v) { return left + (v - xlo) / (xhi - xlo) * (right - left); };
    auto row = [&](double v) { return bottom - (v - ylo) / (yhi - ylo) * (bottom - top); };

    t.box.x = (kLinePlotWidth - t.box.w) / 2;
    t.box.y = M;
    canvas.draw(t);
    const double ax0 = std::floor(left) - 0.5, ay0 = std::ceil(bottom) + 0.5;
    canvas.segment(ax0, ay0, right, ay0, kFrameColour);
    canvas.segment(ax0, ay0, ax0, top, kFrameColour);
    for (std::size_t i = 0; i < ax.ticks.size(); ++i) {
        const double x = std::floor(col(ax.positions[i])) + 0.5;
        canvas.segment(x, ay0, x, ay0 + kPlotTickLength, kFrameColour);
        Label l = canvas.label(ax.labels[i], kTickFontSize);
        l.box.x = x - l.box.w / 2;
        l.box.y = bottom + out;
        canvas.draw(l);
    }
    for (std::size_t i = 0; i < ay.ticks.size(); ++i) {
        const double y = std::floor(row(ay.positions[i])) + 0.5;
        canvas.segment(ax0, y, ax0 - kPlotTickLength, y, kFrameColour);
        Label l = canvas.label(ay.labels[i], kTickFontSize);
        l.box.x = left - out - l.box.w;
        l.box.y = y - th / 2.0;
        canvas.draw(l);
    }
    Label xl = canvas.label(x_label, kLabelFontSize);
    xl.box.x = (left + right) / 2 - xl.box.w / 2;
    xl.box.y = bottom + out + th + kPlotAxisLabelGap;
    canvas.draw(xl);
    Label yl = canvas.label(y_label, kLabelFontSize, true);
    yl.box.x = M;
    yl.box.y = (top + bottom) / 2 - yl.box.h / 2;
    canvas.draw(yl);

    for (std::size_t si = 0; si < series.size(); ++si) {
        const Series& s = series[si];
        const int style = s.dashed ? 1 : s.dotted ? 2 : 0;
        bool pen = false;
        double px = 0, py = 0;
        for (std::size_t i = 0; i < s.x.size(); ++i) {
            if (!drawable(s.x[i], s.y[i])) {
                pen = false;
                continue;
            }
            const double x = col(log_x ? std::log10(s.x[i]) : s.x[i]), y = row(log_y ? std::log10(s.y[i]) : s.y[i]);
            if (pen) canvas.segment(px, py, x, y, s.colour, style);
            canvas.fill({x - 1.5, y - 1.5, 3, 3}, s.colour);
            pen = true;
            px = x;
            py = y;
        }
        const double ly = top + si * (th + 2) + th / 2.0;
        canvas.segment(right + 2 * kLegendGap, ly, right + 2 * kLegendGap + kLegendSample, ly, s.colour, style);
        Label l = canvas.label(s.name, kTickFontSize);
        l.box.x = right + 2 * kLegendGap + kLegendSample + kLegendGap;
        l.box.y = ly - th / 2.0;
        canvas.draw(l);
    }
    return canvas.image();
}

}  // namespace ltm
