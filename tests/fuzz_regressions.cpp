// Every input a fuzzer ever found a problem with (fuzz/regressions/<target>/), and the text seeds,
// replayed through the fuzz targets themselves (fuzz/Targets.h) in the ordinary test suite, under
// the ordinary build and under scripts/test --sanitize. A target that throws anything but the
// parser's documented error, or traps, fails here as it did under the fuzzer.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>

#include "fuzz/Targets.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

const std::string& ltm::fuzz::source_dir() { return ltm::test::source_dir(); }

namespace {

using Target = std::function<void(const std::uint8_t*, std::size_t)>;

const std::map<std::string, Target>& targets() {
    static const std::map<std::string, Target> t = {{"scene", ltm::fuzz::scene},
                                                    {"rays", ltm::fuzz::rays},
                                                    {"ltm_npz", ltm::fuzz::ltm_npz},
                                                    {"image", ltm::fuzz::image},
                                                    {"dataset_spec", ltm::fuzz::dataset_spec}};
    return t;
}

void replay(const std::string& target, const fs::path& folder) {
    if (!fs::is_directory(folder)) return;
    for (const auto& e : fs::directory_iterator(folder)) {
        SCOPED_TRACE(e.path().string());
        const std::string bytes = ltm::test::slurp(e.path());
        EXPECT_NO_THROW(targets().at(target)(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
    }
}

}  // namespace

TEST(FuzzRegressions, FoundInputsAndSeedsAreHandled) {
    const fs::path src(ltm::test::source_dir());
    for (const auto& [name, target] : targets()) replay(name, src / "fuzz" / "regressions" / name);
    replay("rays", src / "fuzz" / "seeds" / "rays");
    replay("dataset_spec", src / "scenes" / "datasets");
    for (const auto& e : fs::recursive_directory_iterator(src / "scenes"))
        if (e.path().extension() == ".yaml" && e.path().parent_path().filename() != "datasets") {
            SCOPED_TRACE(e.path().string());
            const std::string bytes = ltm::test::slurp(e.path());
            EXPECT_NO_THROW(ltm::fuzz::scene(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
        }
}

// Pathological texts, each through its target (an exception other than the documented
// one, or a crash, fails): a scene nested 10^5 levels deep, numbers beyond a double or -0.
TEST(FuzzRegressions, PathologicalTexts) {
    auto run = [](const Target& t, const std::string& s) { t(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()); };
    const std::string deep_flow = "object: " + std::string(100000, '[') + std::string(100000, ']') + "\n";
    std::string deep_block = "object:\n";
    for (int i = 0; i < 100000; ++i) deep_block += "- ";
    deep_block += "1\n";
    for (const std::string& s : {deep_flow, deep_block, std::string("object: {type: lens, r1: 1e400}\n"),
                                 std::string("camera: {size: [-0, -0.0]}\n")}) {
        EXPECT_NO_THROW(run(ltm::fuzz::scene, s));
        EXPECT_THROW(ltm::parse_scene(s, "x.yaml"), ltm::InputError);
    }
    const std::string deep_json = std::string(100000, '[') + std::string(100000, ']') + "\n";
    EXPECT_NO_THROW(run(ltm::fuzz::rays, deep_json));
    EXPECT_NO_THROW(run(ltm::fuzz::rays, "{\"origin\": [1e400, 0, 0], \"direction\": [0, 0, 1]}\n"));
    EXPECT_NO_THROW(run(ltm::fuzz::rays, "{\"origin\": [-0, 0, 0], \"direction\": [0, -0.0, 1]}\n"));
}
