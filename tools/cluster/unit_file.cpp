#include "cluster/unit_file.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <fstream>

namespace vl::cluster {
namespace {

constexpr char kMagic[] = "VOXLIGHT-UNIT";
constexpr uint32_t kVersion = 1;

uint64_t fnv1a(const uint8_t* bytes, size_t size) {
    uint64_t hash = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    return hash;
}

template <typename T>
void put(std::vector<uint8_t>& out, T value) {
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    out.insert(out.end(), p, p + sizeof(T));
}

}  // namespace

void UnitFile::checkArray(size_t k, size_t elementSize, const std::string& path) const {
    if (k >= arrays.size() || arrays[k].size() % elementSize != 0)
        throw InputError(path + ": array " + std::to_string(k) + " is missing or of the wrong size");
}

void writeUnitFile(const UnitFile& file, const std::string& path) {
    std::vector<uint8_t> bytes(kMagic, kMagic + sizeof kMagic - 1);
    put(bytes, kVersion);
    const std::string header = file.header.dump();
    put(bytes, uint64_t(header.size()));
    bytes.insert(bytes.end(), header.begin(), header.end());
    put(bytes, uint32_t(file.arrays.size()));
    for (const auto& array : file.arrays) {
        put(bytes, uint64_t(array.size()));
        bytes.insert(bytes.end(), array.begin(), array.end());
    }
    put(bytes, fnv1a(bytes.data(), bytes.size()));
    writeAtomically(path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        if (!out) throw Error("cannot write " + temp);
    });
}

UnitFile readUnitFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw InputError(path + ": cannot be opened");
    const std::streamsize size = in.tellg();
    std::vector<uint8_t> bytes(size > 0 ? size_t(size) : 0);
    in.seekg(0);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) throw InputError(path + ": cannot be read");
    const size_t magic = sizeof kMagic - 1;
    if (bytes.size() < magic + 4 + 8 + 4 + 8 || std::memcmp(bytes.data(), kMagic, magic) != 0)
        throw InputError(path + ": not a voxlight unit file");
    const size_t bodySize = bytes.size() - 8;  // the checksum covers all before it
    uint64_t stored = 0;
    std::memcpy(&stored, bytes.data() + bodySize, 8);
    if (stored != fnv1a(bytes.data(), bodySize)) throw InputError(path + ": damaged (checksum mismatch)");
    size_t at = magic;
    const auto get = [&](auto& value) {
        if (at + sizeof value > bodySize) throw InputError(path + ": truncated");
        std::memcpy(&value, bytes.data() + at, sizeof value);
        at += sizeof value;
    };
    uint32_t version = 0;
    get(version);
    if (version != kVersion)
        throw InputError(path + ": unit file version " + std::to_string(version) + ", this voxlight reads " +
                         std::to_string(kVersion));
    const auto span = [&](uint64_t n) {
        if (n > bodySize - at) throw InputError(path + ": truncated");
        const size_t begin = at;
        at += size_t(n);
        return begin;
    };
    uint64_t headerSize = 0;
    get(headerSize);
    const size_t headerBegin = span(headerSize);
    UnitFile file;
    try {
        file.header = nlohmann::json::parse(bytes.begin() + long(headerBegin), bytes.begin() + long(headerBegin + headerSize));
    } catch (const std::exception& e) {
        throw InputError(path + ": its header is not JSON (" + e.what() + ")");
    }
    uint32_t count = 0;
    get(count);
    for (uint32_t k = 0; k < count; ++k) {
        uint64_t n = 0;
        get(n);
        const size_t begin = span(n);
        file.arrays.emplace_back(bytes.begin() + long(begin), bytes.begin() + long(begin + n));
    }
    if (at != bodySize) throw InputError(path + ": trailing bytes");
    return file;
}

}  // namespace vl::cluster
