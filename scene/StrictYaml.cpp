#include "scene/StrictYaml.h"

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

namespace ltm::yaml {

// ---------------------------------------------------------------------------------------------
// Locations and mapping entries

Loc loc_of(const YAML::Node& n) {
    const YAML::Mark m = n.Mark();
    if (m.is_null() || m.line < 0) return {1, 1};
    return {m.line + 1, m.column + 1};
}

std::vector<Item> items_of(const YAML::Node& map) {
    std::vector<Item> out;
    for (auto it = map.begin(); it != map.end(); ++it)
        out.push_back({it->first.IsScalar() ? it->first.Scalar() : std::string(), it->first, it->second});
    return out;
}

const Item* find_item(const std::vector<Item>& items, const std::string& key) {
    for (const Item& it : items)
        if (it.key_node.IsScalar() && it.key == key) return &it;
    return nullptr;
}

std::string enclosing_key(const std::string& key, const std::function<bool(const std::string&)>& known) {
    for (std::string k = key; !k.empty();) {
        if (known(k)) return k;
        const auto cut = k.find_last_of(".[");
        if (cut == std::string::npos) break;
        k = k.substr(0, cut);
    }
    return "";
}

Loc located(const Where& where, const std::string& key, Loc fallback) {
    const std::string k = enclosing_key(key, [&](const std::string& x) { return where.count(x) > 0; });
    return k.empty() ? fallback : where.at(k);
}

std::string join_path(const std::string& parent, const std::string& key) {
    if (parent.empty()) return key;
    if (key.empty()) return parent;
    if (!key.empty() && key.front() == '[') return parent + key;
    return parent + "." + key;
}

// ---------------------------------------------------------------------------------------------
// Words in messages

std::string one_line(const std::string& s) {
    std::string t;
    for (char c : s) t += (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
    return t;
}

namespace {

std::string clip(const std::string& s) {
    std::string t = one_line(s);
    if (t.size() > 40) t = t.substr(0, 37) + "...";
    return t;
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::size_t levenshtein(const std::string& a, const std::string& b) {
    std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

}  // namespace

bool is_plain(const YAML::Node& n) {
    const std::string& tag = n.Tag();
    return tag == "?" || tag == "tag:yaml.org,2002:float" || tag == "tag:yaml.org,2002:int" ||
           tag == "tag:yaml.org,2002:bool";
}

std::string describe(const YAML::Node& n) {
    switch (n.Type()) {
        case YAML::NodeType::Undefined:
        case YAML::NodeType::Null: return "an empty value";
        case YAML::NodeType::Sequence:
            return n.size() == 1 ? "a list of 1 item" : fmt::format("a list of {} items", n.size());
        case YAML::NodeType::Map: return "a mapping";
        case YAML::NodeType::Scalar:
            if (!is_plain(n)) return fmt::format("the quoted string \"{}\"", clip(n.Scalar()));
            return fmt::format("'{}'", clip(n.Scalar()));
    }
    return "an unknown node";
}

std::optional<std::string> nearest(const std::string& word, const std::vector<std::string>& valid) {
    const std::string w = lower(word);
    const std::size_t limit = std::min<std::size_t>(3, std::max<std::size_t>(1, w.size() / 2));
    std::optional<std::string> best;
    std::size_t best_d = limit + 1;
    for (const auto& v : valid) {
        const std::size_t d = levenshtein(w, lower(v));
        if (d < best_d) best = v, best_d = d;
    }
    if (best) return best;
    for (const auto& v : valid) {
        const std::string lv = lower(v);
        if ((w.size() >= 3 && lv.find(w) != std::string::npos) ||
            (lv.size() >= 3 && w.find(lv) != std::string::npos))
            return v;
    }
    return std::nullopt;
}

std::string list_words(const std::vector<std::string>& words, const char* last_sep) {
    std::string s;
    for (std::size_t i = 0; i < words.size(); ++i) {
        if (i > 0) s += (i + 1 == words.size()) ? last_sep : ", ";
        s += words[i];
    }
    return s;
}

std::string join_keys(const std::vector<std::string>& keys) { return list_words(keys, ", "); }

// ---------------------------------------------------------------------------------------------
// Scalars

Real parse_real(const std::string& s, double& out) {
    std::size_t i = 0;
    bool negative = false;
    if (!s.empty() && (s[0] == '+' || s[0] == '-')) negative = s[0] == '-', i = 1;
    const std::string body = s.substr(i);
    const std::string lb = lower(body);
    if (lb == "inf" || lb == ".inf" || lb == "infinity") {
        out = negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
        return Real::Infinite;
    }
    if (lb == "nan" || lb == ".nan") {
        out = std::numeric_limits<double>::quiet_NaN();
        return Real::NaN;
    }
    // [0-9]* ('.' [0-9]*)? ([eE] [-+]? [0-9]+)?, at least one mantissa digit.
    std::size_t j = 0, digits = 0;
    while (j < body.size() && std::isdigit(static_cast<unsigned char>(body[j]))) ++j, ++digits;
    if (j < body.size() && body[j] == '.') {
        ++j;
        while (j < body.size() && std::isdigit(static_cast<unsigned char>(body[j]))) ++j, ++digits;
    }
    if (digits == 0) return Real::Invalid;
    if (j < body.size() && (body[j] == 'e' || body[j] == 'E')) {
        ++j;
        if (j < body.size() && (body[j] == '+' || body[j] == '-')) ++j;
        std::size_t exp_digits = 0;
        while (j < body.size() && std::isdigit(static_cast<unsigned char>(body[j]))) ++j, ++exp_digits;
        if (exp_digits == 0) return Real::Invalid;
    }
    if (j != body.size()) return Real::Invalid;
    double v = 0;
    const auto r = std::from_chars(body.data(), body.data() + body.size(), v, std::chars_format::general);
    if (r.ec == std::errc::result_out_of_range) {
        v = std::strtod(body.c_str(), nullptr);  // +-HUGE_VAL or 0, as the value rounds
    } else if (r.ec != std::errc() || r.ptr != body.data() + body.size()) {
        return Real::Invalid;
    }
    out = negative ? -v : v;
    return std::isfinite(out) ? Real::Number : Real::Overflow;
}

bool is_infinity_word(const std::string& s) {
    const std::string l = lower(!s.empty() && (s[0] == '+' || s[0] == '-') ? s.substr(1) : s);
    return l == "inf" || l == ".inf" || l == "infinity";
}

bool parse_integer(const std::string& s, long long& out, bool& overflow) {
    overflow = false;
    std::size_t i = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
    if (i == s.size()) return false;
    for (std::size_t j = i; j < s.size(); ++j)
        if (!std::isdigit(static_cast<unsigned char>(s[j]))) return false;
    const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(begin, s.data() + s.size(), out);
    if (r.ec == std::errc::result_out_of_range) {
        overflow = true;
        return false;
    }
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// ---------------------------------------------------------------------------------------------
// The reader

std::string unknown_key_message(const std::string& key, const KeyRule& rule) {
    if (rule.hint)
        if (auto h = rule.hint(key)) return fmt::format("unknown key '{}'{}{}", key, rule.context, *h);
    if (auto s = nearest(key, rule.keys))
        return fmt::format("unknown key '{}'{} (did you mean '{}'?)", key, rule.context, *s);
    return fmt::format("unknown key '{}'{}; valid keys are: {}", key, rule.context, join_keys(rule.keys));
}

Reader::Reader(std::string file, std::string prefix) : file_(std::move(file)), prefix_(std::move(prefix)) {}

void Reader::fail(Loc at, const std::string& path, const std::string& message) const {
    throw InputError(file_, at.line, at.column, join_path(prefix_, path), message);
}

void Reader::walk(const YAML::Node& map, const std::string& path, const KeyRule& rule,
                  const std::function<void(const Item&)>& visit) const {
    std::map<std::string, Loc> seen;
    for (const Item& it : items_of(map)) {
        if (!it.key_node.IsScalar())
            fail(it.key_loc(), path, fmt::format("expected a key name, got {}", describe(it.key_node)));
        const std::string key_path = join_path(path, it.key);
        const auto prev = seen.find(it.key);
        if (prev != seen.end())
            fail(it.key_loc(), key_path,
                 fmt::format("duplicate key '{}' (first given on line {})", it.key, prev->second.line));
        seen.emplace(it.key, it.key_loc());
        if (std::find(rule.keys.begin(), rule.keys.end(), it.key) == rule.keys.end())
            fail(it.key_loc(), key_path, unknown_key_message(it.key, rule));
        visit(it);
    }
}

void Reader::require_map(const Item& it, const std::string& path) const {
    if (!it.value.IsMap()) fail(it.value_loc(), path, fmt::format("expected a mapping, got {}", describe(it.value)));
}

void Reader::require_keys(const YAML::Node& map, const std::string& path, const Where& present,
                          const std::vector<std::string>& keys) const {
    for (const auto& k : keys)
        if (!present.count(k)) fail(loc_of(map), join_path(path, k), fmt::format("missing required key '{}'", k));
}

double Reader::number(const YAML::Node& v, Loc at, const std::string& path, bool allow_inf) const {
    const char* expected = allow_inf ? "a number or inf" : "a number";
    double x = 0;
    Real kind = Real::Invalid;
    if (v.IsScalar()) {
        if (is_plain(v))
            kind = parse_real(v.Scalar(), x);
        else if (allow_inf && is_infinity_word(v.Scalar()))
            kind = parse_real(v.Scalar(), x);  // "inf" in quotes is accepted where inf is (the word only)
    }
    switch (kind) {
        case Real::Number: return x;
        case Real::Infinite:
            if (allow_inf) return x;
            fail(at, path, fmt::format("expected a finite number, got {}", describe(v)));
        case Real::NaN:
            fail(at, path, fmt::format("expected {}, got {} (not a number)", allow_inf ? expected : "a finite number",
                                       describe(v)));
        case Real::Overflow:
            fail(at, path, fmt::format("{} is beyond the range of a double (about 1.8e308){}", v.Scalar(),
                                       allow_inf ? "; write inf for an infinite value" : ""));
        case Real::Invalid: break;
    }
    fail(at, path, fmt::format("expected {}, got {}", expected, describe(v)));
}

double Reader::positive_length(const YAML::Node& v, Loc at, const std::string& path) const {
    const double x = number(v, at, path);
    if (!(x > 0)) fail(at, path, fmt::format("must be a positive length (mm), got {}", v.Scalar()));
    return x;
}

long long Reader::integer(const YAML::Node& v, Loc at, const std::string& path, long long min, long long max,
                          const char* expected) const {
    long long x = 0;
    bool overflow = false;
    const bool parsed = v.IsScalar() && is_plain(v) && parse_integer(v.Scalar(), x, overflow);
    if (parsed && x >= min && x <= max) return x;
    if (overflow || (parsed && x > max))
        fail(at, path, fmt::format("expected {} (at most {}), got {}", expected, max, describe(v)));
    fail(at, path, fmt::format("expected {}, got {}", expected, describe(v)));
}

int Reader::positive_int(const YAML::Node& v, Loc at, const std::string& path) const {
    return static_cast<int>(integer(v, at, path, 1, INT_MAX, "a positive integer"));
}

std::uint64_t Reader::seed(const YAML::Node& v, Loc at, const std::string& path) const {
    const char* expected = "a non-negative integer";
    const std::string s = v.IsScalar() ? v.Scalar() : std::string();
    const std::size_t skip = !s.empty() && s[0] == '+' ? 1 : 0;
    const auto is_digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
    const bool digits =
        v.IsScalar() && is_plain(v) && s.size() > skip && std::all_of(s.begin() + skip, s.end(), is_digit);
    if (!digits) fail(at, path, fmt::format("expected {}, got {}", expected, describe(v)));
    std::uint64_t x = 0;
    const auto r = std::from_chars(s.data() + skip, s.data() + s.size(), x);
    if (r.ec == std::errc::result_out_of_range)
        fail(at, path, fmt::format("expected {} (at most {}), got {}", expected,
                                   std::numeric_limits<std::uint64_t>::max(), describe(v)));
    return x;
}

bool Reader::boolean(const YAML::Node& v, Loc at, const std::string& path) const {
    if (v.IsScalar() && is_plain(v)) {
        const std::string& s = v.Scalar();
        if (s == "true" || s == "True" || s == "TRUE") return true;
        if (s == "false" || s == "False" || s == "FALSE") return false;
    }
    fail(at, path, fmt::format("expected true or false, got {}", describe(v)));
}

std::size_t Reader::choice(const YAML::Node& v, Loc at, const std::string& path,
                           const std::vector<std::string>& options) const {
    if (v.IsScalar()) {
        const auto hit = std::find(options.begin(), options.end(), v.Scalar());
        if (hit != options.end()) return static_cast<std::size_t>(hit - options.begin());
    }
    std::string msg = fmt::format("expected {}, got {}", list_words(options, " or "), describe(v));
    if (v.IsScalar())
        if (auto s = nearest(v.Scalar(), options)) msg += fmt::format(" (did you mean '{}'?)", *s);
    fail(at, path, msg);
}

std::vector<double> Reader::number_list(
    const YAML::Node& v, Loc at, const std::string& path, const std::vector<std::size_t>& lengths,
    const std::string& shape,
    const std::function<double(const YAML::Node&, Loc, const std::string&)>& element) const {
    const bool length_ok =
        v.IsSequence() && std::find(lengths.begin(), lengths.end(), v.size()) != lengths.end();
    if (!length_ok) {
        std::vector<std::string> ls;
        for (auto n : lengths) ls.push_back(std::to_string(n));
        fail(at, path, fmt::format("expected a list of {} {}, got {}", list_words(ls, " or "), shape, describe(v)));
    }
    std::vector<double> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const YAML::Node e = v[i];
        out.push_back(element(e, e.IsNull() ? at : loc_of(e), fmt::format("{}[{}]", path, i)));
    }
    return out;
}

Vec3 Reader::vec3(const Item& it, const std::string& path, const std::string& shape) const {
    const auto xs = number_list(it.value, it.value_loc(), path, {3}, shape,
                                [&](const YAML::Node& e, Loc at, const std::string& p) { return number(e, at, p); });
    return {xs[0], xs[1], xs[2]};
}

Vec3 Reader::positive_vec3(const Item& it, const std::string& path, const std::string& shape) const {
    const auto xs = number_list(
        it.value, it.value_loc(), path, {3}, shape,
        [&](const YAML::Node& e, Loc at, const std::string& p) { return positive_length(e, at, p); });
    return {xs[0], xs[1], xs[2]};
}

// ---------------------------------------------------------------------------------------------
// Documents

namespace {

// "a scene file", "an input file".
std::string with_article(const std::string& noun) {
    const bool vowel = !noun.empty() && std::string("aeiou").find(noun.front()) != std::string::npos;
    return (vowel ? "an " : "a ") + noun;
}

}  // namespace

std::string read_file(const std::string& path, const std::string& kind) {
    auto unreadable = [&](const std::string& reason) {
        return InputError(path, 0, 0, "", "cannot read " + kind + ": " + reason);
    };
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw unreadable(std::strerror(EISDIR));
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw unreadable(std::strerror(errno != 0 ? errno : ENOENT));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw unreadable(std::strerror(errno != 0 ? errno : EIO));
    return text.str();
}

namespace {

// Where each document of a YAML stream starts, and where its root node is, from yaml-cpp's event
// interface (no nodes are built).
struct DocumentStarts : YAML::EventHandler {
    std::vector<YAML::Mark> starts, roots;
    void OnDocumentStart(const YAML::Mark& m) override { starts.push_back(m); }
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark& m, YAML::anchor_t) override { node(m); }
    void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { node(m); }
    void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string&) override { node(m); }
    void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
        node(m);
    }
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override { node(m); }
    void OnMapEnd() override {}
    void node(const YAML::Mark& m) {
        if (roots.size() < starts.size()) roots.push_back(m);
    }
};

// The 1-based column of the first tab in the indentation of `text`'s line `line` (1-based), or 0.
// The indentation is the run of spaces and block indicators ("- ", "? ", ": ") before the line's
// content: YAML counts it in spaces only, and yaml-cpp stops at a tab there with "illegal map
// value", "illegal block entry" or "illegal tab when looking for indentation", always on the
// tab's own line. A tab elsewhere (between a key and its value, inside a [flow] list) is
// separation, which YAML allows.
int indentation_tab(const std::string& text, int line) {
    std::size_t begin = 0;
    for (int l = 1; l < line; ++l) {
        begin = text.find('\n', begin);
        if (begin == std::string::npos) return 0;
        ++begin;
    }
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    auto blank = [&](std::size_t i) { return i >= end || text[i] == ' ' || text[i] == '\t'; };
    for (std::size_t i = begin; i < end; ++i) {
        const char c = text[i];
        if (c == '\t') return static_cast<int>(i - begin) + 1;
        if (c != ' ' && !((c == '-' || c == '?' || c == ':') && blank(i + 1))) break;
    }
    return 0;
}

InputError malformed(const YAML::Exception& e, const std::string& text, const std::string& file) {
    const Loc at = e.mark.is_null() ? Loc{1, 1} : Loc{e.mark.line + 1, e.mark.column + 1};
    if (const int tab = indentation_tab(text, at.line))
        return InputError(file, at.line, tab, "",
                          "malformed YAML: a tab in the indentation (YAML does not allow tabs for indentation; use "
                          "spaces)");
    return InputError(file, at.line, at.column, "", "malformed YAML: " + one_line(e.msg));
}

}  // namespace

YAML::Node parse_document(const std::string& text, const std::string& file, const std::string& kind) {
    // The documents are counted first. yaml-cpp 0.7 never consumes a ',' outside a flow
    // collection: YAML::LoadAll(",") returns empty document after empty document until memory
    // runs out (fuzz/fuzz_scene reaches it). A document that starts where the previous one started
    // made no progress, and is reported as the stray character it is.
    DocumentStarts docs;
    try {
        std::istringstream in(text);
        YAML::Parser parser(in);
        while (parser.HandleNextDocument(docs)) {
            const std::size_t n = docs.starts.size();
            if (n >= 2 && docs.starts[n - 1].pos == docs.starts[n - 2].pos) {
                const YAML::Mark& m = docs.starts[n - 1];
                const char c = m.pos >= 0 && static_cast<std::size_t>(m.pos) < text.size() ? text[static_cast<std::size_t>(m.pos)] : '?';
                throw InputError(file, m.line + 1, m.column + 1, "",
                                 fmt::format("malformed YAML: unexpected '{}' outside a [list] or {{mapping}}", c));
            }
        }
    } catch (const YAML::Exception& e) {
        throw malformed(e, text, file);
    }
    if (docs.starts.size() > 1) {
        const YAML::Mark& m = docs.roots.size() > 1 ? docs.roots[1] : docs.starts[1];
        throw InputError(file, m.line + 1, m.column + 1, "",
                         fmt::format("the file holds {} YAML documents (separated by ---); {} holds one",
                                     docs.starts.size(), with_article(kind)));
    }
    try {
        return YAML::Load(text);
    } catch (const YAML::Exception& e) {
        throw malformed(e, text, file);
    }
}

YAML::Node load_document(const std::string& path, const std::string& kind) {
    return parse_document(read_file(path, kind), path, kind);
}

}  // namespace ltm::yaml
