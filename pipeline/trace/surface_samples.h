// Points on surfaces at which irradiance is wanted, grouped by output element (a lightmap
// texel, a camera pixel's visible surface): element i owns samples [begin[i], begin[i+1]).
// bake/receivers builds these; the path tracer and the cone tracer both consume them. An
// element's value is Σ weight·f(sample) over its samples: several sub-texel positions, or
// one per triangle a texel overlaps (a chart edge, a shared atlas), each weighted by the
// share of the element it stands for. Weights sum to 1 for a covered texel and to the hit
// fraction for a pixel that partly sees the (black) background. An element with no sample
// is not covered (lightmap padding, a pixel that sees nothing).
#pragma once

#include "core/math.h"

#include <cstdint>
#include <vector>

namespace vl {

struct SurfaceSample {
    vec3 position;           // world space, on the triangle
    vec3 normal;             // unit shading normal: the side whose irradiance is wanted
    vec3 albedo;             // base colour there (what a bake multiplies by for outgoing radiance)
    uint32_t triangle = ~0u; // global triangle id (gatherTriangles order)
    float weight = 1.0f;     // share of its element
};

struct SurfaceSampleSet {
    int width = 0;   // elements form a width × height image, row-major from the top row
    int height = 0;
    std::vector<uint32_t> begin;  // width·height + 1 offsets into samples
    std::vector<SurfaceSample> samples;

    size_t elementCount() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
    uint32_t sampleCount(size_t element) const { return begin[element + 1] - begin[element]; }
    bool covered(size_t element) const { return begin[element + 1] > begin[element]; }
};

}  // namespace vl
