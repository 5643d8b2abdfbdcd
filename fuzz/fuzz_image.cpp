// libFuzzer entry point of ltm::fuzz::image (fuzz/Targets.h).
#include "fuzz/Targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ltm::fuzz::image(data, size);
    return 0;
}
