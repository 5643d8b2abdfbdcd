#pragma once
// JSON in and out, through nlohmann-json (Debian's nlohmann-json3-dev, MIT): every JSON file
// ltmsim reads or writes (run.json, trace-rays' JSON lines, a dataset's labels, index and COCO
// annotations) goes through this header.
//
//   io::Json run = {{"seed", 1}, {"render_seconds", io::json_number(t)}};
//   io::write_json_file(dir + "/run.json", run, "run record");
//
//   io::JsonLinesReader rays(path);                  // InputError "PATH: cannot read ..." if missing
//   for (io::Json v; rays.next(v);)                  // InputError "PATH:LINE:COL: malformed JSON: ..."
//       if (!v.is_object()) rays.fail("expected an object");   // InputError "PATH:LINE: ..."
//
// Reading is strict (RFC 8259, as nlohmann parses it, plus one rule of our own):
//   - exactly one value per text (per line for JSON lines); trailing text is an error;
//   - no comments, no NaN or Infinity literals, no trailing commas, strings valid UTF-8;
//   - a key that occurs twice in one object is an error (nlohmann would keep the last one
//     silently; a user's typo must not be silently dropped). Its column is that of the repeated
//     key's opening quote;
//   - numbers keep nlohmann's types: integers that fit int64/uint64 stay integers, others are
//     doubles; a number too large for a double (1e999) is an error ("... is not finite"): JSON
//     has no infinity, and a value the reader cannot hold is not silently changed.
// Errors are InputError (io/InputError.h) with the file, the 1-based line and column of the
// offending byte, and nlohmann's description ("syntax error while parsing object - unexpected
// end of input; expected '}'"), prefixed by "malformed JSON: ".
//
// Writing: nlohmann prints doubles in the shortest form that reads back to the same double
// (1.0 as "1.0", 0.1 as "0.1"), so writing and reading a number adds no error. Objects are
// io::Json = nlohmann::ordered_json, which keeps keys in insertion order, so files read in the
// order they were written.
#include <cstddef>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace ltm::io {

using Json = nlohmann::ordered_json;

// A double as JSON: the number itself, or for a non-finite value the string "inf", "-inf" or
// "nan" (nlohmann would print null, losing which one it was).
Json json_number(double v);

// Parses one JSON text (see above). `file` and `first_line` only locate errors: a text that starts
// on line `first_line` of `file` reports LINE and COLUMN in that file.
Json parse_json(const std::string& text, const std::string& file, int first_line = 1);

// The whole file parsed; InputError "<path>: cannot read <kind>: <reason>" when it cannot be read.
Json read_json_file(const std::string& path, const std::string& kind);

// value.dump(indent) and a newline, written atomically (io/AtomicFile.h); indent < 0 writes one
// line without spaces.
void write_json_file(const std::string& path, const Json& value, const std::string& kind, int indent = 2);

// A JSON-lines file (one value per line, https://jsonlines.org), read line by line. Blank lines
// (only spaces, tabs or a carriage return) are skipped but counted, so LINE is the line in the file.
// A line longer than kMaxJsonLine bytes is an error (InputError "PATH:LINE: line longer than ..."),
// found after reading at most that many bytes of it: a 1 GB line is refused, not loaded.
inline constexpr std::size_t kMaxJsonLine = std::size_t(1) << 20;
class JsonLinesReader {
public:
    // InputError "<path>: cannot read <kind>" when the file cannot be opened.
    explicit JsonLinesReader(std::string path, const std::string& kind = "JSON lines file");
    // Reads `in` (which must outlive the reader); `name` stands for the file in messages.
    JsonLinesReader(std::istream& in, std::string name);
    // The next non-blank line's value; false at the end of the file.
    bool next(Json& value);
    // The line number (1-based) of the value last returned by next().
    int line() const { return line_; }
    // Throws InputError "<path>:<line>: <what>" for the value last returned.
    [[noreturn]] void fail(const std::string& what) const;

private:
    std::string path_;
    std::ifstream file_;
    std::istream* in_ = nullptr;
    int line_ = 0;
};

}  // namespace ltm::io
