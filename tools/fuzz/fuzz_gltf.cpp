// libFuzzer: the glTF loader (scene/gltf_loader.h) on one .gltf file, its buffers and images
// inside it (data: URIs) or refused. A file it cannot read must end in vl::Error naming it;
// any other exception, crash, leak or hang is a finding.
#include "core/error.h"
#include "scene/gltf_loader.h"
#include "tools/fuzz/scratch_file.h"

#ifndef FUZZ_EXTENSION
#define FUZZ_EXTENSION ".gltf"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = vl::fuzz::writeScratch(data, size, FUZZ_EXTENSION);
    vl::LoadOptions options;
    options.echoWarnings = false;
    try {
        (void)vl::loadGltf(path, options);
    } catch (const vl::Error&) {
    }
    return 0;
}
