// Zero heap allocations after init (the firmware's rule "no heap after start-up").
//
//   scopekin_budget_heap [--json FILE]
//
// Runs every scenario through kinetics::init + kinetics::step on a hosted target and counts every
// allocation and deallocation between the end of init and the end of the last step:
//   * global operator new / new[] / delete / delete[] (all sized, aligned and nothrow forms) are
//     replaced here; replacement is program-wide, so it also sees libstdc++'s own calls;
//   * malloc, calloc, realloc, free, aligned_alloc, posix_memalign, memalign are wrapped with the
//     linker's --wrap (tests/budget/CMakeLists.txt): every call from an object of this link —
//     this file, the static firmware library scopekin::firmware, and the harness — goes through
//     the counting __wrap_ functions, and __real_ reaches the C library (or the sanitizer's
//     allocator on the asan preset).
// A self-check first proves each counter works.  Exit status 0 only if nothing was allocated or
// freed after init; with --json FILE the result is written as a part of build/<preset>/budget.json.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>
#include <string>

#include "kinetics_harness.hpp"
#include "scenario_registry.hpp"

extern "C" {
void* __real_malloc(std::size_t size);
void* __real_calloc(std::size_t count, std::size_t size);
void* __real_realloc(void* pointer, std::size_t size);
void __real_free(void* pointer);
void* __real_aligned_alloc(std::size_t alignment, std::size_t size);
int __real_posix_memalign(void** pointer, std::size_t alignment, std::size_t size);
void* __real_memalign(std::size_t alignment, std::size_t size);
}

namespace {

struct HeapCounters {
    std::uint64_t allocations;    // every call that may hand out memory
    std::uint64_t deallocations;  // every call that may give memory back
};

HeapCounters g_heap{};

void count_allocation() noexcept {
    g_heap.allocations = g_heap.allocations + 1U;
}
void count_deallocation() noexcept {
    g_heap.deallocations = g_heap.deallocations + 1U;
}

void* new_memory(std::size_t size) {
    count_allocation();
    void* p = __real_malloc(size == 0U ? 1U : size);
    if (p == nullptr) {
        throw std::bad_alloc();
    }
    return p;
}

void* new_aligned_memory(std::size_t size, std::align_val_t alignment) {
    count_allocation();
    void* p = nullptr;
    const auto align = static_cast<std::size_t>(alignment);
    if (__real_posix_memalign(&p, align < sizeof(void*) ? sizeof(void*) : align,
                              size == 0U ? 1U : size) != 0) {
        throw std::bad_alloc();
    }
    return p;
}

void delete_memory(void* pointer) noexcept {
    count_deallocation();
    __real_free(pointer);
}

}  // namespace

extern "C" {
void* __wrap_malloc(std::size_t size) {
    count_allocation();
    return __real_malloc(size);
}
void* __wrap_calloc(std::size_t count, std::size_t size) {
    count_allocation();
    return __real_calloc(count, size);
}
void* __wrap_realloc(void* pointer, std::size_t size) {
    count_allocation();
    return __real_realloc(pointer, size);
}
void __wrap_free(void* pointer) {
    count_deallocation();
    __real_free(pointer);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
    count_allocation();
    return __real_aligned_alloc(alignment, size);
}
int __wrap_posix_memalign(void** pointer, std::size_t alignment, std::size_t size) {
    count_allocation();
    return __real_posix_memalign(pointer, alignment, size);
}
void* __wrap_memalign(std::size_t alignment, std::size_t size) {
    count_allocation();
    return __real_memalign(alignment, size);
}
}

// --- replaced global allocation functions ([new.delete]) ----------------------------------------
void* operator new(std::size_t size) {
    return new_memory(size);
}
void* operator new[](std::size_t size) {
    return new_memory(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    try {
        return new_memory(size);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
    try {
        return new_memory(size);
    } catch (...) {
        return nullptr;
    }
}
void* operator new(std::size_t size, std::align_val_t alignment) {
    return new_aligned_memory(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
    return new_aligned_memory(size, alignment);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
    try {
        return new_aligned_memory(size, alignment);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
    try {
        return new_aligned_memory(size, alignment);
    } catch (...) {
        return nullptr;
    }
}
void operator delete(void* p) noexcept {
    delete_memory(p);
}
void operator delete[](void* p) noexcept {
    delete_memory(p);
}
void operator delete(void* p, std::size_t) noexcept {
    delete_memory(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    delete_memory(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
    delete_memory(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    delete_memory(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
    delete_memory(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
    delete_memory(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
    delete_memory(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
    delete_memory(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    delete_memory(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    delete_memory(p);
}

namespace {

scopekin::kinetics::State g_state;  // static storage, as on the target
scopekin::kinetics::Outputs g_outputs;

// Called through volatile pointers so the compiler cannot elide the calls of the self-check.
void* (*volatile g_malloc)(std::size_t) = &std::malloc;
void* (*volatile g_calloc)(std::size_t, std::size_t) = &std::calloc;
void* (*volatile g_realloc)(void*, std::size_t) = &std::realloc;
void (*volatile g_free)(void*) = &std::free;
void* (*volatile g_new)(std::size_t) = &::operator new;
void (*volatile g_delete)(void*) noexcept = &::operator delete;

/// Each counter moves when it should; false if a wrapper is not in place.
bool self_check() {
    bool ok = true;
    auto expect = [&ok](const char* what, std::uint64_t allocations, std::uint64_t deallocations,
                        const HeapCounters& before) {
        const HeapCounters after = g_heap;
        if (after.allocations - before.allocations != allocations ||
            after.deallocations - before.deallocations != deallocations) {
            std::cerr << "self-check failed: " << what << " is not counted\n";
            ok = false;
        }
    };
    HeapCounters before = g_heap;
    void* p = g_malloc(16U);
    expect("malloc", 1U, 0U, before);
    before = g_heap;
    p = g_realloc(p, 64U);
    expect("realloc", 1U, 0U, before);
    before = g_heap;
    g_free(p);
    expect("free", 0U, 1U, before);
    before = g_heap;
    p = g_calloc(4U, 8U);
    g_free(p);
    expect("calloc", 1U, 1U, before);
    before = g_heap;
    p = g_new(32U);
    g_delete(p);
    expect("operator new/delete", 1U, 1U, before);
    return ok;
}

std::string json_string(const char* text) {
    std::string out = "\"";
    for (const char* c = text; *c != '\0'; ++c) {
        if (*c == '"' || *c == '\\') {
            out += '\\';
        }
        out += *c;
    }
    return out + "\"";
}

}  // namespace

int main(int argc, char** argv) {
    std::string json_path;
    std::string preset = "unknown";
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--json" && i + 1 < argc) {
            json_path = argv[++i];
        } else if (arg == "--preset" && i + 1 < argc) {
            preset = argv[++i];
        } else {
            std::cerr << "usage: " << argv[0] << " [--json FILE] [--preset NAME]\n";
            return 2;
        }
    }
    if (!json_path.empty()) {
        std::error_code ignored;
        std::filesystem::remove(json_path, ignored);  // never report a part of an earlier run
    }
    if (!self_check()) {
        return 1;
    }

    struct Result {
        std::uint64_t steps, init_allocations, allocations, deallocations;
    };
    constexpr std::size_t max_scenarios = 64;
    Result results[max_scenarios]{};
    std::uint64_t total_allocations = 0;
    std::uint64_t total_deallocations = 0;
    std::size_t n = 0;
    for (const scopekin::test_data::Scenario* scenario : scopekin::test_data::all_scenarios) {
        if (n == max_scenarios) {
            std::cerr << "more than " << max_scenarios << " scenarios\n";
            return 1;
        }
        // --- counted window: nothing below may allocate (no I/O, no strings) ---
        const HeapCounters before_init = g_heap;
        scopekin::kinetics::init(scopekin::kinetics::default_config(), g_state);
        const HeapCounters after_init = g_heap;
        for (std::size_t i = 0; i < scenario->step_count; ++i) {
            const scopekin::kinetics::Inputs inputs =
                scopekin::budget::to_inputs(scenario->steps[i]);
            scopekin::kinetics::step(inputs, g_state, g_outputs);
        }
        const HeapCounters after_steps = g_heap;
        // --- end of the counted window ---
        results[n] = Result{scenario->step_count, after_init.allocations - before_init.allocations,
                            after_steps.allocations - after_init.allocations,
                            after_steps.deallocations - after_init.deallocations};
        total_allocations += results[n].allocations;
        total_deallocations += results[n].deallocations;
        ++n;
    }

    std::ostringstream scenarios_json;
    for (std::size_t i = 0; i < n; ++i) {
        const Result& r = results[i];
        std::cout << "[ heap ] " << scopekin::test_data::all_scenarios[i]->name << ": " << r.steps
                  << " steps, allocations during init " << r.init_allocations
                  << ", after init: " << r.allocations << " allocations, " << r.deallocations
                  << " deallocations\n";
        scenarios_json << (i == 0 ? "" : ",") << "\n    "
                       << json_string(scopekin::test_data::all_scenarios[i]->name)
                       << ": {\"steps\": " << r.steps
                       << ", \"heap_allocations_during_init\": " << r.init_allocations
                       << ", \"heap_allocations_after_init\": " << r.allocations
                       << ", \"heap_deallocations_after_init\": " << r.deallocations << "}";
    }
    const bool pass = total_allocations == 0U && total_deallocations == 0U;
    std::cout << "heap_allocations_after_init = " << total_allocations << " (deallocations "
              << total_deallocations << "): " << (pass ? "PASS" : "FAIL (bound: 0)") << "\n";

    if (!json_path.empty()) {
        std::error_code ignored;
        std::filesystem::create_directories(std::filesystem::path(json_path).parent_path(),
                                            ignored);
        std::ofstream json(json_path, std::ios::trunc);
        json << "{\n  \"heap_allocations_after_init\": " << total_allocations
             << ",\n  \"heap\": {\n    \"preset\": " << json_string(preset.c_str())
             << ",\n    \"bound\": 0"
             << ",\n    \"heap_deallocations_after_init\": " << total_deallocations
             << ",\n    \"method\": \"replaced global operator new/delete + --wrap of malloc, "
                "calloc, "
                "realloc, free, aligned_alloc, posix_memalign, memalign; counted from the end of "
                "init to the end of the last step of every scenario\"\n  },\n"
             << "  \"scenarios\": {" << scenarios_json.str() << "\n  }\n}\n";
        json.close();
        if (!json) {
            std::cerr << "cannot write " << json_path << "\n";
            return 3;
        }
    }
    return pass ? 0 : 1;
}
