#include "io/AtomicFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "io/TemporaryName.h"

namespace fs = std::filesystem;

namespace ltm::io {

namespace {

std::string errno_text(int e) { return std::strerror(e); }

}  // namespace

AtomicFile::AtomicFile(const std::string& path, const std::string& kind, Mode mode)
    : path_(path), kind_(kind), mode_(mode) {
    if (path.empty()) throw std::runtime_error("cannot write " + kind + ": the path is empty");
    const fs::path folder = detail::folder_of(path);
    std::error_code ec;
    if (!fs::exists(folder, ec)) fail("the folder '" + folder.string() + "' does not exist");
    if (!fs::is_directory(folder, ec)) fail("'" + folder.string() + "' is not a folder");
    if (fs::is_directory(fs::path(path), ec)) fail("it is a folder");
    const std::string name = fs::path(path).filename().string();
    for (int attempt = 0; attempt < 16 && fd_ < 0; ++attempt) {
        tmp_ = (folder / detail::temporary_name(name, false)).string();
        fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ < 0 && errno != EEXIST) break;
    }
    if (fd_ < 0) {
        const int e = errno;
        tmp_.clear();
        fail("cannot create a temporary file in '" + folder.string() + "': " + errno_text(e));
    }
    live_ = true;
    if (mode_ == Mode::ByName) {
        // The name is reserved; the library opens it itself.
        const int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0) {
            const int e = errno;
            fail("closing the temporary file '" + tmp_ + "' failed: " + errno_text(e));
        }
    }
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (live_) ::unlink(tmp_.c_str());
    live_ = false;
    tmp_.clear();
}

void AtomicFile::fail(const std::string& reason) {
    discard();
    throw std::runtime_error("cannot write " + kind_ + " '" + path_ + "': " + reason);
}

void AtomicFile::write(const void* bytes, std::size_t n) {
    if (mode_ != Mode::Stream) fail("internal error: write() on an AtomicFile in Mode::ByName");
    if (fd_ < 0) fail("internal error: write after commit or failure");
    const auto* p = static_cast<const char*>(bytes);
    while (n > 0) {
        const ssize_t w = ::pwrite(fd_, p, std::min<std::size_t>(n, std::size_t(1) << 30), static_cast<off_t>(pos_));
        if (w < 0) {
            if (errno == EINTR) continue;
            const int e = errno;
            fail("writing the temporary file '" + tmp_ + "' failed: " + errno_text(e));
        }
        p += w;
        n -= static_cast<std::size_t>(w);
        pos_ += static_cast<std::uint64_t>(w);
    }
#ifdef __linux__
    if (pos_ >= written_back_ + kWritebackBytes) {
        // A failure here is not the file's: fsync in commit() reports any the disk has.
        (void)::sync_file_range(fd_, static_cast<off_t>(written_back_), static_cast<off_t>(pos_ - written_back_),
                                SYNC_FILE_RANGE_WRITE);
        written_back_ = pos_;
    }
#endif
}

void AtomicFile::commit() {
    if (!live_) fail("internal error: commit after commit or failure");
    if (mode_ == Mode::ByName) {
        fd_ = ::open(tmp_.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0) {
            const int e = errno;
            fail("reopening the temporary file '" + tmp_ + "' failed: " + errno_text(e));
        }
    }
    if (::fsync(fd_) != 0) {
        const int e = errno;
        fail("syncing the temporary file '" + tmp_ + "' failed: " + errno_text(e));
    }
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) {
        const int e = errno;
        fail("closing the temporary file '" + tmp_ + "' failed: " + errno_text(e));
    }
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
        const int e = errno;
        fail("renaming the temporary file '" + tmp_ + "' onto it failed: " + errno_text(e));
    }
    live_ = false;
    tmp_.clear();
    try {
        fsync_folder(detail::folder_of(path_).string());
    } catch (const std::exception& e) {
        throw std::runtime_error("cannot write " + kind_ + " '" + path_ +
                                 "': the file is complete and in place, but its name may not survive a crash: " +
                                 e.what());
    }
}

bool AtomicFile::is_temporary_name(const std::string& filename) { return detail::is_temporary_name(filename, false); }

void write_file(const std::string& path, std::string_view bytes, const std::string& kind) {
    AtomicFile file(path, kind);
    file.write(bytes);
    file.commit();
}

void fsync_folder(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        throw std::runtime_error("cannot sync folder '" + path + "': " + errno_text(e));
    }
    const int r = ::fsync(fd);
    const int e = errno;
    ::close(fd);
    if (r != 0 && e != EINVAL) throw std::runtime_error("cannot sync folder '" + path + "': " + errno_text(e));
}

}  // namespace ltm::io
