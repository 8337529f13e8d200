// The shadowmask of an atlas: for each light whose bake mode is LightBake::Shadowmask, how much
// of it each texel sees, 0..1, in that light's channel (TraceLight::maskChannel) of an RGBA
// image (docs/light-bake-modes.md). An engine draws the light's unshadowed direct light times
// the mask read bilinearly; the lightmap keeps the light's indirect light.
#pragma once

#include "core/image.h"
#include "trace/bvh.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

#include <cstdint>

namespace vl {

// n: a sun's penumbra takes n × n stratified directions over its disk (lighting/direct_light.h
// lightVisibility). 8: 64 directions, a step of 1/64 where an 8-bit channel steps 1/255, so the
// strata, not the bytes, set the mask's error (docs/light-bake-modes.md, "Tests").
constexpr int kShadowmaskStrata = 8;

// Whether any light of the scene has a shadowmask channel.
bool hasShadowmaskLights(const TraceSceneView& scene);

// Per texel [firstElement, lastElement) of `receivers` (the rest 0), one channel per
// shadowmask light: the mean over its samples of lightVisibility, at each sample's point,
// weighted by the sample's weight and its cosine to the light. The engine multiplies the mask
// by the light's own cosine, so a sample turned away from the light has no say: at a crease
// the side the light reaches decides. A texel none of whose samples faces the light holds
// kShadowmaskUnseen, for finishing to fill from its neighbours (past a curved surface's
// terminator, a 0 there would darken the lit texels beside it through the bilinear read). A
// texel's samples sit at the texel's centre on a flat surface (receivers.h), so the mask is the
// visibility there: what bilinear reads between texel centres reconstruct. A channel without a
// light holds 1 (opaque alpha: an importer that premultiplies alpha leaves the other channels
// alone). Each sample seeds its strata with its index in the whole set: the same bytes at any
// thread count and in any band of rows. Empty when no light has a channel.
Image shadowmaskTexels(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                       size_t firstElement = 0, size_t lastElement = SIZE_MAX);

}  // namespace vl
