// A cap on single allocations while a library parses a file from elsewhere. OpenVDB reads a
// length from the file and allocates that much before reading the bytes, so a small file that
// claims a huge length takes the machine's memory before it fails (docs/decisions.md,
// "Allocation cap"). No single allocation that parsing a file needs can be larger than the
// file itself, give or take the largest fixed-size node, so a reader sets the cap to that bound
// for the scope of the library's calls.
//
// Inside the scope, on the calling thread, the global operator new (replaced in
// allocation_limit.cpp) refuses any single allocation over the cap with std::bad_alloc before
// asking for the memory; the reader reports the file as unreadable, naming the size it claimed.
// Scopes nest. Not enforced under ThreadSanitizer, whose runtime defines operator new itself.
#pragma once

#include <cstddef>

#if defined(__SANITIZE_THREAD__)
#define VL_ALLOCATION_LIMIT_ENFORCED 0
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define VL_ALLOCATION_LIMIT_ENFORCED 0
#endif
#endif
#ifndef VL_ALLOCATION_LIMIT_ENFORCED
#define VL_ALLOCATION_LIMIT_ENFORCED 1
#endif

namespace vl {

class AllocationLimit {
public:
    static constexpr std::size_t none = ~std::size_t(0);
    static constexpr bool enforced = VL_ALLOCATION_LIMIT_ENFORCED;

    explicit AllocationLimit(std::size_t largestBytes);
    ~AllocationLimit();
    AllocationLimit(const AllocationLimit&) = delete;
    AllocationLimit& operator=(const AllocationLimit&) = delete;

    // The size of the last allocation this thread refused (0: none since the scope began).
    static std::size_t refusedBytes();

private:
    std::size_t previous_;
};

}  // namespace vl
