#pragma once
// SHA-256 checksums (FIPS 180-4) of bytes and files, as lowercase hex (64 characters), the form
// `sha256sum` prints and manifests store. Computed by OpenSSL's EVP interface (libcrypto, a
// private dependency of ltm_io: no OpenSSL header is visible outside io/Checksum.cpp).
#include <string>
#include <string_view>

namespace ltm::io {

// SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);

// SHA-256 of the file's content, read in blocks (the file is never held in memory whole).
// Throws std::runtime_error "cannot checksum file '<path>': <reason>" when it is missing, not a
// regular file, or cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace ltm::io
