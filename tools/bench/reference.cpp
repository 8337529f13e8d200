#include "bench/reference.h"

#include "bench/display_path.h"
#include "bench/traced_scene.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace vl {
namespace fs = std::filesystem;

namespace {

constexpr uint64_t kFnvOffset = 1469598103934665603ull;
constexpr uint64_t kFnvPrime = 1099511628211ull;

void hashBytes(uint64_t& h, const char* data, size_t size) {
    for (size_t i = 0; i < size; ++i) {
        h ^= static_cast<unsigned char>(data[i]);
        h *= kFnvPrime;
    }
}

void hashString(uint64_t& h, const std::string& s) {
    hashBytes(h, s.data(), s.size());
    hashBytes(h, "\0", 1);
}

std::string readFile(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string() + ": cannot read");
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

std::string hex(uint64_t v) {
    char text[20];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
    return text;
}

// Everything that shapes the path-traced reference, as one string for the cache key.
std::string referenceKey(const BakeJob& job, const BenchReferenceSettings& settings) {
    std::ostringstream key;
    const BakeSettings& b = job.settings;
    key << "bench-reference v1; scene " << hex(hashSceneFiles(job.scenePath)) << "; lightmaps " << b.outputs.lightmaps
        << " " << b.lightmap.width << "x" << b.lightmap.height << " n" << b.lightmap.subsamplesPerAxis << " tri"
        << b.lightmap.samplePerTriangle << " side " << toString(b.lightmapSide) << " rule " << kLightmapSideRule << "; images " << b.outputs.images << " " << b.imageWidth << "x" << b.imageHeight
        << "; noise " << settings.targetNoise << " pilot " << settings.pilotSpp << " max " << settings.maxSpp << " budget "
        << settings.budgetSeconds << " seed " << settings.seed << "; bounces " << PathSettings{}.maxBounces << "; sky "
        << b.sky.x << "," << b.sky.y << "," << b.sky.z;
    if (!b.skyImage.empty()) {
        uint64_t image = kFnvOffset;
        const std::string bytes = readFile(b.skyImage);
        hashBytes(image, bytes.data(), bytes.size());
        key << " image " << hex(image) << " rotation " << b.skyRotation << " intensity " << b.skyIntensity;
    }
    for (const Light& l : job.addedLights)
        key << "; light " << l.name << " " << static_cast<int>(l.type) << " " << l.color.x << "," << l.color.y << ","
            << l.color.z << " " << l.intensity << " " << l.range << " " << l.innerConeAngle << " " << l.outerConeAngle
            << " " << l.position.x << "," << l.position.y << "," << l.position.z << " " << l.direction.x << ","
            << l.direction.y << "," << l.direction.z << " disk " << l.angularDiameter;
    for (const Camera& c : job.addedCameras)
        key << "; camera " << c.position.x << "," << c.position.y << "," << c.position.z << " " << c.forward.x << ","
            << c.forward.y << "," << c.forward.z << " " << c.up.x << "," << c.up.y << "," << c.up.z << " " << c.yfov;
    return key.str();
}

Image difference(const Image& total, const Image& direct, const std::string& what) {
    if (total.width != direct.width || total.height != direct.height)
        throw InputError(what + ": the direct image is " + std::to_string(direct.width) + " x " + std::to_string(direct.height) +
                         " but the total is " + std::to_string(total.width) + " x " + std::to_string(total.height));
    Image out(total.width, total.height, 3);
    for (int y = 0; y < total.height; ++y)
        for (int x = 0; x < total.width; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, y, c) = total.at(x, y, std::min(c, total.channels - 1)) -
                                                         direct.at(x, y, std::min(c, direct.channels - 1));
    return out;
}

// Chooses spp for the target noise from a pilot's noise (∝ 1/√spp) and time (∝ spp), rounded
// up to a multiple of `quantum` (the receiver samples of a texel), within the budget.
int chooseSpp(double pilotNoise, double pilotSeconds, const BenchReferenceSettings& s, int quantum) {
    double spp = s.pilotSpp * std::pow(pilotNoise / s.targetNoise, 2.0);
    if (pilotSeconds > 0.0) spp = std::min(spp, s.pilotSpp * s.budgetSeconds / pilotSeconds);
    spp = std::clamp(spp, static_cast<double>(s.pilotSpp), static_cast<double>(s.maxSpp));
    const int q = std::max(1, quantum);
    return std::max(q, static_cast<int>(std::ceil(spp / q)) * q);
}

struct Traced {
    TraceResult result;
    int spp = 0;
    double noise = 0.0;
};

template <typename Trace>
Traced traceToNoise(const Trace& trace, const Image* mask, const BenchReferenceSettings& s, int quantum,
                    const std::string& what) {
    const auto start = std::chrono::steady_clock::now();
    const TraceResult pilot = trace(s.pilotSpp);
    const double pilotSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Traced t;
    t.spp = chooseSpp(relativeNoise(pilot, mask), pilotSeconds, s, quantum);
    if (!s.quiet)
        std::fprintf(stderr, "bench: %s reference: pilot %d spp noise %.1f%% in %.1f s -> %d spp (estimated %.0f s)\n",
                     what.c_str(), s.pilotSpp, 100.0 * relativeNoise(pilot, mask), pilotSeconds, t.spp,
                     pilotSeconds * t.spp / s.pilotSpp);
    t.result = trace(t.spp);
    t.noise = relativeNoise(t.result, mask);
    return t;
}

void writeJson(const fs::path& path, const nlohmann::json& json) {
    writeAtomically(path.string(), [&](const std::string& temp) {
        std::ofstream out(temp);
        out << json.dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp);
    });
}

// Reads a cached reference; false when the folder is incomplete.
bool readCache(const fs::path& dir, BenchReference& ref) {
    if (!fs::exists(dir / "reference.json")) return false;
    std::ifstream in(dir / "reference.json");
    const nlohmann::json meta = nlohmann::json::parse(in, nullptr, false);
    if (meta.is_discarded()) return false;
    if (meta.value("lightmap", false)) {
        ref.lightmap = readImage((dir / "lightmap.exr").string());
        ref.lightmapIndirect = readImage((dir / "lightmap_indirect.exr").string());
        ref.mask = readImage((dir / "lightmap_mask.exr").string());
        ref.hasLightmap = ref.hasLightmapIndirect = true;
        ref.lightmapNoise = meta.value("lightmap_noise", 0.0);
        ref.lightmapSpp = meta.value("lightmap_spp", 0);
    }
    if (meta.value("image", false)) {
        ref.image = readImage((dir / "image.exr").string());
        ref.imageIndirect = readImage((dir / "image_indirect.exr").string());
        ref.hasImage = ref.hasImageIndirect = true;
        ref.imageNoise = meta.value("image_noise", 0.0);
        ref.imageSpp = meta.value("image_spp", 0);
    }
    return true;
}

BenchReference pathTracedReference(const BakeJob& job, const BenchReferenceSettings& settings,
                                   const BenchTraceScene& traced, bool wantLightmap, bool wantImage) {
    BenchReference ref;
    const std::string key = referenceKey(job, settings) + "; want " + std::to_string(wantLightmap) + std::to_string(wantImage);
    uint64_t h = kFnvOffset;
    hashString(h, key);
    const fs::path dir = fs::path(settings.cacheDir) / (traced.scene.name + "-" + hex(h));
    ref.cachePath = dir.string();
    if (readCache(dir, ref)) {
        ref.fromCache = true;
        return ref;
    }
    nlohmann::json meta;
    meta["key"] = key;
    fs::create_directories(dir);
    if (wantLightmap && traced.atlas) {
        const LightmapAtlas& atlas = *traced.atlas;
        const int quantum = job.settings.lightmap.subsamplesPerAxis * job.settings.lightmap.subsamplesPerAxis;
        const Traced t = traceToNoise(
            [&](int spp) { return traceIrradiance(traced.trace, traced.bvh, atlas.receivers, benchPathSettings(spp, settings.seed)); },
            &atlas.mask, settings, quantum, "lightmap");
        ref.lightmap = t.result.beauty;
        ref.lightmapIndirect = t.result.indirect;
        ref.mask = atlas.mask;
        ref.hasLightmap = ref.hasLightmapIndirect = true;
        ref.lightmapNoise = t.noise;
        ref.lightmapSpp = t.spp;
        writeExr(ref.lightmap, (dir / "lightmap.exr").string());
        writeExr(ref.lightmapIndirect, (dir / "lightmap_indirect.exr").string());
        writeExr(ref.mask, (dir / "lightmap_mask.exr").string());
        meta["lightmap"] = true;
        meta["lightmap_spp"] = t.spp;
        meta["lightmap_noise"] = t.noise;
        meta["lightmap_seconds"] = t.result.seconds;
    }
    if (wantImage && traced.camera) {
        const Traced t = traceToNoise(
            [&](int spp) { return renderCamera(traced.trace, traced.bvh, *traced.camera, benchPathSettings(spp, settings.seed)); },
            nullptr, settings, 1, "image");
        ref.image = t.result.beauty;
        ref.imageIndirect = t.result.indirect;
        ref.hasImage = ref.hasImageIndirect = true;
        ref.imageNoise = t.noise;
        ref.imageSpp = t.spp;
        writeExr(ref.image, (dir / "image.exr").string());
        writeExr(ref.imageIndirect, (dir / "image_indirect.exr").string());
        meta["image"] = true;
        meta["image_spp"] = t.spp;
        meta["image_noise"] = t.noise;
        meta["image_seconds"] = t.result.seconds;
    }
    writeJson(dir / "reference.json", meta);  // last: its presence marks the folder complete
    return ref;
}

std::string percent(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f%%", 100.0 * v);
    return text;
}

}  // namespace

uint64_t hashSceneFiles(const std::string& scenePath) {
    uint64_t h = kFnvOffset;
    const std::string text = readFile(scenePath);
    hashString(h, text);
    if (fs::path(scenePath).extension() != ".gltf") return h;
    const nlohmann::json gltf = nlohmann::json::parse(text, nullptr, false);
    if (gltf.is_discarded()) return h;  // the loader reports the syntax error with context
    const fs::path base = fs::path(scenePath).parent_path();
    for (const char* list : {"buffers", "images"}) {
        if (!gltf.contains(list) || !gltf[list].is_array()) continue;
        for (const auto& entry : gltf[list]) {
            if (!entry.is_object() || !entry.contains("uri") || !entry["uri"].is_string()) continue;
            const std::string uri = entry["uri"].get<std::string>();
            if (uri.rfind("data:", 0) == 0) continue;  // embedded: already in the text
            hashString(h, uri);
            std::error_code ec;
            if (fs::is_regular_file(base / uri, ec)) hashString(h, readFile(base / uri));
        }
    }
    return h;
}

BenchReference prepareBenchReference(const BakeJob& job, const BenchReferenceFiles& files,
                                     const BenchReferenceSettings& settings) {
    const bool lightmaps = job.settings.outputs.lightmaps;
    const bool images = job.settings.outputs.images;
    const bool traceLightmap = lightmaps && files.lightmap.empty();
    const bool traceImage = images && files.image.empty();

    BenchTraceScene traced = loadBenchTraceScene(job);
    BenchReference ref;
    if (traceLightmap || traceImage) ref = pathTracedReference(job, settings, traced, traceLightmap, traceImage);
    std::vector<std::string> parts;
    if (traceLightmap && ref.hasLightmap)
        parts.push_back("lightmap: voxlight path tracer, " + std::to_string(ref.lightmapSpp) + " spp (noise " +
                        percent(ref.lightmapNoise) + ")");
    if (traceImage && ref.hasImage)
        parts.push_back("image: voxlight path tracer, " + std::to_string(ref.imageSpp) + " spp (noise " +
                        percent(ref.imageNoise) + ")");

    if (lightmaps && !files.lightmap.empty()) {
        ref.lightmap = readImage(files.lightmap);
        ref.hasLightmap = true;
        ref.lightmapNoise = std::numeric_limits<double>::quiet_NaN();
        ref.hasLightmapIndirect = !files.lightmapDirect.empty();
        if (ref.hasLightmapIndirect)
            ref.lightmapIndirect = difference(ref.lightmap, readImage(files.lightmapDirect), files.lightmapDirect);
        if (!files.lightmapMask.empty()) ref.mask = readImage(files.lightmapMask);
        else if (traced.atlas) ref.mask = traced.atlas->mask;
        else throw InputError(job.scenePath + ": no mesh has TEXCOORD_1 and no --reference-mask was named");
        const BakeSettings& b = job.settings;
        for (const Image* image : {&ref.lightmap, &ref.mask})
            if (image->width != b.lightmap.width || image->height != b.lightmap.height)
                throw InputError(files.lightmap + ": the reference lightmap or mask is " + std::to_string(image->width) +
                                 " x " + std::to_string(image->height) + " but the bake's atlas is " +
                                 std::to_string(b.lightmap.width) + " x " + std::to_string(b.lightmap.height) +
                                 " (set --lightmap-res)");
        parts.push_back("lightmap: " + displayPath(files.lightmap, job.outputDir) +
                        (ref.hasLightmapIndirect ? " (direct: " + displayPath(files.lightmapDirect, job.outputDir) + ")" : ""));
    }
    if (images && !files.image.empty()) {
        ref.image = readImage(files.image);
        ref.hasImage = true;
        ref.imageNoise = std::numeric_limits<double>::quiet_NaN();
        ref.hasImageIndirect = !files.imageDirect.empty();
        if (ref.hasImageIndirect) ref.imageIndirect = difference(ref.image, readImage(files.imageDirect), files.imageDirect);
        if (ref.image.width != job.settings.imageWidth || ref.image.height != job.settings.imageHeight)
            throw InputError(files.image + ": the reference image is " + std::to_string(ref.image.width) + " x " +
                             std::to_string(ref.image.height) + " but the bake renders " +
                             std::to_string(job.settings.imageWidth) + " x " + std::to_string(job.settings.imageHeight));
        parts.push_back("image: " + displayPath(files.image, job.outputDir));
    }
    for (const std::string& p : parts) ref.description += (ref.description.empty() ? "" : "; ") + p;
    if (ref.fromCache) ref.description += " [cached in " + displayPath(ref.cachePath, job.outputDir) + "]";
    return ref;
}

}  // namespace vl
