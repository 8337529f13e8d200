#include "cone/bounces.h"

#include "core/error.h"
#include "core/progress.h"

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
    if (!voxels.faceRadiance.empty()) check(voxels.faceRadiance.size(), "faceRadiance");
    check(voxels.albedo.size(), "albedo");
    check(voxels.normal.size(), "normal");
    check(voxels.axisWeights.size(), "axisWeights");
}

// The lit faces: faceRadiance, or `radiance` on every face with a surface.
std::vector<FaceRadiance> litFaces(const VoxelScene& voxels) {
    if (!voxels.faceRadiance.empty()) return voxels.faceRadiance;
    std::vector<FaceRadiance> faces(voxels.size());
    for (size_t i = 0; i < voxels.size(); ++i)
        for (size_t f = 0; f < 6; ++f) faces[i][f] = voxels.axisWeights[i][f] > 0.0f ? voxels.radiance[i] : vec3(0.0f);
    return faces;
}

std::vector<vec3> isotropic(const VoxelScene& voxels, const std::vector<FaceRadiance>& faces) {
    std::vector<vec3> radiance(faces.size());
    for (size_t i = 0; i < faces.size(); ++i)
        radiance[i] = faceWeightedMean(faces[i].data(), voxels.axisWeights[i].data());
    return radiance;
}

}  // namespace

void propagateBounces(VoxelScene& voxels, const ConeSettings& settings, int bounces, Progress* progress) {
    validateConeSettings(settings);
    if (bounces < 0 || bounces > kMaxBounces)
        throw SettingsError("bounces = " + std::to_string(bounces) + " is outside [0, " +
                            std::to_string(kMaxBounces) + "]");
    checkChannels(voxels);
    if (bounces == 0 || voxels.size() == 0) return;

    const ConeSet& set = coneSet(settings.coneCount);
    const std::vector<FaceRadiance> lit = litFaces(voxels);
    std::vector<FaceRadiance> current = lit;
    std::vector<FaceRadiance> next(voxels.size());
    for (int b = 0; b < bounces; ++b) {
        const RadianceMips mips = buildRadianceMips(voxels, isotropic(voxels, current), current);
        const MipView view = mips.view();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, voxels.size()), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                vec3 e[6];
                faceIrradiance(view, voxels.centre(i), voxels.normal[i], voxels.axisWeights[i].data(), set, settings, e,
                               coneTurn(i));
                const vec3 reflectance = voxels.albedo[i] * kInvPi;
                for (size_t f = 0; f < 6; ++f) next[i][f] = lit[i][f] + reflectance * e[f];
            }
            if (progress) progress->advance(range.size());
        });
        current.swap(next);
    }
    voxels.radiance = isotropic(voxels, current);
    voxels.faceRadiance = std::move(current);
}

}  // namespace vl
