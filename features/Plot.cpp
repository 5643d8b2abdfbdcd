// Plot.h: viridis, a built-in bitmap font, pseudo-colour images with a colour bar, montages.
#include "features/Plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <tuple>

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

// ---- font ----
// One line per glyph: up to 8 rows of 5 pixels ('#' set), rows 0 - 6 above the baseline, row 7
// the descender; missing rows are blank.
struct GlyphArt {
    char c;
    const char* rows[8];
};

const GlyphArt kGlyphArt[] = {
    {' ', {".....", ".....", ".....", ".....", ".....", ".....", "....."}},
    {'!', {"..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."}},
    {'"', {".#.#.", ".#.#.", ".#.#."}},
    {'#', {".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#."}},
    {'$', {"..#..", ".####", "#.#..", ".###.", "..#.#", "####.", "..#.."}},
    {'%', {"##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"}},
    {'&', {".##..", "#..#.", "#.#..", ".#...", "#.#.#", "#..#.", ".##.#"}},
    {'\'', {"..#..", "..#..", ".#..."}},
    {'(', {"...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."}},
    {')', {".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."}},
    {'*', {".....", "..#..", "#.#.#", ".###.", "#.#.#", "..#..", "....."}},
    {'+', {".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."}},
    {',', {".....", ".....", ".....", ".....", ".....", ".##..", "..#..", ".#..."}},
    {'-', {".....", ".....", ".....", "#####", ".....", ".....", "....."}},
    {'.', {".....", ".....", ".....", ".....", ".....", ".##..", ".##.."}},
    {'/', {".....", "....#", "...#.", "..#..", ".#...", "#....", "....."}},
    {'0', {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
    {'1', {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'2', {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}},
    {'3', {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}},
    {'4', {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}},
    {'5', {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
    {'6', {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}},
    {'7', {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}},
    {'8', {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}},
    {'9', {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}},
    {':', {".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."}},
    {';', {".....", ".##..", ".##..", ".....", ".##..", "..#..", ".#..."}},
    {'<', {"...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#."}},
    {'=', {".....", ".....", "#####", ".....", "#####", ".....", "....."}},
    {'>', {".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#..."}},
    {'?', {".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."}},
    {'@', {".###.", "#...#", "....#", ".##.#", "#.#.#", "#.#.#", ".###."}},
    {'A', {".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'B', {"####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."}},
    {'C', {".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."}},
    {'D', {"###..", "#..#.", "#...#", "#...#", "#...#", "#..#.", "###.."}},
    {'E', {"#####", "#....", "#....", "####.", "#....", "#....", "#####"}},
    {'F', {"#####", "#....", "#....", "####.", "#....", "#....", "#...."}},
    {'G', {".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"}},
    {'H', {"#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'I', {".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'J', {"..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."}},
    {'K', {"#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"}},
    {'L', {"#....", "#....", "#....", "#....", "#....", "#....", "#####"}},
    {'M', {"#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"}},
    {'N', {"#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"}},
    {'O', {".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'P', {"####.", "#...#", "#...#", "####.", "#....", "#....", "#...."}},
    {'Q', {".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"}},
    {'R', {"####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"}},
    {'S', {".####", "#....", "#....", ".###.", "....#", "....#", "####."}},
    {'T', {"#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
    {'U', {"#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'V', {"#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
    {'W', {"#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."}},
    {'X', {"#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"}},
    {'Y', {"#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."}},
    {'Z', {"#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"}},
    {'[', {".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###."}},
    {'\\', {".....", "#....", ".#...", "..#..", "...#.", "....#", "....."}},
    {']', {".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###."}},
    {'^', {"..#..", ".#.#.", "#...#"}},
    {'_', {".....", ".....", ".....", ".....", ".....", ".....", ".....", "#####"}},
    {'`', {".#...", "..#.."}},
    {'a', {".....", ".....", ".###.", "....#", ".####", "#...#", ".####"}},
    {'b', {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "####."}},
    {'c', {".....", ".....", ".###.", "#....", "#....", "#...#", ".###."}},
    {'d', {"....#", "....#", ".##.#", "#..##", "#...#", "#...#", ".####"}},
    {'e', {".....", ".....", ".###.", "#...#", "#####", "#....", ".###."}},
    {'f', {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#..."}},
    {'g', {".....", ".....", ".####", "#...#", "#...#", ".####", "....#", ".###."}},
    {'h', {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
    {'i', {"..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."}},
    {'j', {"...#.", ".....", "..##.", "...#.", "...#.", "...#.", "#..#.", ".##.."}},
    {'k', {"#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."}},
    {'l', {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'m', {".....", ".....", "##.#.", "#.#.#", "#.#.#", "#...#", "#...#"}},
    {'n', {".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
    {'o', {".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."}},
    {'p', {".....", ".....", "####.", "#...#", "#...#", "####.", "#....", "#...."}},
    {'q', {".....", ".....", ".####", "#...#", "#...#", ".####", "....#", "....#"}},
    {'r', {".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."}},
    {'s', {".....", ".....", ".####", "#....", ".###.", "....#", "####."}},
    {'t', {".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##."}},
    {'u', {".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#"}},
    {'v', {".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
    {'w', {".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#."}},
    {'x', {".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"}},
    {'y', {".....", ".....", "#...#", "#...#", "#...#", ".####", "....#", ".###."}},
    {'z', {".....", ".....", "#####", "...#.", "..#..", ".#...", "#####"}},
    {'{', {"...#.", "..#..", "..#..", ".#...", "..#..", "..#..", "...#."}},
    {'|', {"..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
    {'}', {".#...", "..#..", "..#..", "...#.", "..#..", "..#..", ".#..."}},
    {'~', {".....", ".....", ".#...", "#.#.#", "...#.", ".....", "....."}},
};

// The unknown-character box: the 5 x 7 outline.
const GlyphArt kBoxArt = {'?', {"#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"}};

using GlyphBits = std::array<std::uint8_t, kGlyphHeight>;  // bit (4 - column) of row r

GlyphBits parse(const GlyphArt& g) {
    GlyphBits bits{};
    for (int r = 0; r < kGlyphHeight; ++r) {
        const char* row = g.rows[r];
        if (!row) continue;
        for (int c = 0; c < kGlyphWidth; ++c) {
            if (row[c] == '#') bits[r] |= static_cast<std::uint8_t>(1u << (kGlyphWidth - 1 - c));
            else if (row[c] != '.') throw std::logic_error(std::string("Plot font: bad row in glyph '") + g.c + "'");
        }
        if (row[kGlyphWidth] != '\0') throw std::logic_error(std::string("Plot font: row too long in glyph '") + g.c + "'");
    }
    return bits;
}

struct Font {
    std::array<GlyphBits, 128> glyphs{};
    std::array<bool, 128> known{};
    GlyphBits box{};
    Font() {
        for (const GlyphArt& g : kGlyphArt) {
            const auto c = static_cast<unsigned char>(g.c);
            glyphs[c] = parse(g);
            known[c] = true;
        }
        box = parse(kBoxArt);
    }
    const GlyphBits& glyph(int code) const { return code >= 0 && code < 128 && known[code] ? glyphs[code] : box; }
};

const Font& font() {
    static const Font f;
    return f;
}

// The text as lines of character codes: ASCII as itself, anything else (a UTF-8 sequence: a lead
// byte and its continuation bytes; a stray continuation byte) as -1.
std::vector<std::vector<int>> split_lines(const std::string& text) {
    std::vector<std::vector<int>> lines(1);
    bool in_sequence = false;
    for (const char ch : text) {
        const auto b = static_cast<unsigned char>(ch);
        if (b == '\n') {
            lines.emplace_back();
            in_sequence = false;
        } else if (b < 0x80) {
            lines.back().push_back(b);
            in_sequence = false;
        } else if ((b & 0xC0) == 0x80 && in_sequence) {
            // continuation of the current sequence: already drawn as one box
        } else {
            lines.back().push_back(-1);
            in_sequence = (b & 0xC0) == 0xC0;
        }
    }
    return lines;
}

void check_scale(int scale, const char* who) {
    if (scale < 1) throw std::invalid_argument(std::string(who) + ": text scale must be >= 1, got " + std::to_string(scale));
}

void set_pixel(Image& img, int row, int col, const Rgb& c) {
    if (row < 0 || col < 0 || row >= img.height || col >= img.width) return;
    for (int k = 0; k < 3; ++k) img.at(row, col, k) = c[k];
}

void fill_rect(Image& img, int x, int y, int w, int h, const Rgb& c) {
    const int r0 = std::max(y, 0), r1 = std::min(y + h, img.height);
    const int c0 = std::max(x, 0), c1 = std::min(x + w, img.width);
    for (int r = r0; r < r1; ++r)
        for (int col = c0; col < c1; ++col)
            for (int k = 0; k < 3; ++k) img.at(r, col, k) = c[k];
}

Image white_canvas(int width, int height) {
    Image img(width, height, 3);
    std::fill(img.data.begin(), img.data.end(), 1.0f);
    return img;
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

int text_width(const std::string& text, int scale) {
    check_scale(scale, "text_width");
    std::size_t longest = 0;
    for (const auto& line : split_lines(text)) longest = std::max(longest, line.size());
    return longest == 0 ? 0 : (kGlyphAdvance * static_cast<int>(longest) - 1) * scale;
}

int text_height(const std::string& text, int scale) {
    check_scale(scale, "text_height");
    const int lines = static_cast<int>(split_lines(text).size());
    return (kLineAdvance * (lines - 1) + kGlyphHeight) * scale;
}

void draw_text(Image& rgb, int x, int y, const std::string& text, int scale, Rgb colour) {
    check_scale(scale, "draw_text");
    if (rgb.channels != 3)
        throw std::invalid_argument("draw_text: needs an RGB image (3 channels), got " + std::to_string(rgb.channels));
    const Font& f = font();
    int line_y = y;
    for (const auto& line : split_lines(text)) {
        int gx = x;
        for (const int code : line) {
            const GlyphBits& g = f.glyph(code);
            for (int r = 0; r < kGlyphHeight; ++r)
                for (int c = 0; c < kGlyphWidth; ++c)
                    if (g[static_cast<std::size_t>(r)] & (1u << (kGlyphWidth - 1 - c)))
                        fill_rect(rgb, gx + c * scale, line_y + r * scale, scale, scale, colour);
            gx += kGlyphAdvance * scale;
        }
        line_y += kLineAdvance * scale;
    }
}

// ---- pseudo colour ----

std::pair<double, double> colour_range(const std::vector<float>& values, double lo, double hi) {
    if (std::isinf(lo) || std::isinf(hi)) throw std::invalid_argument("colour range: lo and hi must be finite or NaN");
    if (std::isnan(lo) || std::isnan(hi)) {
        double mn = std::numeric_limits<double>::infinity(), mx = -mn;
        for (const float v : values)
            if (std::isfinite(v)) {
                mn = std::min(mn, static_cast<double>(v));
                mx = std::max(mx, static_cast<double>(v));
            }
        if (mn > mx) mn = 0, mx = 1;  // no finite value
        if (std::isnan(lo)) lo = mn;
        if (std::isnan(hi)) hi = mx;
    }
    if (lo > hi)
        throw std::invalid_argument("colour range: lo " + format_tick(lo, 9) + " > hi " + format_tick(hi, 9));
    if (lo == hi) lo -= 0.5, hi += 0.5;
    return {lo, hi};
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

PseudoColourLayout pseudo_colour_layout(const std::vector<float>& values, int width, int height,
                                        const std::string& title, double lo, double hi, int pixel_scale) {
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
    const int ts = kPlotTextScale, M = kPlotMargin;
    L.image_w = width * pixel_scale;
    L.image_h = height * pixel_scale;
    L.bar_w = kPlotBarWidth;
    L.bar_h = std::max(L.image_h, kPlotMinBarHeight);

    const int n = L.bar_h >= kPlotFiveTickHeight ? 5 : 3;
    for (int i = 0; i < n; ++i) {
        double v;
        if (i == 0) v = L.hi;
        else if (i == n - 1) v = L.lo;
        else {
            v = L.hi - (L.hi - L.lo) * i / (n - 1);
            if (std::fabs(v) < 1e-9 * (L.hi - L.lo)) v = 0.0;  // no "1e-17" for a zero tick
        }
        L.tick_values.push_back(v);
        L.tick_rows.push_back(0);  // set below, once the bar is placed
    }
    for (int digits = 3; digits <= 9; ++digits) {
        L.tick_labels.clear();
        for (const double v : L.tick_values) L.tick_labels.push_back(format_tick(v, digits));
        bool distinct = true;
        for (int i = 1; i < n; ++i) distinct = distinct && L.tick_labels[i] != L.tick_labels[i - 1];
        if (distinct) break;
    }
    int label_w = 0;
    for (const auto& s : L.tick_labels) label_w = std::max(label_w, text_width(s, ts));

    const int T = title.empty() ? 0 : text_height(title, ts);
    const int Gt = title.empty() ? 0 : kPlotTitleGap;
    L.title_x = M;
    L.title_y = M;
    L.image_x = M;
    L.image_y = M + T + Gt;
    L.bar_x = M + L.image_w + kPlotBarGap;
    L.bar_y = L.image_y;
    for (int i = 0; i < n; ++i)
        L.tick_rows[static_cast<std::size_t>(i)] =
            L.bar_y + static_cast<int>(std::lround((L.bar_h - 1) * static_cast<double>(i) / (n - 1)));
    L.width = std::max(L.bar_x + L.bar_w + kPlotTickLength + kPlotTickLabelGap + label_w + M,
                       M + text_width(title, ts) + M);
    L.height = L.bar_y + L.bar_h + 4 * ts + M;
    return L;
}

Image pseudo_colour(const std::vector<float>& values, int width, int height, const std::string& title,
                    double lo, double hi, int pixel_scale) {
    const PseudoColourLayout L = pseudo_colour_layout(values, width, height, title, lo, hi, pixel_scale);
    Image img = white_canvas(L.width, L.height);
    const int ts = kPlotTextScale;
    const double range = L.hi - L.lo;

    for (int m = 0; m < height; ++m)
        for (int n = 0; n < width; ++n) {
            const double v = values[static_cast<std::size_t>(m) * static_cast<std::size_t>(width) + static_cast<std::size_t>(n)];
            const Rgb c = viridis((v - L.lo) / range);  // NaN stays NaN; +-inf clamp to the ends
            fill_rect(img, L.image_x + n * pixel_scale, L.image_y + m * pixel_scale, pixel_scale, pixel_scale, c);
        }

    // The bar, row r showing t = 1 - r / (H - 1): exactly 1 (hi) on top, exactly 0 (lo) at the bottom.
    for (int r = 0; r < L.bar_h; ++r)
        fill_rect(img, L.bar_x, L.bar_y + r, L.bar_w, 1, viridis(1.0 - static_cast<double>(r) / (L.bar_h - 1)));
    fill_rect(img, L.bar_x - 1, L.bar_y - 1, L.bar_w + 2, 1, kFrameColour);
    fill_rect(img, L.bar_x - 1, L.bar_y + L.bar_h, L.bar_w + 2, 1, kFrameColour);
    fill_rect(img, L.bar_x - 1, L.bar_y, 1, L.bar_h, kFrameColour);
    fill_rect(img, L.bar_x + L.bar_w, L.bar_y, 1, L.bar_h, kFrameColour);

    const int label_x = L.bar_x + L.bar_w + kPlotTickLength + kPlotTickLabelGap;
    for (std::size_t i = 0; i < L.tick_rows.size(); ++i) {
        fill_rect(img, L.bar_x + L.bar_w, L.tick_rows[i], kPlotTickLength, 1, kFrameColour);
        draw_text(img, label_x, L.tick_rows[i] - 7 * ts / 2, L.tick_labels[i], ts, kBlack);
    }
    if (!title.empty()) draw_text(img, L.title_x, L.title_y, title, ts, kBlack);
    return img;
}

void write_pseudo_colour_png(const std::string& path, const std::vector<float>& values, int width, int height,
                             const std::string& title, double lo, double hi, int pixel_scale) {
    write_png(path, pseudo_colour(values, width, height, title, lo, hi, pixel_scale));
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

    const int ts = kPlotTextScale, M = kPlotMargin;
    int sw = cw, label_h = 0, row_label_w = 0;
    for (const auto& s : column_labels) {
        sw = std::max(sw, text_width(s, ts));
        label_h = std::max(label_h, text_height(s, ts));
    }
    for (const auto& s : row_labels) row_label_w = std::max(row_label_w, text_width(s, ts));
    const int T = title.empty() ? 0 : text_height(title, ts) + kMontageLabelGap;
    const int C = column_labels.empty() ? 0 : label_h + kMontageColumnGap;
    const int R = row_labels.empty() ? 0 : row_label_w + kMontageLabelGap;
    const int W = std::max(M + R + columns * sw + (columns - 1) * kMontageGap + M, M + text_width(title, ts) + M);
    const int H = M + T + C + rows * ch + (rows - 1) * kMontageGap + M;
    Image img = white_canvas(W, H);

    const int x0 = M + R, y0 = M + T + C;
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < static_cast<int>(cells[static_cast<std::size_t>(r)].size()); ++c) {
            const Image& cell = cells[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
            if (cell.width <= 0 || cell.height <= 0) continue;
            const int cx = x0 + c * (sw + kMontageGap) + (sw - cell.width) / 2;
            const int cy = y0 + r * (ch + kMontageGap) + (ch - cell.height) / 2;
            for (int i = 0; i < cell.height; ++i)
                for (int j = 0; j < cell.width; ++j) {
                    Rgb px;
                    bool nan = false;
                    for (int k = 0; k < 3; ++k) {
                        px[k] = cell.at(i, j, cell.channels == 1 ? 0 : k);
                        nan = nan || std::isnan(px[k]);
                    }
                    set_pixel(img, cy + i, cx + j, nan ? kNanColour : px);
                }
        }
    for (int c = 0; c < static_cast<int>(column_labels.size()); ++c) {
        const std::string& s = column_labels[static_cast<std::size_t>(c)];
        draw_text(img, x0 + c * (sw + kMontageGap) + (sw - text_width(s, ts)) / 2, M + T, s, ts, kBlack);
    }
    for (int r = 0; r < static_cast<int>(row_labels.size()); ++r) {
        const std::string& s = row_labels[static_cast<std::size_t>(r)];
        draw_text(img, M + R - kMontageLabelGap - text_width(s, ts),
                  y0 + r * (ch + kMontageGap) + (ch - text_height(s, ts)) / 2, s, ts, kBlack);
    }
    if (!title.empty()) draw_text(img, (W - text_width(title, ts)) / 2, M, title, ts, kBlack);
    return img;
}

Image histogram(const std::vector<double>& values, int bins, const std::string& title, const std::string& x_label,
                bool log_x) {
    if (bins < 1) throw std::invalid_argument("histogram: bins must be >= 1");
    std::vector<double> v;
    for (double x : values)
        if (std::isfinite(x) && (!log_x || x > 0)) v.push_back(log_x ? std::log10(x) : x);
    double lo = v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
    double hi = v.empty() ? 1.0 : *std::max_element(v.begin(), v.end());
    if (!(hi > lo)) {
        lo -= 0.5;
        hi += 0.5;
        bins = 1;
    }
    std::vector<long> count(static_cast<size_t>(bins), 0);
    for (double x : v) ++count[static_cast<size_t>(std::min(bins - 1, static_cast<int>((x - lo) / (hi - lo) * bins)))];
    const long peak = std::max(1L, *std::max_element(count.begin(), count.end()));

    const int W = 640, H = 400, ts = kPlotTextScale;
    Image img;
    img.width = W;
    img.height = H;
    img.channels = 3;
    img.data.assign(static_cast<size_t>(W) * H * 3, 1.0f);
    auto fill = [&](int x0, int y0, int x1, int y1, Rgb c) {
        for (int y = std::max(0, y0); y < std::min(H, y1); ++y)
            for (int x = std::max(0, x0); x < std::min(W, x1); ++x)
                for (int k = 0; k < 3; ++k) img.data[(static_cast<size_t>(y) * W + x) * 3 + k] = c[static_cast<size_t>(k)];
    };
    const int left = 80, right = W - 24, top = 16 + text_height(title, ts) + 12, bottom = H - 24 - 2 * text_height("0", ts);
    draw_text(img, (W - text_width(title, ts)) / 2, 12, title, ts, kBlack);
    const Rgb bar = viridis(0.5);
    const double bw = static_cast<double>(right - left) / bins;
    for (int b = 0; b < bins; ++b) {
        const int h = static_cast<int>(std::lround(static_cast<double>(count[static_cast<size_t>(b)]) / peak * (bottom - top)));
        fill(left + static_cast<int>(b * bw) + 1, bottom - h, left + static_cast<int>((b + 1) * bw), bottom, bar);
    }
    fill(left, top, left + 1, bottom + 1, kFrameColour);       // y axis
    fill(left, bottom, right + 1, bottom + 1, kFrameColour);   // x axis
    const std::string ymax = std::to_string(peak);
    draw_text(img, left - 8 - text_width(ymax, ts), top, ymax, ts, kBlack);
    draw_text(img, left - 8 - text_width("0", ts), bottom - text_height("0", ts), "0", ts, kBlack);
    for (double f : {0.0, 0.5, 1.0}) {
        const double x = lo + f * (hi - lo);
        const std::string t = format_tick(log_x ? std::pow(10.0, x) : x);
        const int px = left + static_cast<int>(f * (right - left));
        fill(px, bottom, px + 1, bottom + 5, kFrameColour);
        draw_text(img, std::clamp(px - text_width(t, ts) / 2, 0, W - text_width(t, ts)), bottom + 8, t, ts, kBlack);
    }
    draw_text(img, (W - text_width(x_label, ts)) / 2, H - 8 - text_height(x_label, ts), x_label, ts, kBlack);
    return img;
}

}  // namespace ltm
