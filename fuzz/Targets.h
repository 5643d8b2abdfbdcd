#pragma once
// The fuzz targets: each calls one parser of a user's file on arbitrary bytes. A parser's contract
// is that bad input is reported by the exception type it documents (InputError for the YAML and
// JSON readers, std::runtime_error naming the file for the binary readers); any other exception
// escapes the target, and libFuzzer reports it as a crash, as it does for the sanitizers'
// reports, hangs (-timeout) and runaway memory (-rss_limit_mb). A result that breaks the parser's
// promise (an invalid matrix, an image of the wrong size) traps.
//
// fuzz/fuzz_<name>.cpp makes each one a libFuzzer executable (scripts/fuzz runs them);
// tests/fuzz_regressions.cpp replays fuzz/regressions/<name>/ and the text seeds through the
// same functions in the ordinary test suite.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/Image.h"
#include "io/InputError.h"
#include "io/LtmFile.h"
#include "scene/SceneLoader.h"
#include "study/DatasetSpec.h"
#include "trace/RaysFile.h"

namespace ltm::fuzz {

// The checkout's root folder, absolute: the dataset target resolves the shipped scenes from it.
// Defined by the program that links the targets (fuzz/CMakeLists.txt generates it for the fuzzers;
// tests/fuzz_regressions.cpp gives the tests' own).
const std::string& source_dir();

// The bytes as a string.
inline std::string text(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// The bytes written to this process's own scratch file (for readers that take a path); the same
// file is overwritten by every input.
inline std::string scratch_file(const std::uint8_t* data, std::size_t size, const char* suffix) {
    const char* tmp = std::getenv("TMPDIR");
    const std::string path =
        std::string(tmp && *tmp ? tmp : "/tmp") + "/ltm-fuzz-" + std::to_string(::getpid()) + suffix;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    return path;
}

// The scene loader (scene/SceneLoader.h): a Scene or an InputError.
inline void scene(const std::uint8_t* data, std::size_t size) {
    try {
        (void)parse_scene(text(data, size), "fuzz.yaml");
    } catch (const InputError&) {
    }
}

// The rays reader of `trace-rays` (trace/RaysFile.h, io/Json.h): rays or an InputError.
inline void rays(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(text(data, size));
    try {
        (void)read_rays(in, "fuzz.jsonl");
    } catch (const InputError&) {
    }
}

// The ltm.npz reader that `ltmsim features` uses (io/LtmFile.h): a valid CsrMatrix or a
// std::runtime_error naming the file.
inline void ltm_npz(const std::uint8_t* data, std::size_t size) {
    const std::string path = scratch_file(data, size, ".npz");
    try {
        const CsrMatrix T = read_ltm_npz(path);
        if (!T.check().empty()) __builtin_trap();
    } catch (const std::runtime_error&) {
    }
    std::remove(path.c_str());
}

// Display patterns (io/Image.h: PNG and OpenEXR, recognised by their bytes) and their values: an
// image whose size matches its data, or a std::runtime_error naming the file.
inline void image(const std::uint8_t* data, std::size_t size) {
    const std::string path = scratch_file(data, size, ".img");
    try {
        const Image img = read_image(path);
        if (img.data.size() != img.pixel_count() * static_cast<std::size_t>(img.channels)) __builtin_trap();
        if (pattern_values(img).size() != img.pixel_count()) __builtin_trap();
    } catch (const std::runtime_error&) {
    } catch (const std::invalid_argument&) {  // pattern_values: a channel count it cannot reduce
    }
    std::remove(path.c_str());
}

// Dataset specs (study/DatasetSpec.h): a spec or an InputError. The spec is named as if it lay in
// scenes/datasets/, so that the seeds' relative `scene:` paths reach the shipped base scenes.
inline void dataset_spec(const std::uint8_t* data, std::size_t size) {
    try {
        (void)parse_dataset_spec(text(data, size), source_dir() + "/scenes/datasets/fuzz.yaml");
    } catch (const InputError&) {
    }
}

}  // namespace ltm::fuzz
