#include "cuda/device.h"

#include <cuda_runtime.h>

namespace vl::cuda {

namespace {

// Asked for its attributes only: fails when this build has no code the GPU can run (an
// architecture older than CMAKE_CUDA_ARCHITECTURES), so `auto` falls back instead of the
// first launch failing.
__global__ void probeKernel() {}

}  // namespace

bool compiledWithCuda() { return true; }

DeviceStatus probeDevice() {
    int count = 0;
    const cudaError_t error = cudaGetDeviceCount(&count);
    if (error != cudaSuccess) return {false, std::string("no usable CUDA device: ") + cudaGetErrorString(error)};
    if (count == 0) return {false, "no CUDA device found"};
    cudaDeviceProp properties{};
    if (cudaGetDeviceProperties(&properties, 0) != cudaSuccess) return {false, "cannot query CUDA device 0"};
    const std::string name = std::string(properties.name) + " (compute " + std::to_string(properties.major) + "." +
                             std::to_string(properties.minor) + ")";
    cudaFuncAttributes attributes{};
    const cudaError_t image = cudaFuncGetAttributes(&attributes, probeKernel);
    if (image != cudaSuccess) {
        cudaGetLastError();  // clear it, so later calls do not report it
        return {false, name + " cannot run this build's kernels: " + cudaGetErrorString(image)};
    }
    return {true, name};
}

}  // namespace vl::cuda
