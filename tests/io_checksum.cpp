// SHA-256 (io/Checksum.h) against the FIPS 180-2 test vectors (Appendix B: "abc", the 448-bit
// two-block message, one million 'a'; the empty string's digest is the well-known e3b0c442...),
// files against the bytes they hold and against coreutils' sha256sum, and the errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "io/Checksum.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;
using ltm::io::sha256_file;
using ltm::io::sha256_hex;
using ltm::test::message_of;

namespace {

class ChecksumTest : public ltm::test::LenientTempDirTest {};

TEST(Sha256, Fips180Vectors) {
    EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
              "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
    // Embedded zero bytes count like any other.
    EXPECT_NE(sha256_hex(std::string("a\0b", 3)), sha256_hex("ab"));
}

TEST_F(ChecksumTest, FileMatchesItsBytesAndSha256sum) {
    write("abc.txt", "abc");
    EXPECT_EQ(sha256_file(path("abc.txt")), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    write("empty", "");
    EXPECT_EQ(sha256_file(path("empty")), sha256_hex(""));
    write("million", std::string(1000000, 'a'));
    EXPECT_EQ(sha256_file(path("million")), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");

    // Larger than the 1 MiB read block, not a multiple of it or of SHA-256's 64-byte block.
    std::mt19937 rng(7);
    std::string big(3 * 1024 * 1024 + 1001, '\0');
    for (char& c : big) c = static_cast<char>(rng() & 0xFF);
    write("big.bin", big);
    const std::string digest = sha256_file(path("big.bin"));
    EXPECT_EQ(digest, sha256_hex(big));
    if (::access("/usr/bin/sha256sum", X_OK) == 0) {
        const ltm::test::Outcome r = ltm::test::run_shell("/usr/bin/sha256sum '" + path("big.bin") + "'", dir);
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_EQ(r.out.substr(0, 64), digest);
    }
}

TEST_F(ChecksumTest, ErrorsNameTheFile) {
    EXPECT_EQ(message_of([&] { sha256_file(path("missing")); }),
              "cannot checksum file '" + path("missing") + "': no such file");
    fs::create_directory(dir / "folder");
    EXPECT_EQ(message_of([&] { sha256_file(path("folder")); }),
              "cannot checksum file '" + path("folder") + "': it is a folder");
}

}  // namespace
