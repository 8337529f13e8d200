#include "cuda/device.h"

#include <cuda_runtime.h>

namespace vl::cuda {

bool compiledWithCuda() { return true; }

DeviceStatus probeDevice() {
    int count = 0;
    const cudaError_t error = cudaGetDeviceCount(&count);
    if (error != cudaSuccess) return {false, std::string("no usable CUDA device: ") + cudaGetErrorString(error)};
    if (count == 0) return {false, "no CUDA device found"};
    cudaDeviceProp properties{};
    if (cudaGetDeviceProperties(&properties, 0) != cudaSuccess) return {false, "cannot query CUDA device 0"};
    return {true, std::string(properties.name) + " (compute " + std::to_string(properties.major) + "." +
                      std::to_string(properties.minor) + ")"};
}

}  // namespace vl::cuda
