// Where this build's checkout and ltmsim executable are, for the tests that read shipped files or
// run the command. They come from one file CMake generates in the build folder
// (tests/CMakeLists.txt), not from -D definitions on every test: a definition holding an absolute
// path would make every test's object differ between two checkouts, so ccache could never share
// them (CMakeLists.txt, "ccache").
#pragma once

#include <string>

namespace ltm::test {

// The checkout's root folder, absolute (scenes/, scripts/ and fuzz/ lie under it).
const std::string& source_dir();

// The ltmsim executable this build made, absolute.
const std::string& ltmsim_exe();

}  // namespace ltm::test
