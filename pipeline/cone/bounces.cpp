#include "cone/bounces.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <string>

namespace vl {

namespace {

constexpr int kMaxBounces = 1024;

void checkChannels(const VoxelScene& voxels) {
    const size_t n = voxels.size();
    const auto check = [&](size_t size, const char* name) {
        if (size != n)
            throw Error("propagateBounces(" + voxels.sourceScene + "): " + name + " has " + std::to_string(size) +
                        " values for " + std::to_string(n) + " voxels");
    };
    check(voxels.radiance.size(), "radiance");
    check(voxels.albedo.size(), "albedo");
    check(voxels.normal.size(), "normal");
    check(voxels.axisWeights.size(), "axisWeights");
}

}  // namespace

void propagateBounces(VoxelScene& voxels, const ConeSettings& settings, int bounces) {
    validateConeSettings(settings);
    if (bounces < 0 || bounces > kMaxBounces)
        throw SettingsError("bounces = " + std::to_string(bounces) + " is outside [0, " +
                            std::to_string(kMaxBounces) + "]");
    checkChannels(voxels);
    if (bounces == 0 || voxels.size() == 0) return;

    const ConeSet& set = coneSet(settings.coneCount);
    const std::vector<vec3> lit = voxels.radiance;
    std::vector<vec3> next(voxels.size());
    for (int b = 0; b < bounces; ++b) {
        const RadianceMips mips = buildRadianceMips(voxels, voxels.radiance);
        const MipView view = mips.view();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, voxels.size()), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const vec3 e = voxelIrradiance(view, voxels.centre(i), voxels.normal[i],
                                               voxels.axisWeights[i].data(), set, settings);
                next[i] = lit[i] + voxels.albedo[i] * kInvPi * e;
            }
        });
        voxels.radiance.swap(next);
    }
}

}  // namespace vl
