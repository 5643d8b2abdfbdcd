// The `ltmsim render` command's contract (docs: docs/conventions.md, "Command line" and
// "The light transport matrix"): DIR/ltm.npz (scipy CSR, float32, M*N x P*Q) and DIR/run.json;
// results independent of --threads; existing outputs kept unless --overwrite; --pattern renders
// y = T x (DIR/image.exr with "Image" and "StdError", DIR/image.png, no ltm.npz); bad input exits
// with status 2, a message naming the file, and nothing written; the command's T is the library's
// render, bit for bit (the command links the tracer with link-time optimization).
//
// The scene is small (20 x 20 camera pixels, 16 samples each, 40 x 40 display pixels): every
// render takes a few milliseconds, so the test runs the real executable many times.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "io/Image.h"
#include "tests/TestSupport.h"
#include "tests/Tolerances.h"
#include "io/Json.h"
#include "io/LtmFile.h"
#include "scene/Scene.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "trace/Render.h"

namespace fs = std::filesystem;

namespace {

constexpr const char* kPython = "/usr/bin/python3";  // Debian's, with numpy and scipy

// The paper's lens with two enclosed bubbles (as in tests/validation_render.cpp), at a resolution
// that renders in milliseconds. `seed` is a parameter so that two independent renders can be made.
std::string scene_yaml(int seed) {
    return "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}\n"
           "defects:\n"
           "  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 1.0}\n"
           "  - {type: bubble, center: [5.0, 2.0, 0.0], radius: 0.8}\n"
           "camera: {resolution: [20, 20], size: [26.0, 26.0], numerical_aperture: 0.05, samples_per_pixel: 16}\n"
           "display: {resolution: [40, 40], size: [80.0, 80.0], z: 60.0}\n"
           "seed: " +
           std::to_string(seed) + "\n";
}
constexpr int kN = 20, kM = 20, kQ = 40, kP = 40, kSpp = 16;

// Commands run with stdout and stderr captured (tests/TestSupport.h).
using ltm::test::ltmsim;
using ltm::test::Outcome;
using ltm::test::run_shell;
using ltm::test::slurp;

bool python_has_scipy(const fs::path& dir) {
    if (!fs::exists(kPython)) return false;
    return run_shell(std::string(kPython) + " -c 'import numpy, scipy.sparse'", dir).status == 0;
}

// ---- a minimal 8-bit gray PNG writer, independent of features/Image.cpp ----
// PNG (ISO/IEC 15948): signature, IHDR (width, height, bit depth 8, colour type 0 = gray, no
// interlace), one IDAT holding a zlib stream (RFC 1950) of stored (uncompressed) deflate blocks
// (RFC 1951, BTYPE 00) over the scan lines, each preceded by filter type 0, and IEND. Row 0 of
// `codes` is the first scan line, i.e. the top (+y) edge of the picture and of the display.
std::uint32_t crc32(const std::string& bytes) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (unsigned char b : bytes) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}
void put_be32(std::string& s, std::uint32_t v) {
    for (int sh = 24; sh >= 0; sh -= 8) s += static_cast<char>((v >> sh) & 0xFF);
}
void write_gray_png(const fs::path& path, int width, int height, const std::vector<std::uint8_t>& codes) {
    std::string raw;
    for (int r = 0; r < height; ++r) {
        raw += '\0';
        for (int c = 0; c < width; ++c) raw += static_cast<char>(codes[static_cast<size_t>(r * width + c)]);
    }
    std::string z = "\x78\x01";
    for (size_t at = 0; at < raw.size() || at == 0;) {
        const size_t n = std::min<size_t>(65535, raw.size() - at);
        const bool last = at + n == raw.size();
        z += static_cast<char>(last ? 1 : 0);
        z += static_cast<char>(n & 0xFF);
        z += static_cast<char>(n >> 8);
        z += static_cast<char>(~n & 0xFF);
        z += static_cast<char>((~n >> 8) & 0xFF);
        z += raw.substr(at, n);
        at += n;
        if (last) break;
    }
    std::uint32_t a = 1, b = 0;
    for (unsigned char ch : raw) {
        a = (a + ch) % 65521;
        b = (b + a) % 65521;
    }
    put_be32(z, (b << 16) | a);
    auto chunk = [](const std::string& type, const std::string& data) {
        std::string s;
        put_be32(s, static_cast<std::uint32_t>(data.size()));
        s += type + data;
        put_be32(s, crc32(type + data));
        return s;
    };
    std::string ihdr;
    put_be32(ihdr, static_cast<std::uint32_t>(width));
    put_be32(ihdr, static_cast<std::uint32_t>(height));
    ihdr += std::string("\x08\x00\x00\x00\x00", 5);
    std::ofstream out(path, std::ios::binary);
    out << std::string("\x89PNG\r\n\x1a\n", 8) << chunk("IHDR", ihdr) << chunk("IDAT", z) << chunk("IEND", "");
}

class RenderCommand : public ltm::test::TempDirTest {
protected:
    void SetUp() override {
        TempDirTest::SetUp();
        scene = write("scene.yaml", scene_yaml(3));
    }
    std::string render(const fs::path& scene_file, const fs::path& out, const std::string& extra = "") {
        return "render '" + scene_file.string() + "' -o '" + out.string() + "' " + extra;
    }
    static std::set<std::string> listing(const fs::path& folder) {
        std::set<std::string> names;
        for (const auto& e : fs::directory_iterator(folder)) names.insert(e.path().filename().string());
        return names;
    }
    // Every file of a folder with its bytes.
    static std::map<std::string, std::string> snapshot(const fs::path& folder) {
        std::map<std::string, std::string> files;
        for (const auto& e : fs::directory_iterator(folder)) files[e.path().filename().string()] = slurp(e.path());
        return files;
    }
    // The render writes further files (feature images, previews: conventions.md); these tests
    // check the ones named here and that no temporary (".name.tmp...") is left behind.
    static void expect_outputs(const fs::path& folder, const std::set<std::string>& required,
                               const std::set<std::string>& absent = {}) {
        const std::set<std::string> names = listing(folder);
        for (const auto& n : required) EXPECT_TRUE(names.count(n)) << folder << " lacks " << n;
        for (const auto& n : absent) EXPECT_FALSE(names.count(n)) << folder << " holds " << n;
        for (const auto& n : names) EXPECT_NE(n[0], '.') << folder << " holds a temporary " << n;
    }
    fs::path scene;
};

// Python checks of the two files, printing "OK" or the failures (one per line).
const char* kCheckScript = R"PY(
import json, sys
import numpy as np, scipy.sparse as sp
npz, run, rows, cols, spp, slack = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), float(sys.argv[6])
bad = []
T = sp.load_npz(npz)
if T.format != "csr": bad.append("format %s, expected csr" % T.format)
if T.shape != (rows, cols): bad.append("shape %s, expected %s" % (T.shape, (rows, cols)))
if T.dtype != np.float32: bad.append("dtype %s, expected float32" % T.dtype)
if not T.has_canonical_format: bad.append("not in canonical format (sorted, no duplicates)")
if T.nnz == 0: bad.append("no nonzeros")
if not np.all(np.isfinite(T.data)) or np.any(T.data < 0): bad.append("negative or non-finite values")
s = np.asarray(T.sum(axis=1, dtype=np.float64)).ravel()
if s.max() > 1 + slack: bad.append("row sum %r > 1 + %g at row %d" % (s.max(), slack, int(s.argmax())))
j = json.load(open(run))
sc = j.get("scene", {})
if sc.get("object", {}).get("r2") != -50: bad.append("scene.object.r2 = %r" % sc.get("object", {}).get("r2"))
if sc.get("seed") != 3 or j.get("seed") != 3: bad.append("seed %r / %r" % (sc.get("seed"), j.get("seed")))
if len(sc.get("defects", [])) != 2: bad.append("scene.defects: %r" % sc.get("defects"))
if sc.get("camera", {}).get("samples_per_pixel") != spp: bad.append("camera.samples_per_pixel %r" % sc.get("camera"))
if j.get("representation") not in ("analytic", "refined", "mesh-only"): bad.append("representation %r" % j.get("representation"))
rs = j.get("render_seconds")
if not isinstance(rs, (int, float)) or rs < 0: bad.append("render_seconds %r" % rs)
st = j.get("stages")
if not isinstance(st, list) or not any(isinstance(x, dict) and x.get("stage") == "render" and x.get("seconds", -1) >= 0 for x in st):
    bad.append("stages without a timed 'render' stage: %r" % st)
ps = j.get("path_statistics", {})
if ps.get("nan_events") != 0: bad.append("nan_events %r" % ps.get("nan_events"))
if ps.get("paths") != rows * spp: bad.append("paths %r, expected %d" % (ps.get("paths"), rows * spp))
print("\n".join(bad) if bad else "OK")
)PY";

}  // namespace

TEST_F(RenderCommand, WritesTheMatrixAndTheRunRecord) {
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(scene, out, "--threads 2"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    expect_outputs(out, {"ltm.npz", "run.json"}, {"image.exr", "image.png"});

    // Our own reader (io/LtmFile.h) first: shape and row sums.
    const ltm::CsrMatrix T = ltm::read_ltm_npz((out / "ltm.npz").string());
    EXPECT_EQ(T.rows, kM * kN);
    EXPECT_EQ(T.cols, kP * kQ);
    EXPECT_EQ(T.check(), "");
    EXPECT_GT(T.nnz(), 0u);
    for (std::int64_t k = 0; k < T.rows; ++k) {
        double sum = 0;
        for (auto i = T.indptr[static_cast<size_t>(k)]; i < T.indptr[static_cast<size_t>(k) + 1]; ++i)
            sum += T.data[static_cast<size_t>(i)];
        EXPECT_LE(sum, 1.0 + ltm::tol::ltm_row_sum_slack()) << "row " << k;
    }

    // Then the contract's reader: scipy.sparse.load_npz, and Python's json for run.json.
    if (!python_has_scipy(dir)) LTM_INTEROP_SKIP() << kPython << " cannot import numpy and scipy.sparse";
    const fs::path script = write("check.py", kCheckScript);
    const Outcome py = run_shell(std::string(kPython) + " '" + script.string() + "' '" + (out / "ltm.npz").string() +
                                     "' '" + (out / "run.json").string() + "' " + std::to_string(kM * kN) + " " +
                                     std::to_string(kP * kQ) + " " + std::to_string(kSpp) + " " +
                                     std::to_string(ltm::tol::ltm_row_sum_slack()),
                                 dir);
    EXPECT_EQ(py.status, 0) << py.err;
    EXPECT_EQ(py.out, "OK\n") << py.err;
}

TEST_F(RenderCommand, NumpyReadsTheFeaturesAndThePatternImageWithTheExrsValues) {
    // features.npz and image.npz hold exactly the EXR files' channels (float32, rows x columns,
    // row 0 on top): numpy prints every value, compared bit for bit with read_exr_channels.
    const fs::path out = dir / "out", pat = dir / "pat";
    ASSERT_EQ(ltmsim(render(scene, out, "--threads 2"), dir).status, 0);
    const fs::path png = dir / "ramp.png";
    std::vector<std::uint8_t> codes;
    for (int p = 0; p < kP; ++p)
        for (int q = 0; q < kQ; ++q) codes.push_back(static_cast<std::uint8_t>((7 * p + 3 * q) % 256));
    write_gray_png(png, kQ, kP, codes);
    ASSERT_EQ(ltmsim(render(scene, pat, "--threads 2 --pattern '" + png.string() + "'"), dir).status, 0);
    if (!python_has_scipy(dir)) LTM_INTEROP_SKIP() << kPython << " cannot import numpy";
    const fs::path script = write("dump.py", R"PY(
import sys
import numpy as np
z = np.load(sys.argv[1])
for name in sorted(z.files):
    a = z[name]
    assert a.dtype == np.float32 and a.ndim == 2, (name, a.dtype, a.shape)
    print(name, a.shape[0], a.shape[1], " ".join(v.hex() for v in a.astype(np.float64).ravel()))
)PY");
    for (const auto& [folder, file] : {std::pair{out, std::string("features")}, std::pair{pat, std::string("image")}}) {
        const Outcome py = run_shell(std::string(kPython) + " '" + script.string() + "' '" + (folder / (file + ".npz")).string() + "'", dir);
        ASSERT_EQ(py.status, 0) << py.err;
        int w = 0, h = 0;
        auto exr = ltm::read_exr_channels((folder / (file + ".exr")).string(), &w, &h);
        std::sort(exr.begin(), exr.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        const auto lines = py.lines();
        ASSERT_EQ(lines.size(), exr.size()) << file;
        for (size_t c = 0; c < exr.size(); ++c) {
            std::istringstream in(lines[c]);
            std::string name;
            int rows = 0, cols = 0;
            in >> name >> rows >> cols;
            EXPECT_EQ(name, exr[c].first);
            EXPECT_EQ(rows, h);
            EXPECT_EQ(cols, w);
            for (size_t k = 0; k < exr[c].second.size(); ++k) {
                std::string hex;
                in >> hex;
                const double v = std::strtod(hex.c_str(), nullptr);
                const float e = exr[c].second[k];
                EXPECT_TRUE((std::isnan(v) && std::isnan(e)) || v == static_cast<double>(e)) << name << " pixel " << k;
            }
        }
    }
}

TEST_F(RenderCommand, TheMatrixDoesNotDependOnThreads) {
    // "results do not depend on N", and the writer is byte-for-byte deterministic
    // (io/LtmFile.h): the two files must be identical.
    ASSERT_EQ(ltmsim(render(scene, dir / "one", "--threads 1"), dir).status, 0);
    ASSERT_EQ(ltmsim(render(scene, dir / "two", "--threads 2"), dir).status, 0);
    const std::string a = slurp(dir / "one" / "ltm.npz"), b = slurp(dir / "two" / "ltm.npz");
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "ltm.npz differs between --threads 1 and --threads 2 (" << a.size() << " vs " << b.size()
                        << " bytes)";
}

TEST_F(RenderCommand, TheCommandTracesExactlyAsTheLibrary) {
    // ltmsim links the tracer with link-time optimization, this test the same objects' ordinary
    // code (CMakeLists.txt, LTM_LTO); inlining across files must change no rounding (no fused
    // multiply-adds, no fast-math), so each representation's T is the library's, bit for bit.
    const ltm::Scene scene_in = ltm::load_scene(scene.string());
    for (const auto& [name, representation] : {std::pair{"analytic", ltm::Representation::Analytic},
                                               std::pair{"refined", ltm::Representation::Refined},
                                               std::pair{"mesh-only", ltm::Representation::MeshOnly}}) {
        SCOPED_TRACE(name);
        const fs::path out = dir / name;
        const Outcome r = ltmsim(render(scene, out, std::string("--threads 2 --no-previews --representation ") + name), dir);
        ASSERT_EQ(r.status, 0) << r.err;
        const ltm::CsrMatrix file = ltm::read_ltm_npz((out / "ltm.npz").string());
        const ltm::Solid solid =
            ltm::build_solid(scene_in, nullptr, representation == ltm::Representation::Analytic);
        ltm::TracerOptions topt;
        topt.representation = representation;  // robust, as the command's default
        ltm::RenderOptions ropt;
        ropt.threads = 2;
        const ltm::RenderResult lib = ltm::render(ltm::Tracer(scene_in, solid, topt), ropt);
        EXPECT_EQ(file.rows, lib.T.rows);
        EXPECT_EQ(file.cols, lib.T.cols);
        EXPECT_EQ(file.indptr, lib.T.indptr);
        EXPECT_EQ(file.indices, lib.T.indices);
        ASSERT_EQ(file.data.size(), lib.T.data.size());
        EXPECT_EQ(std::memcmp(file.data.data(), lib.T.data.data(), file.data.size() * sizeof(float)), 0)
            << "the values differ in their bits";
    }
}

TEST_F(RenderCommand, ExistingOutputsAreKeptUnlessOverwrite) {
    const fs::path out = dir / "out";
    ASSERT_EQ(ltmsim(render(scene, out, "--threads 2"), dir).status, 0);
    const auto first = snapshot(out);
    const std::string npz = slurp(out / "ltm.npz");
    ASSERT_FALSE(npz.empty());
    ASSERT_FALSE(slurp(out / "run.json").empty());

    const Outcome again = ltmsim(render(scene, out, "--threads 2"), dir);
    EXPECT_EQ(again.status, 2) << again.err;
    EXPECT_NE(again.err.find(out.string()), std::string::npos) << again.err;
    EXPECT_NE(again.err.find("--overwrite"), std::string::npos) << again.err;
    EXPECT_TRUE(snapshot(out) == first) << "the first render's files changed";
    // Every file of a render counts, the reference among them.
    const fs::path only_reference = dir / "only-reference";
    fs::create_directories(only_reference);
    fs::copy_file(out / "reference.exr", only_reference / "reference.exr");
    const Outcome ref = ltmsim(render(scene, only_reference, "--threads 2"), dir);
    EXPECT_EQ(ref.status, 2) << ref.err;
    EXPECT_EQ(ref.err, "ltmsim render: " + (only_reference / "reference.exr").string() + " exists; pass --overwrite to replace it\n");

    const Outcome forced = ltmsim(render(scene, out, "--threads 2 --overwrite"), dir);
    EXPECT_EQ(forced.status, 0) << forced.err;
    EXPECT_TRUE(slurp(out / "ltm.npz") == npz);  // same scene and seed: the same matrix, the same bytes
    expect_outputs(out, {"ltm.npz", "run.json"});
}

// A successful render says on stdout, in one line, what it wrote where and how fast it traced:
// here T of 20 x 20 camera pixels by 40 x 40 display pixels, 20 x 20 x 16 = 6400 camera paths.
TEST_F(RenderCommand, OneSummaryLineOnSuccess) {
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(scene, out, "--threads 2"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_EQ(r.lines().size(), 1u) << r.out;
    const std::string line = r.lines()[0];
    EXPECT_EQ(line.rfind("ltmsim render: wrote " + out.string() + "/: ltm.npz (T 400 x 1600, ", 0), 0u) << line;
    EXPECT_NE(line.find(" nonzeros), features.exr and features.npz ("), std::string::npos) << line;
    EXPECT_NE(line.find(" images, previews in features/), reference.exr, run.json; 6400 paths in "), std::string::npos)
        << line;
    EXPECT_EQ(line.substr(line.size() - 9), " Mpaths/s") << line;
    // A defect-free scene's render writes (and names) the reference too: its deflection map is
    // measured against one as well.
    std::string free_yaml = scene_yaml(3);
    free_yaml.erase(free_yaml.find("defects:\n"), free_yaml.find("camera:") - free_yaml.find("defects:\n"));
    const fs::path free = write("free.yaml", free_yaml);
    const Outcome f = ltmsim(render(free, dir / "free", "--threads 2 --no-previews"), dir);
    ASSERT_EQ(f.status, 0) << f.err;
    ASSERT_EQ(f.lines().size(), 1u) << f.out;
    EXPECT_NE(f.lines()[0].find(" images), reference.exr, run.json; "), std::string::npos) << f.lines()[0];
    EXPECT_TRUE(fs::is_regular_file(dir / "free" / "reference.exr"));
    // A pattern's render names its image.
    const fs::path png = dir / "white.png";
    write_gray_png(png, kQ, kP, std::vector<std::uint8_t>(static_cast<std::size_t>(kP * kQ), 255));
    const Outcome p = ltmsim(render(scene, dir / "img", "--threads 2 --no-previews --pattern '" + png.string() + "'"), dir);
    ASSERT_EQ(p.status, 0) << p.err;
    ASSERT_EQ(p.lines().size(), 1u) << p.out;
    EXPECT_EQ(p.lines()[0].rfind("ltmsim render: wrote " + (dir / "img").string() +
                                     "/: image.exr and image.npz (20 x 20 image of " + png.string() +
                                     "), run.json; 6400 paths in ",
                                 0),
              0u)
        << p.lines()[0];
}

// The issue's first case: the lens in metres (diameter 0.025 mm) under 1.3 mm pixels renders a
// flat image; the render goes on, and says so on stderr in one line naming the sizes and the unit.
TEST_F(RenderCommand, ObjectSmallerThanAPixelWarns) {
    const fs::path metres =
        write("metres.yaml",
              "object: {type: lens, r1: 0.05, r2: -0.05, center_thickness: 0.006, diameter: 0.025, ior: 1.5168}\n"
              "camera: {resolution: [20, 20], size: [26.0, 26.0], numerical_aperture: 0.05, samples_per_pixel: 16}\n"
              "display: {resolution: [40, 40], size: [80.0, 80.0], z: 60.0}\n");
    const Outcome r = ltmsim(render(metres, dir / "out", "--threads 2 --no-previews"), dir);
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, metres.string() + ":1:78: warning: object.diameter: the object (diameter 0.025 mm) is smaller "
                                       "than one camera pixel (1.3 x 1.3 mm: camera.size over camera.resolution), "
                                       "0.00029 of its area; lengths are in mm: were the object's given in metres?\n");
    EXPECT_TRUE(fs::exists(dir / "out" / "ltm.npz"));
}

// A field of 26 um for the 25 mm lens (camera.size in metres) sees 4 (0.013 / 12.5)^2 / pi =
// 1.38e-6 of it: a warning at camera.size, and the render goes on.
TEST_F(RenderCommand, FieldThatSeesASliverWarns) {
    const std::string yaml = scene_yaml(3);
    const fs::path sliver = write("sliver.yaml", std::regex_replace(yaml, std::regex("size: \\[26.0, 26.0\\]"),
                                                                     "size: [0.026, 0.026]"));
    const Outcome r = ltmsim(render(sliver, dir / "out", "--threads 2 --no-previews"), dir);
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, sliver.string() + ":5:38: warning: camera.size: the camera's field (0.026 x 0.026 mm, centred on "
                                       "the axis) sees 1.38e-06 of the object's extent (diameter 25 mm); lengths are in "
                                       "mm: was camera.size given in metres?\n");
}

namespace {

// y and its standard error from DIR/image.exr.
struct PatternImage {
    std::vector<float> y, se;
};
PatternImage read_pattern_image(const fs::path& exr) {
    int w = 0, h = 0;
    const auto channels = ltm::read_exr_channels(exr.string(), &w, &h);
    EXPECT_EQ(w, kN);
    EXPECT_EQ(h, kM);
    std::set<std::string> names;
    PatternImage img;
    for (const auto& [name, values] : channels) {
        names.insert(name);
        if (name == "Image") img.y = values;
        if (name == "StdError") img.se = values;
    }
    EXPECT_EQ(names, (std::set<std::string>{"Image", "StdError"}));
    EXPECT_EQ(img.y.size(), static_cast<size_t>(kN * kM));
    EXPECT_EQ(img.se.size(), static_cast<size_t>(kN * kM));
    return img;
}

}  // namespace

// The pattern render against T x, through the files. Two relations:
//  1. Same seed: `render --pattern` traces exactly the paths the plain render traced (the same
//     per-pixel, per-sample random streams, trace/Render.cpp), so y = T x holds per pixel up to
//     the float32 storage of T, y and x (tol::pattern_identity). A pseudo-random pattern makes
//     this per-pixel identity sensitive to any misreading of the pattern (flipped rows or columns,
//     a transposition): x is built here from the convention (PNG row 0 = display row p = 0 = +y
//     edge, l = p * Q + q), independently of the project's image reader.
//  2. Another seed: an independent estimate of the same expectation (tests/validation_render.cpp,
//     expect_linear). With 16 samples per pixel a per-pixel normal Z-test is not justified (the
//     per-pixel means are far from normal), so the test is on the sum over all pixels: pixels
//     are independent, 400 x 16 samples make the sum normal, and its variance is the sum of the
//     per-pixel variances se_T^2 + se_y^2. se_T (the standard error of T x) is exactly the
//     StdError the same-seed pattern render reports (same samples, same values), so no assumption
//     about path weights is needed.
TEST_F(RenderCommand, PatternRenderIsTTimesThePattern) {
    const fs::path plain = dir / "plain";
    ASSERT_EQ(ltmsim(render(scene, plain, "--threads 2"), dir).status, 0);
    const ltm::CsrMatrix T = ltm::read_ltm_npz((plain / "ltm.npz").string());
    ASSERT_EQ(T.rows, kM * kN);
    ASSERT_EQ(T.cols, kP * kQ);

    struct Pattern {
        std::string name;
        std::vector<std::uint8_t> codes;
    };
    std::vector<Pattern> patterns(2);
    patterns[0].name = "all-on";
    patterns[0].codes.assign(static_cast<size_t>(kP * kQ), 255);
    patterns[1].name = "scrambled";
    for (int p = 0; p < kP; ++p)
        for (int q = 0; q < kQ; ++q) patterns[1].codes.push_back(static_cast<std::uint8_t>((37 * p + 101 * q + 13 * p * q) % 256));

    const fs::path scene4 = write("scene4.yaml", scene_yaml(4));
    for (const Pattern& pat : patterns) {
        SCOPED_TRACE(pat.name);
        const fs::path png = dir / (pat.name + ".png");
        write_gray_png(png, kQ, kP, pat.codes);
        std::vector<float> x;
        for (std::uint8_t c : pat.codes) x.push_back(static_cast<float>(c) / 255.0f);
        std::vector<double> tx(static_cast<size_t>(T.rows)), s(static_cast<size_t>(T.rows));
        T.multiply(x.data(), tx.data());
        for (std::int64_t k = 0; k < T.rows; ++k)
            for (auto i = T.indptr[static_cast<size_t>(k)]; i < T.indptr[static_cast<size_t>(k) + 1]; ++i)
                s[static_cast<size_t>(k)] += std::fabs(T.data[static_cast<size_t>(i)] * x[static_cast<size_t>(T.indices[static_cast<size_t>(i)])]);

        // 1. The same seed.
        const fs::path same = dir / (pat.name + "-same");
        const Outcome r = ltmsim(render(scene, same, "--threads 2 --pattern '" + png.string() + "'"), dir);
        ASSERT_EQ(r.status, 0) << r.err;
        expect_outputs(same, {"image.exr", "image.png", "run.json"}, {"ltm.npz"});
        const ltm::Image preview = ltm::read_image((same / "image.png").string());
        EXPECT_EQ(preview.width, kN);
        EXPECT_EQ(preview.height, kM);
        const PatternImage y3 = read_pattern_image(same / "image.exr");
        ASSERT_EQ(y3.y.size(), tx.size());
        int lit = 0;
        for (size_t k = 0; k < tx.size(); ++k) {
            EXPECT_NEAR(y3.y[k], tx[k], ltm::tol::pattern_identity(s[k], std::fabs(y3.y[k])))
                << "camera pixel " << k << " (row " << k / kN << ", column " << k % kN << ")";
            lit += tx[k] > 0;
        }
        EXPECT_GT(lit, kN * kM / 2);

        // 2. An independent seed: the sum over all pixels.
        const fs::path other = dir / (pat.name + "-seed4");
        const Outcome r4 = ltmsim(render(scene4, other, "--threads 2 --pattern '" + png.string() + "'"), dir);
        ASSERT_EQ(r4.status, 0) << r4.err;
        const PatternImage y4 = read_pattern_image(other / "image.exr");
        ASSERT_EQ(y4.y.size(), tx.size());
        double diff = 0, var = 0;
        for (size_t k = 0; k < tx.size(); ++k) {
            diff += tx[k] - y4.y[k];
            var += double(y3.se[k]) * y3.se[k] + double(y4.se[k]) * y4.se[k];
        }
        ASSERT_GT(var, 0);
        const double z = diff / std::sqrt(var);
        EXPECT_LT(std::fabs(z), ltm::tol::normal_two_sided_quantile(ltm::tol::kFamilyAlpha))
            << "sum of T x - y over all pixels " << diff << ", standard error " << std::sqrt(var);
        ::testing::Test::RecordProperty(pat.name + "_z", std::to_string(z));
    }
}

// ---- bad input: exit 2, one message naming the file, nothing written ----

TEST_F(RenderCommand, PatternOfTheWrongSize) {
    const fs::path png = dir / "small.png";
    write_gray_png(png, 10, 10, std::vector<std::uint8_t>(100, 255));
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(scene, out, "--pattern '" + png.string() + "'"), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(png.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("10 x 10"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("40 x 40"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("display.resolution"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, PatternThatDoesNotExist) {
    const fs::path png = dir / "nope.png";
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(scene, out, "--pattern '" + png.string() + "'"), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(png.string()), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

// A pattern render that fails part-way leaves the folder's earlier files as they were: its image
// files are made durable together (io::CommitGroup) and put in place only when all are written.
// Here the preview cannot be written (its path is a folder), after image.exr and image.npz were:
// the earlier render's image.exr, image.npz and run.json keep their bytes (before, the new
// image.exr replaced the old one and was then removed with it).
TEST_F(RenderCommand, APatternRenderThatFailsLeavesTheEarlierFilesAsTheyWere) {
    const fs::path png = dir / "on.png";
    write_gray_png(png, kQ, kP, std::vector<std::uint8_t>(static_cast<std::size_t>(kP * kQ), 255));
    const fs::path out = dir / "out";
    ASSERT_EQ(ltmsim(render(scene, out, "--threads 2 --pattern '" + png.string() + "'"), dir).status, 0);
    ASSERT_TRUE(fs::remove(out / "image.png"));
    ASSERT_TRUE(fs::create_directory(out / "image.png"));
    const auto before = snapshot(out);
    ASSERT_FALSE(before.at("image.exr").empty());

    // Another seed: the new image differs, so a replaced file would show.
    const fs::path other = write("other.yaml", scene_yaml(4));
    const Outcome r = ltmsim(render(other, out, "--threads 2 --overwrite --pattern '" + png.string() + "'"), dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find((out / "image.png").string()), std::string::npos) << r.err;
    EXPECT_TRUE(snapshot(out) == before) << "an earlier file changed or went";
    expect_outputs(out, {"image.exr", "image.npz", "run.json"});
}

TEST_F(RenderCommand, UnreadableOrMalformedScene) {
    const fs::path out = dir / "out";
    const fs::path missing = dir / "nope.yaml";
    Outcome r = ltmsim(render(missing, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(missing.string() + ": cannot read scene file"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));

    r = ltmsim(render(dir, out), dir);  // a folder is not a scene file
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(dir.string()), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));

    const fs::path malformed = write("malformed.yaml", "object: [1, 2\n");
    r = ltmsim(render(malformed, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(malformed.string() + ":"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("malformed YAML"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

// A scene indented with tabs (an editor's habit): the message says so, at the first tab's line
// and column, rather than yaml-cpp's "illegal map value" at the end of the key (3:12 here).
TEST_F(RenderCommand, ASceneIndentedWithATabNamesTheTab) {
    const fs::path tabbed = write("tabbed.yaml",
                                  "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}\n"
                                  "camera:\n"
                                  "\tresolution: [20, 20]\n"
                                  "\tsize: [26.0, 26.0]\n"
                                  "display: {resolution: [40, 40], size: [80.0, 80.0], z: 60.0}\n");
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(tabbed, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.err, tabbed.string() + ":3:1: malformed YAML: a tab in the indentation (YAML does not allow tabs for indentation; "
                         "use spaces)\n");
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, SceneWithAnUnknownKey) {
    const fs::path bad = write("typo.yaml",
                               "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}\n"
                               "camera:\n"
                               "  resolution: [20, 20]\n"
                               "  size: [26.0, 26.0]\n"
                               "  numerical_aperture: 0.05\n"
                               "  samples_per_pixle: 16\n"
                               "display: {resolution: [40, 40], size: [80.0, 80.0], z: 60.0}\n"
                               "seed: 3\n");
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(bad, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(bad.string() + ":6:3: camera.samples_per_pixle: unknown key"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, SceneWithAWrongType) {
    std::string text = scene_yaml(3);
    text.replace(text.find("samples_per_pixel: 16"), 21, "samples_per_pixel: many");
    const fs::path bad = write("type.yaml", text);
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(bad, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(bad.string() + ":5:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("camera.samples_per_pixel"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, OutputFolderWhoseParentDoesNotExist) {
    const fs::path out = dir / "missing" / "out";
    const Outcome r = ltmsim(render(scene, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "missing"));
}

TEST_F(RenderCommand, OutputThatIsAFile) {
    const fs::path out = write("out", "the user's own file");
    const Outcome r = ltmsim(render(scene, out), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
    EXPECT_EQ(slurp(out), "the user's own file");
}

TEST_F(RenderCommand, AnalyticRepresentationOfAPitIsRefused) {
    // scenes/examples/pit.yaml: a surface-breaking bubble cuts the front face; the analytic
    // representation only handles defects that neither touch a face nor each other.
    const std::string pit = ltm::test::source_dir() + "/scenes/examples/pit.yaml";
    const fs::path out = dir / "out";
    const Outcome r = ltmsim(render(pit, out, "--representation analytic"), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(pit), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("analytic representation"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("defect 0"), std::string::npos) << r.err;  // the reason names the defect
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, UsageErrorsExitTwo) {
    const fs::path out = dir / "out";
    EXPECT_EQ(ltmsim(render(scene, out, "--representation exact"), dir).status, 2);
    EXPECT_EQ(ltmsim(render(scene, out, "--threads -1"), dir).status, 2);
    EXPECT_EQ(ltmsim("render '" + scene.string() + "'", dir).status, 2);  // no -o
    EXPECT_FALSE(fs::exists(out));
}

// Every integer option of every command takes whole numbers in a stated range and says so in
// words, naming the option: a negative, fractional, too large (beyond an int) or non-numeric value
// is a usage error (exit 2, one short message, nothing written), refused before any input is read.
TEST_F(RenderCommand, IntegerOptionsStateTheirRangeInWords) {
    const fs::path out = dir / "out";
    const std::string s = "'" + scene.string() + "'", o = "'" + out.string() + "'";
    const std::string threads = "expected a whole number >= 1, or 0 for all cores";
    struct Case {
        std::string args, message;
    };
    std::vector<Case> cases;
    for (const char* bad : {"-1", "1.5", "99999999999", "abc", "+-2"})
        cases.push_back({"render " + s + " -o " + o + " --threads " + bad,
                         fmt::format("--threads: {}; got '{}'", threads, bad)});
    // The other commands that compute (their positional arguments need not exist: the option is
    // refused first).
    for (const std::string& command :
         {"mesh " + s + " -o " + (dir / "m.ply").string(), "trace-rays " + s + " --rays r.jsonl", "validate " + s,
          "features " + o, "experiment " + o + " -o " + o, "dataset " + s + " -o " + o,
          "acquire " + o + " --patterns 8"})
        cases.push_back({command + " --threads -1", "--threads: " + threads + "; got '-1'"});
    cases.push_back({"dataset " + s + " -o " + o + " --jobs -1",
                     "--jobs: expected a whole number >= 1, or 0 for threads + 1; got '-1'"});
    cases.push_back({"validate " + s + " --density 0", "--density: expected a whole number >= 1; got '0'"});
    cases.push_back({"render " + s + " -o " + o + " --estimator split --split-depth " + std::to_string(ltm::kMaxSplitDepth + 1),
                     fmt::format("--split-depth: expected a whole number from 0 to {}; got '{}'", ltm::kMaxSplitDepth,
                                 ltm::kMaxSplitDepth + 1)});
    cases.push_back({"render " + s + " -o " + o + " --estimator split --split-depth 1.5",
                     fmt::format("--split-depth: expected a whole number from 0 to {}; got '1.5'", ltm::kMaxSplitDepth)});
    // A negative block side would otherwise fall back to the default block silently.
    cases.push_back({"render " + s + " -o " + o + " --dark-block -5", "--dark-block: expected a whole number >= 0; got '-5'"});
    cases.push_back({"features " + o + " --dark-block -1", "--dark-block: expected a whole number >= 0; got '-1'"});
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const Outcome r = ltmsim(c.args, dir);
        EXPECT_EQ(r.status, 2);
        EXPECT_EQ(r.err.substr(0, r.err.find('\n')), c.message);
        EXPECT_LT(r.err.size(), 200u) << r.err;
        EXPECT_FALSE(fs::exists(out));
    }
    // The bounds themselves are taken.
    EXPECT_EQ(ltmsim(render(scene, out, "--threads +1 --estimator split --split-depth 0 --dark-block 0"), dir).status, 0);
}

TEST_F(RenderCommand, TheEstimatorComesFromTheSceneOrTheCommandLineAndRunJsonRecordsIt) {
    // tracing: {estimator: split, split_depth: 5} in the scene; --estimator and --split-depth
    // override it. run.json records what ran (top level and in the resolved scene), with the
    // split and branch counts. --estimator sample on the split scene is the plain scene's render
    // byte for byte, and a split render does not depend on --threads either.
    const fs::path split_scene = write("split.yaml", scene_yaml(3) + "tracing: {estimator: split, split_depth: 5}\n");
    const auto record = [&](const fs::path& out) { return ltm::io::read_json_file((out / "run.json").string(), "run record"); };
    const Outcome a = ltmsim(render(split_scene, dir / "split", "--threads 1"), dir);
    ASSERT_EQ(a.status, 0) << a.err;
    const auto ra = record(dir / "split");
    EXPECT_EQ(ra["estimator"]["estimator"], "split");
    EXPECT_EQ(ra["estimator"]["split_depth"], 5);
    EXPECT_EQ(ra["scene"]["tracing"], ra["estimator"]);
    EXPECT_GT(ra["path_statistics"]["splits"].get<std::uint64_t>(), 0u);
    EXPECT_GT(ra["path_statistics"]["branches"].get<std::uint64_t>(), ra["path_statistics"]["paths"].get<std::uint64_t>());

    ASSERT_EQ(ltmsim(render(split_scene, dir / "split2", "--threads 2"), dir).status, 0);
    EXPECT_TRUE(slurp(dir / "split" / "ltm.npz") == slurp(dir / "split2" / "ltm.npz"));

    ASSERT_EQ(ltmsim(render(split_scene, dir / "deep", "--split-depth 7"), dir).status, 0);
    EXPECT_EQ(record(dir / "deep")["estimator"]["split_depth"], 7);
    EXPECT_FALSE(slurp(dir / "deep" / "ltm.npz") == slurp(dir / "split" / "ltm.npz"));

    ASSERT_EQ(ltmsim(render(split_scene, dir / "sampled", "--estimator sample"), dir).status, 0);
    ASSERT_EQ(ltmsim(render(scene, dir / "plain"), dir).status, 0);
    const auto rs = record(dir / "sampled");
    EXPECT_EQ(rs["estimator"], (ltm::io::Json{{"estimator", "sample"}}));
    EXPECT_EQ(rs["path_statistics"]["splits"], 0);
    EXPECT_EQ(record(dir / "plain")["estimator"], rs["estimator"]);
    EXPECT_TRUE(slurp(dir / "sampled" / "ltm.npz") == slurp(dir / "plain" / "ltm.npz"));

    ASSERT_EQ(ltmsim(render(scene, dir / "cli", "--estimator split"), dir).status, 0);
    EXPECT_EQ(record(dir / "cli")["estimator"]["split_depth"], 4);  // kDefaultSplitDepth
}

TEST_F(RenderCommand, BadEstimatorInputExitsTwoWithALocatedMessage) {
    const fs::path out = dir / "out";
    struct Case {
        std::string tracing, options, message;
    };
    const std::vector<Case> cases{
        {"", "--split-depth -1", "--split-depth"},
        {"", "--split-depth 17", "--split-depth"},
        {"", "--estimator splitting", "--estimator"},
        {"", "--split-depth 3", "--split-depth applies only to the split estimator"},
        {"tracing: {estimator: split}\n", "--estimator sample --split-depth 3", "--split-depth applies only"},
        // Scene keys: file:line:column and the key path (the tracing line is line 8).
        {"tracing: {estimator: splitt}\n", "", ":8:22: tracing.estimator: expected sample or split"},
        {"tracing: {estimator: split, split_depth: -1}\n", "", ":8:42: tracing.split_depth: expected an integer in [0, 16]"},
        {"tracing: {estimator: split, split_depth: 2.5}\n", "", ":8:42: tracing.split_depth:"},
        {"tracing: {split_depth: 3}\n", "", ":8:11: tracing.split_depth: applies only to 'estimator: split'"},
        {"tracing: {estimator: split, depth: 3}\n", "", ":8:29: tracing.depth: unknown key"},
        {"tracing: split\n", "", ":8:10: tracing:"},
    };
    int i = 0;
    for (const Case& c : cases) {
        const fs::path file = write("bad" + std::to_string(i++) + ".yaml", scene_yaml(3) + c.tracing);
        const Outcome r = ltmsim(render(file, out, c.options), dir);
        EXPECT_EQ(r.status, 2) << c.tracing << c.options << ": " << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.tracing << c.options << ": " << r.err;
        if (c.options.empty()) {
            EXPECT_NE(r.err.find(file.string() + ":8:"), std::string::npos) << r.err;
        }
        EXPECT_FALSE(fs::exists(out)) << c.tracing << c.options;
    }
}

// ---- --max-memory: T streamed to ltm.npz in row blocks when it exceeds the budget ----

TEST_F(RenderCommand, AStreamedRenderWritesTheSameFilesAsOneThatKeepsT) {
    // A budget of 2^-30 GiB = 1 byte: every row is streamed (spilled beside ltm.npz, the archive
    // written from the spill files, the features computed from the same blocks). Every file is
    // byte-identical to the render that keeps T whole; run.json says which way T went.
    const fs::path whole = dir / "whole", streamed = dir / "streamed";
    Outcome r = ltmsim(render(scene, whole, "--threads 2"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = ltmsim(render(scene, streamed, "--threads 1 --max-memory 9.313225746154785e-10 --verbose"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("T streamed"), std::string::npos) << r.err;
    expect_outputs(streamed, {"ltm.npz", "run.json", "features.exr", "features.npz", "reference.exr"});
    for (const char* f : {"ltm.npz", "features.exr", "features.npz", "reference.exr"})
        EXPECT_EQ(slurp(whole / f), slurp(streamed / f)) << f << " differs";

    const ltm::io::Json a = ltm::io::read_json_file((whole / "run.json").string(), "run record");
    const ltm::io::Json b = ltm::io::read_json_file((streamed / "run.json").string(), "run record");
    EXPECT_EQ(a["result"]["streamed"], false);
    EXPECT_EQ(b["result"]["streamed"], true);
    EXPECT_EQ(a["result"]["nnz"], b["result"]["nnz"]);
    EXPECT_EQ(b["memory"]["streamed"], true);
    EXPECT_EQ(b["memory"]["max_memory_bytes"], 1);
    EXPECT_EQ(a["memory"]["streamed"], false);
    const std::uint64_t nnz = a["result"]["nnz"].get<std::uint64_t>();
    EXPECT_EQ(a["memory"]["matrix_bytes"].get<std::uint64_t>(), 8 * nnz + 8 * (kM * kN + 1));
    for (const ltm::io::Json* j : {&a, &b}) {
        const ltm::io::Json& m = (*j)["memory"];
        ASSERT_TRUE(m.contains("render_peak_rss_bytes")) << m.dump();
        EXPECT_GE(m["render_peak_rss_bytes"].get<std::uint64_t>(), m["render_start_rss_bytes"].get<std::uint64_t>());
        EXPECT_GE(m["process_peak_rss_bytes"].get<std::uint64_t>(), m["render_peak_rss_bytes"].get<std::uint64_t>());
        EXPECT_TRUE(m["peak_rss_method"].is_string());
    }

    if (!python_has_scipy(dir)) LTM_INTEROP_SKIP() << kPython << " cannot import numpy and scipy.sparse";
    const Outcome py = run_shell(std::string(kPython) + " -c 'import sys, scipy.sparse as sp; T = sp.load_npz(sys.argv[1]); "
                                                        "print(T.format, T.shape[0], T.shape[1], T.nnz, T.has_canonical_format)' '" +
                                     (streamed / "ltm.npz").string() + "'",
                                 dir);
    EXPECT_EQ(py.status, 0) << py.err;
    EXPECT_EQ(py.out, "csr " + std::to_string(kM * kN) + " " + std::to_string(kP * kQ) + " " + std::to_string(nnz) + " True\n")
        << py.err;
}

TEST_F(RenderCommand, BadMaxMemoryExitsTwoNamingTheOptionAndWritesNothing) {
    const fs::path out = dir / "out";
    for (const char* v : {"0", "-1", "-0.5", "abc", "1e", "8GiB", "nan", "inf", "''"}) {
        SCOPED_TRACE(v);
        const Outcome r = ltmsim(render(scene, out, std::string("--max-memory ") + v), dir);
        EXPECT_EQ(r.status, 2) << r.err;
        EXPECT_EQ(r.err.rfind("ltmsim render: --max-memory: ", 0), 0u) << r.err;
        EXPECT_FALSE(fs::exists(out));
    }
    EXPECT_NE(ltmsim(render(scene, out, "--max-memory abc"), dir).err.find("'abc' is not a number"), std::string::npos);
    EXPECT_NE(ltmsim(render(scene, out, "--max-memory 0"), dir).err.find("0 GiB is not positive"), std::string::npos);
    // A pattern render keeps no T: the budget does not apply, and saying so beats ignoring it.
    const fs::path pattern = dir / "p.png";
    write_gray_png(pattern, kQ, kP, std::vector<std::uint8_t>(static_cast<size_t>(kQ * kP), 255));
    const Outcome r = ltmsim(render(scene, out, "--pattern '" + pattern.string() + "' --max-memory 1"), dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("--max-memory applies to T"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCommand, NoPreviewsLeavesOutThePngsAndChangesNothingElse) {
    // --no-previews skips DIR/features/*.png (and, with a pattern, DIR/image.png): the files it
    // does write are byte for byte those of a render with previews, and run.json says so.
    const fs::path with = dir / "with", without = dir / "without";
    Outcome r = ltmsim(render(scene, with, "--threads 2"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = ltmsim(render(scene, without, "--threads 2 --no-previews"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(fs::is_directory(with / "features"));
    EXPECT_FALSE(fs::exists(without / "features"));
    for (const char* f : {"ltm.npz", "features.exr", "features.npz", "reference.exr"})
        EXPECT_EQ(slurp(with / f), slurp(without / f)) << f << " differs";
    const auto previews = [](const fs::path& out) {
        return ltm::io::read_json_file((out / "run.json").string(), "run record")["result"]["previews"];
    };
    EXPECT_EQ(previews(with), true);
    EXPECT_EQ(previews(without), false);

    const fs::path png = dir / "on.png", pat = dir / "pattern";
    write_gray_png(png, kQ, kP, std::vector<std::uint8_t>(static_cast<size_t>(kP * kQ), 255));
    r = ltmsim(render(scene, pat, "--threads 2 --no-previews --pattern '" + png.string() + "'"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    expect_outputs(pat, {"image.exr", "image.npz", "run.json"}, {"image.png", "ltm.npz"});
    EXPECT_EQ(previews(pat), false);
}
