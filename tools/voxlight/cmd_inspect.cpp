// `voxlight inspect file.vdb [--json] [--slice x|y|z=INDEX --grid NAME -o slice.png]`: what a
// .vdb holds, ours or any other program's.
#include "tools/voxlight/commands.h"

#include "core/error.h"
#include "core/image_io.h"
#include "voxel/vdb_inspect.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace vl::cli {

namespace {

struct InspectOptions {
    std::string file;
    bool json = false;
    std::string slice;
    std::string grid;
    std::string output;
};

std::string humanBytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 5) {
        bytes /= 1024.0;
        ++u;
    }
    char text[32];
    std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
    return text;
}

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

std::string triple(const std::array<double, 3>& v) {
    return "(" + number(v[0]) + ", " + number(v[1]) + ", " + number(v[2]) + ")";
}

std::string triple(const std::array<int, 3>& v) {
    return "(" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " + std::to_string(v[2]) + ")";
}

void printText(const VdbFileInfo& info) {
    std::printf("%s: %zu grid%s\n", info.path.c_str(), info.grids.size(), info.grids.size() == 1 ? "" : "s");
    for (const auto& [key, value] : info.metadata) std::printf("  %-16s %s\n", key.c_str(), value.c_str());
    for (const GridInfo& g : info.grids) {
        std::printf("\ngrid '%s'\n", g.name.c_str());
        std::printf("  type         %s, class %s\n", g.valueType.c_str(), g.gridClass.c_str());
        std::printf("  voxel size   %s%s\n",
                    g.voxelSize[0] == g.voxelSize[1] && g.voxelSize[1] == g.voxelSize[2] ? number(g.voxelSize[0]).c_str()
                                                                                        : triple(g.voxelSize).c_str(),
                    g.linearTransform ? "" : " (non-linear transform: at the origin)");
        std::printf("  active       %llu voxels\n", static_cast<unsigned long long>(g.activeVoxels));
        if (!g.empty) {
            std::printf("  bbox index   %s .. %s  (%d x %d x %d)\n", triple(g.indexMin).c_str(),
                        triple(g.indexMax).c_str(), g.indexMax[0] - g.indexMin[0] + 1,
                        g.indexMax[1] - g.indexMin[1] + 1, g.indexMax[2] - g.indexMin[2] + 1);
            std::printf("  bbox world   %s .. %s\n", triple(g.worldMin).c_str(), triple(g.worldMax).c_str());
        }
        std::printf("  memory       %s", humanBytes(double(g.memoryBytes)).c_str());
        if (g.denseBytes > 0)
            std::printf(", dense bbox %s (%.3g %%)", humanBytes(double(g.denseBytes)).c_str(),
                        100.0 * double(g.memoryBytes) / double(g.denseBytes));
        std::printf("\n");
        const GridValueStats& s = g.stats;
        if (s.available) {
            const char* of = s.ofMagnitude ? "|v|" : "value";
            std::printf("  %-12s min %s  max %s  mean %s\n", of, number(s.min).c_str(), number(s.max).c_str(),
                        number(s.mean).c_str());
            if (s.ofMagnitude)
                std::printf("  components   min %s  max %s\n", triple(s.componentMin).c_str(),
                            triple(s.componentMax).c_str());
            const uint64_t peak = *std::max_element(s.histogram.begin(), s.histogram.end());
            const double width = (s.max - s.min) / double(s.histogram.size());
            // A constant grid has one value: one line says it.
            const size_t bins = s.max > s.min ? s.histogram.size() : 1;
            for (size_t b = 0; b < bins; ++b) {
                constexpr int kBarWidth = 40;
                const int bar = peak ? static_cast<int>((s.histogram[b] * kBarWidth + peak - 1) / peak) : 0;
                std::printf("  %12s |%-*s| %llu\n", number(s.min + width * double(b)).c_str(), kBarWidth,
                            std::string(static_cast<size_t>(bar), '#').c_str(),
                            static_cast<unsigned long long>(s.histogram[b]));
            }
        } else {
            std::printf("  values       none to summarize\n");
        }
        if (s.nonFinite) std::printf("  non-finite   %llu voxels (NaN or Inf)\n", static_cast<unsigned long long>(s.nonFinite));
        for (const auto& [key, value] : g.metadata) std::printf("  %-12s %s\n", key.c_str(), value.c_str());
    }
    uint64_t used = 0, dense = 0;
    for (const GridInfo& g : info.grids) {
        used += g.memoryBytes;
        dense += g.denseBytes;
    }
    if (!info.grids.empty())
        std::printf("\ntotal memory %s, dense bboxes %s\n", humanBytes(double(used)).c_str(),
                    humanBytes(double(dense)).c_str());
}

nlohmann::ordered_json toJson(const VdbFileInfo& info) {
    using json = nlohmann::ordered_json;
    json out;
    out["file"] = info.path;
    json meta = json::object();
    for (const auto& [key, value] : info.metadata) meta[key] = value;
    out["metadata"] = meta;
    json grids = json::array();
    for (const GridInfo& g : info.grids) {
        json j;
        j["name"] = g.name;
        j["value_type"] = g.valueType;
        j["class"] = g.gridClass;
        j["voxel_size"] = g.voxelSize;
        j["linear_transform"] = g.linearTransform;
        j["active_voxels"] = g.activeVoxels;
        if (!g.empty) {
            j["bbox_index"] = {{"min", g.indexMin}, {"max", g.indexMax}};
            j["bbox_world"] = {{"min", g.worldMin}, {"max", g.worldMax}};
        } else {
            j["bbox_index"] = nullptr;
            j["bbox_world"] = nullptr;
        }
        j["memory_bytes"] = g.memoryBytes;
        j["dense_bytes"] = g.denseBytes;
        const GridValueStats& s = g.stats;
        if (s.available) {
            json stats;
            stats["of"] = s.ofMagnitude ? "magnitude" : "value";
            stats["min"] = s.min;
            stats["max"] = s.max;
            stats["mean"] = s.mean;
            stats["histogram"] = s.histogram;
            if (s.ofMagnitude) {
                stats["component_min"] = s.componentMin;
                stats["component_max"] = s.componentMax;
            }
            stats["non_finite"] = s.nonFinite;
            j["stats"] = stats;
        } else {
            j["stats"] = nullptr;
        }
        json gridMeta = json::object();
        for (const auto& [key, value] : g.metadata) gridMeta[key] = value;
        j["metadata"] = gridMeta;
        grids.push_back(j);
    }
    out["grids"] = grids;
    return out;
}

// "z=12" → (Z, 12).
std::pair<SliceAxis, int> parseSlice(const std::string& text) {
    const auto fail = [&] {
        return SettingsError("inspect: --slice wants x=INDEX, y=INDEX or z=INDEX (an integer voxel index), got '" +
                             text + "'");
    };
    if (text.size() < 3 || text[1] != '=') throw fail();
    const char a = static_cast<char>(std::tolower(static_cast<unsigned char>(text[0])));
    if (a != 'x' && a != 'y' && a != 'z') throw fail();
    const std::string digits = text.substr(2);
    size_t used = 0;
    int index = 0;
    try {
        index = std::stoi(digits, &used);
    } catch (const std::exception&) {
        throw fail();
    }
    if (used != digits.size()) throw fail();
    return {a == 'x' ? SliceAxis::X : a == 'y' ? SliceAxis::Y : SliceAxis::Z, index};
}

void runInspect(const InspectOptions& options) {
    if (options.slice.empty()) {
        if (!options.grid.empty() || !options.output.empty())
            throw SettingsError("inspect: --grid and -o go with --slice");
        const VdbFileInfo info = inspectVoxelFile(options.file);
        if (options.json) std::cout << toJson(info).dump(2) << '\n';
        else printText(info);
        return;
    }
    if (options.json) throw SettingsError("inspect: --json prints the summary; it does not go with --slice");
    if (options.grid.empty()) throw SettingsError("inspect: --slice needs --grid NAME");
    if (options.output.empty()) throw SettingsError("inspect: --slice needs -o FILE (.png or .exr)");
    const auto [axis, index] = parseSlice(options.slice);
    const Image image = sliceImage(options.file, options.grid, axis, index);
    std::string extension = std::filesystem::path(options.output).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (extension == ".exr") writeExr(image, options.output);
    else if (extension == ".png") writePngSrgb(image, options.output);
    else throw SettingsError("inspect: -o " + options.output + ": the slice is written as .png or .exr");
    std::printf("wrote %s (%d x %d) from grid '%s' of %s\n", options.output.c_str(), image.width, image.height,
                options.grid.c_str(), options.file.c_str());
}

}  // namespace

void addInspectCommand(CLI::App& app) {
    auto options = std::make_shared<InspectOptions>();
    auto* cmd = app.add_subcommand("inspect", "Show the grids of a .vdb file (any program's), or write a slice image");
    cmd->add_option("file", options->file, "the .vdb file")->required();
    cmd->add_flag("--json", options->json, "print the summary as JSON");
    cmd->add_option("--slice", options->slice, "write one index plane: x=INDEX, y=INDEX or z=INDEX");
    cmd->add_option("--grid", options->grid, "the grid to slice");
    cmd->add_option("-o,--output", options->output, "slice image (.png preview or linear .exr)");
    cmd->callback([options] { runInspect(*options); });
}

}  // namespace vl::cli
