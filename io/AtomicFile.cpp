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
#include <system_error>
#include <utility>

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

void AtomicFile::commit(CommitGroup* group) {
    if (!live_) fail("internal error: commit after commit or failure");
    if (mode_ == Mode::ByName) {
        fd_ = ::open(tmp_.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0) {
            const int e = errno;
            fail("reopening the temporary file '" + tmp_ + "' failed: " + errno_text(e));
        }
    }
    // Committed alone, the file is a group of one: the same steps, the same messages.
    CommitGroup alone;
    hand_to(group ? *group : alone);
    if (!group) alone.commit();
}

void AtomicFile::hand_to(CommitGroup& group) {
#ifdef __linux__
    // The rest of the file to the kernel's writeback (nbytes 0: to the end); only a hint, as in
    // write(): the group's fsync is what makes it durable.
    (void)::sync_file_range(fd_, static_cast<off_t>(written_back_), 0, SYNC_FILE_RANGE_WRITE);
#endif
    try {
        group.add({fd_, tmp_, path_, kind_});
    } catch (const std::exception& e) {
        fail(std::string("handing the file to its commit group failed: ") + e.what());
    }
    // The group owns the temporary now.
    fd_ = -1;
    live_ = false;
    tmp_.clear();
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

CommitGroup::~CommitGroup() {
    stop_syncer(false);
    for (File& f : files_) discard(f);
}

void CommitGroup::add(File&& file) {
    const std::lock_guard<std::mutex> lock(mutex_);
    files_.push_back(std::move(file));
    if (files_.size() == 2 && !syncer_.joinable()) {
        // Without a thread (none can be made), commit() syncs the files itself.
        try {
            syncer_ = std::thread([this] { sync_loop(); });
        } catch (const std::system_error&) {
        }
    }
    wake_.notify_one();
}

// The syncer: fsyncs files_[next_sync_] onward as they are handed in, outside the lock (the file
// stays open: only the syncer's stop, which joins it, lets anyone close it).
void CommitGroup::sync_loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [&] { return stopping_ || next_sync_ < files_.size(); });
        if (stopping_ && (!draining_ || next_sync_ == files_.size())) return;
        const std::size_t k = next_sync_;
        const int fd = files_[k].fd;
        lock.unlock();
        const int r = ::fsync(fd);
        const int e = errno;
        lock.lock();
        files_[k].synced = r == 0 ? 1 : -e;  // files_ may have grown: indexed again under the lock
        ++next_sync_;
    }
}

void CommitGroup::stop_syncer(bool drain) noexcept {
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
        draining_ = drain;
    }
    wake_.notify_one();
    if (syncer_.joinable()) syncer_.join();
}

std::size_t CommitGroup::size() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return files_.size();
}

void CommitGroup::discard(File& f) noexcept {
    if (f.fd >= 0) ::close(f.fd);
    f.fd = -1;
    if (!f.tmp.empty()) ::unlink(f.tmp.c_str());
    f.tmp.clear();
}

void CommitGroup::commit() {
    stop_syncer(true);  // every file handed in is synced (or its failure recorded) after this
    std::vector<File> files;
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        files.swap(files_);
    }
    // From here `files` owns the temporaries: whatever is not renamed is discarded on the way out.
    struct Owner {
        std::vector<File>& files;
        ~Owner() {
            for (File& f : files) discard(f);
        }
    } owner{files};
    std::vector<std::pair<std::string, const File*>> folders;  // distinct, each with its first file
    for (File& f : files) {
        // errno is read before any string is built.
        const auto failed = [&](int e, const char* step, const char* after) {
            throw std::runtime_error("cannot write " + f.kind + " '" + f.path + "': " + step + " the temporary file '" +
                                     f.tmp + "'" + after + " failed: " + errno_text(e));
        };
        if (f.synced < 0) failed(-f.synced, "syncing", "");
        if (f.synced == 0 && ::fsync(f.fd) != 0) failed(errno, "syncing", "");
        const int fd = f.fd;
        f.fd = -1;
        if (::close(fd) != 0) failed(errno, "closing", "");
        if (std::rename(f.tmp.c_str(), f.path.c_str()) != 0) failed(errno, "renaming", " onto it");
        f.tmp.clear();  // in place: nothing left to discard
        std::string folder = detail::folder_of(f.path).string();
        if (std::none_of(folders.begin(), folders.end(), [&](const auto& g) { return g.first == folder; }))
            folders.emplace_back(std::move(folder), &f);
    }
    for (const auto& [folder, first] : folders) {
        try {
            fsync_folder(folder);
        } catch (const std::exception& e) {
            throw std::runtime_error("cannot write " + first->kind + " '" + first->path +
                                     "': the file is complete and in place, but its name may not survive a crash" +
                                     (files.size() > 1 ? " (nor those of the files committed with it)" : "") + ": " +
                                     e.what());
        }
    }
}

}  // namespace ltm::io
