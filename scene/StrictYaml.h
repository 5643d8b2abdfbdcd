#pragma once
// The strict YAML engine behind every data file ltmsim reads: scene files (scene/SceneLoader.h)
// and any other file held to the same standard (a dataset spec). A data file is parsed strictly:
// every key is known, no key is given twice, every value has the expected type and range; the
// first problem stops reading with one InputError "FILE:LINE:COLUMN: key.path: message".
//
// A parser for one file format derives from (or holds) a Reader and walks the document with it:
//
//   yaml::Reader r(file);
//   const YAML::Node root = yaml::parse_document(text, file, "dataset spec");
//   yaml::KeyRule rule;
//   rule.keys = {"scene", "count"};
//   r.walk(root, "", rule, [&](const yaml::Item& e) {
//       if (e.key == "count") count = r.positive_int(e.value, e.value_loc(), "count");
//   });
//
// Error locations (1-based line and column, as an editor shows them):
//   unknown or duplicate key            -> the key itself
//   wrong type or out-of-range value    -> the value (the list element, when one element is bad)
//   missing required key                -> the mapping that lacks it
//   malformed YAML                      -> where yaml-cpp stopped
//   a tab in the indentation            -> the tab (YAML indents with spaces only)
// Locations are those of the document a node belongs to, so a mapping nested in a larger file
// (a scene inside a dataset spec) is reported at its lines in that file.
//
// Values (docs/scene-format.md, "Values"): numbers are plain (unquoted) YAML 1.2 numbers, never
// nan, infinite only where allowed; integers are digits only (no 1e3, no 100.0); booleans are
// true/false (True, TRUE, False, FALSE), never yes/no/on/off; choices are exact, case-sensitive
// words; lists have exactly the stated length.
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geometry/Vec3.h"
#include "io/InputError.h"

namespace ltm::yaml {

// ---------------------------------------------------------------------------------------------
// Locations and mapping entries

struct Loc {
    int line = 1, column = 1;  // 1-based
};

// The node's position in its document ({1, 1} if yaml-cpp has none).
Loc loc_of(const YAML::Node& n);

// One `key: value` entry of a mapping. An empty value (`key:`) has a mark on the following line
// in yaml-cpp, so problems with it are reported at the key.
struct Item {
    std::string key;            // "" when the key is not a scalar
    YAML::Node key_node, value;
    Loc key_loc() const { return loc_of(key_node); }
    Loc value_loc() const { return value.IsNull() ? loc_of(key_node) : loc_of(value); }
};

// The entries of a mapping, in file order (duplicates included: Reader::walk rejects them).
std::vector<Item> items_of(const YAML::Node& map);
// The first entry with the scalar key `key`, or nullptr.
const Item* find_item(const std::vector<Item>& items, const std::string& key);

// Where each key's value sits in the file, to report later (geometric) problems at it. Keys of
// nested mappings may be entered as "arc.radius", "index_field.g".
using Where = std::map<std::string, Loc>;

// `key`, or its nearest enclosing key ("center[2]" -> "center", "arc.radius" -> "arc"), for which
// `known` holds; "" when none does.
std::string enclosing_key(const std::string& key, const std::function<bool(const std::string&)>& known);
// The location of `key` in `where`, or of its nearest enclosing key that is there, else `fallback`.
Loc located(const Where& where, const std::string& key, Loc fallback);

// "camera" + "size" -> "camera.size"; "size" + "[1]" -> "size[1]"; "" + "seed" -> "seed";
// "scene" + "" -> "scene".
std::string join_path(const std::string& parent, const std::string& key);

// ---------------------------------------------------------------------------------------------
// Words in messages

// The text with line breaks and tabs as spaces: messages are one paragraph.
std::string one_line(const std::string& s);
// A plain scalar is unquoted and has no tag (or a numeric or boolean one): only those can be
// numbers or booleans; "50" in quotes is a string, as YAML says.
bool is_plain(const YAML::Node& n);
// What a node is, for "expected X, got <describe>": "an empty value", "a list of 2 items",
// "a mapping", "'six'", "the quoted string \"6\"" (scalars clipped to 40 characters).
std::string describe(const YAML::Node& n);
// The valid name closest to a misspelt one: edit distance up to 3 (at most half the word, so a
// two-letter typo does not "suggest" an unrelated key), else a name that contains the word or is
// contained in it ("thickness" -> "center_thickness"). Case-insensitive.
std::optional<std::string> nearest(const std::string& word, const std::vector<std::string>& valid);
// "a, b<last_sep>c": list_words({"V", "U"}, " or ") = "V or U".
std::string list_words(const std::vector<std::string>& words, const char* last_sep);
// "a, b, c".
std::string join_keys(const std::vector<std::string>& keys);

// ---------------------------------------------------------------------------------------------
// Scalars

// YAML 1.2 core-schema floats and integers, plus the spellings of infinity people write
// (inf, +inf, -inf, .inf, -.inf, Infinity; case-insensitive). A finite number whose magnitude is
// beyond the largest double (1e400) is Overflow, never silently infinity: only the words mean
// inf. Magnitudes below the smallest double round to it or to 0, as strtod does; -0 is 0.
enum class Real { Number, Infinite, NaN, Overflow, Invalid };
Real parse_real(const std::string& s, double& out);
// The word is one of the spellings of (signed) infinity above.
bool is_infinity_word(const std::string& s);
// Decimal integer, optional sign, digits only (no 1e3, no 100.0). `overflow` is set when the
// digits do not fit a long long.
bool parse_integer(const std::string& s, long long& out, bool& overflow);

// ---------------------------------------------------------------------------------------------
// The reader

// How a mapping talks about its unknown keys.
struct KeyRule {
    std::vector<std::string> keys;  // valid keys, in documentation order
    std::string context;            // e.g. " for a window"
    // A specific explanation for a key that is valid elsewhere (" (it is a key of scratches)");
    // it follows "unknown key '<key>'<context>" and replaces the suggestion.
    std::function<std::optional<std::string>(const std::string&)> hint;
};

// "unknown key 'k'<context>" followed by the rule's hint, else "(did you mean 'x'?)", else
// "; valid keys are: ...".
std::string unknown_key_message(const std::string& key, const KeyRule& rule);

// Checks and converts the values of one file. Every check throws InputError at the given location
// with the given key path; `prefix` (a key path, e.g. "scene") is put in front of every key path
// it reports, for a mapping that sits inside a larger document.
class Reader {
public:
    explicit Reader(std::string file, std::string prefix = "");

    const std::string& file() const { return file_; }
    const std::string& prefix() const { return prefix_; }

    [[noreturn]] void fail(Loc at, const std::string& path, const std::string& message) const;

    // Structure.
    // Visits the entries of `map` in file order after rejecting a non-scalar key, a duplicate key
    // and a key not in `rule` (each at the key).
    void walk(const YAML::Node& map, const std::string& path, const KeyRule& rule,
              const std::function<void(const Item&)>& visit) const;
    // The entry's value must be a mapping.
    void require_map(const Item& it, const std::string& path) const;
    // Each of `keys` must be in `present` (reported at `map`, the mapping that lacks it).
    void require_keys(const YAML::Node& map, const std::string& path, const Where& present,
                      const std::vector<std::string>& keys) const;

    // Values.
    // A plain number; `allow_inf` admits the infinity words (also quoted: "inf").
    double number(const YAML::Node& v, Loc at, const std::string& path, bool allow_inf = false) const;
    // A number > 0 ("must be a positive length (mm)").
    double positive_length(const YAML::Node& v, Loc at, const std::string& path) const;
    // An integer in [min, max]; `expected` names it ("a positive integer").
    long long integer(const YAML::Node& v, Loc at, const std::string& path, long long min, long long max,
                      const char* expected) const;
    int positive_int(const YAML::Node& v, Loc at, const std::string& path) const;
    bool boolean(const YAML::Node& v, Loc at, const std::string& path) const;
    // A non-negative integer up to 2^64-1 (a random seed).
    std::uint64_t seed(const YAML::Node& v, Loc at, const std::string& path) const;
    // The index of the value among `options` (exact words; "did you mean" for a near miss).
    std::size_t choice(const YAML::Node& v, Loc at, const std::string& path,
                       const std::vector<std::string>& options) const;
    // A list of numbers of one of the given lengths ("expected a list of 3 <shape>");
    // `element` checks and converts each one, at its own location and path "path[i]".
    std::vector<double> number_list(
        const YAML::Node& v, Loc at, const std::string& path, const std::vector<std::size_t>& lengths,
        const std::string& shape,
        const std::function<double(const YAML::Node&, Loc, const std::string&)>& element) const;
    // [x, y, z] of numbers / of positive lengths; `shape` as for number_list ("numbers [x, y, z]").
    Vec3 vec3(const Item& it, const std::string& path, const std::string& shape) const;
    Vec3 positive_vec3(const Item& it, const std::string& path, const std::string& shape) const;

private:
    std::string file_;
    std::string prefix_;
};

// ---------------------------------------------------------------------------------------------
// Documents

// `kind` names the file in messages: "scene file" gives "cannot read scene file: ..." and
// "... a scene file holds one".

// The whole file as text; InputError "<path>: cannot read <kind>: <reason>" (line 0) if it cannot
// be read (missing, a directory, an I/O error).
std::string read_file(const std::string& path, const std::string& kind);

// The single root node of YAML text (a Null node for an empty text). Throws InputError for
// malformed YAML ("malformed YAML: ...", where yaml-cpp stopped) and for more than one document
// (at the second one).
YAML::Node parse_document(const std::string& text, const std::string& file, const std::string& kind);

// read_file + parse_document.
YAML::Node load_document(const std::string& path, const std::string& kind);

}  // namespace ltm::yaml
