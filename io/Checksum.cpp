#include "io/Checksum.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

namespace ltm::io {

namespace {

// One SHA-256 computation; `fail` receives OpenSSL's failures (which only an allocation failure
// or a broken library can cause).
class Sha256 {
public:
    template <class Fail>
    explicit Sha256(Fail fail) : ctx_(EVP_MD_CTX_new(), &EVP_MD_CTX_free) {
        if (!ctx_ || EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) != 1) fail("OpenSSL cannot start SHA-256");
    }
    template <class Fail>
    void update(const void* p, std::size_t n, Fail fail) {
        if (n > 0 && EVP_DigestUpdate(ctx_.get(), p, n) != 1) fail("OpenSSL's SHA-256 update failed");
    }
    template <class Fail>
    std::string hex(Fail fail) {
        unsigned char md[EVP_MAX_MD_SIZE];
        unsigned int len = 0;
        if (EVP_DigestFinal_ex(ctx_.get(), md, &len) != 1) fail("OpenSSL's SHA-256 finalisation failed");
        static const char* digits = "0123456789abcdef";
        std::string out;
        out.reserve(2 * len);
        for (unsigned int i = 0; i < len; ++i) {
            out.push_back(digits[md[i] >> 4]);
            out.push_back(digits[md[i] & 15]);
        }
        return out;
    }

private:
    std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx_;
};

}  // namespace

std::string sha256_hex(std::string_view bytes) {
    const auto fail = [](const std::string& why) -> void { throw std::runtime_error("cannot compute SHA-256: " + why); };
    Sha256 h(fail);
    h.update(bytes.data(), bytes.size(), fail);
    return h.hex(fail);
}

std::string sha256_file(const std::string& path) {
    const auto fail = [&](const std::string& why) -> void {
        throw std::runtime_error("cannot checksum file '" + path + "': " + why);
    };
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        fail(e == ENOENT ? std::string("no such file") : std::string("cannot open it: ") + std::strerror(e));
    }
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0) fail(std::string("cannot stat it: ") + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) fail("it is a folder");
    if (!S_ISREG(st.st_mode)) fail("it is not a regular file");
    Sha256 h(fail);
    std::vector<unsigned char> buf(std::size_t(1) << 20);
    for (;;) {
        const ssize_t n = ::read(fd, buf.data(), buf.size());
        if (n < 0) {
            if (errno == EINTR) continue;
            fail(std::string("reading it failed: ") + std::strerror(errno));
        }
        if (n == 0) break;
        h.update(buf.data(), static_cast<std::size_t>(n), fail);
    }
    return h.hex(fail);
}

}  // namespace ltm::io
