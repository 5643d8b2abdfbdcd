#include "io/Json.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "io/AtomicFile.h"
#include "io/InputError.h"

namespace ltm::io {

namespace {

// A character iterator that records how many characters nlohmann's lexer has consumed, so that a
// problem found in the parser callback (which is given no position) can still be located.
struct CountingIterator {
    using iterator_category = std::forward_iterator_tag;
    using value_type = char;
    using difference_type = std::ptrdiff_t;
    using pointer = const char*;
    using reference = const char&;

    const char* p = nullptr;
    const char* base = nullptr;
    std::size_t* consumed = nullptr;

    reference operator*() const { return *p; }
    CountingIterator& operator++() {
        ++p;
        *consumed = static_cast<std::size_t>(p - base);
        return *this;
    }
    CountingIterator operator++(int) {
        CountingIterator old = *this;
        ++*this;
        return old;
    }
    bool operator==(const CountingIterator& o) const { return p == o.p; }
    bool operator!=(const CountingIterator& o) const { return p != o.p; }
};

struct DuplicateKey {
    std::size_t offset;  // 0-based offset of the repeated key's opening quote
    std::string key;
};

// The 0-based offset of the opening quote of the string whose closing quote is at `close`:
// the nearest '"' before it that is not escaped (preceded by an even number of backslashes).
std::size_t opening_quote(const std::string& text, std::size_t close) {
    for (std::size_t j = close; j-- > 0;) {
        if (text[j] != '"') continue;
        std::size_t backslashes = 0;
        while (j > backslashes && text[j - 1 - backslashes] == '\\') ++backslashes;
        if (backslashes % 2 == 0) return j;
    }
    return 0;
}

// Line and column (1-based) of the 0-based offset `at` in `text`, the text starting on first_line.
std::pair<int, int> locate(const std::string& text, std::size_t at, int first_line) {
    at = std::min(at, text.size());
    int line = first_line;
    std::size_t line_start = 0;
    for (std::size_t i = 0; i < at; ++i)
        if (text[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    return {line, static_cast<int>(at - line_start) + 1};
}

// nlohmann's message without its "[json.exception.parse_error.101] parse error at line 1,
// column 5: " prefix (the location is ours, in the user's file).
std::string bare_message(const std::string& what) {
    const std::size_t col = what.find("column ");
    const std::size_t colon = col == std::string::npos ? std::string::npos : what.find(": ", col);
    if (colon != std::string::npos) return what.substr(colon + 2);
    const std::size_t bracket = what.find("] ");
    return bracket == std::string::npos ? what : what.substr(bracket + 2);
}

}  // namespace

Json json_number(double v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return v;
}

Json parse_json(const std::string& text, const std::string& file, int first_line) {
    std::size_t consumed = 0;
    const CountingIterator first{text.data(), text.data(), &consumed};
    const CountingIterator last{text.data() + text.size(), text.data(), &consumed};
    std::vector<std::set<std::string>> keys;  // the keys seen in each object being read
    auto check_keys = [&](int /*depth*/, Json::parse_event_t event, Json& parsed) {
        switch (event) {
            case Json::parse_event_t::object_start: keys.emplace_back(); break;
            case Json::parse_event_t::object_end: keys.pop_back(); break;
            case Json::parse_event_t::key: {
                // The lexer has just read the key's closing quote (strings need no look-ahead).
                std::string key = parsed.get<std::string>();
                if (!keys.back().insert(key).second) throw DuplicateKey{opening_quote(text, consumed - 1), std::move(key)};
                break;
            }
            default: break;
        }
        return true;
    };
    try {
        return Json::parse(first, last, check_keys);
    } catch (const DuplicateKey& d) {
        const auto [line, column] = locate(text, d.offset, first_line);
        throw InputError(file, line, column, "", "malformed JSON: duplicate key " + Json(d.key).dump());
    } catch (const Json::out_of_range& e) {
        // nlohmann refuses a number that overflows a double ("number overflow parsing '1e999'"):
        // locate the number (the lexer has read it and one character more).
        const std::string what = e.what();
        const std::size_t q0 = what.find('\''), q1 = what.rfind('\'');
        const std::string token = q0 != std::string::npos && q1 > q0 ? what.substr(q0 + 1, q1 - q0 - 1) : "";
        const std::size_t at = token.empty() ? std::string::npos : text.rfind(token, consumed);
        const auto [line, column] = locate(text, at == std::string::npos ? consumed : at, first_line);
        throw InputError(file, line, column, "",
                         "malformed JSON: the number " + (token.empty() ? std::string("read") : token) +
                             " is not finite (it overflows a double)");
    } catch (const Json::parse_error& e) {
        // e.byte: the 1-based count of characters read, the last one being the offending one.
        const auto [line, column] = locate(text, e.byte > 0 ? e.byte - 1 : 0, first_line);
        throw InputError(file, line, column, "", "malformed JSON: " + bare_message(e.what()));
    }
}

Json read_json_file(const std::string& path, const std::string& kind) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, 0, "", "cannot read " + kind + ": " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path, 0, 0, "", "cannot read " + kind + ": read error");
    return parse_json(text.str(), path);
}

void write_json_file(const std::string& path, const Json& value, const std::string& kind, int indent) {
    write_file(path, value.dump(indent) + "\n", kind);
}

JsonLinesReader::JsonLinesReader(std::string path, const std::string& kind)
    : path_(std::move(path)), file_(path_, std::ios::binary), in_(&file_) {
    if (!file_) throw InputError(path_, 0, 0, "", "cannot read " + kind + ": " + std::strerror(errno));
    std::error_code ec;
    if (std::filesystem::is_directory(path_, ec)) throw InputError(path_, 0, 0, "", "cannot read " + kind + ": it is a folder");
}

JsonLinesReader::JsonLinesReader(std::istream& in, std::string name) : path_(std::move(name)), in_(&in) {}

bool JsonLinesReader::next(Json& value) {
    std::string text;
    std::streambuf* buf = in_->rdbuf();
    for (;;) {
        text.clear();
        int c = buf ? buf->sbumpc() : std::char_traits<char>::eof();
        if (c == std::char_traits<char>::eof()) return false;
        ++line_;
        for (; c != std::char_traits<char>::eof() && c != '\n'; c = buf->sbumpc()) {
            if (text.size() == kMaxJsonLine)
                fail("line longer than " + std::to_string(kMaxJsonLine) + " bytes (one JSON value per line is expected)");
            text.push_back(static_cast<char>(c));
        }
        if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
        value = parse_json(text, path_, line_);
        return true;
    }
}

void JsonLinesReader::fail(const std::string& what) const { throw InputError(path_, line_, 0, "", what); }

}  // namespace ltm::io
