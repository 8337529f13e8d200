#include "bench/display_path.h"

#include <filesystem>
#include <optional>

namespace vl {
namespace fs = std::filesystem;

namespace {

// `path` relative to `dir` when it lies inside it, both resolved (symbolic links, "..").
std::optional<fs::path> inside(const fs::path& path, const fs::path& dir) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(path, ec);
    if (ec) return std::nullopt;
    fs::path d = fs::weakly_canonical(dir, ec);
    if (ec) return std::nullopt;
    if (!d.has_filename()) d = d.parent_path();  // "out/" is "out"
    const fs::path relative = p.lexically_relative(d);
    if (relative.empty() || *relative.begin() == "..") return std::nullopt;
    return relative;
}

}  // namespace

std::string displayPath(const std::string& path, const std::string& outputDir) {
    if (!fs::path(path).is_absolute()) return path;
    const fs::path repository = VOXLIGHT_SOURCE_DIR;
    if (const auto r = inside(path, repository)) return r->string();
    if (const auto r = inside(path, repository / ".." / "shared")) return (fs::path("..") / "shared" / *r).string();
    if (!outputDir.empty())
        if (const auto r = inside(path, outputDir)) return r->string();
    return path;
}

}  // namespace vl
