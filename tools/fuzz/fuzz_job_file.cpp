// libFuzzer: job files (bake/job_file.h), as people edit them by hand: settings, scenes,
// lights, cameras, atlas groups. Parsed, not baked.
#include "bake/job_file.h"
#include "core/error.h"
#include "tools/fuzz/scratch_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = vl::fuzz::writeScratch(data, size, ".json");
    vl::BakeSettings defaults;
    defaults.quiet = true;
    try {
        (void)vl::readJobFile(path, defaults, "output");
    } catch (const vl::Error&) {
    }
    return 0;
}
