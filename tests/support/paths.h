// Where tests find their inputs. ../shared (the corpora and Cycles references) sits beside
// the checkout in CI; a test that needs it says it is skipping when it is absent.
#pragma once

#include "support/skip.h"

#include <filesystem>
#include <string>

namespace vl::test {

inline std::string sourceDir() { return VOXLIGHT_SOURCE_DIR; }
inline std::string sharedDir() { return std::string(VOXLIGHT_SOURCE_DIR) + "/../shared"; }
inline bool haveShared() { return std::filesystem::exists(sharedDir() + "/scenes"); }
inline std::string tempDir(const std::string& name) {
    const auto dir = std::filesystem::path(VOXLIGHT_BINARY_DIR) / "test-output" / name;
    std::filesystem::create_directories(dir);
    return dir.string();
}

}  // namespace vl::test

#define VL_SKIP_WITHOUT_SHARED()                                                      \
    do {                                                                              \
        if (!vl::test::haveShared()) VL_SKIP(vl::test::sharedDir() << " is absent");  \
    } while (0)
