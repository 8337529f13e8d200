// OpenVDB-free hand-off of the topology to the read side: a NanoVDB grid whose value at an
// active voxel is that voxel's index into VoxelScene's channel arrays (−1 in the
// background). Kernels look channels up through it and step through it with HDDA.
#pragma once

#include "voxel/voxel_scene.h"

#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

namespace vl {

using VoxelIndexGrid = nanovdb::NanoGrid<int32_t>;

nanovdb::GridHandle<nanovdb::HostBuffer> buildIndexGrid(const VoxelScene& voxels);

}  // namespace vl
