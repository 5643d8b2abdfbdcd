#include "scene/SceneLoader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstdint>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "defects/DefectSolid.h"

namespace ltm {

namespace {

std::string compose_message(const std::string& file, int line, int column, const std::string& key_path,
                            const std::string& message) {
    if (line <= 0) return file + ": " + message;
    if (key_path.empty()) return fmt::format("{}:{}:{}: {}", file, line, column, message);
    return fmt::format("{}:{}:{}: {}: {}", file, line, column, key_path, message);
}

}  // namespace

SceneError::SceneError(std::string file_, int line_, int column_, std::string key_path_, std::string message_)
    : std::runtime_error(compose_message(file_, line_, column_, key_path_, message_)),
      file(std::move(file_)),
      line(line_),
      column(column_),
      key_path(std::move(key_path_)),
      message(std::move(message_)) {}

namespace {

// ---------------------------------------------------------------------------------------------
// Locations, descriptions, suggestions

struct Loc {
    int line = 1, column = 1;  // 1-based
};

Loc loc_of(const YAML::Node& n) {
    const YAML::Mark m = n.Mark();
    if (m.is_null() || m.line < 0) return {1, 1};
    return {m.line + 1, m.column + 1};
}

// One `key: value` entry of a mapping. An empty value (`key:`) has a mark on the following line
// in yaml-cpp, so problems with it are reported at the key.
struct Item {
    std::string key;
    YAML::Node key_node, value;
    Loc key_loc() const { return loc_of(key_node); }
    Loc value_loc() const { return value.IsNull() ? loc_of(key_node) : loc_of(value); }
};

std::vector<Item> items_of(const YAML::Node& map) {
    std::vector<Item> out;
    for (auto it = map.begin(); it != map.end(); ++it)
        out.push_back({it->first.IsScalar() ? it->first.Scalar() : std::string(), it->first, it->second});
    return out;
}

std::string join_path(const std::string& parent, const std::string& key) {
    if (parent.empty()) return key;
    if (!key.empty() && key.front() == '[') return parent + key;
    return parent + "." + key;
}

// Messages are one paragraph: no line breaks from the file's text.
std::string one_line(const std::string& s) {
    std::string t;
    for (char c : s) t += (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
    return t;
}

std::string clip(const std::string& s) {
    std::string t = one_line(s);
    if (t.size() > 40) t = t.substr(0, 37) + "...";
    return t;
}

// A plain scalar is unquoted and has no tag (or a numeric one): only those can be numbers or
// booleans; "50" in quotes is a string, as YAML says.
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

// The valid name closest to a misspelt one: edit distance up to 3 (at most half the word, so a
// two-letter typo does not "suggest" an unrelated key), else a key that contains the word or is
// contained in it ("thickness" -> "center_thickness").
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

// YAML 1.2 core-schema floats and integers, plus the spellings of infinity people write.
enum class Real { Number, Infinite, NaN, Invalid };

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
    return std::isfinite(out) ? Real::Number : Real::Infinite;
}

bool is_infinity_word(const std::string& s) {
    const std::string l = lower(!s.empty() && (s[0] == '+' || s[0] == '-') ? s.substr(1) : s);
    return l == "inf" || l == ".inf" || l == "infinity";
}

// Decimal integer, optional sign, digits only (no 1e3, no 100.0).
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
// The parser

// How a typed mapping (the object, a defect) talks about its unknown keys.
struct KeyRule {
    std::vector<std::string> keys;  // valid keys, in documentation order
    std::string context;            // e.g. " for a window"
    // A specific explanation for a key that is valid elsewhere (" (it is a key of scratches)").
    std::function<std::optional<std::string>(const std::string&)> hint;
};

// Where each key's value sits in the file, to report geometry problems at it.
using Where = std::map<std::string, Loc>;

class Parser {
public:
    explicit Parser(std::string file) : file_(std::move(file)) {}

    Scene run(const YAML::Node& root);

    [[noreturn]] void fail(Loc at, const std::string& path, const std::string& message) const {
        throw SceneError(file_, at.line, at.column, path, message);
    }

private:
    // Structure
    void walk(const YAML::Node& map, const std::string& path, const KeyRule& rule,
              const std::function<void(const Item&)>& visit) const;
    void require_map(const Item& it, const std::string& path) const;
    void require_keys(const YAML::Node& map, const std::string& path, const Where& present,
                      const std::vector<std::string>& keys) const;
    std::string unknown_key_message(const std::string& key, const KeyRule& rule) const;
    const Item* find_item(const std::vector<Item>& items, const std::string& key) const;

    // Values
    double number(const YAML::Node& v, Loc at, const std::string& path, bool allow_inf = false) const;
    double positive_length(const YAML::Node& v, Loc at, const std::string& path) const;
    long long integer(const YAML::Node& v, Loc at, const std::string& path, long long min, long long max,
                      const char* expected) const;
    int positive_int(const YAML::Node& v, Loc at, const std::string& path) const;
    bool boolean(const YAML::Node& v, Loc at, const std::string& path) const;
    std::uint64_t seed(const YAML::Node& v, Loc at) const;
    std::size_t choice(const YAML::Node& v, Loc at, const std::string& path,
                       const std::vector<std::string>& options) const;
    // A list of numbers of one of the given lengths; `element` checks and converts each one.
    std::vector<double> number_list(
        const YAML::Node& v, Loc at, const std::string& path, std::vector<std::size_t> lengths,
        const std::string& shape,
        const std::function<double(const YAML::Node&, Loc, const std::string&)>& element) const;
    Vec3 vec3(const Item& it, const std::string& path, const std::string& shape) const;
    Vec3 positive_vec3(const Item& it, const std::string& path, const std::string& shape) const;
    Vec3 point23(const Item& it, const std::string& path, bool& has_z) const;

    // Sections
    void parse_object(const Item& it, ObjectDesc& object, Where& where) const;
    void parse_index_field(const Item& it, IndexField& field, Where& where) const;
    void check_object(const ObjectDesc& object, const Where& where, Loc object_loc) const;
    Defect parse_defect(const YAML::Node& node, const std::string& path, Where& where) const;
    void parse_ellipsoid_keys(const YAML::Node& map, const std::string& path, DefectType type, Defect& d,
                              Where& where) const;
    void parse_scratch_keys(const YAML::Node& map, const std::string& path, Defect& d, Where& where) const;
    void parse_arc(const Item& it, const std::string& path, Defect& d, Where& where) const;
    void check_defect(const ObjectDesc& object, const std::vector<Defect>& defects, std::size_t index,
                      const Where& where, Loc defect_loc) const;
    // [columns, rows] of positive integers; [width, height] of positive lengths (mm).
    std::array<int, 2> resolution(const YAML::Node& v, Loc at, const std::string& p) const {
        const auto xs = number_list(v, at, p, {2}, "positive integers [columns, rows]",
                                    [&](const YAML::Node& x, Loc l, const std::string& q) {
                                        return static_cast<double>(positive_int(x, l, q));
                                    });
        return {static_cast<int>(xs[0]), static_cast<int>(xs[1])};
    }
    std::array<double, 2> size2(const YAML::Node& v, Loc at, const std::string& p) const {
        const auto xs = number_list(v, at, p, {2}, "positive lengths [width, height]",
                                    [&](const YAML::Node& x, Loc l, const std::string& q) { return positive_length(x, l, q); });
        return {xs[0], xs[1]};
    }
    void parse_camera(const Item& it, CameraDesc& camera) const;
    void parse_display(const Item& it, DisplayDesc& display, Loc& z_loc, bool& z_given) const;
    void parse_mesh(const Item& it, MeshOptions& mesh) const;
    void check_display(const ObjectDesc& object, const DisplayDesc& display, Loc z_loc, bool z_given) const;

    std::string file_;
};

void Parser::walk(const YAML::Node& map, const std::string& path, const KeyRule& rule,
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

std::string Parser::unknown_key_message(const std::string& key, const KeyRule& rule) const {
    if (rule.hint)
        if (auto h = rule.hint(key)) return fmt::format("unknown key '{}'{}{}", key, rule.context, *h);
    if (auto s = nearest(key, rule.keys))
        return fmt::format("unknown key '{}'{} (did you mean '{}'?)", key, rule.context, *s);
    return fmt::format("unknown key '{}'{}; valid keys are: {}", key, rule.context, join_keys(rule.keys));
}

void Parser::require_map(const Item& it, const std::string& path) const {
    if (!it.value.IsMap()) fail(it.value_loc(), path, fmt::format("expected a mapping, got {}", describe(it.value)));
}

void Parser::require_keys(const YAML::Node& map, const std::string& path, const Where& present,
                          const std::vector<std::string>& keys) const {
    for (const auto& k : keys)
        if (!present.count(k)) fail(loc_of(map), join_path(path, k), fmt::format("missing required key '{}'", k));
}

const Item* Parser::find_item(const std::vector<Item>& items, const std::string& key) const {
    for (const Item& it : items)
        if (it.key_node.IsScalar() && it.key == key) return &it;
    return nullptr;
}

double Parser::number(const YAML::Node& v, Loc at, const std::string& path, bool allow_inf) const {
    const char* expected = allow_inf ? "a number or inf" : "a number";
    double x = 0;
    Real kind = Real::Invalid;
    if (v.IsScalar()) {
        if (is_plain(v))
            kind = parse_real(v.Scalar(), x);
        else if (allow_inf && is_infinity_word(v.Scalar()))
            kind = parse_real(v.Scalar(), x);  // "inf" in quotes is accepted for radii (the word only)
    }
    switch (kind) {
        case Real::Number: return x;
        case Real::Infinite:
            if (allow_inf) return x;
            fail(at, path, fmt::format("expected a finite number, got {}", describe(v)));
        case Real::NaN:
            fail(at, path, fmt::format("expected {}, got {} (not a number)", allow_inf ? expected : "a finite number",
                                       describe(v)));
        case Real::Invalid: break;
    }
    fail(at, path, fmt::format("expected {}, got {}", expected, describe(v)));
}

double Parser::positive_length(const YAML::Node& v, Loc at, const std::string& path) const {
    const double x = number(v, at, path);
    if (!(x > 0)) fail(at, path, fmt::format("must be a positive length (mm), got {}", v.Scalar()));
    return x;
}

long long Parser::integer(const YAML::Node& v, Loc at, const std::string& path, long long min, long long max,
                          const char* expected) const {
    long long x = 0;
    bool overflow = false;
    const bool parsed = v.IsScalar() && is_plain(v) && parse_integer(v.Scalar(), x, overflow);
    if (parsed && x >= min && x <= max) return x;
    if (overflow || (parsed && x > max))
        fail(at, path, fmt::format("expected {} (at most {}), got {}", expected, max, describe(v)));
    fail(at, path, fmt::format("expected {}, got {}", expected, describe(v)));
}

int Parser::positive_int(const YAML::Node& v, Loc at, const std::string& path) const {
    return static_cast<int>(integer(v, at, path, 1, INT_MAX, "a positive integer"));
}

std::uint64_t Parser::seed(const YAML::Node& v, Loc at) const {
    const char* expected = "a non-negative integer";
    const std::string s = v.IsScalar() ? v.Scalar() : std::string();
    const std::size_t skip = !s.empty() && s[0] == '+' ? 1 : 0;
    const auto is_digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
    const bool digits =
        v.IsScalar() && is_plain(v) && s.size() > skip && std::all_of(s.begin() + skip, s.end(), is_digit);
    if (!digits) fail(at, "seed", fmt::format("expected {}, got {}", expected, describe(v)));
    std::uint64_t x = 0;
    const auto r = std::from_chars(s.data() + skip, s.data() + s.size(), x);
    if (r.ec == std::errc::result_out_of_range)
        fail(at, "seed", fmt::format("expected {} (at most {}), got {}", expected,
                                     std::numeric_limits<std::uint64_t>::max(), describe(v)));
    return x;
}

bool Parser::boolean(const YAML::Node& v, Loc at, const std::string& path) const {
    if (v.IsScalar() && is_plain(v)) {
        const std::string& s = v.Scalar();
        if (s == "true" || s == "True" || s == "TRUE") return true;
        if (s == "false" || s == "False" || s == "FALSE") return false;
    }
    fail(at, path, fmt::format("expected true or false, got {}", describe(v)));
}

std::size_t Parser::choice(const YAML::Node& v, Loc at, const std::string& path,
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

std::vector<double> Parser::number_list(
    const YAML::Node& v, Loc at, const std::string& path, std::vector<std::size_t> lengths, const std::string& shape,
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

Vec3 Parser::vec3(const Item& it, const std::string& path, const std::string& shape) const {
    const auto xs = number_list(it.value, it.value_loc(), path, {3}, shape,
                                [&](const YAML::Node& e, Loc at, const std::string& p) { return number(e, at, p); });
    return {xs[0], xs[1], xs[2]};
}

Vec3 Parser::positive_vec3(const Item& it, const std::string& path, const std::string& shape) const {
    const auto xs = number_list(
        it.value, it.value_loc(), path, {3}, shape,
        [&](const YAML::Node& e, Loc at, const std::string& p) { return positive_length(e, at, p); });
    return {xs[0], xs[1], xs[2]};
}

Vec3 Parser::point23(const Item& it, const std::string& path, bool& has_z) const {
    const auto xs = number_list(it.value, it.value_loc(), path, {2, 3}, "numbers [x, y] or [x, y, z]",
                                [&](const YAML::Node& e, Loc at, const std::string& p) { return number(e, at, p); });
    has_z = xs.size() == 3;
    return {xs[0], xs[1], has_z ? xs[2] : 0.0};
}

// ---------------------------------------------------------------------------------------------
// The object

const std::vector<std::string> kLensKeys{"type", "r1", "r2", "center_thickness", "diameter", "ior", "rim", "absorption",
                                         "index_field"};
const std::vector<std::string> kWindowKeys{"type", "thickness", "diameter", "ior", "rim", "absorption", "index_field"};
const std::vector<std::string> kSphereKeys{"type", "radius", "ior", "absorption", "index_field"};

void Parser::parse_object(const Item& it, ObjectDesc& object, Where& where) const {
    const std::string path = "object";
    require_map(it, path);
    const auto items = items_of(it.value);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(it.value), "object.type", "missing required key 'type'");
    const std::size_t kind = choice(type_item->value, type_item->value_loc(), "object.type", {"lens", "window", "sphere"});
    const bool window = kind == 1, sphere = kind == 2;
    object.type = sphere ? ObjectType::Sphere : (window ? ObjectType::Window : ObjectType::Lens);
    object.lens = LensSpec{};

    KeyRule rule;
    rule.keys = sphere ? kSphereKeys : (window ? kWindowKeys : kLensKeys);
    rule.context = sphere ? " for a sphere" : (window ? " for a window" : " for a lens");
    rule.hint = [window, sphere, keys = rule.keys](const std::string& k) -> std::optional<std::string> {
        if (window && (k == "r1" || k == "r2"))
            return std::string(": windows have flat faces (use type: lens for curved faces); valid keys are: ") +
                   join_keys(keys);
        if (sphere && (k == "r1" || k == "r2" || k == "diameter" || k == "center_thickness" || k == "thickness"))
            return std::string(": a sphere is given by its radius alone; valid keys are: ") + join_keys(keys);
        if (sphere && k == "rim") return std::string(": a sphere has no rim; valid keys are: ") + join_keys(keys);
        return std::nullopt;
    };

    double radius = 0;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "type") return;
        if (e.key == "r1" || e.key == "r2") {
            double r = number(e.value, at, p, /*allow_inf=*/true);
            if (std::isinf(r)) r = std::numeric_limits<double>::infinity();  // a plane has no sign
            (e.key == "r1" ? object.lens.r1 : object.lens.r2) = r;
        } else if (e.key == "center_thickness" || e.key == "thickness") {
            object.lens.center_thickness = number(e.value, at, p);
        } else if (e.key == "diameter") {
            object.lens.diameter = number(e.value, at, p);
        } else if (e.key == "radius") {
            radius = number(e.value, at, p);
        } else if (e.key == "ior") {
            object.lens.ior = number(e.value, at, p);
        } else if (e.key == "rim") {
            object.rim = choice(e.value, at, p, {"polished", "absorbing"}) == 0 ? RimFinish::Polished
                                                                                : RimFinish::Absorbing;
        } else if (e.key == "absorption") {
            const double a = number(e.value, at, p);
            if (!(a >= 0)) fail(at, p, fmt::format("must be >= 0 (1/mm), got {}", e.value.Scalar()));
            object.absorption = a;
        } else if (e.key == "index_field") {
            parse_index_field(e, object.index_field, where);
        }
    });
    if (sphere) {
        require_keys(it.value, path, where, {"radius", "ior"});
        object.lens = ball_spec(radius, object.lens.ior);
    } else if (window) {
        require_keys(it.value, path, where, {"thickness", "diameter", "ior"});
        object.lens.r1 = object.lens.r2 = std::numeric_limits<double>::infinity();
    } else {
        require_keys(it.value, path, where, {"r1", "r2", "center_thickness", "diameter", "ior"});
    }
    object.index_field.ior = object.lens.ior;
}

// object.index_field: {type: linear_n2 | radial_n2 | spherical_n2 | quadratic_n2 | linear_n, ...}
// (geometry/IndexField.h). Positions of its keys go into `where` as "index_field.<key>".
void Parser::parse_index_field(const Item& it, IndexField& f, Where& where) const {
    const std::string path = "object.index_field";
    require_map(it, path);
    const auto items = items_of(it.value);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(it.value), path + ".type", "missing required key 'type'");
    const std::vector<std::string> kinds{"linear_n2", "radial_n2", "spherical_n2", "quadratic_n2", "linear_n"};
    const std::size_t kind = choice(type_item->value, type_item->value_loc(), path + ".type", kinds);
    const IndexFieldType types[] = {IndexFieldType::LinearN2, IndexFieldType::RadialN2, IndexFieldType::SphericalN2,
                                    IndexFieldType::QuadraticN2, IndexFieldType::LinearN};
    f = IndexField{};
    f.type = types[kind];
    KeyRule rule;
    switch (f.type) {
        case IndexFieldType::RadialN2:
        case IndexFieldType::SphericalN2: rule.keys = {"type", "g"}; break;
        case IndexFieldType::QuadraticN2: rule.keys = {"type", "gradient", "hessian"}; break;
        default: rule.keys = {"type", "gradient"}; break;
    }
    rule.context = " for an index field of type " + kinds[kind];
    Where local;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        local[e.key] = at;
        where["index_field." + e.key] = at;
        if (e.key == "g") {
            f.g = number(e.value, at, p);
        } else if (e.key == "gradient") {
            f.gradient = vec3(e, p, "numbers [gx, gy, gz]");
        } else if (e.key == "hessian") {
            const bool rows_ok = e.value.IsSequence() && e.value.size() == 3;
            if (!rows_ok)
                fail(at, p, fmt::format("expected a list of 3 rows of 3 numbers [[..], [..], [..]], got {}",
                                        describe(e.value)));
            for (std::size_t r = 0; r < 3; ++r) {
                const YAML::Node row = e.value[r];
                const std::string rp = fmt::format("{}[{}]", p, r);
                const auto xs = number_list(row, row.IsNull() ? at : loc_of(row), rp, {3}, "numbers (a row of the hessian)",
                                            [&](const YAML::Node& x, Loc l, const std::string& q) { return number(x, l, q); });
                for (std::size_t c = 0; c < 3; ++c) f.hessian(static_cast<int>(r), static_cast<int>(c)) = xs[c];
            }
        }
    });
    if (f.type == IndexFieldType::QuadraticN2) require_keys(it.value, path, local, {"hessian"});
    else if (f.type == IndexFieldType::RadialN2 || f.type == IndexFieldType::SphericalN2)
        require_keys(it.value, path, local, {"g"});
    else
        require_keys(it.value, path, local, {"gradient"});
    where["index_field"] = it.value_loc();
}

void Parser::check_object(const ObjectDesc& object, const Where& where, Loc object_loc) const {
    auto located = [&](const std::string& key) {
        for (std::string k = key; !k.empty();) {
            const auto w = where.find(k);
            if (w != where.end()) return w->second;
            const auto cut = k.find_last_of(".[");
            if (cut == std::string::npos) break;
            k = k.substr(0, cut);
        }
        return object_loc;
    };
    const auto problems = Lens::problems(object.lens);
    if (!problems.empty()) {
        std::string key = problems.front().key;
        if (object.type == ObjectType::Window && key == "center_thickness") key = "thickness";
        fail(located(key), join_path("object", key), problems.front().message);
    }
    if (!object.index_field.graded()) return;
    const auto field_problems = index_field_problems(Lens(object.lens), object.index_field);
    if (field_problems.empty()) return;
    const std::string key = field_problems.front().key.empty() ? "index_field" : "index_field." + field_problems.front().key;
    fail(located(key), join_path("object", key), field_problems.front().message);
}

// ---------------------------------------------------------------------------------------------
// Defects

const std::vector<std::string> kBubbleKeys{"type", "center", "radius", "semi_axes", "rotation", "surface_breaking"};
const std::vector<std::string> kParticleKeys{"type", "center", "radius", "semi_axes", "rotation"};
const std::vector<std::string> kInhomogeneityKeys{"type", "center", "radius", "semi_axes", "rotation", "delta_n", "profile"};
const std::vector<std::string> kScratchKeys{"type", "surface", "width", "depth", "profile", "start", "end", "arc"};
const std::vector<std::string> kArcKeys{"center", "radius", "start_angle", "end_angle"};

Defect Parser::parse_defect(const YAML::Node& node, const std::string& path, Where& where) const {
    if (!node.IsMap())
        fail(loc_of(node), path,
             fmt::format("expected a mapping with a 'type' key (bubble, scratch, particle or inhomogeneity), got {}",
                         describe(node)));
    const auto items = items_of(node);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(node), join_path(path, "type"), "missing required key 'type'");
    Defect d;
    switch (choice(type_item->value, type_item->value_loc(), join_path(path, "type"),
                   {"bubble", "scratch", "particle", "inhomogeneity"})) {
        case 0: parse_ellipsoid_keys(node, path, DefectType::Bubble, d, where); break;
        case 1: parse_scratch_keys(node, path, d, where); break;
        case 2: parse_ellipsoid_keys(node, path, DefectType::Particle, d, where); break;
        default: parse_ellipsoid_keys(node, path, DefectType::Inhomogeneity, d, where); break;
    }
    return d;
}

void Parser::parse_ellipsoid_keys(const YAML::Node& map, const std::string& path, DefectType type, Defect& d,
                                  Where& where) const {
    const bool bubble = type == DefectType::Bubble, inclusion = type == DefectType::Inhomogeneity;
    d.type = type;
    KeyRule rule;
    rule.keys = bubble ? kBubbleKeys : (inclusion ? kInhomogeneityKeys : kParticleKeys);
    rule.context = bubble ? " for a bubble" : (inclusion ? " for an inhomogeneity" : " for a particle");
    rule.hint = [bubble, inclusion, keys = rule.keys](const std::string& k) -> std::optional<std::string> {
        if (!bubble && !inclusion && k == "surface_breaking")
            return std::string(": particles always lie strictly inside the glass (a surface-breaking void is a "
                               "bubble); valid keys are: ") +
                   join_keys(keys);
        if (inclusion && k == "surface_breaking")
            return std::string(": an inhomogeneity is clipped to the glass where it reaches a face; valid keys are: ") +
                   join_keys(keys);
        if (k == "index_field")
            return std::string(": index_field is a key of the object (the glass's index as a field); a defect "
                               "changes the index locally as type inhomogeneity with delta_n; valid keys are: ") +
                   join_keys(keys);
        if (!inclusion && (k == "delta_n"))
            return fmt::format(" ({} is a key of inhomogeneities); valid keys are: {}", k, join_keys(keys));
        if (std::find(kScratchKeys.begin(), kScratchKeys.end(), k) != kScratchKeys.end())
            return fmt::format(" ({} is a key of scratches); valid keys are: {}", k, join_keys(keys));
        return std::nullopt;
    };

    Loc rotation_key;
    Vec3 rotation;
    double radius = 0;
    walk(map, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "center") {
            d.center = vec3(e, p, "numbers [x, y, z]");
        } else if (e.key == "radius") {
            if (where.count("semi_axes"))
                fail(e.key_loc(), p, "give either radius (a sphere) or semi_axes (an ellipsoid), not both");
            radius = positive_length(e.value, at, p);
        } else if (e.key == "semi_axes") {
            if (where.count("radius"))
                fail(e.key_loc(), p, "give either radius (a sphere) or semi_axes (an ellipsoid), not both");
            d.semi_axes = positive_vec3(e, p, "positive lengths [a, b, c]");
        } else if (e.key == "rotation") {
            rotation_key = e.key_loc();
            rotation = vec3(e, p, "angles in degrees [rx, ry, rz]");
        } else if (e.key == "surface_breaking") {
            d.surface_breaking = boolean(e.value, at, p);
        } else if (e.key == "delta_n") {
            d.delta_n = number(e.value, at, p);
            if (d.delta_n == 0)
                fail(at, p, "must be non-zero: delta_n = 0 leaves the glass unchanged (remove the defect instead)");
        } else if (e.key == "profile") {
            d.index_profile = choice(e.value, at, p, {"smooth", "uniform"}) == 0 ? IndexProfile::Smooth
                                                                                  : IndexProfile::Uniform;
        }
    });
    require_keys(map, path, where, inclusion ? std::vector<std::string>{"center", "delta_n"}
                                             : std::vector<std::string>{"center"});
    if (!where.count("radius") && !where.count("semi_axes"))
        fail(loc_of(map), path, "missing required key 'radius' (a sphere) or 'semi_axes' (an ellipsoid)");
    if (where.count("rotation") && where.count("radius"))
        fail(rotation_key, join_path(path, "rotation"),
             "rotation applies only to an ellipsoid given by semi_axes: a sphere (radius) has no orientation");
    if (where.count("radius")) d.semi_axes = {radius, radius, radius};
    d.frame = where.count("rotation") ? rotation_from_euler_deg(rotation) : Mat3::identity();
}

void Parser::parse_scratch_keys(const YAML::Node& map, const std::string& path, Defect& d, Where& where) const {
    d.type = DefectType::Scratch;
    KeyRule rule;
    rule.keys = kScratchKeys;
    rule.context = " for a scratch";
    rule.hint = [](const std::string& k) -> std::optional<std::string> {
        if (k == "center" || k == "radius" || k == "start_angle" || k == "end_angle")
            return fmt::format(": an arc scratch takes {} inside arc: {{center, radius, start_angle, end_angle}}", k);
        if (k == "semi_axes" || k == "rotation" || k == "surface_breaking")
            return fmt::format(" ({} is a key of bubbles and particles); valid keys are: {}", k, join_keys(kScratchKeys));
        return std::nullopt;
    };
    const char* both = "give either start and end (a straight scratch) or arc (a circular one), not both";
    walk(map, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "surface") {
            d.side = static_cast<int>(choice(e.value, at, p, {"front", "back"}));
        } else if (e.key == "width") {
            d.width = positive_length(e.value, at, p);
        } else if (e.key == "depth") {
            d.depth = positive_length(e.value, at, p);
        } else if (e.key == "profile") {
            d.profile = choice(e.value, at, p, {"V", "U"}) == 0 ? ScratchProfile::V : ScratchProfile::U;
        } else if (e.key == "start" || e.key == "end") {
            if (where.count("arc")) fail(e.key_loc(), p, both);
            if (e.key == "start")
                d.start = point23(e, p, d.start_has_z);
            else
                d.end = point23(e, p, d.end_has_z);
        } else if (e.key == "arc") {
            if (where.count("start") || where.count("end")) fail(e.key_loc(), p, both);
            parse_arc(e, p, d, where);
        }
    });
    require_keys(map, path, where, {"surface", "width", "depth"});
    if (where.count("arc")) {
        d.arc = true;
        return;
    }
    const bool s = where.count("start") > 0, e = where.count("end") > 0;
    if (s != e) {
        const char* missing = s ? "end" : "start";
        fail(loc_of(map), join_path(path, missing),
             fmt::format("missing required key '{}' (a straight scratch needs start and end)", missing));
    }
    if (!s)
        fail(loc_of(map), path, "missing required key 'start' and 'end' (a straight scratch) or 'arc' (a circular one)");
    d.arc = false;  // distinct end points, on the face: defect_problems
}

void Parser::parse_arc(const Item& it, const std::string& path, Defect& d, Where& where) const {
    require_map(it, path);
    KeyRule rule;
    rule.keys = kArcKeys;
    Where arc_where;
    double start = 0, end = 0;
    std::string start_text, end_text;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        arc_where[e.key] = at;
        where["arc." + e.key] = at;
        if (e.key == "center") {
            d.arc_center = point23(e, p, d.arc_center_has_z);
        } else if (e.key == "radius") {
            d.arc_radius = positive_length(e.value, at, p);
        } else if (e.key == "start_angle") {
            start = number(e.value, at, p);
            start_text = e.value.Scalar();
        } else if (e.key == "end_angle") {
            end = number(e.value, at, p);
            end_text = e.value.Scalar();
        }
    });
    require_keys(it.value, path, arc_where, kArcKeys);
    const Loc end_loc = arc_where.at("end_angle");
    if (!(end > start))
        fail(end_loc, join_path(path, "end_angle"),
             fmt::format("must be greater than start_angle ({}), got {}", start_text, end_text));
    if (!(end - start < 360.0))
        fail(end_loc, join_path(path, "end_angle"),
             fmt::format("the arc spans {:g} degrees from start_angle {}: it must span less than 360", end - start,
                         start_text));
    d.start_angle = start;
    d.end_angle = end;
}

void Parser::check_defect(const ObjectDesc& object, const std::vector<Defect>& defects, std::size_t index,
                          const Where& where, Loc defect_loc) const {
    const Lens lens(object.lens);
    const Defect& d = defects[index];
    const std::string path = fmt::format("defects[{}]", index);
    auto problems = defect_problems(lens, d, object.index_field);
    for (std::size_t j = 0; j < index && problems.empty(); ++j)
        problems = defect_pair_problems(lens, d, defects[j], static_cast<int>(j));
    if (problems.empty()) return;
    std::string key = problems.front().key;
    // An arc scratch's centre and radius live in its `arc` mapping.
    if (d.type == DefectType::Scratch && d.arc && !where.count(key) &&
        std::find(kArcKeys.begin(), kArcKeys.end(), key) != kArcKeys.end())
        key = "arc." + key;
    // The value of the named key, or of its nearest enclosing key in the file ("center[2]" ->
    // "center"), else the defect's own mapping.
    Loc at = defect_loc;
    for (std::string k = key; !k.empty();) {
        const auto w = where.find(k);
        if (w != where.end()) {
            at = w->second;
            break;
        }
        const auto cut = k.find_last_of(".[");
        if (cut == std::string::npos) break;
        k = k.substr(0, cut);
    }
    fail(at, join_path(path, key), problems.front().message);
}

// ---------------------------------------------------------------------------------------------
// Camera, display, mesh

void Parser::parse_camera(const Item& it, CameraDesc& camera) const {
    const std::string path = "camera";
    require_map(it, path);
    KeyRule rule;
    rule.keys = {"resolution", "size", "numerical_aperture", "samples_per_pixel", "focus_z"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "resolution") {
            camera.resolution = resolution(e.value, at, p);
        } else if (e.key == "size") {
            camera.size = size2(e.value, at, p);
        } else if (e.key == "numerical_aperture") {
            const double na = number(e.value, at, p);
            if (!(na > 0 && na < 1)) fail(at, p, fmt::format("must be in (0, 1), got {}", e.value.Scalar()));
            camera.numerical_aperture = na;
        } else if (e.key == "samples_per_pixel") {
            camera.samples_per_pixel = positive_int(e.value, at, p);
        } else if (e.key == "focus_z") {
            camera.focus_z = number(e.value, at, p);
        }
    });
}

void Parser::parse_display(const Item& it, DisplayDesc& display, Loc& z_loc, bool& z_given) const {
    const std::string path = "display";
    require_map(it, path);
    z_loc = loc_of(it.value);
    z_given = false;
    KeyRule rule;
    rule.keys = {"resolution", "size", "z"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "resolution") {
            display.resolution = resolution(e.value, at, p);
        } else if (e.key == "size") {
            display.size = size2(e.value, at, p);
        } else if (e.key == "z") {
            display.z = number(e.value, at, p);
            z_loc = at;
            z_given = true;
        }
    });
}

void Parser::check_display(const ObjectDesc& object, const DisplayDesc& display, Loc z_loc, bool z_given) const {
    // The back face's farthest point: its vertex, or its rim when the back face bulges toward +z
    // (a spherical cap is monotonic in rho, so rho in {0, a} covers it).
    const Lens lens(object.lens);
    const double back = std::max(lens.z_back(0.0), lens.z_back(lens.aperture_radius()));
    if (display.z > back) return;
    fail(z_loc, "display.z",
         fmt::format("the display must lie behind the object: z must be greater than {:g} mm (the object's back "
                     "extent), got {:g}{}",
                     back, display.z, z_given ? "" : " (the default)"));
}

void Parser::parse_mesh(const Item& it, MeshOptions& mesh) const {
    const std::string path = "mesh";
    require_map(it, path);
    KeyRule rule;
    rule.keys = {"chord_tolerance", "defect_relative_tolerance", "always_boolean", "index_tolerance"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "chord_tolerance") {
            mesh.chord_tolerance = positive_length(e.value, at, p);
        } else if (e.key == "defect_relative_tolerance") {
            const double r = number(e.value, at, p);
            if (!(r > 0 && r <= 0.5)) fail(at, p, fmt::format("must be in (0, 0.5], got {}", e.value.Scalar()));
            mesh.defect_relative_tolerance = r;
        } else if (e.key == "always_boolean") {
            mesh.always_boolean = boolean(e.value, at, p);
        } else if (e.key == "index_tolerance") {
            const double t = number(e.value, at, p);
            if (!(t > 0 && t <= 0.1)) fail(at, p, fmt::format("must be in (0, 0.1] (a tolerance on n^2), got {}", e.value.Scalar()));
            mesh.index_tolerance = t;
        }
    });
}

// ---------------------------------------------------------------------------------------------
// The document

Scene Parser::run(const YAML::Node& root) {
    Scene scene;
    scene.source = file_;
    if (!root.IsDefined() || root.IsNull())
        fail({1, 1}, "", "the scene file is empty: expected a mapping with at least the key 'object'");
    if (!root.IsMap())
        fail(loc_of(root), "",
             fmt::format("expected a mapping of scene keys (object, defects, camera, display, mesh, seed) at the "
                         "top level, got {}",
                         describe(root)));

    // Geometry checks need the object; defects and the display are checked as soon as both they
    // and a valid object are known (at once in the usual key order).
    struct PendingDefect {
        std::size_t index;
        Where where;
        Loc loc;
    };
    bool have_object = false, have_display = false;
    Where object_where;
    Loc object_loc, display_z_loc = loc_of(root);
    bool display_z_given = false;
    std::vector<PendingDefect> pending;
    auto check_pending = [&] {
        for (const auto& p : pending) check_defect(scene.object, scene.defects, p.index, p.where, p.loc);
        pending.clear();
    };

    KeyRule rule;
    rule.keys = {"object", "defects", "camera", "display", "mesh", "seed"};
    walk(root, "", rule, [&](const Item& e) {
        const Loc at = e.value_loc();
        if (e.key == "object") {
            parse_object(e, scene.object, object_where);
            object_loc = loc_of(e.value);
            check_object(scene.object, object_where, object_loc);
            have_object = true;
            check_pending();
            if (have_display) check_display(scene.object, scene.display, display_z_loc, display_z_given);
        } else if (e.key == "defects") {
            if (e.value.IsNull()) return;
            if (!e.value.IsSequence())
                fail(at, "defects", fmt::format("expected a list of defects, got {}", describe(e.value)));
            for (std::size_t i = 0; i < e.value.size(); ++i) {
                const YAML::Node node = e.value[i];
                const std::string path = fmt::format("defects[{}]", i);
                Where where;
                scene.defects.push_back(parse_defect(node, path, where));
                pending.push_back({i, std::move(where), loc_of(node)});
                if (have_object) check_pending();
            }
        } else if (e.key == "camera") {
            parse_camera(e, scene.camera);
        } else if (e.key == "display") {
            parse_display(e, scene.display, display_z_loc, display_z_given);
            have_display = true;
            if (have_object) check_display(scene.object, scene.display, display_z_loc, display_z_given);
        } else if (e.key == "mesh") {
            parse_mesh(e, scene.mesh);
        } else if (e.key == "seed") {
            scene.seed = seed(e.value, at);
        }
    });
    if (!have_object) fail(loc_of(root), "object", "missing required key 'object'");
    if (!have_display) check_display(scene.object, scene.display, loc_of(root), false);
    return scene;
}

}  // namespace

Scene parse_scene(const std::string& yaml_text, const std::string& file_name_for_messages) {
    Parser parser(file_name_for_messages);
    std::vector<YAML::Node> docs;
    try {
        docs = YAML::LoadAll(yaml_text);
    } catch (const YAML::Exception& e) {
        const Loc at = e.mark.is_null() ? Loc{1, 1} : Loc{e.mark.line + 1, e.mark.column + 1};
        parser.fail(at, "", "malformed YAML: " + one_line(e.msg));
    }
    if (docs.size() > 1)
        parser.fail(loc_of(docs[1]), "",
                    fmt::format("the file holds {} YAML documents (separated by ---); a scene file holds one",
                                docs.size()));
    return parser.run(docs.empty() ? YAML::Node() : docs.front());
}

Scene load_scene(const std::string& path) {
    auto unreadable = [&](const std::string& reason) {
        return SceneError(path, 0, 0, "", "cannot read scene file: " + reason);
    };
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw unreadable(std::strerror(EISDIR));
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw unreadable(std::strerror(errno != 0 ? errno : ENOENT));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw unreadable(std::strerror(errno != 0 ? errno : EIO));
    return parse_scene(text.str(), path);
}

}  // namespace ltm
