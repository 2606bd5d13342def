// Reading JSON files strictly (model/io/strict_json.hpp): hostile text is a ModelError naming the
// file, line, column and JSON path, never a crash, a silent choice or an unbounded message.
// Nesting deeper than kMaxJsonDepth, a key twice in one object, a number beyond double's range,
// syntax errors; and the bounded quoting every reader's messages use (quoted, json_excerpt).
#include <gtest/gtest.h>

#include <string>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::model::io {
namespace {

/// The message of the ModelError parsing `text` throws (or a test failure).
std::string error_of(const std::string& text) {
    try {
        (void)parse_json_text(text, "s.json");
    } catch (const ModelError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no ModelError for " << text.substr(0, 200);
    return "";
}

std::string nested(std::size_t depth, const std::string& inside = "") {
    return std::string(depth, '[') + inside + std::string(depth, ']');
}

TEST(StrictJson, DeepNestingIsRefusedAtTheLimitWithItsPlace) {
    // 60,000 arrays where a number is expected: once a stack overflow in the error message's
    // dump. Refused at the 65th level: the object is the first, the arrays start at column 23
    // of line 2, so the 64th '[' (column 86) would open the 65th.
    const std::string deep = "{\"a\": 1,\n \"gravity_mm_per_s2\": " + nested(60000) + "}";
    const std::string message = error_of(deep);
    EXPECT_EQ(message.rfind("s.json: line 2, column 86: gravity_mm_per_s2[0][0]", 0), 0u)
        << message;
    EXPECT_NE(message.find("nested deeper than 64 levels"), std::string::npos) << message;
    EXPECT_LT(message.size(), 250u) << message;
    // Exactly the limit is fine: 64 levels, the outermost the object.
    EXPECT_NO_THROW((void)parse_json_text("{\"a\": " + nested(63, "1") + "}", "s.json"));
    EXPECT_NE(error_of("{\"a\": " + nested(64, "1") + "}").find("nested deeper"),
              std::string::npos);
    // Objects count as levels too.
    std::string objects;
    for (int i = 0; i < 100; ++i)
        objects += "{\"k\": ";
    objects += "1" + std::string(100, '}');
    EXPECT_NE(error_of(objects).find("line 1, column 385: k.k.k."), std::string::npos)
        << error_of(objects);
}

TEST(StrictJson, DuplicateKeysAreRefusedNamingBothPlaces) {
    EXPECT_EQ(error_of("{\"initial_insertion_mm\": 20,\n \"initial_insertion_mm\": 30}"),
              "s.json: line 2, column 2: initial_insertion_mm: key given twice in one object "
              "(first at line 1, column 2, again here); a key may appear only once");
    // In a nested object, with its path; a key spelt with an escape is the same key.
    EXPECT_EQ(error_of("{\"procedure\": [{\"action\": \"hold\"},\n {\"a\": 1, \"\\u0061\": 2}]}"),
              "s.json: line 2, column 11: procedure[1].a: key given twice in one object (first "
              "at line 2, column 3, again here); a key may appear only once");
    // The same key in two objects is fine.
    EXPECT_NO_THROW((void)parse_json_text("[{\"a\": 1}, {\"a\": 2}, {\"b\": {\"a\": 3}}]", "s"));
}

TEST(StrictJson, NumbersBeyondDoubleAreOutOfRangeWithTheirField) {
    EXPECT_EQ(error_of("{\"gravity_mm_per_s2\": [0, 1e400, 0]}"),
              "s.json: line 1, column 27: gravity_mm_per_s2[1]: '1e400' is out of range (a "
              "number's magnitude must be below 1.8e308)");
    EXPECT_NE(error_of("{\"scope\": {\"length_mm\": -1e309}}").find("scope.length_mm: '-1e309'"),
              std::string::npos);
    // An integer too long for 64 bits is still a number, out of range only beyond double.
    EXPECT_NE(error_of("{\"n\": 1" + std::string(400, '0') + "}").find("is out of range"),
              std::string::npos);
    EXPECT_DOUBLE_EQ(parse_json_text("{\"n\": 1e308}", "s")["n"].get<double>(), 1e308);
    // Underflow is zero, as the parser has it (no magnitude is lost that a reader could use).
    EXPECT_EQ(parse_json_text("{\"n\": 1e-400}", "s")["n"].get<double>(), 0.0);
}

TEST(StrictJson, SyntaxErrorsNameThePlaceAndComeFirst) {
    const std::string bad = error_of("{\"a\": 1,\n \"b\": }");
    EXPECT_EQ(bad.rfind("s.json: not valid JSON: parse error at line 2, column 7", 0), 0u) << bad;
    // A syntax error before a duplicate key is the one reported.
    EXPECT_NE(error_of("{\"a\": x, \"a\": 1}").find("not valid JSON"), std::string::npos);
    // A long bad token is not echoed whole.
    const std::string long_token = error_of("{\"a\": " + std::string(1 << 20, 'x') + "}");
    EXPECT_LT(long_token.size(), 200u) << long_token;
    // A byte-order mark is skipped, as the parser does.
    EXPECT_EQ(parse_json_text("\xEF\xBB\xBF{\"a\": 1}", "s")["a"].get<int>(), 1);
}

TEST(StrictJson, QuotedTextIsBoundedWithItsLength) {
    EXPECT_EQ(quote_text("abc"), "'abc'");
    const std::string long_text(20 * 1024 * 1024, '7');
    EXPECT_EQ(quote_text(long_text), "'" + std::string(80, '7') + "…' (20971520 bytes)");
    EXPECT_EQ(quote_text("a\tb\x01"), "'a\\x09b\\x01'");
    // Cut at a character boundary: 79 ASCII bytes, then a 2-byte character.
    const std::string utf8 = std::string(79, 'a') + "\xC3\xA9" + "tail";
    EXPECT_EQ(quote_text(utf8), "'" + std::string(79, 'a') + "…' (85 bytes)");
}

TEST(StrictJson, JsonExcerptNeverRecursesUnbounded) {
    nlohmann::json deep = 1;
    for (int i = 0; i < 200000; ++i) {
        nlohmann::json outer = nlohmann::json::array();
        outer.push_back(std::move(deep));
        deep = std::move(outer);
    }
    EXPECT_EQ(json_excerpt(deep), std::string(80, '[') + "…");
    EXPECT_EQ(json_excerpt(nlohmann::json::parse(R"({"a": [1, 2.5, "x"], "b": null})")),
              R"({"a":[1,2.5,"x"],"b":null})");
    EXPECT_EQ(json_excerpt(nlohmann::json(std::string(1000, 'y'))),
              "\"" + std::string(79, 'y') + "…");
    // Through a reader: a 1 MB string where a boolean is expected.
    const nlohmann::json doc = {{"flag", std::string(1 << 20, 'z')}};
    const JsonObject o(doc, "s.json:");
    try {
        (void)o.boolean_or("flag", false);
        FAIL() << "no error";
    } catch (const ModelError& e) {
        EXPECT_LT(std::string(e.what()).size(), 150u) << e.what();
    }
}

TEST(StrictJson, UnknownKeysAreShownBounded) {
    const nlohmann::json doc = {{std::string(100000, 'k'), 1}};
    const JsonObject o(doc, "s.json:");
    try {
        o.allow_only({"a", "b"});
        FAIL() << "no error";
    } catch (const ModelError& e) {
        const std::string m = e.what();
        EXPECT_LT(m.size(), 200u) << m;
        EXPECT_NE(m.find("…' (100000 bytes): unknown key (allowed here: a, b)"), std::string::npos)
            << m;
    }
    // A short key keeps the plain form.
    const nlohmann::json plain = {{"c", 1}};
    try {
        JsonObject(plain, "s.json:").allow_only({"a"});
        FAIL() << "no error";
    } catch (const ModelError& e) {
        EXPECT_EQ(std::string(e.what()), "s.json: c: unknown key (allowed here: a)");
    }
}

}  // namespace
}  // namespace scopekin::model::io
