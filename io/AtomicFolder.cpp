#include "io/AtomicFolder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>  // renameat2, RENAME_EXCHANGE, RENAME_NOREPLACE (glibc >= 2.28, _GNU_SOURCE)
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "io/AtomicFile.h"
#include "io/TemporaryName.h"

namespace fs = std::filesystem;

namespace ltm::io {

namespace {

std::string errno_text(int e) { return std::strerror(e); }

// The flag is unknown to this file system (or kernel): the caller falls back to plain renames.
bool flag_unsupported(int e) { return e == EINVAL || e == ENOSYS || e == ENOTSUP; }

// fsync of one regular file; throws std::runtime_error naming it.
void fsync_file(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) {
        const int e = errno;
        throw std::runtime_error("cannot open '" + path + "' to sync it: " + errno_text(e));
    }
    const int r = ::fsync(fd);
    const int e = errno;
    ::close(fd);
    if (r != 0) throw std::runtime_error("cannot sync '" + path + "': " + errno_text(e));
}

// fsyncs every regular file and folder below `root` (symbolic links are not followed), then `root`.
void fsync_tree(const std::string& root) {
    for (fs::recursive_directory_iterator it(root), end; it != end; ++it) {
        const fs::file_status st = it->symlink_status();
        if (fs::is_regular_file(st))
            fsync_file(it->path().string());
        else if (fs::is_directory(st))
            fsync_folder(it->path().string());
    }
    fsync_folder(root);
}

}  // namespace

AtomicFolder::AtomicFolder(const std::string& final_path, const std::string& kind) : final_(final_path), kind_(kind) {
    while (final_.size() > 1 && final_.back() == '/') final_.pop_back();
    if (final_.empty()) throw std::runtime_error("cannot write " + kind + ": the path is empty");
    const std::string name = fs::path(final_).filename().string();
    if (name.empty() || name == "." || name == ".." || name == "/") fail("it does not name a folder to create");
    const fs::path parent = detail::folder_of(final_);
    std::error_code ec;
    if (!fs::exists(parent, ec)) fail("the folder '" + parent.string() + "' does not exist");
    if (!fs::is_directory(parent, ec)) fail("'" + parent.string() + "' is not a folder");
    const fs::file_status st = fs::symlink_status(final_, ec);
    if (fs::exists(st) && !fs::is_directory(st)) fail("it exists and is not a folder");
    int e = 0;
    for (int attempt = 0; attempt < 16 && !live_; ++attempt) {
        tmp_ = (parent / detail::temporary_name(name, true)).string();
        if (::mkdir(tmp_.c_str(), 0777) == 0)
            live_ = true;
        else if ((e = errno) != EEXIST)
            break;
    }
    if (!live_) {
        tmp_.clear();
        fail("cannot create a temporary folder in '" + parent.string() + "': " + errno_text(e));
    }
}

AtomicFolder::~AtomicFolder() { discard(); }

void AtomicFolder::discard() noexcept {
    if (live_) {
        std::error_code ec;
        fs::remove_all(tmp_, ec);
    }
    live_ = false;
    tmp_.clear();
}

void AtomicFolder::fail(const std::string& reason) {
    discard();
    throw std::runtime_error("cannot write " + kind_ + " '" + final_ + "': " + reason);
}

void AtomicFolder::commit() {
    if (!live_) fail("internal error: commit after commit or failure");
    try {
        fsync_tree(tmp_);
    } catch (const std::exception& e) {
        fail(std::string("syncing the temporary folder failed: ") + e.what());
    }

    const std::string parent = detail::folder_of(final_).string();
    std::string old;  // where the replaced folder ends up, to be removed at the end
    struct stat st {};
    if (::lstat(final_.c_str(), &st) != 0) {
        const int e = errno;
        if (e != ENOENT) fail("cannot inspect it: " + errno_text(e));
        int r = ::renameat2(AT_FDCWD, tmp_.c_str(), AT_FDCWD, final_.c_str(), RENAME_NOREPLACE);
        if (r != 0 && flag_unsupported(errno)) r = std::rename(tmp_.c_str(), final_.c_str());
        if (r != 0) {
            const int e2 = errno;
            fail("renaming the temporary folder '" + tmp_ + "' onto it failed: " + errno_text(e2));
        }
    } else if (S_ISDIR(st.st_mode)) {
        if (::renameat2(AT_FDCWD, tmp_.c_str(), AT_FDCWD, final_.c_str(), RENAME_EXCHANGE) == 0) {
            old = tmp_;  // the exchange left the old folder under the temporary's name
        } else {
            const int e = errno;
            if (!flag_unsupported(e))
                fail("exchanging the temporary folder '" + tmp_ + "' with it failed: " + errno_text(e));
            const std::string aside =
                (fs::path(parent) / detail::temporary_name(fs::path(final_).filename().string(), true)).string();
            if (std::rename(final_.c_str(), aside.c_str()) != 0) {
                const int e2 = errno;
                fail("renaming it aside to '" + aside + "' failed: " + errno_text(e2));
            }
            if (std::rename(tmp_.c_str(), final_.c_str()) != 0) {
                const int e2 = errno;
                const bool restored = std::rename(aside.c_str(), final_.c_str()) == 0;
                fail("renaming the temporary folder '" + tmp_ + "' onto it failed: " + errno_text(e2) +
                     (restored ? "" : "; the previous folder is kept as '" + aside + "'"));
            }
            old = aside;
        }
    } else {
        fail("it exists and is not a folder");
    }
    live_ = false;
    tmp_.clear();

    std::string sync_error;
    try {
        fsync_folder(parent);
    } catch (const std::exception& e) {
        sync_error = e.what();
    }
    if (!old.empty()) {
        std::error_code ec;
        fs::remove_all(old, ec);  // a failure leaves a recognisable temporary, not an incomplete result
    }
    if (!sync_error.empty())
        throw std::runtime_error("cannot write " + kind_ + " '" + final_ +
                                 "': the folder is complete and in place, but its name may not survive a crash: " +
                                 sync_error);
}

bool AtomicFolder::is_temporary_name(const std::string& filename) { return detail::is_temporary_name(filename, true); }

}  // namespace ltm::io
