// Device copies of the kernels' POD views: each array a view points at is copied to the
// device (NanoVDB grids whole, as one buffer of gridSize() bytes) and a view of the same
// type is returned with device pointers. `owner` keeps the copies alive.
#pragma once

#include "gather/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "cuda/device_memory.cuh"
#include "lighting/lighting_kernels.h"
#include "trace/bvh.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

#include <vector>

namespace vl::cuda {

using DeviceBuffers = std::vector<DeviceArray<unsigned char>>;

template <typename BuildT>
const nanovdb::NanoGrid<BuildT>* uploadGrid(DeviceBuffers& owner, const nanovdb::NanoGrid<BuildT>* grid) {
    if (!grid) return nullptr;
    const unsigned char* copy =
        upload(owner, reinterpret_cast<const unsigned char*>(grid), static_cast<size_t>(grid->gridSize()));
    return reinterpret_cast<const nanovdb::NanoGrid<BuildT>*>(copy);
}

TraceSceneView uploadTraceScene(DeviceBuffers& owner, const TraceSceneView& host);
BvhView uploadBvh(DeviceBuffers& owner, const BvhView& host);
MipView uploadMips(DeviceBuffers& owner, const MipView& host);
// The cache's arrays; its occupancy is level 0 of `deviceMips` (already on the device).
IrradianceCacheView uploadCache(DeviceBuffers& owner, const IrradianceCacheView& host, const MipView& deviceMips);
lighting::LightingView uploadLighting(DeviceBuffers& owner, const lighting::LightingView& host, uint32_t voxelCount);

}  // namespace vl::cuda
