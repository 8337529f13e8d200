#include "tools/fuzz/scratch_file.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace vl::fuzz {

namespace {

struct ScratchFolder {
    std::string path;
    ScratchFolder() {
        char name[] = "/tmp/voxlight-fuzz-XXXXXX";
        if (!::mkdtemp(name)) throw std::runtime_error("cannot make a scratch folder in /tmp");
        path = name;
    }
    ~ScratchFolder() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

}  // namespace

std::string writeScratch(const uint8_t* data, size_t size, const std::string& extension) {
    static ScratchFolder folder;
    const std::string path = folder.path + "/input" + extension;
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
    std::fclose(file);
    return path;
}

}  // namespace vl::fuzz
