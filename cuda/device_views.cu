#include "cuda/device_views.cuh"

#include "cuda/view_extents.h"

namespace vl::cuda {

TraceSceneView uploadTraceScene(DeviceBuffers& owner, const TraceSceneView& host) {
    TraceSceneView d = host;
    const size_t corners = 3 * static_cast<size_t>(host.triangleCount);
    d.vertices = upload(owner, host.vertices, corners);
    d.normals = upload(owner, host.normals, corners);
    d.uv0 = upload(owner, host.uv0, corners);
    d.uv1 = upload(owner, host.uv1, corners);
    d.colors = upload(owner, host.colors, corners);
    d.materialIds = upload(owner, host.materialIds, host.triangleCount);
    d.materials = upload(owner, host.materials, host.materialCount);
    d.textures = upload(owner, host.textures, host.textureCount);
    d.texels = upload(owner, host.texels, texelFloatCount(host));
    d.lights = upload(owner, host.lights, host.lightCount);
    d.emitters = upload(owner, host.emitters, host.emitterCount);
    d.emitterCdf = upload(owner, host.emitterCdf, host.emitterCount);
    d.emitterSelectPdf = upload(owner, host.emitterSelectPdf, host.emitterSelectPdf ? host.triangleCount : 0);
    d.emitterQuad = upload(owner, host.emitterQuad, host.emitterCount);
    d.pointLightTree.nodes = upload(owner, host.pointLightTree.nodes, host.pointLightTree.nodeCount);
    d.emitterTree.nodes = upload(owner, host.emitterTree.nodes, host.emitterTree.nodeCount);
    const size_t skyTexels = host.sky.hasImage() ? size_t(host.sky.width) * size_t(host.sky.height) : 0;
    d.sky.texels = upload(owner, host.sky.texels, skyTexels);
    d.sky.rowCdf = upload(owner, host.sky.rowCdf, host.sky.rowCdf ? size_t(host.sky.height) : 0);
    d.sky.columnCdf = upload(owner, host.sky.columnCdf, host.sky.columnCdf ? skyTexels : 0);
    return d;
}

BvhView uploadBvh(DeviceBuffers& owner, const BvhView& host) {
    BvhView d = host;
    const size_t slots = leafSlotCount(host);
    d.nodes = upload(owner, host.nodes, host.nodeCount);
    d.vertices = upload(owner, host.vertices, 3 * slots);
    d.triangleIds = upload(owner, host.triangleIds, slots);
    d.wideNodes = upload(owner, host.wideNodes, host.wideNodes ? host.wideNodeCount : 0);
    if (!d.wideNodes) d.wideNodeCount = 0;
    return d;
}

MipView uploadMips(DeviceBuffers& owner, const MipView& host) {
    MipView d = host;
    for (int k = 0; k < host.levelCount; ++k) {
        const MipLevelView& level = host.levels[k];
        d.levels[k].index = uploadGrid(owner, level.index);
        d.levels[k].texels = upload(owner, level.texels, mipTexelCount(level));
    }
    return d;
}

IrradianceCacheView uploadCache(DeviceBuffers& owner, const IrradianceCacheView& host, const MipView& deviceMips) {
    IrradianceCacheView d = host;
    d.occupancy = deviceMips.levelCount > 0 ? deviceMips.levels[0] : MipLevelView{};
    d.cells = uploadGrid(owner, host.cells);
    d.cellBegin = upload(owner, host.cellBegin, cacheCellSlotCount(host) + 1);
    d.points = upload(owner, host.points, host.pointCount);
    d.irradiance = upload(owner, host.irradiance, host.pointCount);
    d.neighbourBegin = upload(owner, host.neighbourBegin, host.neighbourBegin ? host.pointCount + 1 : 0);
    d.neighbours = upload(owner, host.neighbours, host.neighbourBegin ? host.neighbourBegin[host.pointCount] : 0);
    d.surfacePlanes = upload(owner, host.surfacePlanes,
                             host.surfacePlanes && host.occupancy.index ? size_t(host.occupancy.index->activeVoxelCount()) : 0);
    return d;
}

lighting::LightingView uploadLighting(DeviceBuffers& owner, const lighting::LightingView& host, uint32_t voxelCount) {
    lighting::LightingView d = host;
    const size_t n = voxelCount;
    d.grid = uploadGrid(owner, host.grid);
    d.coords = upload(owner, host.coords, n);
    d.albedo = upload(owner, host.albedo, n);
    d.normal = upload(owner, host.normal, n);
    d.axisWeights = upload(owner, host.axisWeights, 6 * n);
    d.opacity = upload(owner, host.opacity, n);
    d.solid = upload(owner, host.solid, n);
    d.surfaceOffset = host.surfaceOffset ? upload(owner, host.surfaceOffset, n) : nullptr;
    d.lights = upload(owner, host.lights, host.lightCount);
    d.emitters = upload(owner, host.emitters, host.emitterCount);
    d.emitterSamples = upload(owner, host.emitterSamples, emitterSampleCount(host));
    return d;
}

}  // namespace vl::cuda
