// `ltmsim features DIR` and the feature outputs of `ltmsim render`: the paper's features checked
// against a direct computation from ltm.npz (scipy), the channel names, and the bad-input contract.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "io/Image.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::slurp;

// The render folder dir/r of the small bubble scene (tests/TestSupport.h).
using FeaturesCommand = ltm::test::RenderedFolderTest;

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
