// portable_check.hpp — one test source, every target.
//
// Test files use SCOPEKIN_TEST / SCOPEKIN_EXPECT_EQ / SCOPEKIN_EXPECT_TRUE only.
// * Hosted targets (x86-64, aarch64 Linux; SCOPEKIN_PORTABLE_CHECK_GTEST defined): the macros are
//   GoogleTest's TEST / EXPECT_EQ / EXPECT_TRUE, linked with GTest::gtest_main.
// * Bare metal (Cortex-M4): a minimal runner with the same semantics (a failed expectation marks
//   the test failed and the test continues), a fixed-capacity registry filled by static
//   constructors (no heap), GoogleTest-like output through `write_text`, which the platform's
//   runner main (bare_metal_main.cpp) provides, and `run_all()` returning the number of failed
//   tests, which main() turns into the exit status.
#pragma once

#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)

#include <gtest/gtest.h>

#define SCOPEKIN_TEST(suite, name) TEST(suite, name)
#define SCOPEKIN_EXPECT_EQ(actual, expected) EXPECT_EQ(actual, expected)
#define SCOPEKIN_EXPECT_TRUE(condition) EXPECT_TRUE(condition)

#else

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "decimal_text.hpp"

namespace scopekin::portable_check {

/// Console output of the bare-metal runner (semihosting on Cortex-M4).
void write_text(const char* text) noexcept;

using TestFunction = void (*)();

struct TestCase {
    const char* suite;
    const char* name;
    TestFunction function;
};

/// Capacity of the registry: tests per executable.
inline constexpr std::size_t max_tests = 128;

struct Registry {
    TestCase cases[max_tests];
    std::size_t count;
    bool overflowed;
    bool current_failed;
};

// Constant-initialised, hence ready before any static constructor registers a test.
constinit inline Registry registry{};

struct Registrar {
    Registrar(const char* suite, const char* name, TestFunction function) noexcept {
        if (registry.count < max_tests) {
            registry.cases[registry.count] = TestCase{suite, name, function};
            ++registry.count;
        } else {
            registry.overflowed = true;
        }
    }
};

inline void write_unsigned(std::uint64_t value) noexcept {
    DecimalBuffer buffer;
    write_text(decimal_text(value, buffer));
}

inline void write_signed(std::int64_t value) noexcept {
    if (value < 0) {
        write_text("-");
        // Magnitude without overflow for INT64_MIN.
        write_unsigned(static_cast<std::uint64_t>(-(value + 1)) + 1U);
    } else {
        write_unsigned(static_cast<std::uint64_t>(value));
    }
}

template <typename T>
void write_value(const T& value) noexcept {
    if constexpr (std::is_same_v<T, bool>) {
        write_text(value ? "true" : "false");
    } else if constexpr (std::is_integral_v<T> && std::is_signed_v<T>) {
        write_signed(static_cast<std::int64_t>(value));
    } else if constexpr (std::is_integral_v<T>) {
        write_unsigned(static_cast<std::uint64_t>(value));
    } else {
        write_text("(value not printable)");
    }
}

inline void write_location(const char* file, int line) noexcept {
    write_text(file);
    write_text(":");
    write_signed(line);
    write_text(": Failure\n");
}

template <typename A, typename E>
void expect_eq(const A& actual, const E& expected, const char* actual_text,
               const char* expected_text, const char* file, int line) noexcept {
    if (actual == expected) {
        return;
    }
    registry.current_failed = true;
    write_location(file, line);
    write_text("Expected equality of these values:\n  ");
    write_text(actual_text);
    write_text("\n    Which is: ");
    write_value(actual);
    write_text("\n  ");
    write_text(expected_text);
    write_text("\n    Which is: ");
    write_value(expected);
    write_text("\n");
}

inline void expect_true(bool condition, const char* condition_text, const char* file,
                        int line) noexcept {
    if (condition) {
        return;
    }
    registry.current_failed = true;
    write_location(file, line);
    write_text("Value of: ");
    write_text(condition_text);
    write_text("\n  Actual: false\nExpected: true\n");
}

/// Runs every registered test; returns the number of failed tests (a registry overflow counts
/// as one failure).
inline int run_all() noexcept {
    int failed = 0;
    write_text("[==========] Running ");
    write_unsigned(registry.count);
    write_text(" tests (scopekin portable_check, bare metal).\n");
    for (std::size_t i = 0; i < registry.count; ++i) {  // bound: max_tests
        const TestCase& test = registry.cases[i];
        registry.current_failed = false;
        write_text("[ RUN      ] ");
        write_text(test.suite);
        write_text(".");
        write_text(test.name);
        write_text("\n");
        test.function();
        write_text(registry.current_failed ? "[  FAILED  ] " : "[       OK ] ");
        write_text(test.suite);
        write_text(".");
        write_text(test.name);
        write_text("\n");
        if (registry.current_failed) {
            ++failed;
        }
    }
    if (registry.overflowed) {
        write_text("[  FAILED  ] registry overflow: raise portable_check::max_tests\n");
        ++failed;
    }
    write_text("[==========] ");
    write_unsigned(registry.count);
    write_text(" tests ran.\n");
    if (failed == 0) {
        write_text("[  PASSED  ] ");
        write_unsigned(registry.count);
        write_text(" tests.\n");
    } else {
        write_text("[  FAILED  ] ");
        write_signed(failed);
        write_text(" tests failed.\n");
    }
    return failed;
}

}  // namespace scopekin::portable_check

#define SCOPEKIN_TEST(suite, name)                                                          \
    static void scopekin_test_##suite##_##name();                                           \
    static const ::scopekin::portable_check::Registrar scopekin_registrar_##suite##_##name{ \
        #suite, #name, &scopekin_test_##suite##_##name};                                    \
    static void scopekin_test_##suite##_##name()

#define SCOPEKIN_EXPECT_EQ(actual, expected)                                                  \
    ::scopekin::portable_check::expect_eq((actual), (expected), #actual, #expected, __FILE__, \
                                          __LINE__)

#define SCOPEKIN_EXPECT_TRUE(condition)                                                         \
    ::scopekin::portable_check::expect_true(static_cast<bool>(condition), #condition, __FILE__, \
                                            __LINE__)

#endif
