// Catch2 v2 has no SKIP: a test that cannot run on this machine says why and leaves. The
// marker makes CTest count it as skipped (SKIP_REGULAR_EXPRESSION in tests/CMakeLists.txt),
// so a missing optional part (../shared, a GPU, pyopenvdb) shows in ctest's summary under
// "The following tests did not run" instead of passing silently.
#pragma once

#include <catch2/catch.hpp>

#define VL_SKIP(why)                 \
    do {                             \
        WARN("SKIPPED: " << why);    \
        return;                      \
    } while (0)
