// OpenVDB's readers of a leaf's compressed block, defined again with the checks OpenVDB 10.0
// (Debian 12's) lacks. A block is an Int64 length, then that many blosc or zlib bytes, or raw
// values when the length is negative. OpenVDB 10.0 reads a negative length's bytes into the
// leaf's buffer without comparing it with the buffer's size: a corrupt .vdb overflows the heap
// (fuzz_vdb, tests/voxel/data/raw_block_longer_than_its_leaf.vdb); later OpenVDB compares them.
// Here every length is checked against the node's buffer and the bytes read, and blosc's own
// header against the bytes it is given, before anything is written.
//
// The linker binds OpenVDB's templates compiled into voxlight (readData in io/Compression.h)
// to these definitions, and the dynamic linker binds libopenvdb's own calls to them too (the
// executable's symbols come first). tests/voxel holds the corrupt file under ASan in CI.
#include <openvdb/Exceptions.h>
#include <openvdb/io/Compression.h>

#include <blosc.h>
#include <zlib.h>

#include <cstdint>
#include <istream>
#include <memory>
#include <string>

namespace {

using Decode = bool (*)(const char* packed, std::size_t packedSize, char* data, std::size_t size);

bool bloscDecode(const char* packed, std::size_t packedSize, char* data, std::size_t size) {
    std::size_t unpackedSize = 0;
    if (blosc_cbuffer_validate(packed, packedSize, &unpackedSize) != 0 || unpackedSize != size) return false;
    return blosc_decompress_ctx(packed, data, size, /*numinternalthreads=*/1) == int(size);
}

bool zlibDecode(const char* packed, std::size_t packedSize, char* data, std::size_t size) {
    uLongf unpackedSize = uLongf(size);
    return uncompress(reinterpret_cast<Bytef*>(data), &unpackedSize, reinterpret_cast<const Bytef*>(packed),
                      uLong(packedSize)) == Z_OK &&
           unpackedSize == size;
}

// One block into `data`, which holds exactly `size` bytes (nullptr: skip the block).
void readBlock(std::istream& is, char* data, std::size_t size, const char* codec, Decode decode) {
    std::int64_t length = 0;
    is.read(reinterpret_cast<char*>(&length), sizeof length);
    if (!is) throw openvdb::IoError("the file ends inside a block's length");
    const bool raw = length <= 0;
    const std::uint64_t stored = raw ? std::uint64_t(0) - std::uint64_t(length) : std::uint64_t(length);
    if (data == nullptr) {
        is.seekg(std::streamoff(stored), std::ios_base::cur);
        return;
    }
    if (raw) {
        if (stored != size)
            throw openvdb::IoError("a block of " + std::to_string(stored) + " raw bytes for a node of " +
                                   std::to_string(size));
        is.read(data, std::streamsize(size));
        return;
    }
    std::unique_ptr<char[]> packed(new char[stored]);  // its length is capped by the reader's AllocationLimit
    is.read(packed.get(), std::streamsize(stored));
    if (!is) throw openvdb::IoError("the file ends inside a " + std::string(codec) + " block");
    if (!decode(packed.get(), stored, data, size))
        throw openvdb::IoError("a " + std::string(codec) + " block of " + std::to_string(stored) +
                               " bytes that does not decompress to its node's " + std::to_string(size));
}

}  // namespace

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
namespace io {

void bloscFromStream(std::istream& is, char* data, size_t numBytes) { readBlock(is, data, numBytes, "blosc", bloscDecode); }

void unzipFromStream(std::istream& is, char* data, size_t numBytes) { readBlock(is, data, numBytes, "zlib", zlibDecode); }

}  // namespace io
}  // namespace OPENVDB_VERSION_NAME
}  // namespace openvdb
