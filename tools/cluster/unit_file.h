// The files a cluster bake's units hand to each other (cluster/units.h): a JSON header and
// raw little-endian arrays, checked by a checksum, so a unit never reads another's half-written
// or damaged result as data. Written through core/atomic_file.h.
//
//   "VOXLIGHT-UNIT" u32 version | u64 n, n bytes of JSON | u32 arrays | per array: u64 n, n bytes | u64 FNV-1a of all before
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vl::cluster {

struct UnitFile {
    nlohmann::json header;
    std::vector<std::vector<uint8_t>> arrays;

    // Appends a vector of trivially copyable values as one array.
    template <typename T>
    void add(const std::vector<T>& values) {
        std::vector<uint8_t> bytes(values.size() * sizeof(T));
        if (!bytes.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
        arrays.push_back(std::move(bytes));
    }
    // Array k as values of T; InputError naming `path` when its size is not a whole number of them.
    template <typename T>
    std::vector<T> take(size_t k, const std::string& path) const {
        checkArray(k, sizeof(T), path);
        std::vector<T> values(arrays[k].size() / sizeof(T));
        if (!values.empty()) std::memcpy(values.data(), arrays[k].data(), arrays[k].size());
        return values;
    }

private:
    void checkArray(size_t k, size_t elementSize, const std::string& path) const;
};

void writeUnitFile(const UnitFile& file, const std::string& path);
// InputError naming the file for a missing, truncated, damaged or foreign file.
UnitFile readUnitFile(const std::string& path);

}  // namespace vl::cluster
