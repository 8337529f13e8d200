// The reference a bench measures every method against: a lightmap atlas (E/π per covered
// texel) and a camera image (radiance), each with its indirect part when known. Either the
// user names EXR files (for example Cycles' 4096-spp renders) or the path tracer makes a
// converged one, with the spp chosen for a target noise level from a pilot run, cached on
// disk under a hash of the scene's files and the settings that shape the reference.
#pragma once

#include "bake/bake_job.h"
#include "core/image.h"

#include <cstdint>
#include <string>

namespace vl {

// User-named reference files; an empty name means "not given".
struct BenchReferenceFiles {
    std::string lightmap;        // total, E/π
    std::string lightmapDirect;  // direct only: indirect = lightmap − lightmapDirect
    std::string lightmapMask;    // 1 channel, covered where > 0.5 (default: our own rasteriser's mask)
    std::string image;           // total radiance of the first camera
    std::string imageDirect;     // direct only (emission seen directly counted as direct)

    bool any() const { return !lightmap.empty() || !image.empty(); }
};

struct BenchReferenceSettings {
    double targetNoise = 0.02;      // relative standard error (RMS / mean) the path-traced reference aims at
    int pilotSpp = 16;
    int maxSpp = 4096;
    double budgetSeconds = 300.0;   // for each of lightmap and image, estimated from the pilot
    std::string cacheDir = "output/bench-cache";
    uint64_t seed = 0x5EEDBE4C4ull; // differs from the sweep's seed so errors are honest
    bool quiet = false;
};

struct BenchReference {
    bool hasLightmap = false;
    bool hasLightmapIndirect = false;
    bool hasImage = false;
    bool hasImageIndirect = false;
    Image lightmap, lightmapIndirect, mask;  // mask: 1 channel
    Image image, imageIndirect;
    // Estimated relative noise (RMS standard error / mean) of the reference itself; NaN when
    // unknown (a user file). A method's measured relRMSE is about √(true² + noise²).
    double lightmapNoise = 0.0;
    double imageNoise = 0.0;
    int lightmapSpp = 0;
    int imageSpp = 0;
    std::string description;  // one line for reports: where it came from (files named by displayPath)
    std::string cachePath;    // the cache folder of a path-traced reference
    bool fromCache = false;
};

// A 64-bit FNV-1a hash of the scene file and every file it references (glTF buffers and
// images), so a cached reference follows the scene's content, not its name.
uint64_t hashSceneFiles(const std::string& scenePath);

// The reference for `job` (its scene, added lights, lightmap and image settings): the named
// files where given, the rest path-traced (or read from the cache). `mask` is our rasteriser's
// coverage of the atlas, used when no mask file is named.
BenchReference prepareBenchReference(const BakeJob& job, const BenchReferenceFiles& files,
                                     const BenchReferenceSettings& settings);

}  // namespace vl
