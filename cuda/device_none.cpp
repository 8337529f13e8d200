// The build without a CUDA compiler: every request for the GPU gets the reason.
#include "cuda/device.h"

namespace vl::cuda {

bool compiledWithCuda() { return false; }

DeviceStatus probeDevice() { return {false, "voxlight was built without CUDA (no nvcc found at configure time)"}; }

}  // namespace vl::cuda
