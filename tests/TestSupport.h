// Shared helpers of the tests that run the ltmsim executable (tests/app_*.cpp): running a command
// with its exit status and output, reading and writing whole files, a fresh temporary folder per
// test, and the message of an expected exception. Header-only (inline), with no dependency on the
// project's libraries (only on ltm_test_paths, which every test links), so any test may include it:
// all but the command helpers also serve tests of other layers.
//
// The executable is the one CMake builds for this tree: ltm::test::ltmsim_exe() (tests/BuildPaths.h).
#pragma once

#include "tests/BuildPaths.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace ltm::test {

// ---- interoperability checks ----------------------------------------------------------------

// True where LTM_REQUIRE_INTEROP is set (to anything but "" or "0"): scripts/test sets it after
// installing the tools the interoperability checks run (scipy, numpy, meshio, MeshLab), so there
// a missing tool is a failure, not a skip that could hide a broken check.
inline bool interop_required() {
    const char* v = std::getenv("LTM_REQUIRE_INTEROP");
    return v && *v && std::string(v) != "0";
}

}  // namespace ltm::test

// Ends an interoperability test whose tool is missing: a skip on a developer's machine, a fatal
// failure under LTM_REQUIRE_INTEROP. Streams like GTEST_SKIP():
//   if (!python_has_scipy()) LTM_INTEROP_SKIP() << "python3 cannot import scipy.sparse";
#define LTM_INTEROP_SKIP()                                                                                    \
    return GTEST_MESSAGE_(::ltm::test::interop_required()                                                     \
                              ? "interoperability tool missing, and LTM_REQUIRE_INTEROP is set"               \
                              : "Skipped",                                                                    \
                          ::ltm::test::interop_required() ? ::testing::TestPartResult::kFatalFailure          \
                                                          : ::testing::TestPartResult::kSkip)

namespace ltm::test {

// ---- files ---------------------------------------------------------------------------------

// The whole content of file `p`, byte for byte ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Writes `bytes` to file `p` exactly (binary, replacing any previous content).
inline void spit(const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// ---- exceptions ------------------------------------------------------------------------------

// The message of the E (std::runtime_error unless given, or a subclass) that f throws,
// "(no exception)" when it throws none; other exceptions pass through.
template <class E = std::runtime_error>
std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    return "(no exception)";
}

// ---- running commands ------------------------------------------------------------------------

// The exit status of a child from the raw value std::system returns: the status the program
// passed to exit (0 to 255) when it exited normally, -1 otherwise (killed by a signal, or the
// shell could not be started).
inline int exit_status(int raw) { return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1; }

// Which output streams of a command run_shell keeps.
enum class Capture {
    StdoutAndStderr,  // both, into Outcome::out and Outcome::err
    StderrOnly,       // stderr into Outcome::err; stdout goes to /dev/null and Outcome::out stays ""
};

// What a command did: its exit status (as exit_status) and what it wrote.
struct Outcome {
    int status = -1;
    std::string out, err;
    // Outcome::out split into lines (without the '\n's).
    std::vector<std::string> lines() const {
        std::vector<std::string> v;
        std::istringstream in(out);
        for (std::string l; std::getline(in, l);) v.push_back(l);
        return v;
    }
};

// Runs `command` through the shell (std::system), with the streams chosen by `what` redirected to
// the files `dir`/stdout.txt and `dir`/stderr.txt; reads them into the Outcome and removes them,
// so that they are not left among the files a test inspects. `dir` must exist and its path must
// not hold a single quote. `command` itself must not redirect the streams captured.
inline Outcome run_shell(const std::string& command, const std::filesystem::path& dir,
                         Capture what = Capture::StdoutAndStderr) {
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string to_out = what == Capture::StdoutAndStderr ? "'" + out.string() + "'" : std::string("/dev/null");
    const std::string cmd = command + " > " + to_out + " 2> '" + err.string() + "'";
    Outcome r;
    r.status = exit_status(std::system(cmd.c_str()));
    if (what == Capture::StdoutAndStderr) r.out = slurp(out);
    r.err = slurp(err);
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
}

// Runs `ltmsim <args>` (the executable ltmsim_exe()) as run_shell does. `args` go through the shell:
// quote paths that may hold spaces.
inline Outcome ltmsim(const std::string& args, const std::filesystem::path& dir,
                      Capture what = Capture::StdoutAndStderr) {
    return run_shell(ltm::test::ltmsim_exe() + " " + args, dir, what);
}

// ---- a temporary folder per test -------------------------------------------------------------

// A fresh, empty folder for the running test (call it from a test body or fixture SetUp):
// <temp>/ltmsim-<pid>-<test suite>-<test name>, removed first if it exists. The process id keeps
// concurrent runs apart, the names keep the tests of one process apart ('/' of parameterised
// names becomes '_').
inline std::filesystem::path make_test_dir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "ltmsim-" + std::to_string(::getpid()) + "-" + info->test_suite_name() + "-" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// A fixture with a fresh folder `dir` per test (make_test_dir), removed with everything in it
// after the test. A derived fixture that overrides SetUp or TearDown calls these first / last.
class TempDirTest : public ::testing::Test {
protected:
    void SetUp() override { dir = make_test_dir(); }
    void TearDown() override { std::filesystem::remove_all(dir); }

    // Writes `text` to dir/name (as spit) and returns that path.
    std::filesystem::path write(const std::string& name, const std::string& text) const {
        spit(dir / name, text);
        return dir / name;
    }
    // The path dir/name as a string.
    std::string path(const std::string& name) const { return (dir / name).string(); }
    // The names of the entries of dir, sorted.
    std::vector<std::string> listing() const {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }

    std::filesystem::path dir;
};

// A fixture for the commands that read a render folder (features, acquire): SetUp renders a small
// lens with one bubble (16 x 12 camera over 25 x 20 mm, 50 x 40 display over 100 x 80 mm, 16
// samples per pixel) into dir/r, failing the test if the render does.
class RenderedFolderTest : public TempDirTest {
protected:
    // Runs `ltmsim <args>` and returns its exit status; stderr into *err if given, stdout dropped.
    int run(const std::string& args, std::string* err = nullptr) {
        const Outcome o = ltmsim(args, dir, Capture::StderrOnly);
        if (err) *err = o.err;
        return o.status;
    }
    void SetUp() override {
        TempDirTest::SetUp();
        write("scene.yaml", R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 0.6}
camera: {resolution: [16, 12], size: [25.0, 20.0], numerical_aperture: 0.002, samples_per_pixel: 16}
display: {resolution: [50, 40], size: [100.0, 80.0], z: 60.0}
)");
        ASSERT_EQ(run("render " + path("scene.yaml") + " -o " + r()), 0);
    }
    // The render folder.
    std::string r() const { return (dir / "r").string(); }
};

// TempDirTest whose TearDown ignores a failure to remove the folder (TempDirTest's lets the
// std::filesystem::filesystem_error escape, which fails the test).
class LenientTempDirTest : public TempDirTest {
protected:
    void TearDown() override {
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
};

}  // namespace ltm::test
