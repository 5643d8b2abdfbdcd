// `ltmsim acquire DIR`: a small end-to-end run (files, channels, report, thread-count
// independence, the CNR in given regions) and the bad-input contract (exit 2, a located message,
// nothing written).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "io/Image.h"
#include "io/Json.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::slurp;

// The render folder dir/r of the small bubble scene (tests/TestSupport.h): 16 x 12 camera, 50 x 40
// display, so Gray code needs 2 (ceil log2 40 + ceil log2 50) = 24 patterns.
using AcquireCommand = ltm::test::RenderedFolderTest;

std::map<std::string, std::vector<float>> channels_of(const fs::path& p) {
    int w = 0, h = 0;
    const auto c = ltm::read_exr_channels(p.string(), &w, &h);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 12);
    return {c.begin(), c.end()};
}

TEST_F(AcquireCommand, GrayCodeRunWritesFeatureImagesAndAReport) {
    std::string err;
    ASSERT_EQ(run("acquire " + r() + " --method gray --patterns 24 32 --threads 2", &err), 0) << err;
    const fs::path out = dir / "r" / "acquire-gray";
    for (const char* f : {"features-K24.exr", "features-K32.exr", "report.json", "plot.png"})
        EXPECT_TRUE(fs::exists(out / f)) << f;
    const auto ch = channels_of(out / "features-K32.exr");
    for (const char* name : {"MeanX", "MeanY", "DeflectionX", "DeflectionY", "Deflection"})
        EXPECT_TRUE(ch.count(name)) << name;
    const ltm::io::Json rep = ltm::io::read_json_file((out / "report.json").string(), "report");
    ASSERT_EQ(rep["runs"].size(), 2u);
    EXPECT_EQ(rep["runs"][0]["patterns"], 24);
    EXPECT_EQ(rep["runs"][1]["patterns"], 32);
    EXPECT_TRUE(rep["runs"][1]["errors"].contains("MeanX"));
    EXPECT_EQ(rep["method"], "gray");
    // No regions.json in a plain render folder: no defects measured.
    EXPECT_EQ(rep["runs"][0]["defects"].size(), 0u);
}

TEST_F(AcquireCommand, ResultsDoNotDependOnTheThreadCount) {
    ASSERT_EQ(run("acquire " + r() + " --method compressive --stripe-width 4 --patterns 60 --threads 1 -o " +
                  (dir / "one").string()), 0);
    ASSERT_EQ(run("acquire " + r() + " --method compressive --stripe-width 4 --patterns 60 --threads 2 -o " +
                  (dir / "two").string()), 0);
    EXPECT_EQ(slurp(dir / "one" / "features-K60.exr"), slurp(dir / "two" / "features-K60.exr"));
    EXPECT_TRUE(channels_of(dir / "one" / "features-K60.exr").count("ScatterCount"));
}

TEST_F(AcquireCommand, ContrastIsMeasuredInTheGivenRegions) {
    // A hand-made regions.json (as `ltmsim experiment` writes): the 4 centre pixels and a ring.
    std::ofstream(dir / "r" / "regions.json")
        << R"({"defects": [{"defect": 0, "kind": "bubble", "size": {"semi_axis_a_mm": 0.6, "semi_axis_b_mm": 0.6,)"
        << R"( "semi_axis_c_mm": 0.6}, "defect_pixels": [87, 88, 103, 104],)"
        << R"( "surround_pixels": [53, 54, 55, 56, 57, 58, 69, 74, 133, 138, 149, 150, 151, 152, 153, 154]}]})";
    std::string err;
    ASSERT_EQ(run("acquire " + r() + " --method stripes --patterns 90", &err), 0) << err;
    const ltm::io::Json rep = ltm::io::read_json_file((dir / "r" / "acquire-stripes" / "report.json").string(), "report");
    const auto& d = rep["runs"][0]["defects"];
    ASSERT_EQ(d.size(), 1u);
    for (const char* kind : {"exact", "acquired", "sensor"}) {
        EXPECT_TRUE(d[0]["channels"]["ScatterRows"].contains(kind)) << kind;
        EXPECT_TRUE(d[0]["bright_field"].contains(kind)) << kind;
    }
    EXPECT_EQ(rep["visible"].size(), 1u);
    EXPECT_EQ(d[0]["kind"], "bubble");
    EXPECT_EQ(d[0]["label"], "bubble r = 0.6 mm");
}

// The summary says what its numbers are: one line per K naming the error measure, and with
// regions each defect's CNR under the sensor in the method's main channel beside the bright field.
TEST_F(AcquireCommand, TheSummaryLabelsItsNumbers) {
    std::ofstream(dir / "r" / "regions.json")
        << R"({"defects": [{"defect": 0, "kind": "bubble", "size": {"semi_axis_a_mm": 0.6, "semi_axis_b_mm": 0.6,)"
        << R"( "semi_axis_c_mm": 0.6}, "defect_pixels": [87, 88, 103, 104],)"
        << R"( "surround_pixels": [53, 54, 55, 56, 57, 58, 69, 74, 133, 138, 149, 150, 151, 152, 153, 154]}]})";
    const ltm::test::Outcome o = ltm::test::ltmsim("acquire " + r() + " --method stripes --patterns 18 90", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const auto lines = o.lines();
    ASSERT_EQ(lines.size(), 4u) << o.out;
    for (int i : {0, 2}) {
        EXPECT_EQ(lines[static_cast<std::size_t>(i)].rfind(std::string("K = ") + (i == 0 ? "18" : "90") +
                                                               " (stripes): relative RMS error against the exact features of T: ",
                                                           0),
                  0u)
            << lines[static_cast<std::size_t>(i)];
        EXPECT_NE(lines[static_cast<std::size_t>(i)].find("ScatterRows "), std::string::npos);
    }
    for (int i : {1, 3}) {
        EXPECT_EQ(lines[static_cast<std::size_t>(i)].rfind("  defect 0 (bubble r = 0.6 mm): CNR under the sensor: ScatterRows ", 0), 0u)
            << lines[static_cast<std::size_t>(i)];
        EXPECT_NE(lines[static_cast<std::size_t>(i)].find(", bright field "), std::string::npos);
    }
}

// A scene file where a render folder belongs: the advice is to render it first, not to write
// into the scene file's name.
TEST_F(AcquireCommand, ASceneFileIsToldToBeRenderedFirst) {
    std::string err;
    EXPECT_EQ(run("acquire " + path("scene.yaml") + " --patterns 24", &err), 2);
    EXPECT_NE(err.find(path("scene.yaml") + " is a file, not a render folder"), std::string::npos) << err;
    EXPECT_NE(err.find("ltmsim render " + path("scene.yaml") + " -o DIR"), std::string::npos) << err;
    EXPECT_EQ(err.find("-o " + path("scene.yaml")), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + path("nothing-here") + " --patterns 24", &err), 2);
    EXPECT_NE(err.find("no such folder"), std::string::npos) << err;
}

TEST_F(AcquireCommand, BadInputExitsTwoWithALocatedMessageAndWritesNothing) {
    std::string err;
    const fs::path out = dir / "r" / "acquire-gray";
    fs::create_directories(dir / "empty");
    EXPECT_EQ(run("acquire " + (dir / "empty").string() + " --patterns 24", &err), 2);
    EXPECT_NE(err.find("no ltm.npz"), std::string::npos) << err;

    // A method that does not match the display: Gray code needs 24 (+ 2 s, s >= 3) for 50 x 40.
    EXPECT_EQ(run("acquire " + r() + " --method gray --patterns 25", &err), 2);
    EXPECT_NE(err.find("--patterns 25: method gray needs 2 (ceil log2 P + ceil log2 Q) = 24"), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + r() + " --method stripes --patterns 89", &err), 2);
    EXPECT_NE(err.find("is not such a count"), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + r() + " --method brute-force --patterns 24", &err), 2);
    EXPECT_NE(err.find("K = P Q = 2000"), std::string::npos) << err;
    // K out of range.
    EXPECT_EQ(run("acquire " + r() + " --patterns 0", &err), 2);
    EXPECT_NE(err.find("--patterns must be in [1, 2000]"), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + r() + " --method compressive --patterns 2001", &err), 2);
    EXPECT_NE(err.find("--patterns must be in [1, 2000]"), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + r() + " --method nonsense --patterns 24", &err), 2);
    EXPECT_NE(err.find("--method"), std::string::npos) << err;

    // Negative noise parameters, quantisation with 0 bits, unknown keys: file, line, column, key.
    const std::string s = write("sensor.yaml", "sensor:\n  camera:\n    read_noise: -1\n").string();
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + s, &err), 2);
    EXPECT_NE(err.find(s + ":3:17: sensor.camera.read_noise: must be >= 0 (got -1)"), std::string::npos) << err;
    write("sensor.yaml", "sensor:\n  camera: {bits: 0}\n");
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + s, &err), 2);
    EXPECT_NE(err.find(s + ":2:18: sensor.camera.bits: the camera quantises to 8, 10, 12 or 16 bits (got 0)"),
              std::string::npos) << err;
    write("sensor.yaml", "sensor:\n  display: {gamma: 2.2, black_level: -0.1}\n");
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + s, &err), 2);
    EXPECT_NE(err.find(s + ":2:38: sensor.display.black_level: must be >= 0"), std::string::npos) << err;
    write("sensor.yaml", "sensor:\n  display: {contrast_ratio: 1000, black_level: 0.001}\n");
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + s, &err), 2);
    EXPECT_NE(err.find("not both"), std::string::npos) << err;
    write("sensor.yaml", "sensor:\n  camera: {full_wel: 100}\n");
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + s, &err), 2);
    EXPECT_NE(err.find(s + ":2:12: sensor.camera.full_wel: unknown key 'full_wel'"), std::string::npos) << err;
    EXPECT_NE(err.find("did you mean 'full_well'"), std::string::npos) << err;
    EXPECT_EQ(run("acquire " + r() + " --patterns 24 --sensor " + (dir / "missing.yaml").string(), &err), 2);
    EXPECT_NE(err.find("missing.yaml"), std::string::npos) << err;

    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir / "r" / "acquire-stripes"));
    EXPECT_FALSE(fs::exists(dir / "r" / "acquire-brute-force"));
    EXPECT_FALSE(fs::exists(dir / "r" / "acquire-compressive"));

    // An existing output folder is not replaced without --overwrite.
    ASSERT_EQ(run("acquire " + r() + " --patterns 24", &err), 0) << err;
    const std::string before = slurp(out / "report.json");
    EXPECT_EQ(run("acquire " + r() + " --patterns 30", &err), 2);
    EXPECT_NE(err.find("--overwrite"), std::string::npos) << err;
    EXPECT_EQ(slurp(out / "report.json"), before);
}

}  // namespace
