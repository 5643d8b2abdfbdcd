#pragma once
// The project's one way of writing a file or a folder so that it appears complete or not at all.
//
// What a reader of the target can see, whatever happens to the writer (an exception, the process
// killed at any instant, the machine losing power):
//   - the previous content of the path (or no file, if there was none), or
//   - the complete new content,
// never a mixture or a prefix. At most a temporary named ".<name>.tmp-..." is left beside the
// target (only when the process died or the machine stopped; every failure that the process
// survives removes it): AtomicFile::is_temporary_name and AtomicFolder::is_temporary_name
// recognise these names, so that a later run can clean them up.
//
// What is durable when: nothing before commit(). Once commit() returns, the new content and its
// name are on stable storage (the file's data and the rename are both fsync'ed, the latter by
// syncing the containing folder), as far as the file system honours fsync. A crash *during*
// commit() leaves the old or the new content at the path (rename(2) is atomic), never neither.
//
// Errors are std::runtime_error "cannot write <kind> '<path>': <reason>", where <kind> is what
// the caller writes ("LTM file", "PNG image", "mesh") and <reason> names the folder or the
// temporary file and the system's error text.
//
// All of this is POSIX (open O_EXCL, fsync, rename); the target's folder must be on a local file
// system that implements rename atomically (every Linux one does; some network file systems only
// approximately).
#include <cstddef>
#include <cstdint>
#include <condition_variable>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace ltm::io {

class CommitGroup;

// A file written atomically.
//
// The bytes go to a new temporary file ".<name>.tmp-<16 hex digits>" in the folder of `path`,
// created with O_EXCL (so it never clobbers anything, not even a concurrent writer's temporary)
// and mode 0666 minus the umask, like any new file. commit() fsyncs it, closes it, renames it
// onto `path` and fsyncs the folder. Destroying an AtomicFile that was not committed (e.g. while
// an exception propagates) removes the temporary and leaves `path` as it was.
//
// The constructor fails when `path` is empty, its folder does not exist (the message names the
// folder; it is never created), is not a folder or is not writable, or `path` is a folder.
//
// Two modes:
//   Mode::Stream  the caller writes the bytes through write() (with tell() and seek(): write_exr
//                 and libzip's write source go back to patch tables and headers).
//   Mode::ByName  for libraries that insist on opening a file by name themselves: the temporary
//                 file is created (empty, reserving its unique name) and closed; hand
//                 temporary_path() to the library, let it write (it may truncate, rewrite or
//                 even replace the file), then commit() as usual, which reopens it to fsync it.
//                 write() is not available in this mode.
//
// Not thread-safe; one AtomicFile per writer. Not copyable or movable (the temporary's owner is
// the object on the stack).
class AtomicFile {
public:
    enum class Mode { Stream, ByName };

    AtomicFile(const std::string& path, const std::string& kind, Mode mode = Mode::Stream);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    // Writes n bytes at the current position and advances it. Writing after a seek past the end
    // extends the file (the gap reads as zeros). Mode::Stream only.
    void write(const void* bytes, std::size_t n);
    void write(std::string_view bytes) { write(bytes.data(), bytes.size()); }
    std::uint64_t tell() const { return pos_; }
    void seek(std::uint64_t pos) { pos_ = pos; }

    // Every kWritebackBytes written, the bytes since the last time are handed to the kernel's
    // writeback (Linux's sync_file_range, SYNC_FILE_RANGE_WRITE: it starts the disk writes and
    // does not wait for them), so that the disk writes while the caller computes the next bytes
    // and commit's fsync waits only for the last few. Without it nothing reaches the disk before
    // the fsync: an industrial render's outputs waited 0.22 s in fsync (strace), a fifth of the
    // write stage's thread time. Only a hint: commit's fsync is what makes the bytes durable.
    static constexpr std::uint64_t kWritebackBytes = 4u << 20;

    // fsync, close, rename onto path(), fsync the folder (as a CommitGroup of this one file). After it, the object holds nothing; any
    // further write() or commit() is an error. If it throws, the temporary is gone and path() is as
    // it was before, except when only the final folder sync failed (the message says so): then
    // the new file is in place but its name may not survive a power loss.
    //
    // With a `group` (see CommitGroup), the file is completed by the group instead: its writeback
    // is started now (sync_file_range) and the object hands the temporary to the group, which
    // fsyncs it, renames it onto path() and syncs its folder in group->commit(). After it, the
    // object holds nothing; if it throws, the temporary is gone and path() is as it was.
    void commit(CommitGroup* group = nullptr);

    // Removes the temporary and throws "cannot write <kind> '<path>': <reason>"; for callers
    // whose own step fails (a library reporting an error) so that their message has the same form.
    [[noreturn]] void fail(const std::string& reason);

    const std::string& path() const { return path_; }
    const std::string& kind() const { return kind_; }
    // The temporary file; empty once committed or failed.
    const std::string& temporary_path() const { return tmp_; }

    // True for the names this class gives its temporaries (".<name>.tmp-<16 hex digits>"; `filename`
    // without a folder). A temporary that a running writer still owns has such a name too: clean
    // up only where no other writer can be active.
    static bool is_temporary_name(const std::string& filename);

private:
    void hand_to(CommitGroup& group);
    void discard() noexcept;
    std::string path_, kind_, tmp_;
    Mode mode_;
    int fd_ = -1;
    std::uint64_t pos_ = 0;
    std::uint64_t written_back_ = 0;  // bytes below this were handed to the kernel's writeback
    bool live_ = false;  // a temporary exists that this object owns
};

// Files made durable together: the outputs of a render, written at once by several threads.
//
// Committed alone, each file costs two fsyncs, its own and its folder's, and on ext4 each is a
// journal commit and a flush of the disk's cache: the default scene's 21 outputs, committed alone,
// spend 39 ms of thread time in 44 fsyncs (strace), half of the write stage. Committed into a group, a file's
// writeback starts at once (sync_file_range), and from the group's second file on a thread of the
// group's fsyncs the files as they come in, while the writers compute the next ones (an fsync
// mostly waits for the disk); commit() waits for that thread to have synced every file (one
// journal commit often covers several), then renames each onto its path and syncs each distinct
// folder once. A file committed alone (a group of one) is synced by commit() itself: no thread.
//
// The guarantees are AtomicFile's, for every file of the group, with group.commit() in the place
// of the file's commit(): before it, no file of the group is at its path (every path holds what
// it held); once it returns, every file and its name are on stable storage; a crash in between
// leaves each path with its old or its new content. If commit() throws (the message names the
// file, as AtomicFile's do), the files before the failing one are in place, complete, and the
// failing one and those after it are discarded: their temporaries removed, their paths as they
// were. Destroying a group that was not committed (e.g. while an exception propagates) discards
// every file in it.
//
// AtomicFile::commit(group) may be called from several threads at once; the group's commit()
// once, after every file is in.
class CommitGroup {
public:
    CommitGroup() = default;
    ~CommitGroup();
    CommitGroup(const CommitGroup&) = delete;
    CommitGroup& operator=(const CommitGroup&) = delete;

    void commit();
    // Files handed in and not yet committed or discarded.
    std::size_t size() const;

private:
    friend class AtomicFile;
    struct File {
        int fd = -1;  // the temporary, open
        std::string tmp, path, kind;
        int synced = 0;  // 1 once fsync'ed by the syncer, -errno if that failed, 0 not yet
    };
    void add(File&& file);
    static void discard(File& file) noexcept;
    void sync_loop();
    // Stops the syncer: at once (`drain` false: the group is discarded) or once it has synced
    // every file handed in. Joins it.
    void stop_syncer(bool drain) noexcept;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::vector<File> files_;
    std::thread syncer_;          // started by the second file
    std::size_t next_sync_ = 0;   // files_[next_sync_] is the next the syncer takes
    bool stopping_ = false, draining_ = false;
};

// Writes `bytes` to `path` atomically, with `kind` in error messages (an AtomicFile written and
// committed in one call).
void write_file(const std::string& path, std::string_view bytes, const std::string& kind);

// fsyncs the folder `path`, making the creation, renaming and removal of its entries durable.
// Throws std::runtime_error "cannot sync folder '<path>': <reason>". A file system that cannot
// sync folders at all (fsync fails with EINVAL) is not an error: nothing more can be done there.
void fsync_folder(const std::string& path);

}  // namespace ltm::io
