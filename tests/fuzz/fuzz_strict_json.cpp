// fuzz_strict_json.cpp — libFuzzer target: the strict JSON reader (model/io/strict_json.hpp,
// parse_json_text) on any text, as `scopekin simulate`, `discrepancy` and `batch` read scenario
// and model files someone else wrote; and its message helpers (quote_text, json_excerpt).
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * a refusal is a ModelError (no other exception) whose message starts with "fuzz.json" and is
//     short whatever the input (at most 1,000 characters: values and lines are quoted with at
//     most kMaxQuoted characters);
//   * accepted: nested at most kMaxJsonDepth deep; the same document nlohmann's own parser reads
//     (strictness refuses, it never changes a value); it serialises (valid UTF-8), and the
//     serialised text is accepted again as the same document and serialises to the same text;
//   * quote_text() of the input and json_excerpt() of the document are bounded (kMaxQuoted
//     characters, control characters as \xNN, plus the length note).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace {

namespace io = scopekin::model::io;
using nlohmann::json;

/// Nesting depth of arrays and objects (a scalar: 0), without recursion.
std::size_t depth_of(const json& document) {
    std::size_t deepest = 0;
    std::vector<std::pair<const json*, std::size_t>> stack{{&document, 0}};
    while (!stack.empty()) {  // bound: the document's size
        const auto [value, depth] = stack.back();
        stack.pop_back();
        if (!value->is_structured()) continue;
        deepest = std::max(deepest, depth + 1);
        for (const json& child : *value)
            stack.emplace_back(&child, depth + 1);
    }
    return deepest;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const std::string quoted = io::quote_text(text);
    require(quoted.size() <= 4U * io::kMaxQuoted + 64U);

    json document;
    try {
        document = io::parse_json_text(text, "fuzz.json");
    } catch (const scopekin::model::ModelError& error) {
        const std::string message = error.what();
        require(message.rfind("fuzz.json", 0) == 0);
        require(message.size() <= 1000U);
        return 0;
    } catch (...) {
        require(false);  // only ModelError may leave the reader
    }

    require(depth_of(document) <= io::kMaxJsonDepth);
    require(io::json_excerpt(document).size() <= 4U * io::kMaxQuoted + 64U);
    json plain;
    try {
        plain = json::parse(text);
    } catch (...) {
        require(false);  // what the strict reader accepts is JSON
    }
    require(plain == document);

    std::string serialised;
    try {
        serialised = document.dump();
    } catch (...) {
        require(false);  // an accepted document is valid UTF-8
    }
    json again;
    try {
        again = io::parse_json_text(serialised, "again.json");
    } catch (...) {
        require(false);  // the serialised document is accepted too
    }
    require(again == document);
    require(again.dump() == serialised);
    return 0;
}
