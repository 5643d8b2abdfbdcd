// libFuzzer entry point of ltm::fuzz::scene (fuzz/Targets.h).
#include "fuzz/Targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ltm::fuzz::scene(data, size);
    return 0;
}
