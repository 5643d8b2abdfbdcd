#pragma once
// A folder that appears complete or not at all (the folder form of io/AtomicFile.h).
//
//   io::AtomicFolder sample(out + "/sample-0007");
//   io::write_file(sample.path() + "/image.png", png, "PNG image");   // any number of files
//   io::write_npz(sample.path() + "/arrays.npz", arrays);
//   sample.commit();                                                  // now out/sample-0007 exists, whole
//
// The constructor creates a fresh, empty temporary folder ".<name>.tmp-<pid>-<16 hex digits>"
// beside the final path (in the same parent folder, so that the final rename never crosses file
// systems). Write into path() with AtomicFile, io::write_npz, or plain files; subfolders are fine.
//
// commit():
//   1. fsyncs every regular file and every folder below path() and path() itself, so the
//      contents are on stable storage before the folder gets its final name;
//   2. renames path() onto the final path:
//      - if nothing is there: a plain rename (RENAME_NOREPLACE where the file system supports it,
//        so that a folder appearing there meanwhile is not silently merged or replaced);
//      - if a folder is there, it is replaced. Where the file system supports it (Linux
//        renameat2 RENAME_EXCHANGE: ext4, XFS, Btrfs, tmpfs), the two folders swap names in one
//        atomic step, so the final path holds the old or the new complete folder at every
//        instant. Elsewhere the old folder is first renamed aside to a temporary name and the new
//        one renamed in: a crash between the two renames leaves no folder at the final path but
//        the old complete one under its temporary name;
//      - anything else there (a file) is an error;
//   3. fsyncs the parent folder (now the new name is durable);
//   4. removes the old folder, if any (its temporary name, recognised by is_temporary_name, is
//      all that stays behind if the process dies now or the removal fails; that is not an error,
//      as the new folder is complete and in place).
// So after a crash at any point the final path holds the old complete folder, or the new
// complete folder, or (only with the rename-aside fallback, between its two renames) nothing,
// with the old complete folder kept under a temporary name; never a partial folder. Plus at most
// stray temporaries, for a later run to remove.
//
// Destroying an AtomicFolder that was not committed removes the temporary folder with all it
// holds (errors ignored: a destructor cannot report them, and what is left is recognisable).
//
// Errors are std::runtime_error "cannot write <kind> '<final path>': <reason>"; the constructor
// names the parent folder when it does not exist (it is never created).
//
// Stale temporaries: a killed process leaves its temporary folder behind. is_temporary_name
// recognises the names AtomicFolder creates (only those: AtomicFile::is_temporary_name recognises
// a file's); the process id in the name tells which process owned it (kill(pid, 0) on the same
// machine says whether it still runs). Remove one only where no other writer can be active.
#include <string>

namespace ltm::io {

class AtomicFolder {
public:
    explicit AtomicFolder(const std::string& final_path, const std::string& kind = "folder");
    ~AtomicFolder();
    AtomicFolder(const AtomicFolder&) = delete;
    AtomicFolder& operator=(const AtomicFolder&) = delete;

    // The temporary folder to write into; empty once committed (or after a failed commit).
    const std::string& path() const { return tmp_; }
    const std::string& final_path() const { return final_; }

    // Steps 1-4 above. If it throws before the rename, the temporary folder is removed and the
    // final path is as it was.
    void commit();

    // True for the names AtomicFolder gives its temporaries (".<name>.tmp-<pid>-<16 hex digits>";
    // `filename` without a folder).
    static bool is_temporary_name(const std::string& filename);

private:
    [[noreturn]] void fail(const std::string& reason);
    void discard() noexcept;
    std::string final_, kind_, tmp_;
    bool live_ = false;  // tmp_ exists and this object owns it
};

}  // namespace ltm::io
