#include "voxel/index_grid.h"

#include "core/error.h"

#include <nanovdb/util/GridBuilder.h>

#include <limits>

namespace vl {

nanovdb::GridHandle<nanovdb::HostBuffer> buildIndexGrid(const VoxelScene& voxels) {
    if (voxels.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
        throw Error("buildIndexGrid: more active voxels than a 32-bit index holds");
    nanovdb::GridBuilder<int32_t> builder(-1);
    builder.setStats(nanovdb::StatsMode::BBox);  // the index needs no value statistics
    auto accessor = builder.getAccessor();
    for (size_t i = 0; i < voxels.size(); ++i) {
        const ivec3& c = voxels.coords[i];
        accessor.setValue(nanovdb::Coord(c.x, c.y, c.z), static_cast<int32_t>(i));
    }
    return builder.getHandle<>(voxels.voxelSize, nanovdb::Vec3d(0.0), "index");
}

}  // namespace vl
