// Writes the binary seed corpora of the fuzz targets into the folder given, with the project's
// own writers (so no binary file is kept in the repository):
//   ltm_npz/   small light transport matrices (empty, one nonzero, several rows; int32 indptr)
//   image/     8-bit gray and RGB PNG, 16-bit gray PNG, 1-channel and RGB OpenEXR
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "io/Image.h"
#include "io/LtmFile.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fuzz_make_seeds DIR\n");
        return 2;
    }
    const fs::path dir(argv[1]);
    fs::create_directories(dir / "ltm_npz");
    fs::create_directories(dir / "image");

    ltm::write_ltm_npz((dir / "ltm_npz" / "zeros.npz").string(), ltm::CsrMatrix::zeros(2, 3));
    ltm::CsrMatrix T;
    T.rows = 3;
    T.cols = 5;
    T.indptr = {0, 2, 2, 3};
    T.indices = {0, 4, 2};
    T.data = {0.5f, 0.25f, 1.0f};
    ltm::write_ltm_npz((dir / "ltm_npz" / "small.npz").string(), T);
    ltm::write_ltm_npz((dir / "ltm_npz" / "stored.npz").string(), T, ltm::NpzWriteOptions{0});

    ltm::Image gray(4, 3, 1), rgb(3, 2, 3);
    for (std::size_t i = 0; i < gray.data.size(); ++i) gray.data[i] = static_cast<float>(i % 5) / 4.0f;
    for (std::size_t i = 0; i < rgb.data.size(); ++i) rgb.data[i] = static_cast<float>(i % 7) / 6.0f;
    ltm::write_png((dir / "image" / "gray.png").string(), gray);
    ltm::write_png((dir / "image" / "rgb.png").string(), rgb);
    ltm::write_png16((dir / "image" / "gray16.png").string(), 3, 2, {0, 1, 2, 65535, 300, 7});
    ltm::write_exr((dir / "image" / "one.exr").string(), 4, 3, {{"Y", gray.data}});
    std::vector<float> r(6), g(6), b(6);
    for (int i = 0; i < 6; ++i) r[i] = 0.1f * i, g[i] = 1.0f - 0.1f * i, b[i] = 0.5f;
    ltm::write_exr((dir / "image" / "rgb.exr").string(), 3, 2, {{"R", r}, {"G", g}, {"B", b}});
    return 0;
}
