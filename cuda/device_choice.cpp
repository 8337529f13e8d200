#include "cuda/device_choice.h"

#include "core/error.h"
#include "cuda/device.h"

#include <ostream>

namespace vl::cuda {

DeviceChoice parseDeviceChoice(const std::string& name) {
    if (name == "cpu") return DeviceChoice::Cpu;
    if (name == "cuda") return DeviceChoice::Cuda;
    if (name == "auto") return DeviceChoice::Auto;
    throw SettingsError("device '" + name + "': expected cpu, cuda or auto");
}

const char* toString(DeviceChoice choice) {
    switch (choice) {
    case DeviceChoice::Cpu: return "cpu";
    case DeviceChoice::Cuda: return "cuda";
    case DeviceChoice::Auto: return "auto";
    }
    return "auto";
}

bool resolveDevice(DeviceChoice choice, std::ostream& messages) {
    if (choice == DeviceChoice::Cpu) return false;
    const DeviceStatus status = probeDevice();
    if (status.usable) return true;
    if (choice == DeviceChoice::Cuda) throw Error("--device cuda: " + status.description);
    messages << "running on the CPU: " << status.description << '\n';
    return false;
}

}  // namespace vl::cuda
