// io/Json.h: strict reading with located errors (the contract of every JSON file a user hands
// ltmsim), exact numbers on writing, JSON lines with counted blank lines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "io/InputError.h"
#include "io/Json.h"
#include "tests/TestSupport.h"

namespace {

using ltm::InputError;
using ltm::io::Json;

// The InputError that parsing `text` throws (fails the test when it parses).
InputError error_of(const std::string& text, int first_line = 1) {
    try {
        ltm::io::parse_json(text, "f.json", first_line);
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "parsed: " << text;
    return InputError("", 0, 0, "", "");
}

}  // namespace

TEST(Json, ValidTextsParseWithTheirKeysInFileOrder) {
    const Json v = ltm::io::parse_json(R"({"z": 1, "a": [true, null, "x\"y"], "m": {"k": -2.5e-3}})", "f.json");
    ASSERT_TRUE(v.is_object());
    std::vector<std::string> keys;
    for (const auto& [k, x] : v.items()) keys.push_back(k);
    EXPECT_EQ(keys, (std::vector<std::string>{"z", "a", "m"}));
    EXPECT_EQ(v["a"][2].get<std::string>(), "x\"y");
    EXPECT_EQ(v["m"]["k"].get<double>(), -2.5e-3);
    EXPECT_TRUE(v["z"].is_number_integer());
}

// Each malformed text names the byte at fault, counted as an editor does (1-based line and
// column). The columns are derived by hand from the texts.
TEST(Json, MalformedTextsAreLocated) {
    struct Case {
        const char* text;
        int line, column;
        const char* says;
    };
    const std::vector<Case> cases = {
        {R"({"a": 1, "a": 2})", 1, 10, "duplicate key \"a\""},             // the second "a" opens at column 10
        {R"({"o": {"k": 1, "k": 2}})", 1, 16, "duplicate key \"k\""},      // nested object
        {R"({"q\"": 1, "q\"": 2})", 1, 12, "duplicate key \"q\\\"\""},    // escaped quote inside the key
        {"{\"a\": 1,\n \"b\": 2,\n \"a\": 3}", 3, 2, "duplicate key"},     // on line 3, after one space
        {R"({"a": 1} x)", 1, 10, "syntax error"},                          // trailing text
        {R"({"a": NaN})", 1, 7, "syntax error"},                           // no NaN literal
        {R"({"a": 1,})", 1, 9, "syntax error"},                            // trailing comma
        {"{\"a\": 1 // c\n}", 1, 9, "syntax error"},                       // no comments
        {R"({"a": 1e999})", 1, 7, "not finite"},                           // overflows a double
        {R"({"a": [1, -1e400]})", 1, 11, "not finite"},
        {"{\"a\": 1", 1, 8, "unexpected end of input"},                    // just after the last byte
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.text);
        const InputError e = error_of(c.text);
        EXPECT_EQ(e.file, "f.json");
        EXPECT_EQ(e.line, c.line);
        EXPECT_EQ(e.column, c.column);
        EXPECT_NE(e.message.find("malformed JSON"), std::string::npos) << e.what();
        EXPECT_NE(e.message.find(c.says), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).rfind("f.json:" + std::to_string(c.line) + ":" + std::to_string(c.column) + ": ", 0),
                  0u)
            << e.what();
    }
    // The same key in different objects is no duplicate.
    EXPECT_NO_THROW(ltm::io::parse_json(R"([{"a": 1}, {"a": 2}, {"b": {"a": 3}, "a": 4}])", "f.json"));
    // A text starting on line 7 of its file reports that file's lines.
    EXPECT_EQ(error_of(R"({"a": 1, "a": 2})", 7).line, 7);
}

// Writing then reading a double gives the same double (nlohmann prints the shortest form that
// reads back exactly); non-finite values become the strings inf, -inf, nan.
TEST(Json, NumbersRoundTripExactly) {
    std::mt19937_64 rng(12345);
    for (int i = 0; i < 20000; ++i) {
        double v;
        const std::uint64_t bits = rng();
        std::memcpy(&v, &bits, sizeof v);
        if (!std::isfinite(v)) continue;
        const Json back = ltm::io::parse_json(Json{{"v", ltm::io::json_number(v)}}.dump(), "f.json");
        ASSERT_EQ(back["v"].get<double>(), v) << back.dump();
    }
    EXPECT_EQ(ltm::io::json_number(std::numeric_limits<double>::infinity()), Json("inf"));
    EXPECT_EQ(ltm::io::json_number(-std::numeric_limits<double>::infinity()), Json("-inf"));
    EXPECT_EQ(ltm::io::json_number(std::nan("")), Json("nan"));
}

class JsonFiles : public ltm::test::TempDirTest {};

TEST_F(JsonFiles, LinesCountBlankLinesAndFailNamesTheLine) {
    const std::string file = path("r.jsonl");
    write("r.jsonl", "{\"a\": 1}\n\n  \t\r\n[2]\n");
    ltm::io::JsonLinesReader r(file, "rays file");
    Json v;
    ASSERT_TRUE(r.next(v));
    EXPECT_EQ(r.line(), 1);
    ASSERT_TRUE(r.next(v));
    EXPECT_EQ(r.line(), 4);
    EXPECT_EQ(v, Json::array({2}));
    EXPECT_EQ(ltm::test::message_of([&] { r.fail("expected an object"); }), file + ":4: expected an object");
    EXPECT_FALSE(r.next(v));

    write("bad.jsonl", "{\"a\": 1}\n\n{\"a\": 1, \"a\": 2}\n");
    ltm::io::JsonLinesReader b(path("bad.jsonl"));
    ASSERT_TRUE(b.next(v));
    EXPECT_EQ(ltm::test::message_of([&] { b.next(v); }), path("bad.jsonl") + ":3:10: malformed JSON: duplicate key \"a\"");

    EXPECT_NE(ltm::test::message_of([&] { ltm::io::JsonLinesReader m(path("missing.jsonl"), "rays file"); })
                  .find(path("missing.jsonl") + ": cannot read rays file"),
              std::string::npos);
}

// A 1 GB line is refused after reading kMaxJsonLine bytes of it (the file is sparse: creating it
// costs nothing, and reading it whole would take seconds and a gigabyte of memory).
TEST_F(JsonFiles, AnOverlongLineIsRefusedWithoutLoadingIt) {
    const std::string file = path("huge.jsonl");
    write("huge.jsonl", "{\"a\": 1}\n");
    std::filesystem::resize_file(file, std::uintmax_t(1) << 30);
    ltm::io::JsonLinesReader r(file, "rays file");
    Json v;
    ASSERT_TRUE(r.next(v));
    EXPECT_EQ(ltm::test::message_of([&] { r.next(v); }),
              file + ":2: line longer than " + std::to_string(ltm::io::kMaxJsonLine) +
                  " bytes (one JSON value per line is expected)");
    // A line of exactly the limit is read (and here is malformed JSON, located on line 1).
    write("edge.jsonl", std::string(ltm::io::kMaxJsonLine, 'x'));
    ltm::io::JsonLinesReader e(path("edge.jsonl"));
    EXPECT_NE(ltm::test::message_of([&] { e.next(v); }).find(path("edge.jsonl") + ":1:1: malformed JSON"), std::string::npos);
    // A folder is no file.
    EXPECT_NE(ltm::test::message_of([&] { ltm::io::JsonLinesReader d(dir.string(), "rays file"); }).find("it is a folder"),
              std::string::npos);
}

TEST_F(JsonFiles, WrittenFilesReadBackEqual) {
    const Json v = {{"name", "a \"quoted\"\n\tname"}, {"values", {1, 2.5, -0.0}}, {"nested", {{"x", nullptr}}}};
    ltm::io::write_json_file(path("v.json"), v, "test record");
    EXPECT_EQ(ltm::io::read_json_file(path("v.json"), "test record"), v);
    EXPECT_EQ(ltm::test::slurp(path("v.json")).back(), '\n');
    ltm::io::write_json_file(path("one.json"), v, "test record", -1);
    const std::string one = ltm::test::slurp(path("one.json"));
    EXPECT_EQ(std::count(one.begin(), one.end(), '\n'), 1) << one;
}
