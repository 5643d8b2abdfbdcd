// libFuzzer entry point of ltm::fuzz::rays (fuzz/Targets.h).
#include "fuzz/Targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ltm::fuzz::rays(data, size);
    return 0;
}
