// The lengths of the arrays a kernel view points at, where the view does not store them:
// what the launchers copy to the device. Derived from the view alone (texture extents, leaf
// ranges, active voxels), so tests/cuda checks them against the owning containers on the host.
#pragma once

#include "gather/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "lighting/lighting_kernels.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <algorithm>
#include <cstddef>

namespace vl::cuda {

// Floats of TraceSceneView::texels: the end of the texture that ends last.
inline size_t texelFloatCount(const TraceSceneView& view) {
    size_t floats = 0;
    for (uint32_t t = 0; t < view.textureCount; ++t) {
        const TraceTexture& texture = view.textures[t];
        floats = std::max(floats, static_cast<size_t>(texture.offset) +
                                      4 * static_cast<size_t>(texture.width) * static_cast<size_t>(texture.height));
    }
    return floats;
}

// Leaf slots of BvhView (entries of triangleIds; vertices has 3 per slot): the end of the
// leaf that ends last.
inline size_t leafSlotCount(const BvhView& view) {
    size_t slots = 0;
    for (uint32_t i = 0; i < view.nodeCount; ++i)
        if (view.nodes[i].count > 0)
            slots = std::max(slots, static_cast<size_t>(view.nodes[i].firstOrChild) + view.nodes[i].count);
    return slots;
}

// Texels of one mip level: facesPerVoxel per active voxel of its index grid.
inline size_t mipTexelCount(const MipLevelView& level) {
    if (!level.index) return 0;
    return static_cast<size_t>(level.index->activeVoxelCount()) * static_cast<size_t>(level.facesPerVoxel);
}

// Cell slots of an IrradianceCacheView (cellBegin has one more entry): its grid's active cells.
inline size_t cacheCellSlotCount(const IrradianceCacheView& view) {
    return view.cells ? static_cast<size_t>(view.cells->activeVoxelCount()) : 0;
}

// Entries of LightingView::emitterSamples: the end of the triangle whose samples end last.
inline size_t emitterSampleCount(const lighting::LightingView& view) {
    size_t samples = 0;
    for (uint32_t e = 0; e < view.emitterCount; ++e)
        samples = std::max(samples, static_cast<size_t>(view.emitters[e].firstSample) + view.emitters[e].sampleCount);
    return samples;
}

}  // namespace vl::cuda
