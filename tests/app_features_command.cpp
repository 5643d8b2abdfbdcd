// `ltmsim features DIR` and the feature outputs of `ltmsim render`: the paper's features checked
// against a direct computation from ltm.npz (scipy), the channel names, and the bad-input contract.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "io/CsrMatrix.h"
#include "io/Image.h"
#include "io/LtmFile.h"
#include "io/Npy.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::slurp;

// The render folder dir/r of the small bubble scene (tests/TestSupport.h).
using FeaturesCommand = ltm::test::RenderedFolderTest;

// The fixture's camera (16 x 12) and display (Q = 50 columns, P = 40 rows).
constexpr int kN = 16, kM = 12, kQ = 50, kP = 40, kPQ = kP * kQ;

// A hand-built T of the fixture's size with dyadic values, so that every product with the dyadic
// patterns below and every sum of them is exact in double and in float: row k holds
// (k % 8 + 1) / 8 at column 37 k mod PQ and (k % 5 + 1) / 4 at (37 k + 1001) mod PQ; every
// eleventh row is empty.
struct HandT {
    struct Entry {
        int k, l;
        float v;
    };
    std::vector<Entry> entries;
    ltm::CsrMatrix T = ltm::CsrMatrix::zeros(kN * kM, kPQ);
    HandT() {
        for (int k = 0; k < kN * kM; ++k) {
            if (k % 11 != 0) {
                const int a = (37 * k) % kPQ, b = (37 * k + 1001) % kPQ;
                const float va = static_cast<float>(k % 8 + 1) / 8, vb = static_cast<float>(k % 5 + 1) / 4;
                for (const Entry& e : a < b ? std::vector<Entry>{{k, a, va}, {k, b, vb}} : std::vector<Entry>{{k, b, vb}, {k, a, va}}) {
                    entries.push_back(e);
                    T.indices.push_back(e.l);
                    T.data.push_back(e.v);
                }
            }
            T.indptr[static_cast<std::size_t>(k) + 1] = static_cast<std::int64_t>(T.data.size());
        }
    }
    // y = T x from the entries themselves (not through the library's product).
    std::vector<float> apply(const std::vector<float>& x) const {
        std::vector<double> y(kN * kM, 0.0);
        for (const Entry& e : entries) y[static_cast<std::size_t>(e.k)] += double(e.v) * double(x[static_cast<std::size_t>(e.l)]);
        return std::vector<float>(y.begin(), y.end());
    }
};

// A float32 (K, P, Q) stack as numpy.save writes it (C order, little-endian: the test hosts').
void write_npy_stack(const fs::path& p, const std::vector<std::vector<float>>& stack,
                     std::vector<std::uint64_t> shape = {}) {
    if (shape.empty()) shape = {stack.size(), kP, kQ};
    std::string bytes = ltm::io::npy_preamble("<f4", shape);
    for (const auto& x : stack) bytes.append(reinterpret_cast<const char*>(x.data()), x.size() * sizeof(float));
    ltm::test::spit(p, bytes);
}

// The dyadic patterns of the tests: a (EXR, sixteenths), b (PNG, 0 or 1), s.0 .. s.2 (a stack).
std::vector<float> pattern_a() {
    std::vector<float> x(kPQ);
    for (int l = 0; l < kPQ; ++l) x[static_cast<std::size_t>(l)] = static_cast<float>((7 * l) % 16) / 16;
    return x;
}
std::vector<float> pattern_b() {
    std::vector<float> x(kPQ);
    for (int l = 0; l < kPQ; ++l) x[static_cast<std::size_t>(l)] = l % 3 == 0 ? 1.f : 0.f;
    return x;
}
std::vector<std::vector<float>> stack_s() {
    std::vector<std::vector<float>> s(3, std::vector<float>(kPQ));
    for (int j = 0; j < 3; ++j)
        for (int l = 0; l < kPQ; ++l) s[static_cast<std::size_t>(j)][static_cast<std::size_t>(l)] = static_cast<float>((l + 5 * j) % 8) / 8;
    return s;
}

void write_pattern_exr(const fs::path& p, const std::vector<float>& x) { ltm::write_exr(p.string(), kQ, kP, {{"Y", x}}); }
void write_pattern_png(const fs::path& p, const std::vector<float>& x) {
    ltm::Image img(kQ, kP, 1);
    img.data = x;
    ltm::write_png(p.string(), img);
}

std::map<std::string, std::vector<float>> exr_channels(const fs::path& p) {
    int w = 0, h = 0;
    const auto c = ltm::read_exr_channels(p.string(), &w, &h);
    EXPECT_EQ(w, kN);
    EXPECT_EQ(h, kM);
    return {c.begin(), c.end()};
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The fixture with T replaced by HandT and the pattern files a.exr, b.png, s.npy written.
class FeaturesPatterns : public FeaturesCommand {
protected:
    void SetUp() override {
        FeaturesCommand::SetUp();
        ltm::write_ltm_npz((dir / "r" / "ltm.npz").string(), hand.T);
        write_pattern_exr(dir / "a.exr", pattern_a());
        write_pattern_png(dir / "b.png", pattern_b());
        write_npy_stack(dir / "s.npy", stack_s());
    }
    HandT hand;
};

}  // namespace

TEST_F(FeaturesCommand, RenderWritesNamedFloatChannelsMatchingADirectComputation) {
    int w = 0, h = 0;
    const auto channels = ltm::read_exr_channels((dir / "r" / "features.exr").string(), &w, &h);
    ASSERT_EQ(w, 16);
    ASSERT_EQ(h, 12);
    std::map<std::string, std::vector<float>> byname(channels.begin(), channels.end());
    for (const char* c : {"BrightField", "ScatterCount", "ScatterWidth", "DarkField", "ScatterDiameter", "EllipseMajor",
                          "RobustScatterCount", "RobustScatterDiameter", "Deflection"})
        EXPECT_TRUE(byname.count(c)) << c;
    EXPECT_TRUE(fs::exists(dir / "r" / "features" / "ScatterCount.png"));
    // The paper's equations from ltm.npz with scipy, independently: ScatterCount = the number of
    // entries > 0 of a row, ScatterWidth = last - first nonzero column (0 for an empty row),
    // BrightField = the row sum.
    if (std::system("/usr/bin/python3 -c 'import scipy.sparse' 2>/dev/null") != 0) LTM_INTEROP_SKIP() << "no scipy";
    const fs::path py = dir / "direct.txt";
    const std::string script =
        "import scipy.sparse as s, numpy as np\n"
        "T = s.load_npz('" + (dir / "r" / "ltm.npz").string() + "').tocsr()\n"
        "for k in range(T.shape[0]):\n"
        "    r = T.getrow(k); c = r.indices[r.data > 0]\n"
        "    print(len(c), (c.max() - c.min()) if len(c) else 0, repr(float(r.data.astype(np.float64).sum())))\n";
    std::ofstream(dir / "direct.py") << script;
    ASSERT_EQ(std::system(("/usr/bin/python3 " + (dir / "direct.py").string() + " > " + py.string()).c_str()), 0);
    std::ifstream in(py);
    for (int k = 0; k < w * h; ++k) {
        double count, width, sum;
        ASSERT_TRUE(in >> count >> width >> sum);
        EXPECT_EQ(byname["ScatterCount"][static_cast<size_t>(k)], count) << k;
        EXPECT_EQ(byname["ScatterWidth"][static_cast<size_t>(k)], width) << k;
        // Float storage of the double row sum: relative 2^-24.
        EXPECT_NEAR(byname["BrightField"][static_cast<size_t>(k)], sum, std::ldexp(1.0, -24) * (1 + sum)) << k;
    }
}

TEST_F(FeaturesCommand, RecomputesWithOptionsWithoutTracing) {
    const std::string before = slurp(dir / "r" / "features.exr");
    ASSERT_EQ(run("features " + (dir / "r").string() + " --threshold 0.1 --energy-fraction 0.9 --dark-block 10"), 0);
    EXPECT_NE(slurp(dir / "r" / "features.exr"), before);  // another threshold, other counts
    int w = 0, h = 0;
    const auto channels = ltm::read_exr_channels((dir / "r" / "features.exr").string(), &w, &h);
    for (const auto& [name, v] : channels) {
        if (name != "ScatterCount") continue;
        for (float x : v) EXPECT_LE(x, 16 * 0.9 + 1);  // entries > 0.1 of a 16-sample row: at most 9
    }
}

TEST_F(FeaturesCommand, PreviewsAreTheRendersOnes) {
    // Recomputed with the render's options, the previews come out byte for byte as `render` wrote
    // them: same data, and the same axes in mm (the camera's 25 x 20 mm, read back from run.json).
    const std::string before = slurp(dir / "r" / "features" / "ScatterCount.png");
    const ltm::Image png = ltm::read_image((dir / "r" / "features" / "ScatterCount.png").string());
    fs::remove(dir / "r" / "features" / "ScatterCount.png");
    ASSERT_EQ(run("features " + (dir / "r").string()), 0);
    EXPECT_EQ(slurp(dir / "r" / "features" / "ScatterCount.png"), before);
    // 16 x 12 pixels at 400 / 16 = 25 per pixel: 400 x 300, with room for axes, title and bar
    EXPECT_GT(png.width, 400 + 60);
    EXPECT_GT(png.height, 300 + 60);
}

TEST_F(FeaturesCommand, BadInputExitsTwoAndOverwritesNothing) {
    const std::string before = slurp(dir / "r" / "features.exr");
    std::string err;
    fs::create_directories(dir / "empty");
    EXPECT_EQ(run("features " + (dir / "empty").string(), &err), 2);
    EXPECT_NE(err.find("no ltm.npz"), std::string::npos) << err;
    EXPECT_EQ(run("features " + (dir / "r").string() + " --threshold -1", &err), 2);
    EXPECT_NE(err.find("--threshold"), std::string::npos) << err;
    EXPECT_EQ(run("features " + (dir / "r").string() + " --energy-fraction 1.5", &err), 2);
    EXPECT_EQ(run("features " + (dir / "r").string() + " --dark-block 500", &err), 2);
    EXPECT_NE(err.find("--dark-block"), std::string::npos) << err;
    // A pattern of the wrong size (the display is 50 x 40).
    ltm::Image small;
    small.width = 10;
    small.height = 10;
    small.channels = 1;
    small.data.assign(100, 1.0f);
    ltm::write_png((dir / "small.png").string(), small);
    EXPECT_EQ(run("features " + (dir / "r").string() + " --pattern " + (dir / "small.png").string(), &err), 2);
    EXPECT_NE(err.find("50 x 40"), std::string::npos) << err;
    EXPECT_EQ(slurp(dir / "r" / "features.exr"), before);
    EXPECT_FALSE(fs::exists(dir / "r" / "pattern.exr"));
}

// One image gives pattern.exr (channel Image) and its values are y = T x.
TEST_F(FeaturesPatterns, OneImageWritesPatternExrWithTheProduct) {
    std::string err;
    ASSERT_EQ(run("features " + r() + " --pattern " + path("a.exr"), &err), 0) << err;
    const auto c = exr_channels(dir / "r" / "pattern.exr");
    ASSERT_EQ(c.size(), 1u);
    ASSERT_TRUE(c.count("Image"));
    EXPECT_EQ(c.at("Image"), hand.apply(pattern_a()));
    EXPECT_FALSE(fs::exists(dir / "r" / "patterns.exr"));
    EXPECT_FALSE(fs::exists(dir / "r" / "patterns.npz"));
}

// Several patterns in one call: one channel per pattern (named after the files, the stack's
// after its stem and index), each equal bit for bit to the same pattern alone and to y = T x
// computed here; whatever --threads, the same files byte for byte.
TEST_F(FeaturesPatterns, StackEqualsSinglePatternsAndTheProduct) {
    std::string err;
    const std::string all = " --pattern " + path("a.exr") + " --pattern " + path("b.png") + " --pattern " + path("s.npy");
    ASSERT_EQ(run("features " + r() + all + " --threads 1", &err), 0) << err;
    const auto stack = exr_channels(dir / "r" / "patterns.exr");
    const std::string exr1 = slurp(dir / "r" / "patterns.exr"), npz1 = slurp(dir / "r" / "patterns.npz");
    std::vector<std::string> names;
    for (const auto& [n, v] : stack) names.push_back(n);
    EXPECT_EQ(names, (std::vector<std::string>{"a", "b", "s.0", "s.1", "s.2"}));  // EXR sorts by name
    EXPECT_FALSE(fs::exists(dir / "r" / "pattern.exr"));

    const std::vector<std::vector<float>> s = stack_s();
    const std::map<std::string, std::vector<float>> x = {
        {"a", pattern_a()}, {"b", pattern_b()}, {"s.0", s[0]}, {"s.1", s[1]}, {"s.2", s[2]}};
    for (const auto& [name, values] : x) {
        // Alone: the stack's slices as EXR images of their own.
        const fs::path alone = dir / (name + "_alone.exr");
        write_pattern_exr(alone, values);
        ASSERT_EQ(run("features " + r() + " --pattern " + alone.string() + " --threads 2", &err), 0) << err;
        const auto single = exr_channels(dir / "r" / "pattern.exr");
        EXPECT_TRUE(same_bits(stack.at(name), single.at("Image"))) << name;
        EXPECT_EQ(stack.at(name), hand.apply(values)) << name;
    }
    ASSERT_EQ(run("features " + r() + all + " --threads 3", &err), 0) << err;
    EXPECT_EQ(slurp(dir / "r" / "patterns.exr"), exr1);
    EXPECT_EQ(slurp(dir / "r" / "patterns.npz"), npz1);
}

// numpy reads patterns.npz: images (K, rows, columns) float32 in the order given, names beside
// them, the values the EXR holds; and a float64 Fortran-order stack numpy wrote gives the same
// images as the float32 C-order one.
TEST_F(FeaturesPatterns, NumpyReadsTheStackAndWritesOne) {
    if (std::system("/usr/bin/python3 -c 'import numpy' 2>/dev/null") != 0) LTM_INTEROP_SKIP() << "no numpy";
    std::string err;
    ASSERT_EQ(run("features " + r() + " --pattern " + path("s.npy") + " --pattern " + path("b.png"), &err), 0) << err;
    const auto exr = exr_channels(dir / "r" / "patterns.exr");
    const std::string script =
        "import numpy as np\n"
        "z = np.load('" + (dir / "r" / "patterns.npz").string() + "')\n"
        "im, names = z['images'], z['names']\n"
        "print(im.dtype, im.shape, ' '.join(n.decode() for n in names))\n"
        "for v in im.reshape(len(names), -1): print(' '.join(repr(float(t)) for t in v))\n"
        "s = np.load('" + path("s.npy") + "')\n"
        "np.save('" + path("f.npy") + "', np.asfortranarray(s.astype(np.float64)))\n";
    std::ofstream(dir / "read.py") << script;
    const ltm::test::Outcome o = ltm::test::run_shell("/usr/bin/python3 " + path("read.py"), dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const std::vector<std::string> lines = o.lines();
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_EQ(lines[0], "float32 (4, 12, 16) s.0 s.1 s.2 b");
    const char* order[] = {"s.0", "s.1", "s.2", "b"};
    for (int j = 0; j < 4; ++j) {
        std::istringstream in(lines[static_cast<std::size_t>(j) + 1]);
        std::vector<float> v;
        for (double t; in >> t;) v.push_back(static_cast<float>(t));
        EXPECT_EQ(v, exr.at(order[j])) << order[j];
    }
    const std::string npz_c = slurp(dir / "r" / "patterns.npz");
    fs::rename(dir / "f.npy", dir / "s_f.npy");
    ASSERT_EQ(run("features " + r() + " --pattern " + path("s_f.npy"), &err), 0) << err;
    const auto f = exr_channels(dir / "r" / "patterns.exr");
    for (int j = 0; j < 3; ++j) EXPECT_EQ(f.at("s_f." + std::to_string(j)), exr.at("s." + std::to_string(j))) << j;
}

// Every bad pattern input exits 2 naming the file, and writes nothing: no pattern output, the
// feature images untouched.
TEST_F(FeaturesPatterns, BadPatternInputsExitTwoAndWriteNothing) {
    const std::string features = slurp(dir / "r" / "features.exr");
    std::vector<float> nan = pattern_a();
    nan[123] = std::numeric_limits<float>::quiet_NaN();
    write_pattern_exr(dir / "nan.exr", nan);
    std::vector<std::vector<float>> inf = stack_s();
    inf[2][kQ + 4] = std::numeric_limits<float>::infinity();
    write_npy_stack(dir / "inf.npy", inf);
    write_npy_stack(dir / "empty.npy", {}, {0, kP, kQ});
    write_npy_stack(dir / "transposed.npy", stack_s(), {3, kQ, kP});
    write_npy_stack(dir / "flat.npy", {pattern_a()}, {kP, kQ});
    std::string ints = ltm::io::npy_preamble("<i4", {1, kP, kQ});
    ints.append(4 * kPQ, '\0');
    ltm::test::spit(dir / "ints.npy", ints);
    const std::string whole = slurp(dir / "s.npy");
    ltm::test::spit(dir / "short.npy", whole.substr(0, whole.size() - 4));
    ltm::test::spit(dir / "garbage.png", "not an image");
    ltm::Image small(10, 10, 1);
    ltm::write_png((dir / "small.png").string(), small);
    fs::create_directories(dir / "other");
    write_pattern_png(dir / "other" / "a.png", pattern_b());

    struct Case {
        std::string args, file, says;
    };
    const std::string a = " --pattern " + path("a.exr");
    const std::vector<Case> cases = {
        {a + " --pattern " + path("small.png"), "small.png", "10 x 10 pixels but the display is 50 x 40"},
        {a + " --pattern " + path("missing.exr"), "missing.exr", "missing.exr"},
        {a + " --pattern " + path("garbage.png"), "garbage.png", "garbage.png"},
        {a + " --pattern " + path("nan.exr"), "nan.exr", "value nan at display pixel (p, q) = (2, 23)"},
        {" --pattern " + path("nan.exr"), "nan.exr", "must be finite"},  // one image, too
        {a + " --pattern " + path("inf.npy"), "inf.npy", "pattern 2 has the value inf at display pixel (p, q) = (1, 4)"},
        {a + " --pattern " + path("empty.npy"), "empty.npy", "holds no patterns (shape (0, 40, 50))"},
        {a + " --pattern " + path("transposed.npy"), "transposed.npy", "shape (3, 50, 40) but this display needs (K, 40, 50)"},
        {a + " --pattern " + path("flat.npy"), "flat.npy", "shape (40, 50) but this display needs (K, 40, 50)"},
        {a + " --pattern " + path("ints.npy"), "ints.npy", "dtype '<i4' is not float32 or float64"},
        {a + " --pattern " + path("short.npy"), "short.npy", "bytes of data"},
        {a + " --pattern " + (dir / "other" / "a.png").string(), "other/a.png", "would be named 'a', as " + path("a.exr")},
        {a + a, "a.exr", "given twice"},
    };
    for (const Case& c : cases) {
        std::string err;
        EXPECT_EQ(run("features " + r() + c.args, &err), 2) << c.args;
        EXPECT_NE(err.find(c.file), std::string::npos) << c.args << "\n" << err;
        EXPECT_NE(err.find(c.says), std::string::npos) << c.args << "\n" << err;
        EXPECT_FALSE(fs::exists(dir / "r" / "pattern.exr")) << c.args;
        EXPECT_FALSE(fs::exists(dir / "r" / "patterns.exr")) << c.args;
        EXPECT_FALSE(fs::exists(dir / "r" / "patterns.npz")) << c.args;
        EXPECT_EQ(slurp(dir / "r" / "features.exr"), features) << c.args;
    }
}
