#include "core/allocation_limit.h"

#include <cstdlib>
#include <new>

namespace {
thread_local std::size_t largestAllowed = vl::AllocationLimit::none;
thread_local std::size_t lastRefused = 0;

void* allocate(std::size_t size) {
    if (size > largestAllowed) {
        lastRefused = size;
        throw std::bad_alloc();
    }
    for (;;) {
        if (void* p = std::malloc(size ? size : 1)) return p;
        const std::new_handler handler = std::get_new_handler();
        if (!handler) throw std::bad_alloc();
        handler();
    }
}

void* allocateOrNull(std::size_t size) noexcept {
    try {
        return allocate(size);
    } catch (const std::bad_alloc&) {
        return nullptr;
    }
}
}  // namespace

namespace vl {

AllocationLimit::AllocationLimit(std::size_t largestBytes) : previous_(largestAllowed) {
    largestAllowed = largestBytes;
    lastRefused = 0;
}

AllocationLimit::~AllocationLimit() { largestAllowed = previous_; }

std::size_t AllocationLimit::refusedBytes() { return lastRefused; }

}  // namespace vl

#if VL_ALLOCATION_LIMIT_ENFORCED
// The replaceable global allocation functions ([new.delete]); the aligned forms keep
// libstdc++'s own, which pair with each other.
void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocateOrNull(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocateOrNull(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#endif
