// Opening .vdb files with errors a user can act on. Includes OpenVDB: only for voxel/*.cpp.
#pragma once

#include <openvdb/openvdb.h>

#include <functional>
#include <string>
#include <vector>

namespace vl::vdb_detail {

// Every grid of the file, and its file-level metadata (never null).
struct LoadedFile {
    openvdb::GridPtrVecPtr grids;
    openvdb::MetaMap::Ptr metadata;
};

// The grids of the file whose names are in `names` (absent ones are skipped: the caller
// decides which are required), and the file-level metadata. InputError naming the file
// when it is missing, not a VDB file, or unreadable, and when it claims more than it holds
// (a count read past its end, a block longer than the file). The whole file is read.
LoadedFile readGridsNamed(const std::string& path, const std::vector<std::string>& names);

// Calls visit(grid) for every grid of the file; returns the file-level metadata. Errors as
// readGridsNamed.
openvdb::MetaMap::Ptr forEachGrid(const std::string& path,
                                  const std::function<void(const openvdb::GridBase&)>& visit);

// One grid by name; InputError naming the file and the grid (listing the grids the file
// has) when it is absent.
openvdb::GridBase::Ptr readGrid(const std::string& path, const std::string& gridName);

}  // namespace vl::vdb_detail
