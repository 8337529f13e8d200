// libFuzzer: .vdb files from other tools, as `voxlight inspect` and `voxlight light` read
// them (voxel/vdb_inspect.h, voxel/vdb_file.h): OpenVDB parsing a corrupt or hostile file.
#include "core/error.h"
#include "tools/fuzz/scratch_file.h"
#include "voxel/vdb_file.h"
#include "voxel/vdb_inspect.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = vl::fuzz::writeScratch(data, size, ".vdb");
    try {
        (void)vl::inspectVoxelFile(path);
    } catch (const vl::Error&) {
    }
    try {
        (void)vl::readVoxelFile(path);
    } catch (const vl::Error&) {
    }
    return 0;
}
