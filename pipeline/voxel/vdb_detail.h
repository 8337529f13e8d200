// Opening .vdb files with errors a user can act on. Includes OpenVDB: only for voxel/*.cpp.
#pragma once

#include <openvdb/openvdb.h>

#include <string>

namespace vl::vdb_detail {

// Every grid of the file, and its file-level metadata (never null).
struct LoadedFile {
    openvdb::GridPtrVecPtr grids;
    openvdb::MetaMap::Ptr metadata;
};

// InputError naming the file when it is missing, not a VDB file, or unreadable.
LoadedFile readAllGrids(const std::string& path);

// One grid by name; InputError naming the file and the grid (listing the grids the file
// has) when it is absent.
openvdb::GridBase::Ptr readGrid(const std::string& path, const std::string& gridName);

}  // namespace vl::vdb_detail
