#include "core/atomic_file.h"

#include "core/error.h"

#include <atomic>
#include <filesystem>
#include <unistd.h>

namespace vl {

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
    namespace fs = std::filesystem;
    static std::atomic<unsigned> counter{0};
    const fs::path target(path);
    if (target.has_parent_path()) fs::create_directories(target.parent_path());
    // Keep the extension last: OpenImageIO and OpenVDB choose the format by it.
    const fs::path temp = target.parent_path() /
        (target.stem().string() + ".tmp" + std::to_string(getpid()) + "-" + std::to_string(counter++) +
         target.extension().string());
    try {
        write(temp.string());
        fs::rename(temp, target);
    } catch (...) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        throw;
    }
}

}  // namespace vl
