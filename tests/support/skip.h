// Catch2 v2 has no SKIP: a test that cannot run on this machine says why and leaves. The
// marker makes CTest count it as skipped (SKIP_REGULAR_EXPRESSION in tests/CMakeLists.txt),
// so a missing optional part (../shared, a GPU, pyopenvdb) shows in ctest's summary under
// "The following tests did not run" instead of passing silently.
#pragma once

#include <catch2/catch.hpp>

// 1 in a build with AddressSanitizer (tools/sanitize.sh), where some library behaviour differs
// (an allocation that fails stops the process instead of throwing).
#if defined(__SANITIZE_ADDRESS__)
#define VL_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VL_ADDRESS_SANITIZER 1
#endif
#endif
#ifndef VL_ADDRESS_SANITIZER
#define VL_ADDRESS_SANITIZER 0
#endif

#define VL_SKIP(why)                 \
    do {                             \
        WARN("SKIPPED: " << why);    \
        return;                      \
    } while (0)
