// libFuzzer entry point of ltm::fuzz::ltm_npz (fuzz/Targets.h).
#include "fuzz/Targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ltm::fuzz::ltm_npz(data, size);
    return 0;
}
