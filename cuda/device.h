// Which device runs the kernels. Free of CUDA headers: the CPU build includes it too.
#pragma once

#include <string>

namespace vl::cuda {

struct DeviceStatus {
    bool usable = false;
    std::string description;  // the GPU's name, or why none can be used
};

// Never crashes without a driver or GPU: asks cudaGetDeviceCount first (NanoVDB's
// CudaDeviceBuffer segfaults when no driver is present).
DeviceStatus probeDevice();

bool compiledWithCuda();

}  // namespace vl::cuda
