#include "app/JsonLine.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

namespace ltm::app {

namespace {

class Reader {
public:
    explicit Reader(const std::string& s) : s_(s) {}
    JsonValue document() {
        JsonValue v = value();
        space();
        if (i_ != s_.size()) fail("unexpected text after the JSON value");
        return v;
    }

private:
    [[noreturn]] void fail(const std::string& what) const { throw JsonError(what, i_ + 1); }
    void space() {
        while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\r' || s_[i_] == '\n')) ++i_;
    }
    bool literal(const char* word) {
        const std::string w(word);
        if (s_.compare(i_, w.size(), w) == 0) {
            i_ += w.size();
            return true;
        }
        return false;
    }
    JsonValue value() {
        space();
        if (i_ >= s_.size()) fail("unexpected end of line");
        JsonValue v;
        const char c = s_[i_];
        if (c == '{') return object();
        if (c == '[') return array();
        if (c == '"') {
            v.type = JsonValue::Type::String;
            v.string = string();
            return v;
        }
        if (literal("true")) { v.type = JsonValue::Type::Bool; v.boolean = true; return v; }
        if (literal("false")) { v.type = JsonValue::Type::Bool; return v; }
        if (literal("null")) return v;
        if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) return number();
        fail(std::string("unexpected character '") + c + "'");
    }
    JsonValue number() {
        // JSON grammar: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
        const size_t start = i_;
        if (s_[i_] == '-') ++i_;
        auto digits = [&] {
            const size_t d0 = i_;
            while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
            if (i_ == d0) fail("malformed number");
        };
        if (i_ < s_.size() && s_[i_] == '0') ++i_; else digits();
        if (i_ < s_.size() && s_[i_] == '.') { ++i_; digits(); }
        if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
            ++i_;
            if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
            digits();
        }
        JsonValue v;
        v.type = JsonValue::Type::Number;
        v.number = std::strtod(s_.substr(start, i_ - start).c_str(), nullptr);
        return v;
    }
    std::string string() {
        ++i_;  // opening quote
        std::string out;
        while (true) {
            if (i_ >= s_.size()) fail("unterminated string");
            const char c = s_[i_++];
            if (c == '"') return out;
            if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
            if (c != '\\') { out += c; continue; }
            if (i_ >= s_.size()) fail("unterminated escape");
            const char e = s_[i_++];
            switch (e) {
                case '"': out += '"'; break;
                case '\\': out += '\\'; break;
                case '/': out += '/'; break;
                case 'b': out += '\b'; break;
                case 'f': out += '\f'; break;
                case 'n': out += '\n'; break;
                case 'r': out += '\r'; break;
                case 't': out += '\t'; break;
                case 'u':
                    if (i_ + 4 > s_.size()) fail("short \\u escape");
                    out += '?';  // keys of interest are ASCII; the code point itself is not needed
                    i_ += 4;
                    break;
                default: fail(std::string("bad escape \\") + e);
            }
        }
    }
    JsonValue array() {
        ++i_;
        JsonValue v;
        v.type = JsonValue::Type::Array;
        space();
        if (i_ < s_.size() && s_[i_] == ']') { ++i_; return v; }
        while (true) {
            v.array.push_back(value());
            space();
            if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
            if (i_ < s_.size() && s_[i_] == ']') { ++i_; return v; }
            fail("expected ',' or ']' in an array");
        }
    }
    JsonValue object() {
        ++i_;
        JsonValue v;
        v.type = JsonValue::Type::Object;
        space();
        if (i_ < s_.size() && s_[i_] == '}') { ++i_; return v; }
        while (true) {
            space();
            if (i_ >= s_.size() || s_[i_] != '"') fail("expected a quoted key");
            const size_t key_at = i_;
            std::string key = string();
            for (const auto& kv : v.object)
                if (kv.first == key) { i_ = key_at; fail("duplicate key \"" + key + "\""); }
            space();
            if (i_ >= s_.size() || s_[i_] != ':') fail("expected ':' after a key");
            ++i_;
            v.object.emplace_back(std::move(key), value());
            space();
            if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
            if (i_ < s_.size() && s_[i_] == '}') { ++i_; return v; }
            fail("expected ',' or '}' in an object");
        }
    }
    const std::string& s_;
    size_t i_ = 0;
};

}  // namespace

JsonValue parse_json_line(const std::string& text) { return Reader(text).document(); }

}  // namespace ltm::app
