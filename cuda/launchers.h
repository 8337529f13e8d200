// The GPU launchers of the kernels the CPU stages run: the same VL_HOSTDEV functions over
// the same POD views, every array a view points at copied to the device (NanoVDB grids as one
// buffer each, BVH and TraceScene arrays, material and texture tables) and the results copied
// back into the host structures the CPU functions return. Free of CUDA types: the CPU build
// includes it too, and there every launcher throws. Without a usable device (probeDevice())
// a launcher throws vl::Error "CUDA: <reason>", never crashes; device_choice.h picks one.
//
// Agreement with the CPU (floating-point order, FMA contraction and the CUDA maths library
// differ, so results are close, not equal; tests/cuda checks these on a GPU machine):
//   lighting, receivers (deterministic): per element |gpu − cpu| ≤ 1e-3·max(|cpu|, mean)
//     for ≥ 99.5 % of the elements (the rest: a shadow ray or a stepped voxel that flips
//     at an edge), and image means within 0.1 %;
//   path tracing (Monte Carlo; a flipped branch reseeds nothing but changes that path):
//     image means per channel within 1 % + 4 standard errors.
#pragma once

#include "gather/gather_device.h"
#include "gather/shade_receivers.h"
#include "lighting/lighting.h"
#include "trace/path_tracer.h"

#include <cstdint>
#include <vector>

namespace vl {

namespace lighting {
struct LightingView;
struct VoxelLighting;
struct KernelStats;
}  // namespace lighting

namespace cuda {

// lighting::shadeVoxel for voxels [0, voxelCount) of a view over host memory; results[i]
// gets voxel i's lighting, stats the summed counters.
void shadeVoxelsCuda(const lighting::LightingView& view, uint32_t voxelCount, bool hierarchical,
                     lighting::VoxelLighting* results, lighting::KernelStats& stats);

// lightVoxels with the per-voxel loop on the GPU (same preparation, validation and stats).
LightingStats lightVoxelsCuda(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings);

// shadeReceivers on the GPU.
ReceiverLighting shadeReceiversCuda(const SurfaceSampleSet& receivers, const TraceSceneView& scene,
                                    const BvhView& bvh, const MipView* mips, const IrradianceCacheView* cache,
                                    const ConeSettings& cone, const DirectLightSettings& direct, bool mayBeBuried);

// IrradianceCache::gather on the GPU: the cone-traced irradiance at every gather point.
std::vector<vec3> gatherIrradianceCuda(const std::vector<GatherPoint>& points, const MipView& mips,
                                       const ConeSettings& cone, int turns);

// The gather's kernels on the GPU (gather/gather_device.h): gatherIrradianceCuda and
// shadeReceiversCuda. Its calls throw as theirs do without a usable device.
const GatherDevice& gatherDevice();

// renderCamera and traceIrradiance on the GPU; thread (x, y) = (blockIdx·blockDim +
// threadIdx) per axis is pixel or texel (x, y) (ERRATA eq. 7–8).
TraceResult renderCameraCuda(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                             const PathTracerSettings& settings);
TraceResult traceIrradianceCuda(const TraceScene& scene, const Bvh& bvh, const SurfaceSampleSet& receivers,
                                const PathTracerSettings& settings);

}  // namespace cuda
}  // namespace vl
