// The paper's experiment (scenes/paper) end to end: `ltmsim experiment` renders the four scenes
// and its numbers must uphold the paper's claim: for the smallest bubbles (half a pixel's area),
// ScatterCount's and ScatterWidth's contrast-to-noise ratio exceeds the bright field's. The robust
// variants must remove sampling-noise false positives in the defect-free scene.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "io/Image.h"
#include "study/Experiment.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

struct Row {
    std::string scene, channel;
    int defect = -1;
    double radius = 0, cnr = 0;
};

std::vector<std::string> split(const std::string& s, char c) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string x;
    while (std::getline(ss, x, c)) out.push_back(x);
    return out;
}

}  // namespace

TEST(PaperExperiment, ScatterFeaturesBeatTheBrightFieldOnTheSmallestBubbles) {
    // A fresh folder for the output folder (made by the command) and the command's log (stdout
    // and stderr together), both kept when the test fails.
    const fs::path work = ltm::test::make_test_dir();
    const fs::path out = work / "out";
    const std::string cmd = ltm::test::ltmsim_exe() + " experiment " + ltm::test::source_dir() + "/scenes/paper -o " + out.string() +
                            " > " + (work / "experiment.log").string() + " 2>&1";
    ASSERT_EQ(ltm::test::exit_status(std::system(cmd.c_str())), 0) << cmd;
    ASSERT_TRUE(fs::exists(out / "contrast.md"));
    const ltm::Image montage = ltm::read_image((out / "montage.png").string());
    EXPECT_GT(montage.width, 800);
    EXPECT_GT(montage.height, 600);
    for (const char* s : {"defect-free", "bubbles-r0.5", "bubbles-r1", "bubbles-r2"}) {
        EXPECT_TRUE(fs::exists(out / s / "ltm.npz")) << s;
        EXPECT_TRUE(fs::exists(out / s / "features.exr")) << s;
        EXPECT_TRUE(fs::exists(out / s / "regions.json")) << s;
    }
    // The regions the table measured, for later measurements of the same scene (ltmsim acquire):
    // three bubbles in bubbles-r1, each with defect and surround pixels; none in the defect-free scene.
    const auto regions = ltm::read_regions_json((out / "bubbles-r1" / "regions.json").string(), 100 * 100);
    ASSERT_EQ(regions.size(), 3u);
    for (const auto& g : regions) {
        EXPECT_GE(g.defect_pixels.pixels.size(), 2u);
        EXPECT_GE(g.surround.pixels.size(), 2u);
    }
    EXPECT_TRUE(ltm::read_regions_json((out / "defect-free" / "regions.json").string(), 100 * 100).empty());

    std::ifstream in(out / "contrast.csv");
    std::string line;
    std::getline(in, line);  // header
    std::map<std::string, std::map<int, double>> small;  // channel -> defect -> CNR (r = 0.5 scene)
    std::map<std::string, int> false_positives;
    while (std::getline(in, line)) {
        const auto f = split(line, ',');
        ASSERT_GE(f.size(), 10u) << line;
        if (f[9].rfind("false_positives=", 0) == 0) {
            false_positives[f[3]] = std::stoi(f[9].substr(16));
            continue;
        }
        if (f[0] == "bubbles-r0.5") small[f[3]][std::stoi(f[1])] = std::stod(f[7]);
    }
    ASSERT_EQ(small["BrightField"].size(), 3u);
    for (int k = 0; k < 3; ++k) {
        const double bf = small["BrightField"][k];
        EXPECT_GT(bf, 0.0);
        EXPECT_GT(small["ScatterCount"][k], bf) << "bubble " << k;
        EXPECT_GT(small["ScatterWidth"][k], bf) << "bubble " << k;
    }
    // The paper's "white dots" are rare far-off paths: the energy-robust diameter discards them.
    EXPECT_LT(false_positives["RobustScatterDiameter"], false_positives["ScatterDiameter"] / 10);
    EXPECT_LE(false_positives["RobustScatterCount"], false_positives["ScatterCount"]);
    fs::remove_all(work);
}
