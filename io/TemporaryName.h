#pragma once
// Internal to io/: the names of the temporaries AtomicFile and AtomicFolder create beside their
// targets, and the folder a path lives in.
//   file:   ".<name>.tmp-<16 lowercase hex digits>"
//   folder: ".<name>.tmp-<pid>-<16 lowercase hex digits>"
// The leading dot hides them from a plain `ls`; the random part (from std::random_device, so a
// forked child never repeats its parent's names) makes a collision unlikely, and O_EXCL / mkdir
// make one harmless (the caller retries with a new name).
#include <filesystem>
#include <string>

namespace ltm::io::detail {

// The folder of `path` ("." for a bare file name).
std::filesystem::path folder_of(const std::string& path);

// A fresh temporary name for the target file name `name` (with the process id for folders).
std::string temporary_name(const std::string& name, bool with_pid);

// Whether `filename` has the form temporary_name gives (with or without the process id).
bool is_temporary_name(const std::string& filename, bool with_pid);

}  // namespace ltm::io::detail
