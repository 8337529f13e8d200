#include "core/allocation_limit.h"
#include "support/skip.h"

#include <catch2/catch.hpp>

#include <new>
#include <string>
#include <thread>

using namespace vl;

namespace {
// Calls operator new[] itself: a new-expression whose result is unused may be elided (clang
// does, at -O2), and then nothing is asked of the allocator.
void allocateAndFree(std::size_t bytes) { ::operator delete[](::operator new[](bytes)); }
}  // namespace

TEST_CASE("An allocation limit refuses larger single allocations on its thread, and scopes nest", "[core]") {
    if (!AllocationLimit::enforced) VL_SKIP("ThreadSanitizer's runtime owns operator new in this build");
    const std::size_t cap = std::size_t(1) << 20;
    {
        const AllocationLimit limit(cap);
        CHECK(AllocationLimit::refusedBytes() == 0);
        CHECK_NOTHROW(allocateAndFree(cap));  // at the cap: allowed
        CHECK_THROWS_AS(allocateAndFree(cap + 1), std::bad_alloc);
        CHECK(AllocationLimit::refusedBytes() == cap + 1);
        // A string filled to a claimed length is refused before it is filled.
        CHECK_THROWS_AS(std::string(3 * cap, ' '), std::bad_alloc);
        CHECK(AllocationLimit::refusedBytes() >= 3 * cap);
        // nothrow new answers null instead.
        void* none = ::operator new[](cap + 1, std::nothrow);
        CHECK(none == nullptr);
        ::operator delete[](none);
        // Another thread is not limited.
        bool otherThreadAllocated = false;
        std::thread([&] {
            allocateAndFree(4 * cap);
            otherThreadAllocated = true;
        }).join();
        CHECK(otherThreadAllocated);
        {
            const AllocationLimit lifted(AllocationLimit::none);
            CHECK_NOTHROW(allocateAndFree(4 * cap));
        }
        CHECK_THROWS_AS(allocateAndFree(4 * cap), std::bad_alloc);  // the outer cap again
    }
    CHECK_NOTHROW(allocateAndFree(4 * cap));
}
