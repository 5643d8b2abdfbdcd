#include "io/InputError.h"

#include <utility>

namespace ltm {

namespace {

std::string compose_message(const std::string& file, int line, int column, const std::string& key_path,
                            const std::string& message) {
    if (line <= 0) return file + ": " + message;
    std::string at = file + ":" + std::to_string(line) + ":";
    if (column > 0) at += std::to_string(column) + ":";
    return at + " " + (key_path.empty() ? "" : key_path + ": ") + message;
}

}  // namespace

InputError::InputError(std::string file_, int line_, int column_, std::string key_path_, std::string message_)
    : std::runtime_error(compose_message(file_, line_, column_, key_path_, message_)),
      file(std::move(file_)),
      line(line_),
      column(column_),
      key_path(std::move(key_path_)),
      message(std::move(message_)) {}

}  // namespace ltm
