// Atomic files and folders (io/AtomicFile.h, io/AtomicFolder.h): exact bytes once committed, the
// target untouched and no temporary left after a failure, errors that name the folder, and
// processes killed with SIGKILL at random moments (fork; fixed seed) never leaving a partial
// target behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "io/AtomicFile.h"
#include "io/AtomicFolder.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;
using ltm::io::AtomicFile;
using ltm::io::AtomicFolder;
using ltm::io::CommitGroup;
using ltm::test::message_of;
using ltm::test::slurp;
using ltm::test::spit;

namespace {

class AtomicFileTest : public ltm::test::LenientTempDirTest {};
class AtomicFolderTest : public ltm::test::LenientTempDirTest {};

// Deterministic bytes (including zeros and every byte value) of length n for a seed.
std::string pattern(std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::string s(n, '\0');
    for (char& c : s) c = static_cast<char>(rng() & 0xFF);
    return s;
}

std::vector<std::string> listing_of(const fs::path& d) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(d)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

struct Boom : std::runtime_error {
    Boom() : std::runtime_error("boom") {}
};

// ---- AtomicFile ----------------------------------------------------------------------------

TEST_F(AtomicFileTest, CommittedFileHasExactlyTheBytes) {
    const std::string bytes = pattern(3 * 1024 * 1024 + 17, 1);
    {
        AtomicFile f(path("a.bin"), "test file");
        EXPECT_EQ(fs::path(f.temporary_path()).parent_path(), dir);
        EXPECT_TRUE(fs::exists(f.temporary_path()));
        f.write(bytes.data(), bytes.size());
        EXPECT_EQ(f.tell(), bytes.size());
        EXPECT_FALSE(fs::exists(path("a.bin")));  // nothing visible before commit
        f.commit();
        EXPECT_TRUE(f.temporary_path().empty());
    }
    EXPECT_EQ(slurp(path("a.bin")), bytes);
    EXPECT_EQ(listing(), std::vector<std::string>{"a.bin"});
}

// Seeking back patches bytes in place (the ZIP writer and OpenEXR do this); a seek past the end
// leaves a gap of zeros.
TEST_F(AtomicFileTest, SeekPatchesAndExtends) {
    {
        AtomicFile f(path("s.bin"), "test file");
        f.write(std::string_view("header??body"));
        f.seek(6);
        f.write(std::string_view("!!"));
        f.seek(14);
        f.write(std::string_view("end"));
        EXPECT_EQ(f.tell(), 17u);
        f.commit();
    }
    EXPECT_EQ(slurp(path("s.bin")), std::string("header!!body\0\0end", 17));
}

TEST_F(AtomicFileTest, WriteFileReplacesAnExistingFileWhole) {
    write("t.txt", "a much longer previous content than the new one\n");
    ltm::io::write_file(path("t.txt"), "new\n", "text file");
    EXPECT_EQ(slurp(path("t.txt")), "new\n");
    ltm::io::write_file(path("empty"), "", "text file");
    EXPECT_TRUE(fs::exists(path("empty")));
    EXPECT_EQ(fs::file_size(path("empty")), 0u);
    EXPECT_EQ(listing(), (std::vector<std::string>{"empty", "t.txt"}));
}

TEST_F(AtomicFileTest, ExceptionBeforeCommitLeavesTheTargetUntouchedAndNoTemporary) {
    const std::string old = "old content\n";
    write("keep.txt", old);
    const auto mtime = fs::last_write_time(path("keep.txt"));
    std::string tmp;
    EXPECT_THROW(
        {
            AtomicFile f(path("keep.txt"), "test file");
            tmp = f.temporary_path();
            f.write(pattern(100000, 2));
            throw Boom();
        },
        Boom);
    EXPECT_FALSE(tmp.empty());
    EXPECT_FALSE(fs::exists(tmp));
    EXPECT_EQ(slurp(path("keep.txt")), old);
    EXPECT_EQ(fs::last_write_time(path("keep.txt")), mtime);
    EXPECT_EQ(listing(), std::vector<std::string>{"keep.txt"});

    // Without a previous file: nothing at all appears.
    EXPECT_THROW(
        {
            AtomicFile f(path("new.txt"), "test file");
            f.write(std::string_view("partial"));
            throw Boom();
        },
        Boom);
    EXPECT_EQ(listing(), std::vector<std::string>{"keep.txt"});
}

TEST_F(AtomicFileTest, MissingFolderIsNamedAndNothingIsCreated) {
    const std::string target = path("no/such/folder/x.bin");
    const std::string msg = message_of([&] { AtomicFile f(target, "test file"); });
    EXPECT_EQ(msg, "cannot write test file '" + target + "': the folder '" + path("no/such/folder") +
                       "' does not exist");
    EXPECT_TRUE(listing().empty());
    EXPECT_EQ(message_of([&] { ltm::io::write_file(target, "x", "text file"); }),
              "cannot write text file '" + target + "': the folder '" + path("no/such/folder") + "' does not exist");

    write("plain", "x");
    EXPECT_EQ(message_of([&] { AtomicFile f(path("plain/x.bin"), "test file"); }),
              "cannot write test file '" + path("plain/x.bin") + "': '" + path("plain") + "' is not a folder");
    EXPECT_EQ(message_of([&] { AtomicFile f("", "test file"); }), "cannot write test file: the path is empty");
}

TEST_F(AtomicFileTest, TargetThatIsAFolderIsRefused) {
    fs::create_directories(dir / "taken" / "inside");
    EXPECT_EQ(message_of([&] { AtomicFile f(path("taken"), "test file"); }),
              "cannot write test file '" + path("taken") + "': it is a folder");
    EXPECT_EQ(listing(), std::vector<std::string>{"taken"});
    EXPECT_EQ(listing_of(dir / "taken"), std::vector<std::string>{"inside"});
}

// A failure after the temporary exists: a folder appears at the target before commit, so the
// final rename fails. The temporary is removed and the folder is untouched.
TEST_F(AtomicFileTest, FailedRenameRemovesTheTemporary) {
    AtomicFile f(path("late"), "test file");
    f.write(std::string_view("bytes"));
    fs::create_directories(dir / "late" / "inside");
    const std::string msg = message_of([&] { f.commit(); });
    EXPECT_NE(msg.find("cannot write test file '" + path("late") + "': renaming the temporary file"), std::string::npos)
        << msg;
    EXPECT_EQ(listing(), std::vector<std::string>{"late"});
    EXPECT_EQ(listing_of(dir / "late"), std::vector<std::string>{"inside"});
    EXPECT_NE(message_of([&] { f.commit(); }).find("internal error"), std::string::npos);
}

TEST_F(AtomicFileTest, WriteOrCommitAfterCommitIsAnError) {
    AtomicFile f(path("once"), "test file");
    f.write(std::string_view("1"));
    f.commit();
    EXPECT_NE(message_of([&] { f.write(std::string_view("2")); }).find("write after commit"), std::string::npos);
    EXPECT_NE(message_of([&] { f.commit(); }).find("commit after commit"), std::string::npos);
    EXPECT_EQ(slurp(path("once")), "1");
}

// Mode::ByName: a stand-in for a library that opens the file by name (here std::ofstream, and a
// library that writes its own file and renames it onto the name it was given).
TEST_F(AtomicFileTest, ByNameHandsTheTemporaryPathToALibrary) {
    write("lib.out", "old");
    {
        AtomicFile f(path("lib.out"), "library file", AtomicFile::Mode::ByName);
        ASSERT_TRUE(fs::is_regular_file(f.temporary_path()));
        EXPECT_EQ(fs::file_size(f.temporary_path()), 0u);
        std::ofstream(f.temporary_path(), std::ios::binary | std::ios::trunc) << "written by name";
        EXPECT_EQ(slurp(path("lib.out")), "old");
        EXPECT_NE(message_of([&] { f.write(std::string_view("x")); }).find("Mode::ByName"), std::string::npos);
    }
    // The write() attempt failed the AtomicFile: nothing changed.
    EXPECT_EQ(slurp(path("lib.out")), "old");
    EXPECT_EQ(listing(), std::vector<std::string>{"lib.out"});

    {
        AtomicFile f(path("lib.out"), "library file", AtomicFile::Mode::ByName);
        std::ofstream(f.temporary_path(), std::ios::binary | std::ios::trunc) << "written by name";
        f.commit();
    }
    EXPECT_EQ(slurp(path("lib.out")), "written by name");

    {
        AtomicFile f(path("lib.out"), "library file", AtomicFile::Mode::ByName);
        spit(dir / "library-own-temp", "replaced by the library");
        fs::rename(dir / "library-own-temp", f.temporary_path());
        f.commit();
    }
    EXPECT_EQ(slurp(path("lib.out")), "replaced by the library");

    {
        AtomicFile f(path("lib.out"), "library file", AtomicFile::Mode::ByName);
        std::ofstream(f.temporary_path()) << "abandoned";
    }
    EXPECT_EQ(slurp(path("lib.out")), "replaced by the library");
    EXPECT_EQ(listing(), std::vector<std::string>{"lib.out"});

    // A library that removed the file instead of writing it.
    {
        AtomicFile f(path("lib.out"), "library file", AtomicFile::Mode::ByName);
        fs::remove(f.temporary_path());
        EXPECT_NE(message_of([&] { f.commit(); }).find("reopening the temporary file"), std::string::npos);
    }
    EXPECT_EQ(slurp(path("lib.out")), "replaced by the library");
    EXPECT_EQ(listing(), std::vector<std::string>{"lib.out"});
}

TEST_F(AtomicFileTest, TemporaryNamesAreRecognised) {
    AtomicFile f(path("data.npz"), "test file");
    const std::string name = fs::path(f.temporary_path()).filename().string();
    EXPECT_EQ(name.rfind(".data.npz.tmp-", 0), 0u) << name;
    EXPECT_TRUE(AtomicFile::is_temporary_name(name)) << name;
    EXPECT_FALSE(AtomicFolder::is_temporary_name(name)) << name;
    for (const char* other : {"data.npz", ".data.npz", ".data.npz.tmp-", ".data.npz.tmp-0123456789abcdeg",
                              ".data.npz.tmp-0123456789ABCDEF", ".data.npz.tmp-0123456789abcde",
                              ".tmp-0123456789abcdef", "data.npz.tmp-0123456789abcdef",
                              ".data.npz.tmp-12-0123456789abcdef"})
        EXPECT_FALSE(AtomicFile::is_temporary_name(other)) << other;
    EXPECT_TRUE(AtomicFile::is_temporary_name(".x.tmp-0123456789abcdef"));
}

TEST_F(AtomicFileTest, FsyncFolder) {
    EXPECT_NO_THROW(ltm::io::fsync_folder(dir.string()));
    const std::string missing = path("missing");
    EXPECT_EQ(message_of([&] { ltm::io::fsync_folder(missing); }).rfind("cannot sync folder '" + missing + "': ", 0),
              0u);
}

// ---- CommitGroup ---------------------------------------------------------------------------

// The names in d that are AtomicFile temporaries.
std::size_t temporaries_in(const fs::path& d) {
    const auto names = listing_of(d);
    return static_cast<std::size_t>(std::count_if(names.begin(), names.end(), AtomicFile::is_temporary_name));
}

// Files committed into a group from two threads at once, in two folders, one of them replacing a
// file: nothing is at its path until the group's commit (the old content stays readable, the
// temporaries wait beside the targets); after it every file holds exactly its bytes and no
// temporary is left.
TEST_F(AtomicFileTest, AGroupPutsItsFilesInPlaceAtItsCommitOnly) {
    fs::create_directories(dir / "sub");
    write("old.bin", "old content");
    const std::vector<std::string> targets = {path("old.bin"), path("new.bin"), (dir / "sub" / "a.png").string(),
                                              (dir / "sub" / "b.png").string()};
    std::vector<std::string> bytes;
    for (std::size_t k = 0; k < targets.size(); ++k)
        bytes.push_back(pattern(k == 1 ? AtomicFile::kWritebackBytes + 12345 : 1000 + 17 * k, 7 + static_cast<std::uint32_t>(k)));
    CommitGroup group;
    std::vector<std::thread> writers;
    for (std::size_t half = 0; half < 2; ++half)
        writers.emplace_back([&, half] {
            for (std::size_t k = half; k < targets.size(); k += 2) {
                AtomicFile f(targets[k], "test file");
                f.write(bytes[k]);
                f.commit(&group);
                EXPECT_TRUE(f.temporary_path().empty());
            }
        });
    for (auto& w : writers) w.join();
    EXPECT_EQ(group.size(), targets.size());
    EXPECT_EQ(slurp(path("old.bin")), "old content");
    EXPECT_FALSE(fs::exists(path("new.bin")));
    EXPECT_EQ(listing_of(dir / "sub").size(), 2u);
    EXPECT_EQ(temporaries_in(dir), 2u);
    EXPECT_EQ(temporaries_in(dir / "sub"), 2u);

    group.commit();
    EXPECT_EQ(group.size(), 0u);
    for (std::size_t k = 0; k < targets.size(); ++k) EXPECT_EQ(slurp(targets[k]), bytes[k]) << targets[k];
    EXPECT_EQ(listing(), (std::vector<std::string>{"new.bin", "old.bin", "sub"}));
    EXPECT_EQ(listing_of(dir / "sub"), (std::vector<std::string>{"a.png", "b.png"}));
    EXPECT_NO_THROW(group.commit());  // an empty group has nothing to do
}

// A group destroyed without its commit (an exception on the way) discards every file: the paths
// hold what they held and no temporary is left. Mode::ByName files join a group as well.
TEST_F(AtomicFileTest, AGroupNotCommittedLeavesEveryPathAsItWas) {
    write("kept.txt", "kept");
    EXPECT_THROW(
        {
            CommitGroup group;
            AtomicFile a(path("kept.txt"), "test file");
            a.write(std::string_view("replacement"));
            a.commit(&group);
            AtomicFile b(path("by-name.txt"), "library file", AtomicFile::Mode::ByName);
            std::ofstream(b.temporary_path()) << "written by name";
            b.commit(&group);
            EXPECT_EQ(listing().size(), 3u);
            throw Boom();
        },
        Boom);
    EXPECT_EQ(listing(), std::vector<std::string>{"kept.txt"});
    EXPECT_EQ(slurp(path("kept.txt")), "kept");

    CommitGroup group;
    AtomicFile b(path("by-name.txt"), "library file", AtomicFile::Mode::ByName);
    std::ofstream(b.temporary_path()) << "written by name";
    b.commit(&group);
    group.commit();
    EXPECT_EQ(slurp(path("by-name.txt")), "written by name");
    EXPECT_EQ(listing(), (std::vector<std::string>{"by-name.txt", "kept.txt"}));
}

// The group's commit fails at its second file (a folder appeared at its path, so the rename
// fails): the error names that file as AtomicFile's does, the file before it is in place and
// complete, the one after it is discarded, and no temporary is left.
TEST_F(AtomicFileTest, AGroupThatFailsKeepsTheFilesBeforeAndDiscardsTheRest) {
    write("third", "third's old content");
    CommitGroup group;
    for (const char* name : {"first", "second", "third"}) {
        AtomicFile f(path(name), "test file");
        f.write(std::string_view(name));
        f.commit(&group);
    }
    fs::create_directories(dir / "second" / "inside");
    const std::string msg = message_of([&] { group.commit(); });
    EXPECT_EQ(msg.rfind("cannot write test file '" + path("second") + "': renaming the temporary file '", 0), 0u) << msg;
    EXPECT_NE(msg.find("' onto it failed: "), std::string::npos) << msg;
    EXPECT_EQ(slurp(path("first")), "first");
    EXPECT_EQ(listing_of(dir / "second"), std::vector<std::string>{"inside"});
    EXPECT_EQ(slurp(path("third")), "third's old content");
    EXPECT_EQ(listing(), (std::vector<std::string>{"first", "second", "third"}));
    EXPECT_EQ(group.size(), 0u);
}

// ---- AtomicFolder --------------------------------------------------------------------------

TEST_F(AtomicFolderTest, UncommittedLeavesNothing) {
    std::string tmp;
    EXPECT_THROW(
        {
            AtomicFolder f(path("sample"));
            tmp = f.path();
            EXPECT_TRUE(fs::is_directory(tmp));
            EXPECT_EQ(fs::path(tmp).parent_path(), dir);
            ltm::io::write_file(tmp + "/a.bin", pattern(1000, 3), "test file");
            fs::create_directory(tmp + "/sub");
            spit(tmp + "/sub/plain.txt", "plain");
            throw Boom();
        },
        Boom);
    EXPECT_FALSE(fs::exists(tmp));
    EXPECT_FALSE(fs::exists(path("sample")));
    EXPECT_TRUE(listing().empty());
}

TEST_F(AtomicFolderTest, CommittedFolderIsComplete) {
    const std::string a = pattern(200000, 4);
    {
        AtomicFolder f(path("sample"), "sample");
        EXPECT_EQ(f.final_path(), path("sample"));
        ltm::io::write_file(f.path() + "/a.bin", a, "test file");
        fs::create_directory(f.path() + "/sub");
        spit(f.path() + "/sub/plain.txt", "plain");
        EXPECT_FALSE(fs::exists(path("sample")));
        f.commit();
        EXPECT_TRUE(f.path().empty());
    }
    EXPECT_EQ(listing(), std::vector<std::string>{"sample"});
    EXPECT_EQ(listing_of(dir / "sample"), (std::vector<std::string>{"a.bin", "sub"}));
    EXPECT_EQ(slurp(dir / "sample" / "a.bin"), a);
    EXPECT_EQ(slurp(dir / "sample" / "sub" / "plain.txt"), "plain");

    // A trailing slash names the same folder.
    {
        AtomicFolder f(path("other") + "/");
        EXPECT_EQ(f.final_path(), path("other"));
        f.commit();
    }
    EXPECT_TRUE(fs::is_directory(path("other")));
}

TEST_F(AtomicFolderTest, ReplacesAnExistingFolder) {
    fs::create_directories(dir / "sample" / "old-sub");
    spit(dir / "sample" / "old.txt", "old");
    spit(dir / "sample" / "shared.txt", "old shared");
    {
        AtomicFolder f(path("sample"));
        spit(f.path() + "/shared.txt", "new shared");
        spit(f.path() + "/new.txt", "new");
        // Until commit the old folder is there as it was.
        EXPECT_EQ(listing_of(dir / "sample"), (std::vector<std::string>{"old-sub", "old.txt", "shared.txt"}));
        f.commit();
    }
    EXPECT_EQ(listing(), std::vector<std::string>{"sample"});  // the old one is gone, no temporary left
    EXPECT_EQ(listing_of(dir / "sample"), (std::vector<std::string>{"new.txt", "shared.txt"}));
    EXPECT_EQ(slurp(dir / "sample" / "shared.txt"), "new shared");
}

TEST_F(AtomicFolderTest, ErrorsNameTheFolder) {
    const std::string nowhere = path("missing/sample");
    EXPECT_EQ(message_of([&] { AtomicFolder f(nowhere, "sample"); }),
              "cannot write sample '" + nowhere + "': the folder '" + path("missing") + "' does not exist");
    write("file", "x");
    EXPECT_EQ(message_of([&] { AtomicFolder f(path("file")); }),
              "cannot write folder '" + path("file") + "': it exists and is not a folder");
    // A file that appears at the final path before commit: refused, the temporary removed.
    {
        AtomicFolder f(path("late"));
        spit(f.path() + "/x", "x");
        write("late", "a file in the way");
        EXPECT_EQ(message_of([&] { f.commit(); }),
                  "cannot write folder '" + path("late") + "': it exists and is not a folder");
        EXPECT_NE(message_of([&] { f.commit(); }).find("commit after commit or failure"), std::string::npos);
    }
    EXPECT_EQ(slurp(path("late")), "a file in the way");
    EXPECT_EQ(listing(), (std::vector<std::string>{"file", "late"}));
}

TEST_F(AtomicFolderTest, TemporaryNamesAreRecognised) {
    AtomicFolder f(path("sample-0001"));
    const std::string name = fs::path(f.path()).filename().string();
    EXPECT_EQ(name.rfind(".sample-0001.tmp-" + std::to_string(::getpid()) + "-", 0), 0u) << name;
    EXPECT_TRUE(AtomicFolder::is_temporary_name(name)) << name;
    EXPECT_FALSE(AtomicFile::is_temporary_name(name)) << name;
    for (const char* other : {"sample-0001", ".sample-0001", ".sample-0001.tmp-0123456789abcdef",
                              ".sample-0001.tmp--0123456789abcdef", ".sample-0001.tmp-12x-0123456789abcdef",
                              ".sample-0001.tmp-12-0123456789abcdeF", ".tmp-12-0123456789abcdef"})
        EXPECT_FALSE(AtomicFolder::is_temporary_name(other)) << other;
    EXPECT_TRUE(AtomicFolder::is_temporary_name(".s.tmp-1-0123456789abcdef"));
}

// ---- processes killed at random moments ------------------------------------------------------

// Runs `work` in a child process that reports progress by writing one byte to a pipe after each
// step (`work` calls step()). The parent waits for `steps_before_kill` progress bytes (or the
// child's end), then for `delay_us` microseconds, and kills the child with SIGKILL (which no
// handler can intercept: no destructor, no cleanup). Returns false if the child failed by itself.
class Child {
public:
    static bool run_and_kill(const std::function<void(const std::function<void()>&)>& work, int steps_before_kill,
                             int delay_us) {
        int fds[2];
        if (::pipe(fds) != 0) return false;
        const pid_t pid = ::fork();
        if (pid < 0) return false;
        if (pid == 0) {
            ::close(fds[0]);
            const int out = fds[1];
            try {
                work([out] {
                    const char c = 's';
                    (void)!::write(out, &c, 1);
                    ::usleep(200);  // slow enough that a kill after k steps lands near step k
                });
            } catch (...) {
                ::_exit(2);
            }
            ::_exit(0);
        }
        ::close(fds[1]);
        char c;
        for (int seen = 0; seen < steps_before_kill && ::read(fds[0], &c, 1) == 1; ++seen) {
        }
        ::usleep(static_cast<useconds_t>(delay_us));
        ::kill(pid, SIGKILL);
        int status = 0;
        ::waitpid(pid, &status, 0);
        ::close(fds[0]);
        return WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0);
    }
};

constexpr std::size_t kChunk = 256 * 1024;

// A child writes a 4 MiB file (16 steps) with AtomicFile and is killed at a random step. The
// target is then absent (or its old content, when there was one) or complete, never partial;
// anything else left is an AtomicFile temporary, which a cleanup removes.
TEST_F(AtomicFileTest, KilledWriterNeverLeavesAPartialFile) {
    constexpr int kSteps = 16, kIterations = 24;
    const std::string target = path("big.bin");
    std::mt19937 rng(20240611);
    std::map<std::string, int> outcomes;
    for (int it = 0; it < kIterations; ++it) {
        SCOPED_TRACE("iteration " + std::to_string(it));
        const bool had_old = it % 2 == 1;
        const std::string old = "previous content " + std::to_string(it);
        const std::string bytes = pattern(kSteps * kChunk, 100 + static_cast<std::uint32_t>(it));
        if (had_old) spit(target, old);
        // Kill after 0 .. kSteps + 1 steps (the last one is reported after commit returned, so a
        // kill then must find the file complete), waiting for that last one a quarter of the time.
        const int steps = std::min<int>(kSteps + 1, static_cast<int>(rng() % (4 * (kSteps + 1) / 3)));
        const int delay = static_cast<int>(rng() % 400);
        ASSERT_TRUE(Child::run_and_kill(
            [&](const std::function<void()>& step) {
                AtomicFile f(target, "test file");
                for (int k = 0; k < kSteps; ++k) {
                    f.write(bytes.data() + static_cast<std::size_t>(k) * kChunk, kChunk);
                    step();
                }
                f.commit();
                step();
            },
            steps, delay));

        std::string what;
        if (!fs::exists(target)) {
            EXPECT_FALSE(had_old) << "the old file vanished";
            what = "absent";
        } else {
            const std::string got = slurp(target);
            if (got == bytes)
                what = "complete";
            else if (had_old && got == old)
                what = "old";
            else
                ADD_FAILURE() << "partial or corrupt target: " << got.size() << " bytes";
        }
        if (steps == kSteps + 1) {
            EXPECT_EQ(what, "complete") << "killed after commit returned";
        }
        ++outcomes[what];
        for (const std::string& name : listing()) {
            if (name == "big.bin") continue;
            EXPECT_TRUE(AtomicFile::is_temporary_name(name)) << name;
            fs::remove(dir / name);  // the cleanup a later run would do
        }
        fs::remove(target);
    }
    for (const auto& [what, n] : outcomes) std::printf("killed writer: target %s %d times\n", what.c_str(), n);
}

// The same for three files of 1 MiB committed together (CommitGroup), with the kill anywhere from
// the first write to after the group's commit returned: each target is absent (or its old
// content) or complete, never partial, and all three are complete once the commit returned.
TEST_F(AtomicFileTest, KilledGroupWriterNeverLeavesAPartialFile) {
    constexpr int kFiles = 3, kSteps = 4 * kFiles, kIterations = 16;
    std::mt19937 rng(20261205);
    std::map<std::string, int> outcomes;
    for (int it = 0; it < kIterations; ++it) {
        SCOPED_TRACE("iteration " + std::to_string(it));
        std::vector<std::string> targets, bytes;
        for (int k = 0; k < kFiles; ++k) {
            targets.push_back(path("file" + std::to_string(k)));
            bytes.push_back(pattern(4 * kChunk, 300 + static_cast<std::uint32_t>(kFiles * it + k)));
        }
        const bool had_old = it % 2 == 1;
        if (had_old)
            for (const auto& t : targets) spit(t, "old " + t);
        const int steps = std::min<int>(kSteps + 1, static_cast<int>(rng() % (4 * (kSteps + 1) / 3)));
        const int delay = static_cast<int>(rng() % 400);
        ASSERT_TRUE(Child::run_and_kill(
            [&](const std::function<void()>& step) {
                CommitGroup group;
                for (int k = 0; k < kFiles; ++k) {
                    AtomicFile f(targets[static_cast<std::size_t>(k)], "test file");
                    for (int c = 0; c < 4; ++c) {
                        f.write(bytes[static_cast<std::size_t>(k)].data() + static_cast<std::size_t>(c) * kChunk, kChunk);
                        if (c < 3) step();
                    }
                    f.commit(&group);
                    step();
                }
                group.commit();
                step();
            },
            steps, delay));
        for (int k = 0; k < kFiles; ++k) {
            const std::string& t = targets[static_cast<std::size_t>(k)];
            std::string what;
            if (!fs::exists(t)) {
                EXPECT_FALSE(had_old) << "the old file vanished";
                what = "absent";
            } else {
                const std::string got = slurp(t);
                if (got == bytes[static_cast<std::size_t>(k)])
                    what = "complete";
                else if (had_old && got == "old " + t)
                    what = "old";
                else
                    ADD_FAILURE() << "partial or corrupt target " << t << ": " << got.size() << " bytes";
            }
            if (steps == kSteps + 1) {
                EXPECT_EQ(what, "complete") << "killed after the group's commit returned";
            }
            ++outcomes[what];
        }
        for (const std::string& name : listing()) {
            if (name.rfind("file", 0) == 0) continue;
            EXPECT_TRUE(AtomicFile::is_temporary_name(name)) << name;
            fs::remove(dir / name);
        }
        for (const auto& t : targets) fs::remove(t);
    }
    for (const auto& [what, n] : outcomes) std::printf("killed group writer: a target %s %d times\n", what.c_str(), n);
}

// The same for a folder of 8 files of 256 KiB (each written with AtomicFile, one step each):
// afterwards the final folder is absent (or the old complete folder) or complete.
TEST_F(AtomicFolderTest, KilledWriterNeverLeavesAPartialFolder) {
    constexpr int kFiles = 8, kIterations = 16;
    const fs::path final_dir = dir / "sample";
    std::mt19937 rng(20240612);
    std::map<std::string, int> outcomes;
    const std::map<std::string, std::string> old_files = {{"old-a", "old a"}, {"old-b", "old b"}};
    for (int it = 0; it < kIterations; ++it) {
        SCOPED_TRACE("iteration " + std::to_string(it));
        const bool had_old = it % 2 == 1;
        std::map<std::string, std::string> files;
        for (int k = 0; k < kFiles; ++k)
            files["file-" + std::to_string(k)] = pattern(kChunk, 1000 * static_cast<std::uint32_t>(it) + k);
        if (had_old) {
            fs::create_directory(final_dir);
            for (const auto& [name, bytes] : old_files) spit(final_dir / name, bytes);
        }
        const auto holds = [](const fs::path& d, const std::map<std::string, std::string>& expected) {
            std::vector<std::string> names;
            for (const auto& [name, bytes] : expected) {
                names.push_back(name);
                if (slurp(d / name) != bytes) return false;
            }
            return listing_of(d) == names;
        };
        const int steps = std::min<int>(kFiles + 1, static_cast<int>(rng() % (4 * (kFiles + 1) / 3)));
        const int delay = static_cast<int>(rng() % 400);
        ASSERT_TRUE(Child::run_and_kill(
            [&](const std::function<void()>& step) {
                AtomicFolder f(final_dir.string(), "sample");
                for (const auto& [name, bytes] : files) {
                    ltm::io::write_file(f.path() + "/" + name, bytes, "test file");
                    step();
                }
                f.commit();
                step();
            },
            steps, delay));

        std::string what;
        bool old_kept_aside = false;  // the rename-aside fallback, killed between its two renames
        for (const std::string& name : listing()) {
            if (name == "sample") continue;
            EXPECT_TRUE(AtomicFolder::is_temporary_name(name)) << name;
            if (had_old && !fs::exists(final_dir) && holds(dir / name, old_files)) old_kept_aside = true;
        }
        if (!fs::exists(final_dir)) {
            EXPECT_TRUE(!had_old || old_kept_aside) << "the old folder vanished";
            what = "absent";
        } else if (holds(final_dir, files)) {
            what = "complete";
        } else if (had_old && holds(final_dir, old_files)) {
            what = "old";
        } else {
            ADD_FAILURE() << "partial folder: " << ::testing::PrintToString(listing_of(final_dir));
        }
        if (steps == kFiles + 1) {
            EXPECT_EQ(what, "complete") << "killed after commit returned";
        }
        ++outcomes[what];
        for (const std::string& name : listing())
            if (AtomicFolder::is_temporary_name(name)) fs::remove_all(dir / name);  // a later run's cleanup
        fs::remove_all(final_dir);
        EXPECT_TRUE(listing().empty());
    }
    for (const auto& [what, n] : outcomes) std::printf("killed writer: folder %s %d times\n", what.c_str(), n);
}

}  // namespace
