#include "bench/cycles_peer.h"

#include "bench/display_path.h"
#include "core/error.h"
#include "core/image_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <unistd.h>

namespace vl {
namespace fs = std::filesystem;

namespace {

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

std::string onPath(const std::string& name) {
    const char* path = std::getenv("PATH");
    if (!path) return "";
    std::istringstream dirs(path);
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
        std::error_code ec;
        if (fs::is_regular_file(candidate, ec) && access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
    return "";
}

std::string tail(const fs::path& file, size_t chars) {
    std::ifstream in(file);
    std::ostringstream text;
    text << in.rdbuf();
    const std::string s = text.str();
    return s.size() > chars ? s.substr(s.size() - chars) : s;
}

nlohmann::json readJson(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw InputError(file.string() + ": cannot read");
    const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    if (json.is_discarded()) throw InputError(file.string() + ": not valid JSON");
    return json;
}

}  // namespace

CyclesPeer findCyclesPeer(const BenchOptions& options) {
    CyclesPeer peer;
    if (options.blender == "none") {
        peer.why = "Cycles peer off (--blender none, or --methods without cycles)";
        return peer;
    }
    peer.blender = options.blender.empty() ? onPath("blender") : options.blender;
    if (peer.blender.empty()) {
        peer.why = "no Cycles peer: blender is not on the PATH (Debian package blender; see tools/bench/cycles_bake.py)";
        return peer;
    }
    peer.script = options.cyclesScript;
    if (peer.script.empty() || !fs::exists(peer.script)) {
        peer.why = "no Cycles peer: the Blender script '" + displayPath(peer.script, options.base.outputDir) + "' is missing";
        return peer;
    }
    peer.available = true;
    return peer;
}

void runCyclesPoint(const BenchOptions& options, const CyclesPeer& peer, BenchPointResult& p, const CompareOutputs& compare) {
    p.outputDir = "points/cycles-spp=" + std::to_string(p.spec.spp);
    const fs::path dir = fs::path(options.base.outputDir) / p.outputDir;
    fs::create_directories(dir);
    const BakeSettings& s = options.base.settings;
    std::string command = shellQuote(peer.blender) + " -b --factory-startup --python-exit-code 1 --python " +
                          shellQuote(peer.script) + " -- --scene " + shellQuote(fs::absolute(options.base.scenePath).string()) +
                          " --out " + shellQuote(fs::absolute(dir).string()) + " --spp " + std::to_string(p.spec.spp) +
                          " --lightmap-res " + std::to_string(s.lightmap.width) + " --width " + std::to_string(s.imageWidth) +
                          " --height " + std::to_string(s.imageHeight);
    // The sky, which glTF does not carry: Cycles' world colour, or its environment texture.
    const bool uniformSky = maxComponent(s.sky) > 0.0f;
    if (uniformSky && !s.skyImage.empty())
        throw SettingsError("the Cycles peer takes a uniform sky or a sky image, not both");
    if (uniformSky) {
        std::ostringstream sky;  // six significant digits, as the settings print them
        sky << " --sky " << s.sky.x << "," << s.sky.y << "," << s.sky.z;
        command += sky.str();
    }
    if (!s.skyImage.empty()) {
        std::ostringstream sky;
        sky << " --sky-image " << shellQuote(fs::absolute(s.skyImage).string()) << " --sky-rotation " << s.skyRotation
            << " --sky-intensity " << s.skyIntensity;
        command += sky.str();
    }
    if (s.lambertMaterials) command += " --lambert-all";
    if (!s.outputs.lightmaps) command += " --no-lightmap";
    if (!s.outputs.images) command += " --no-image";
    if (!options.base.addedLights.empty())
        throw SettingsError("the Cycles peer cannot add a job file's lights to the scene");
    const fs::path log = dir / "blender.log";
    command += " > " + shellQuote(log.string()) + " 2>&1";
    fs::remove(dir / "cycles.json");
    const int status = std::system(command.c_str());
    if (status != 0 || !fs::exists(dir / "cycles.json"))
        throw Error("blender failed (status " + std::to_string(status) + "), log " +
                    displayPath(log.string(), options.base.outputDir) + ":\n" + tail(log, 1500));
    const nlohmann::json times = readJson(dir / "cycles.json");
    if (times.contains("lightmap_seconds")) {
        p.lightmapRuns.push_back(times["lightmap_seconds"].get<double>());
        // The indirect part: 3.4 bakes an indirect-only pass as zero, so total − direct.
        const Image total = readImage((dir / "lightmap.exr").string());
        const Image direct = readImage((dir / "lightmap_direct.exr").string());
        Image indirect(total.width, total.height, 3);
        for (int y = 0; y < total.height; ++y)
            for (int x = 0; x < total.width; ++x)
                for (int c = 0; c < 3; ++c) indirect.at(x, y, c) = total.at(x, y, c) - direct.at(x, y, c);
        writeExr(indirect, (dir / "lightmap_indirect.exr").string());
    }
    if (times.contains("image_seconds")) p.imageRuns.push_back(times["image_seconds"].get<double>());
    p.cpuRuns.push_back(times.value("cpu_seconds", 0.0));
    p.peakMemoryBytes = times.value("peak_memory_bytes", 0.0);
    p.note = "one Blender run; times from the script, around each bake/render";
    compare(p, dir);
}

std::vector<BenchPointResult> cyclesFilePoints(const std::string& dir, const std::string& scenePath,
                                               const BenchReferenceFiles& reference, const CompareStems& compare) {
    std::vector<BenchPointResult> points;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return points;
    const std::string stem = fs::path(scenePath).stem().string();
    const std::string variant = stem.substr(stem.find_last_of('_') + 1);
    nlohmann::json timings;
    if (fs::exists(fs::path(dir) / "timings.json")) timings = readJson(fs::path(dir) / "timings.json");
    const std::regex pattern(stem + "_lightmap_([0-9]+)spp\\.exr");
    std::vector<int> spps;
    for (const auto& entry : fs::directory_iterator(dir)) {
        std::smatch m;
        const std::string name = entry.path().filename().string();
        if (!std::regex_match(name, m, pattern)) continue;
        if (fs::equivalent(entry.path(), reference.lightmap, ec)) continue;  // the reference itself
        spps.push_back(std::stoi(m[1]));
    }
    std::sort(spps.begin(), spps.end());
    for (int spp : spps) {
        BenchPointResult p;
        p.spec = {"cycles-files", "spp=" + std::to_string(spp), {}, spp};
        const std::string n = std::to_string(spp) + "spp";
        auto seconds = [&](const std::string& key) {
            return timings.contains(key) && timings[key].contains("seconds") ? timings[key]["seconds"].get<double>() : 0.0;
        };
        const double lightmap = seconds("lightmap_" + variant + "_" + n);
        const double image = seconds("render_" + variant + "_" + n);
        if (lightmap > 0.0) p.lightmapRuns.push_back(lightmap);
        std::string imageStem = stem + "_render_" + n;
        const bool imageFile = fs::exists(fs::path(dir) / (imageStem + ".exr")) &&
                               !fs::equivalent(fs::path(dir) / (imageStem + ".exr"), reference.image, ec);
        if (!imageFile) imageStem.clear();
        if (imageFile && image > 0.0) p.imageRuns.push_back(image);
        p.lightmapSeconds = lightmap;
        p.imageSeconds = imageFile ? image : 0.0;
        auto cpu = [&](const std::string& key) {
            return timings.contains(key) && timings[key].contains("cpu_seconds") ? timings[key]["cpu_seconds"].get<double>() : 0.0;
        };
        p.cpuSeconds = cpu("lightmap_" + variant + "_" + n) + (imageFile ? cpu("render_" + variant + "_" + n) : 0.0);
        p.outputDir = dir;
        p.note = "precomputed files; times from timings.json (another run, another process)";
        try {
            compare(p, dir, stem + "_lightmap_" + n, imageStem);
            p.ok = true;
        } catch (const std::exception& e) {
            p.error = e.what();
        }
        points.push_back(std::move(p));
    }
    return points;
}

}  // namespace vl
