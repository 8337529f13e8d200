// ReceiverGather::openPoints: an irradiance volume's probes lit as the lightmap's records are.
#include "gather/gather.h"

#include "core/error.h"
#include "core/rng.h"
#include "gather/fan_rays.h"

#include <tbb/parallel_for.h>

namespace vl {

std::vector<vec3> ReceiverGather::openPoints(const std::vector<vec3>& points, const std::vector<vec3>& normals,
                                             int raysPerAxis, uint64_t firstIndex) const {
    const BrightPatchSplit& bright = light_.bright;
    if (points.empty() || normals.empty()) return {};
    if (bright.restFaces.empty())
        throw SettingsError("an irradiance volume reads the final gather's light, and this bake has none "
                            "(gather-level is negative or nothing is gathered)");
    const TraceSceneView scene = tracing_.traceScene.view();
    const BvhView bvh = tracing_.bvh.view();
    const size_t perPoint = normals.size(), count = points.size() * perPoint;
    // As a lightmap's records: the sky through the fans' rays, unless an image sky's sun
    // would need its own draws; every light but the punctual ones per fan.
    const bool skyInFans = !scene.sky.hasImage();
    DirectLightSettings direct = direct_;
    direct.punctualLights = false;
    direct.skyAtSamples = !skyInFans;
    std::vector<FanStart> fans(count);
    tbb::parallel_for(size_t(0), count, [&](size_t k) {
        const vec3& n = normals[k % perPoint];
        vec3 tangent, bitangent;
        orthonormalBasis(n, tangent, bitangent);
        const uint64_t point = firstIndex + k / perPoint;
        const double turn = double(point) * 0.7548776662466927 + double(k % perPoint) * 0.5698402909980532;
        fans[k].origin = points[k / perPoint];
        fans[k].frame = fanFrame(n, tangent, float(turn - std::floor(turn)));
        fans[k].seed = (point * perPoint + k % perPoint) * 0x9E3779B97F4A7C15ull + uint64_t(settings_.lightmapSeed);
        Pcg32 rng(fans[k].seed, 0x7e7e1);
        rng.next2D(fans[k].jitter.x, fans[k].jitter.y);
    });
    FanExtras extras;
    extras.readSky = skyInFans;
    if (!bright.lightsAtHits.empty()) extras.lightsAtHits = &bright.lightsAtHits;
    if (bright.patches.empty()) extras.nearField = settings_.nearFieldVoxels * mipView_.voxelSize;
    std::vector<vec3> irradiance =
        gatherFans(fans, mipView_, bright.restFaces, bvh, scene, raysPerAxis, nullptr, &extras, direct.skyStrata);
    tbb::parallel_for(size_t(0), count, [&](size_t k) {
        const vec3& n = normals[k % perPoint];
        irradiance[k] += extras.sky[k] +
                         brightPatchIrradiance(bright, bvh, fans[k].origin, n, settings_.brightPatches.samples, fans[k].seed) +
                         directIrradianceAt(scene, bvh, fans[k].origin, n, n, direct, fans[k].seed);
    });
    return irradiance;
}

}  // namespace vl
