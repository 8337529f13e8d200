// Which device runs a command's kernels: `--device cpu|cuda|auto`. Free of CUDA headers.
//   cpu:  the TBB path.
//   cuda: the GPU; an Error naming the reason when there is none (no GPU, no driver, or a
//         build without nvcc). Never a crash.
//   auto: the GPU when probeDevice() finds a usable one, else the CPU with the message
//         "running on the CPU: <reason>".
#pragma once

#include <iosfwd>
#include <string>

namespace vl::cuda {

enum class DeviceChoice { Cpu, Cuda, Auto };

// "cpu", "cuda", "auto"; SettingsError naming the option otherwise.
DeviceChoice parseDeviceChoice(const std::string& name);
const char* toString(DeviceChoice choice);

// True when the kernels are to run on the GPU. Cuda without a usable device: Error
// "--device cuda: <reason>". Auto without one: writes "running on the CPU: <reason>" and a
// newline to `messages`, returns false.
bool resolveDevice(DeviceChoice choice, std::ostream& messages);

}  // namespace vl::cuda
