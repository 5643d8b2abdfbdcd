// An experiment's numbers (study/Experiment.h) on small rendered scenes: contrast.md names the best
// new feature only when there are candidates, and judges it on the measured images when there are
// any; a scratch gets its own size columns and a surround along its path; the montage's rows share
// one colour scale.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "features/Plot.h"
#include "study/Experiment.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;
using namespace ltm;

namespace {

// A 4 mm window; 24 x 24 camera pixels over 12 mm (0.5 mm pitch), 16 samples per pixel.
std::string window_scene(const std::string& defects) {
    return "object: {type: window, thickness: 4.0, diameter: 20.0, ior: 1.5}\n"
           "defects:" +
           (defects.empty() ? std::string(" []\n") : "\n" + defects) +
           "camera: {resolution: [24, 24], size: [12.0, 12.0], numerical_aperture: 0.02, samples_per_pixel: 16}\n"
           "display: {resolution: [60, 60], size: [30.0, 30.0], z: 30.0}\n"
           "seed: 3\n";
}
const std::string kBubble = "  - {type: bubble, center: [-2.0, 1.0, 0.0], radius: 0.8}\n";
// A straight, wide and shallow V scratch on the front face (z = -2), 0.8 mm wide and 0.05 mm deep,
// from (1, -4) to (5, -1): 5 mm long on the flat face.
const std::string kScratch =
    "  - {type: scratch, surface: front, profile: V, width: 0.8, depth: 0.05, start: [1.0, -4.0], end: [5.0, -1.0]}\n";

class Experiment : public test::TempDirTest {
protected:
    // Writes the scenes and experiment.yaml (with `extra` appended), loads and renders them.
    void make(const std::string& extra, const std::string& defects = kBubble) {
        write("free.yaml", window_scene(""));
        write("defects.yaml", window_scene(defects));
        write("experiment.yaml", "scenes:\n  - {file: free.yaml, label: free}\n  - {file: defects.yaml, label: defects}\n"
                                 "reference: free.yaml\nmontage: [BrightField, ScatterCount]\n" +
                                     extra);
        spec = load_experiment(path("experiment.yaml"));
        scenes = load_experiment_scenes(spec);
        ReferenceCache cache;
        for (ExperimentScene& s : scenes) render_experiment_scene(s, 2, &cache);
    }
    ExperimentSpec spec;
    std::vector<ExperimentScene> scenes;
};

std::vector<std::string> split(const std::string& s, char c) {
    std::vector<std::string> out;
    std::string x;
    std::stringstream ss(s);
    while (std::getline(ss, x, c)) out.push_back(x);
    if (!s.empty() && s.back() == c) out.emplace_back();
    return out;
}

// contrast.csv as rows of named fields.
std::vector<std::map<std::string, std::string>> rows_of(const std::string& csv) {
    std::stringstream in(csv);
    std::string line;
    std::getline(in, line);
    const auto header = split(line, ',');
    std::vector<std::map<std::string, std::string>> rows;
    while (std::getline(in, line)) {
        const auto f = split(line, ',');
        EXPECT_EQ(f.size(), header.size()) << line;
        std::map<std::string, std::string> row;
        for (std::size_t i = 0; i < header.size() && i < f.size(); ++i) row[header[i]] = f[i];
        rows.push_back(row);
    }
    return rows;
}

}  // namespace

TEST_F(Experiment, WithoutCandidatesNoFeatureIsNamed) {
    make("");
    ASSERT_TRUE(spec.candidates.empty());
    const ExperimentResult r = evaluate_experiment(spec, scenes);
    EXPECT_EQ(r.best, "");
    EXPECT_EQ(r.headline, "No new feature is judged: experiment.yaml lists no candidates.");
    EXPECT_EQ(r.markdown.find("****"), std::string::npos) << r.markdown;
    EXPECT_NE(r.markdown.find(r.headline), std::string::npos);
}

TEST_F(Experiment, NoRenderedCnrIsInfinite) {
    make("candidates: [Deflection, ScatterCount]\n");
    const ExperimentResult r = evaluate_experiment(spec, scenes);
    const auto rows = rows_of(r.csv);
    ASSERT_FALSE(rows.empty());
    for (const auto& row : rows) {
        const double c = std::stod(row.at("cnr"));
        EXPECT_TRUE(std::isfinite(c)) << row.at("channel") << ": " << row.at("cnr");
        // The deflection map's surround shows the reference's noise: not exactly 0.
        if (row.at("channel") == "Deflection") EXPECT_GT(std::stod(row.at("surround_std")), 0.0);
    }
    EXPECT_EQ(r.markdown.find("inf"), std::string::npos) << r.markdown;
}

TEST_F(Experiment, TheBestFeatureIsJudgedOnTheMeasuredImages) {
    make("candidates: [ScatterCount, RobustScatterCount]\n");
    const ExperimentResult rendered = evaluate_experiment(spec, scenes);
    ASSERT_FALSE(rendered.best.empty());
    const std::string other = rendered.best == "ScatterCount" ? "RobustScatterCount" : "ScatterCount";
    // Measured images: the rendered ones, except that the rendered winner reads noise (0 .. 100
    // at random) in every scene: many false positives, no contrast. The other must win.
    Measurement m;
    m.instrument = "a test instrument";
    std::uint64_t x = 12345;
    for (const ExperimentScene& s : scenes) {
        MeasuredImages mi;
        mi.features = s.run.features;
        for (auto& [name, v] : mi.features.channels) {
            mi.how[name] = "test method (K = 7)";
            mi.resolution[name] = 1;
            if (name != rendered.best) continue;
            for (float& f : v) {
                x = x * 6364136223846793005ull + 1442695040888963407ull;
                f = static_cast<float>((x >> 40) % 101);
            }
        }
        m.scenes.push_back(mi);
    }
    const ExperimentResult measured = evaluate_experiment(spec, scenes, &m);
    EXPECT_EQ(measured.best, other);
    EXPECT_NE(measured.headline.find("Best new feature measured under the sensor model: **" + other + "**, by test method (K = 7): "),
              std::string::npos)
        << measured.headline;
    EXPECT_NE(measured.markdown.find("## Measured: the images an instrument would take (a test instrument)"),
              std::string::npos);
    for (const auto& row : rows_of(measured.csv)) EXPECT_EQ(row.at("measured_by"), "test method (K = 7)");
}

TEST_F(Experiment, AScratchHasItsOwnSizeColumnsAndASurroundAlongItsPath) {
    make("", kBubble + kScratch);
    const ExperimentResult r = evaluate_experiment(spec, scenes);
    bool bubble = false, scratch = false;
    for (const auto& row : rows_of(r.csv)) {
        if (row.at("channel") != "BrightField") continue;
        if (row.at("kind") == "bubble") {
            bubble = true;
            for (const char* c : {"semi_axis_a_mm", "semi_axis_b_mm", "semi_axis_c_mm"}) EXPECT_EQ(std::stod(row.at(c)), 0.8);
            for (const char* c : {"width_mm", "depth_mm", "length_mm"}) EXPECT_EQ(row.at(c), "");
        } else {
            ASSERT_EQ(row.at("kind"), "scratch");
            scratch = true;
            EXPECT_EQ(std::stod(row.at("width_mm")), 0.8);
            EXPECT_EQ(std::stod(row.at("depth_mm")), 0.05);
            EXPECT_NEAR(std::stod(row.at("length_mm")), 5.0, 1e-9);  // a segment on the flat face
            for (const char* c : {"semi_axis_a_mm", "semi_axis_b_mm", "semi_axis_c_mm"}) EXPECT_EQ(row.at(c), "");
        }
    }
    EXPECT_TRUE(bubble);
    EXPECT_TRUE(scratch);
    // The surround: pixels whose centre ray (straight through the window) passes between
    // R + 2 r + 2 px and R + 5 r + 4 px of the scratch's centre line, R = hypot(0.8 / 2, 0.05) =
    // 0.40311 (the tube that holds the cross-section: the scratch reaches 0.4 mm to each side),
    // r = min(0.8 / 2, 0.05) = 0.05, px = 0.5: at a distance in (1.50311, 2.65311] mm of the
    // segment from (1, -4) to (5, -1). (A shell beyond a tube of radius r instead would start at
    // 1.15 mm.) The centre rays cross the window straight, and the centre line lies on the front
    // face, so the 3-D distance is the lateral one.
    const std::vector<DefectRegions>& g = r.regions[1];
    ASSERT_EQ(g.size(), 2u);
    ASSERT_EQ(g[1].kind, "scratch");
    ASSERT_FALSE(g[1].surround.pixels.empty());
    for (int k : g[1].surround.pixels) {
        const double x = -6.0 + (k % 24 + 0.5) * 0.5, y = 6.0 - (k / 24 + 0.5) * 0.5;
        const double t = std::clamp(((x - 1) * 4 + (y + 4) * 3) / 25.0, 0.0, 1.0);
        const double d = std::hypot(x - (1 + 4 * t), y - (-4 + 3 * t));
        const double R = std::hypot(0.4, 0.05);
        EXPECT_GT(d, R + 1.1 - 1e-9) << k;
        EXPECT_LE(d, R + 2.25 + 1e-9) << k;
    }
    EXPECT_EQ(g[1].describe(), "scratch 0.8 x 0.05 mm, 5 mm long");
}

TEST_F(Experiment, MontageRowsShareOneColourScale) {
    make("");
    // BrightField constant in each scene: 0.25 and 0.75. On one scale for the row the first is
    // drawn in viridis's first colour and the second in its last, every data pixel of each cell
    // (24 x 24 cells of 12 x 12 output pixels); each on a scale of its own, both would take the
    // map's middle colour (a constant image's range is widened around it).
    for (auto& [name, v] : scenes[0].run.features.channels)
        if (name == "BrightField") std::fill(v.begin(), v.end(), 0.25f);
    for (auto& [name, v] : scenes[1].run.features.channels)
        if (name == "BrightField") std::fill(v.begin(), v.end(), 0.75f);
    const ExperimentResult r = evaluate_experiment(spec, scenes);
    auto count = [&](const Rgb& c) {
        long n = 0;
        for (int i = 0; i < r.montage.height; ++i)
            for (int j = 0; j < r.montage.width; ++j) {
                bool same = true;
                for (int k = 0; k < 3; ++k)
                    same = same && std::lround(255 * r.montage.at(i, j, k)) == std::lround(255 * c[static_cast<std::size_t>(k)]);
                n += same;
            }
        return n;
    };
    const long cell = 288L * 288L;
    EXPECT_GE(count(viridis(0.0)), cell - 2000);  // less the ring around the bubble in the second
    EXPECT_GE(count(viridis(1.0)), cell - 2000);
}
