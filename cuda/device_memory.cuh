// Device arrays for the launchers: RAII over cudaMalloc, every CUDA call checked and turned
// into vl::Error "CUDA: <what>: <reason>". Included by .cu files only.
#pragma once

#include "core/error.h"
#include "cuda/device.h"

#include <cuda_runtime.h>

#include <cstddef>
#include <string>
#include <vector>

namespace vl::cuda {

inline void check(cudaError_t status, const char* what) {
    if (status != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(status));
}

// Throws unless a usable device is present: asked before any other CUDA call, so a machine
// without a driver gets a message, never a crash.
inline void requireDevice() {
    const DeviceStatus status = probeDevice();
    if (!status.usable) throw Error("CUDA: " + status.description);
}

// A device copy of `count` elements of T (nothing allocated for zero).
template <typename T>
class DeviceArray {
public:
    DeviceArray() = default;
    explicit DeviceArray(size_t count) { allocate(count); }
    DeviceArray(const T* host, size_t count) {
        allocate(count);
        if (count > 0) check(cudaMemcpy(data_, host, bytes(), cudaMemcpyHostToDevice), "copy to the device");
    }
    explicit DeviceArray(const std::vector<T>& host) : DeviceArray(host.data(), host.size()) {}
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    DeviceArray(DeviceArray&& other) noexcept : data_(other.data_), count_(other.count_) {
        other.data_ = nullptr;
        other.count_ = 0;
    }
    DeviceArray& operator=(DeviceArray&& other) noexcept {
        if (this != &other) {
            release();
            data_ = other.data_;
            count_ = other.count_;
            other.data_ = nullptr;
            other.count_ = 0;
        }
        return *this;
    }
    ~DeviceArray() { release(); }

    T* get() const { return data_; }
    size_t size() const { return count_; }
    size_t bytes() const { return count_ * sizeof(T); }

    void copyTo(T* host) const {
        if (count_ > 0) check(cudaMemcpy(host, data_, bytes(), cudaMemcpyDeviceToHost), "copy from the device");
    }
    std::vector<T> toHost() const {
        std::vector<T> host(count_);
        copyTo(host.data());
        return host;
    }
    void zero() {
        if (count_ > 0) check(cudaMemset(data_, 0, bytes()), "clear device memory");
    }

private:
    void allocate(size_t count) {
        count_ = count;
        if (count > 0) check(cudaMalloc(reinterpret_cast<void**>(&data_), bytes()), "allocate device memory");
    }
    void release() {
        if (data_) cudaFree(data_);
        data_ = nullptr;
        count_ = 0;
    }

    T* data_ = nullptr;
    size_t count_ = 0;
};

// A device copy of host array `host` (count elements), or null for a null or empty one.
template <typename T>
const T* upload(std::vector<DeviceArray<unsigned char>>& owner, const T* host, size_t count) {
    if (!host || count == 0) return nullptr;
    owner.emplace_back(reinterpret_cast<const unsigned char*>(host), count * sizeof(T));
    return reinterpret_cast<const T*>(owner.back().get());
}

// Waits for the launched kernels and reports a launch or execution error.
inline void finishKernels(const char* what) {
    check(cudaGetLastError(), what);
    check(cudaDeviceSynchronize(), what);
}

// 2D launch shape over a width × height image (ERRATA eq. 7–8).
inline dim3 imageBlocks(int width, int height, dim3 threads) {
    return dim3((static_cast<unsigned>(width) + threads.x - 1) / threads.x,
                (static_cast<unsigned>(height) + threads.y - 1) / threads.y);
}

}  // namespace vl::cuda
