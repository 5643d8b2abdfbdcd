#pragma once
// A strict reader for one line of JSON (RFC 8259): objects, arrays, numbers, strings, true,
// false, null. Enough for the rays files of `ltmsim trace-rays`; errors say what and where.
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace ltm::app {

struct JsonValue {
    enum class Type { Null, Bool, Number, String, Array, Object } type = Type::Null;
    bool boolean = false;
    double number = 0;
    std::string string;
    std::vector<JsonValue> array;
    std::vector<std::pair<std::string, JsonValue>> object;  // in file order (duplicates detected)
};

struct JsonError : std::runtime_error {
    size_t column;  // 1-based
    JsonError(const std::string& what, size_t col) : std::runtime_error(what), column(col) {}
};

JsonValue parse_json_line(const std::string& text);

}  // namespace ltm::app
