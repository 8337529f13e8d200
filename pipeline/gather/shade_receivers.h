// Lights bake receivers: per element (lightmap texel or pixel), the exact direct term through
// the BVH and the indirect term from cones through the radiance mips, both as E/π, plain and
// multiplied by the samples' albedo (outgoing radiance for images). TBB over elements; each
// sample seeds its own generator, so the result does not depend on the thread count.
#pragma once

#include "lighting/direct_light.h"
#include "cone/cone_settings.h"
#include "gather/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "core/image.h"
#include "trace/bvh.h"
#include "trace/surface_samples.h"

#include <cstdint>

namespace vl {

class Progress;

struct ReceiverLighting {
    Image direct;            // RGB E_direct/π per element
    Image indirect;          // RGB E_indirect/π
    Image directRadiance;    // RGB Σ w·albedo·E_direct/π (reflected light, for images)
    Image indirectRadiance;  // RGB Σ w·albedo·E_indirect/π
    // Lightmap texels only (1 channel): the weight of the element's samples that are not buried
    // (shade_element.h isBuried). Empty: every sample is open.
    Image open;
    // Lightmap texels only, when some light's bake mode is LightBake::Shadowmask: RGBA, each
    // such light's visibility in its channel (gather/shadowmask.h). Else empty.
    Image shadowmask;
};

// `mips` may be null (no indirect light: direct only). `cache`, when given, holds the
// irradiance that receivers interpolate (shade_element.h indirectIrradiance); without it
// every sample gathers its own cones. `mayBeBuried`: the receivers are lightmap texels,
// which can lie inside closed geometry (shade_element.h isBuried). Only elements [firstElement,
// lastElement) are shaded (the rest stay 0); an element's value does not depend on the range,
// since each sample seeds its generator with its index in the whole set.
ReceiverLighting shadeReceivers(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                                const MipView* mips, const IrradianceCacheView* cache, const ConeSettings& cone,
                                const DirectLightSettings& direct, bool mayBeBuried, Progress* progress = nullptr,
                                size_t firstElement = 0, size_t lastElement = SIZE_MAX);

}  // namespace vl
