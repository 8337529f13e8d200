#include "voxel/vdb_file.h"

#include "core/allocation_limit.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "voxel/vdb_detail.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <type_traits>

namespace vl {

namespace vdb_detail {

namespace {

void initializeOpenVdb() {
    // Registers the grid types; idempotent and thread-safe in OpenVDB ≥ 8.
    openvdb::initialize();
}

std::uintmax_t fileSizeOf(const std::string& path) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    return ec ? 0 : size;
}

void requireReadableFile(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (ec || !fs::exists(status)) throw InputError(path + ": no such file");
    if (!fs::is_regular_file(status)) throw InputError(path + ": not a regular file");
}

std::string gridNamesOf(const openvdb::GridPtrVec& grids) {
    std::string names;
    for (const openvdb::GridBase::Ptr& grid : grids) {
        if (!names.empty()) names += ", ";
        names += "'" + grid->getName() + "'";
    }
    return names.empty() ? std::string("none") : names;
}

// The first grid called `name` (null: none).
openvdb::GridBase::Ptr gridNamed(const openvdb::GridPtrVec& grids, const std::string& name) {
    for (const openvdb::GridBase::Ptr& grid : grids)
        if (grid->getName() == name) return grid;
    return nullptr;
}

// The largest single allocation parsing `path` may need: no length the file claims can exceed
// the file, and OpenVDB's largest fixed-size node (a 32³ internal node's table) is far below
// the floor.
std::size_t parseAllocationBound(const std::string& path) {
    return std::max<std::size_t>(std::size_t(fileSizeOf(path)), std::size_t(64) << 20);
}

// Every grid of the file and its metadata, guarded against what a file can claim.
// - OpenVDB's readers loop over counts read from the file and look at the stream only
//   afterwards, so a small file claiming a huge count keeps io::File reading past its end
//   (docs/decisions.md, "Allocation cap"). Here the stream throws at its first failed read
//   (io::Stream takes our stream; io::File opens its own).
// - OpenVDB allocates the lengths it reads (a metadata string, a compressed block) before
//   reading them: its calls run under an AllocationLimit of the file's size, so a length
//   claimed beyond it is refused before it is allocated, naming its size.
// Every other failure (not a VDB file, an unknown grid type, a corrupt block) is OpenVDB's
// exception; all of them mean the same to a user.
LoadedFile readWholeFile(const std::string& path) {
    initializeOpenVdb();
    requireReadableFile(path);
    try {
        const AllocationLimit limit(parseAllocationBound(path));
        std::ifstream in(path, std::ios::binary);
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        LoadedFile loaded{stream.getGrids(), stream.getMetadata()};
        if (!loaded.grids) loaded.grids = std::make_shared<openvdb::GridPtrVec>();
        if (!loaded.metadata) loaded.metadata = std::make_shared<openvdb::MetaMap>();
        return loaded;
    } catch (const std::ios_base::failure&) {
        throw InputError(path + ": not a readable OpenVDB file (it ends, or cannot be read, before its grids do)");
    } catch (const std::bad_alloc& e) {
        const std::size_t claimed = AllocationLimit::refusedBytes();
        if (claimed == 0) throw InputError(path + ": not a readable OpenVDB file (" + e.what() + ")");
        throw InputError(path + ": not a readable OpenVDB file (it claims a block of " + std::to_string(claimed) +
                         " bytes in a file of " + std::to_string(fileSizeOf(path)) + " bytes)");
    } catch (const std::exception& e) {
        throw InputError(path + ": not a readable OpenVDB file (" + e.what() + ")");
    }
}

}  // namespace

LoadedFile readGridsNamed(const std::string& path, const std::vector<std::string>& names) {
    LoadedFile loaded = readWholeFile(path);
    auto named = std::make_shared<openvdb::GridPtrVec>();
    for (const std::string& name : names)
        if (openvdb::GridBase::Ptr grid = gridNamed(*loaded.grids, name)) named->push_back(grid);
    loaded.grids = named;
    return loaded;
}

openvdb::MetaMap::Ptr forEachGrid(const std::string& path,
                                  const std::function<void(const openvdb::GridBase&)>& visit) {
    const LoadedFile loaded = readWholeFile(path);
    for (const openvdb::GridBase::Ptr& grid : *loaded.grids) visit(*grid);
    return loaded.metadata;
}

openvdb::GridBase::Ptr readGrid(const std::string& path, const std::string& gridName) {
    const LoadedFile loaded = readWholeFile(path);
    if (openvdb::GridBase::Ptr grid = gridNamed(*loaded.grids, gridName)) return grid;
    throw InputError(path + ": no grid named '" + gridName + "' (the file has " + gridNamesOf(*loaded.grids) + ")");
}

}  // namespace vdb_detail

namespace {

using openvdb::Coord;

const char* const kMetaVoxelSize = "voxel_size";
const char* const kMetaSettings = "settings";
const char* const kMetaSourceScene = "source_scene";
const char* const kMetaVersion = "voxlight_version";

bool lexLess(const ivec3& a, const ivec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); }

std::string coordText(const ivec3& c) {
    return "(" + std::to_string(c.x) + ", " + std::to_string(c.y) + ", " + std::to_string(c.z) + ")";
}

Coord toCoord(const ivec3& c) { return Coord(c.x, c.y, c.z); }
openvdb::Vec3f toVdb(const vec3& v) { return openvdb::Vec3f(v.x, v.y, v.z); }
vec3 fromVdb(const openvdb::Vec3f& v) { return vec3(v.x(), v.y(), v.z()); }

// ---- writing --------------------------------------------------------------------------

void requireFinite(float value, const std::string& gridName, const ivec3& coord) {
    if (!std::isfinite(value))
        throw Error("writeVoxelFile: non-finite value in grid '" + gridName + "' at voxel " + coordText(coord));
}

void requireFinite(const vec3& value, const std::string& gridName, const ivec3& coord) {
    for (int c = 0; c < 3; ++c) requireFinite(value[c], gridName, coord);
}

template <typename GridT>
typename GridT::Ptr newGrid(const std::string& name, const openvdb::math::Transform::Ptr& transform) {
    auto grid = GridT::create();
    grid->setName(name);
    grid->setTransform(transform);
    grid->setCreator(std::string("voxlight ") + VOXLIGHT_VERSION);
    return grid;
}

// A grid active exactly at `coords`, valueAt(i) being the value of coords[i].
template <typename GridT, typename ValueAt>
typename GridT::Ptr channelGrid(const std::string& name, const openvdb::math::Transform::Ptr& transform,
                                const std::vector<ivec3>& coords, ValueAt valueAt) {
    auto grid = newGrid<GridT>(name, transform);
    auto accessor = grid->getAccessor();
    for (size_t i = 0; i < coords.size(); ++i) accessor.setValueOn(toCoord(coords[i]), valueAt(i));
    return grid;
}

void requireChannelSize(size_t actual, size_t expected, const char* name, bool optional) {
    if (actual == expected || (optional && actual == 0)) return;
    throw Error(std::string("writeVoxelFile: channel '") + name + "' has " + std::to_string(actual) +
                " values for " + std::to_string(expected) + " voxels");
}

void validateScene(const VoxelScene& voxels) {
    if (!(voxels.voxelSize > 0.0) || !std::isfinite(voxels.voxelSize))
        throw Error("writeVoxelFile: voxel size must be positive and finite, got " + std::to_string(voxels.voxelSize));
    const size_t n = voxels.size();
    requireChannelSize(voxels.albedo.size(), n, grid_names::albedo, false);
    requireChannelSize(voxels.normal.size(), n, grid_names::normal, false);
    requireChannelSize(voxels.axisWeights.size(), n, "axisWeights", false);
    requireChannelSize(voxels.opacity.size(), n, grid_names::opacity, false);
    requireChannelSize(voxels.solid.size(), n, grid_names::solid, false);
    requireChannelSize(voxels.emission.size(), n, grid_names::emission, true);
    requireChannelSize(voxels.radiance.size(), n, grid_names::radiance, true);
    requireChannelSize(voxels.occlusion.size(), n, grid_names::occlusion, true);
    for (size_t i = 1; i < n; ++i)
        if (!lexLess(voxels.coords[i - 1], voxels.coords[i]))
            throw Error("writeVoxelFile: voxel coords are not sorted and unique at index " + std::to_string(i) + " " +
                        coordText(voxels.coords[i]));
    for (size_t i = 0; i < n; ++i) {
        const ivec3& c = voxels.coords[i];
        requireFinite(voxels.albedo[i], grid_names::albedo, c);
        requireFinite(voxels.normal[i], grid_names::normal, c);
        requireFinite(voxels.opacity[i], grid_names::opacity, c);
        for (float w : voxels.axisWeights[i]) requireFinite(w, "axis_weights", c);
        if (!voxels.emission.empty()) requireFinite(voxels.emission[i], grid_names::emission, c);
        if (!voxels.radiance.empty()) requireFinite(voxels.radiance[i], grid_names::radiance, c);
        if (!voxels.occlusion.empty()) requireFinite(voxels.occlusion[i], grid_names::occlusion, c);
    }
}

void validateExtra(const ExtraGrid& grid, std::set<std::string>& names) {
    if (grid.name.empty()) throw Error("writeVoxelFile: an extra grid has no name");
    if (!names.insert(grid.name).second)
        throw Error("writeVoxelFile: grid name '" + grid.name + "' is used twice");
    if (!(grid.voxelSize > 0.0) || !std::isfinite(grid.voxelSize))
        throw Error("writeVoxelFile: grid '" + grid.name + "' needs a positive finite voxel size");
    if (!grid.scalars.empty() && !grid.vectors.empty())
        throw Error("writeVoxelFile: grid '" + grid.name + "' has both scalar and vector values");
    const size_t values = grid.isVector() ? grid.vectors.size() : grid.scalars.size();
    if (values != grid.coords.size())
        throw Error("writeVoxelFile: grid '" + grid.name + "' has " + std::to_string(values) + " values for " +
                    std::to_string(grid.coords.size()) + " voxels");
    for (size_t i = 0; i < grid.coords.size(); ++i) {
        if (grid.isVector()) requireFinite(grid.vectors[i], grid.name, grid.coords[i]);
        else requireFinite(grid.scalars[i], grid.name, grid.coords[i]);
    }
}

// ---- reading --------------------------------------------------------------------------

// Calls f(coord) for every active voxel, expanding active tiles (which foreign writers or a
// pruned tree may hold).
template <typename GridT, typename F>
void forEachActiveVoxel(const GridT& grid, F&& f) {
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            f(it.getCoord(), *it);
        } else {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) f(*c, *it);
        }
    }
}

// A file's active voxels are counted before any is read: a tile of 1024³ voxels takes a few
// bytes in the file and would take 100 GB as VoxelScene channels (~100 bytes a voxel, as
// bake.cpp estimates), and minutes to expand.
constexpr openvdb::Index64 kMaxReadVoxels = openvdb::Index64(1) << 28;
constexpr double kBytesPerReadVoxel = 100.0;

template <typename GridT>
std::vector<ivec3> sortedActiveCoords(const GridT& grid, const std::string& path) {
    const openvdb::Index64 active = grid.activeVoxelCount();
    const double bytes = double(active) * kBytesPerReadVoxel;
    if (active > kMaxReadVoxels)
        throw InputError(path + ": grid '" + grid.getName() + "' has " + std::to_string(active) +
                         " active voxels, more than voxlight reads (" + std::to_string(kMaxReadVoxels) + ")");
    if (bytes > availableMemoryBytes())
        throw InputError(path + ": grid '" + grid.getName() + "' has " + std::to_string(active) +
                         " active voxels: about " + std::to_string(int(bytes / double(1 << 30))) +
                         " GiB to read, more than this machine has free");
    std::vector<ivec3> coords;
    coords.reserve(grid.activeVoxelCount());
    forEachActiveVoxel(grid, [&](const Coord& c, const auto&) { coords.emplace_back(c.x(), c.y(), c.z()); });
    std::sort(coords.begin(), coords.end(), lexLess);
    return coords;
}

class GridSet {
public:
    GridSet(std::string path, vdb_detail::LoadedFile loaded) : path_(std::move(path)), loaded_(std::move(loaded)) {
        for (const auto& grid : *loaded_.grids)
            if (grid) byName_.emplace(grid->getName(), grid);
    }

    template <typename GridT>
    typename GridT::ConstPtr get(const char* name, bool required, const char* expectedType) const {
        auto it = byName_.find(name);
        if (it == byName_.end()) {
            if (required) throw InputError(path_ + ": required grid '" + name + "' is missing");
            return nullptr;
        }
        auto typed = openvdb::gridConstPtrCast<GridT>(it->second);
        if (!typed)
            throw InputError(path_ + ": grid '" + name + "' has value type " + it->second->valueType() + ", expected " +
                             expectedType);
        return typed;
    }

    const openvdb::MetaMap& metadata() const { return *loaded_.metadata; }

private:
    std::string path_;
    vdb_detail::LoadedFile loaded_;
    std::map<std::string, openvdb::GridBase::ConstPtr> byName_;
};

// A voxlight transform: a uniform scale by h, a rotation (the scene's frame), then a
// translation (voxel_scene.h). Gives h, the rotation and the translation.
double requireVoxlightTransform(const openvdb::GridBase& grid, const std::string& path, glm::dvec3& translation,
                                glm::dmat3& frame) {
    const auto& transform = grid.constTransform();
    bool rigid = transform.isLinear();
    // The map's matrix, not differences of mapped points: those lose h's last bits far from
    // the world origin. Row vectors: world = index · m.
    const openvdb::Mat4d m = rigid ? transform.baseMap()->getAffineMap()->getMat4() : openvdb::Mat4d::identity();
    glm::dvec3 axes[3];
    for (int a = 0; a < 3; ++a) axes[a] = glm::dvec3(m[a][0], m[a][1], m[a][2]);
    const openvdb::Vec3d origin(m[3][0], m[3][1], m[3][2]);
    const double h = glm::length(axes[0]);
    rigid = rigid && h > 0.0 && std::isfinite(h) && std::isfinite(origin[0]) && std::isfinite(origin[1]) &&
            std::isfinite(origin[2]);
    for (int a = 0; a < 3 && rigid; ++a)
        for (int b = 0; b < 3; ++b)
            rigid = rigid && std::abs(glm::dot(axes[a], axes[b]) / (h * h) - (a == b ? 1.0 : 0.0)) <= 1e-9;
    if (rigid) rigid = glm::dot(glm::cross(axes[0], axes[1]), axes[2]) > 0.0;
    if (!rigid)
        throw InputError(path + ": grid '" + grid.getName() +
                         "' does not have a uniform scale, a rotation and a translation (voxlight's convention)");
    translation = glm::dvec3(origin[0], origin[1], origin[2]);
    frame = glm::dmat3(axes[0] / h, axes[1] / h, axes[2] / h);
    return h;
}

// The transform requireVoxlightTransform reads: a scale-translate map where the frame is the
// world's axes (as every file before frames), else an affine map.
openvdb::math::Transform::Ptr voxlightTransform(double h, const glm::dmat3& frame, const glm::dvec3& translation) {
    if (frame == glm::dmat3(1.0)) {
        auto transform = openvdb::math::Transform::createLinearTransform(h);
        transform->postTranslate(openvdb::Vec3d(translation.x, translation.y, translation.z));
        return transform;
    }
    openvdb::Mat4d m = openvdb::Mat4d::identity();  // row vectors: world = index · m
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m[i][j] = h * frame[i][j];
        m[3][i] = translation[i];
    }
    return openvdb::math::Transform::createLinearTransform(m);
}

std::string stringMeta(const openvdb::MetaMap& meta, const char* key) {
    auto value = meta.getMetadata<openvdb::StringMetadata>(key);
    return value ? value->value() : std::string();
}

// OpenVDB stamps every file with a random UUID (Archive::writeHeader), so two writes of the
// same grids differ in 36 header bytes. Replace it with one derived from the bytes after
// the header: same grids, same file, as DESIGN.md asks of every output. The header is
// magic (8 bytes), file version, library major and minor (4 each), a has-offsets byte, then
// the UUID as 36 ASCII characters; a file laid out otherwise is left alone.
void makeUuidDeterministic(const std::string& path) {
    constexpr std::streamoff kUuidOffset = 8 + 4 + 4 + 4 + 1;
    constexpr size_t kUuidLength = 36;
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    std::string header(kUuidOffset + kUuidLength, '\0');
    if (!file.read(header.data(), std::streamsize(header.size()))) return;
    const std::string magic("\x20\x42\x44\x56\0\0\0\0", 8);  // OPENVDB_MAGIC, little-endian
    if (header.compare(0, 8, magic) != 0) return;
    for (size_t i = 0; i < kUuidLength; ++i) {
        const char c = header[kUuidOffset + i];
        const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
        if (dash ? c != '-' : !std::isxdigit(static_cast<unsigned char>(c))) return;
    }
    // Two FNV-1a 64-bit hashes with different offset bases make the 128 bits.
    uint64_t h0 = 14695981039346656037ull, h1 = 0x6c62272e07bb0142ull;
    constexpr uint64_t kPrime = 1099511628211ull;
    char buffer[1 << 16];
    while (file.read(buffer, sizeof buffer) || file.gcount() > 0) {
        for (std::streamsize i = 0; i < file.gcount(); ++i) {
            const auto byte = static_cast<unsigned char>(buffer[i]);
            h0 = (h0 ^ byte) * kPrime;
            h1 = (h1 ^ byte) * kPrime;
        }
    }
    char hex[33];
    std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h0),
                  static_cast<unsigned long long>(h1));
    const std::string h(hex);
    const std::string uuid = h.substr(0, 8) + "-" + h.substr(8, 4) + "-" + h.substr(12, 4) + "-" + h.substr(16, 4) +
                             "-" + h.substr(20, 12);
    file.clear();
    file.seekp(kUuidOffset);
    if (!file.write(uuid.data(), std::streamsize(uuid.size())) || !file.flush())
        throw Error(path + ": cannot finish writing the voxel grids");
}

}  // namespace

void writeVoxelFile(const VoxelScene& voxels, const std::string& path, const std::vector<ExtraGrid>& extra) {
    vdb_detail::initializeOpenVdb();
    validateScene(voxels);
    std::set<std::string> names = {grid_names::albedo,    grid_names::normal, grid_names::emission,
                                   grid_names::opacity,   grid_names::occlusion, grid_names::solid,
                                   grid_names::radiance,  grid_names::axisWeightsPos, grid_names::axisWeightsNeg};
    for (const ExtraGrid& grid : extra) validateExtra(grid, names);

    const auto transform = voxlightTransform(voxels.voxelSize, voxels.frame, voxels.origin);
    const auto& coords = voxels.coords;
    // Each grid is built on its own task (an accessor fills one grid serially), in file order.
    std::vector<std::function<openvdb::GridBase::Ptr()>> builders;
    builders.push_back([&] {
        return channelGrid<openvdb::Vec3SGrid>(grid_names::albedo, transform, coords,
                                               [&](size_t i) { return toVdb(voxels.albedo[i]); });
    });
    builders.push_back([&] {
        auto normal = channelGrid<openvdb::Vec3SGrid>(grid_names::normal, transform, coords,
                                                      [&](size_t i) { return toVdb(voxels.normal[i]); });
        normal->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);
        return normal;
    });
    if (!voxels.emission.empty())
        builders.push_back([&] {
            return channelGrid<openvdb::Vec3SGrid>(grid_names::emission, transform, coords,
                                                   [&](size_t i) { return toVdb(voxels.emission[i]); });
        });
    builders.push_back([&] {
        auto opacity = channelGrid<openvdb::FloatGrid>(grid_names::opacity, transform, coords,
                                                       [&](size_t i) { return voxels.opacity[i]; });
        opacity->setGridClass(openvdb::GRID_FOG_VOLUME);
        return opacity;
    });
    if (!voxels.occlusion.empty())
        builders.push_back([&] {
            return channelGrid<openvdb::FloatGrid>(grid_names::occlusion, transform, coords,
                                                   [&](size_t i) { return voxels.occlusion[i]; });
        });
    builders.push_back([&] {
        auto solid = newGrid<openvdb::BoolGrid>(grid_names::solid, transform);
        auto accessor = solid->getAccessor();
        for (size_t i = 0; i < coords.size(); ++i)
            if (voxels.solid[i]) accessor.setValueOn(toCoord(coords[i]), true);
        return solid;
    });
    if (!voxels.radiance.empty())
        builders.push_back([&] {
            return channelGrid<openvdb::Vec3SGrid>(grid_names::radiance, transform, coords,
                                                   [&](size_t i) { return toVdb(voxels.radiance[i]); });
        });
    builders.push_back([&] {
        return channelGrid<openvdb::Vec3SGrid>(grid_names::axisWeightsPos, transform, coords, [&](size_t i) {
            const AxisWeights& w = voxels.axisWeights[i];
            return openvdb::Vec3f(w[0], w[2], w[4]);
        });
    });
    builders.push_back([&] {
        return channelGrid<openvdb::Vec3SGrid>(grid_names::axisWeightsNeg, transform, coords, [&](size_t i) {
            const AxisWeights& w = voxels.axisWeights[i];
            return openvdb::Vec3f(w[1], w[3], w[5]);
        });
    });
    for (const ExtraGrid& e : extra)
        builders.push_back([&e]() -> openvdb::GridBase::Ptr {
            const auto extraTransform = voxlightTransform(e.voxelSize, e.frame, e.translation);
            if (e.isVector())
                return channelGrid<openvdb::Vec3SGrid>(e.name, extraTransform, e.coords,
                                                       [&](size_t i) { return toVdb(e.vectors[i]); });
            return channelGrid<openvdb::FloatGrid>(e.name, extraTransform, e.coords,
                                                   [&](size_t i) { return e.scalars[i]; });
        });
    openvdb::GridPtrVec grids(builders.size());
    tbb::parallel_for(size_t(0), builders.size(), [&](size_t k) { grids[k] = builders[k](); });

    openvdb::MetaMap meta;
    meta.insertMeta(kMetaVoxelSize, openvdb::DoubleMetadata(voxels.voxelSize));
    meta.insertMeta(kMetaSettings, openvdb::StringMetadata(voxels.settings));
    meta.insertMeta(kMetaSourceScene, openvdb::StringMetadata(voxels.sourceScene));
    meta.insertMeta(kMetaVersion, openvdb::StringMetadata(VOXLIGHT_VERSION));

    writeAtomically(path, [&](const std::string& tempPath) {
        try {
            openvdb::io::File file(tempPath);
            file.write(grids, meta);
            file.close();
        } catch (const openvdb::Exception& e) {
            throw Error(path + ": cannot write the voxel grids (" + e.what() + ")");
        }
        makeUuidDeterministic(tempPath);
    });
}

VoxelScene readVoxelFile(const std::string& path) {
    namespace g = grid_names;
    const GridSet set(path, vdb_detail::readGridsNamed(path, {g::albedo, g::normal, g::emission, g::opacity,
                                                              g::occlusion, g::solid, g::radiance,
                                                              g::axisWeightsPos, g::axisWeightsNeg}));
    using openvdb::BoolGrid;
    using openvdb::FloatGrid;
    using openvdb::Vec3SGrid;
    const auto albedo = set.get<Vec3SGrid>(grid_names::albedo, true, "vec3s");
    const auto normal = set.get<Vec3SGrid>(grid_names::normal, true, "vec3s");
    const auto emission = set.get<Vec3SGrid>(grid_names::emission, false, "vec3s");
    const auto opacity = set.get<FloatGrid>(grid_names::opacity, true, "float");
    const auto occlusion = set.get<FloatGrid>(grid_names::occlusion, false, "float");
    const auto solid = set.get<BoolGrid>(grid_names::solid, true, "bool");
    const auto radiance = set.get<Vec3SGrid>(grid_names::radiance, false, "vec3s");
    const auto axisPos = set.get<Vec3SGrid>(grid_names::axisWeightsPos, true, "vec3s");
    const auto axisNeg = set.get<Vec3SGrid>(grid_names::axisWeightsNeg, true, "vec3s");

    VoxelScene voxels;
    voxels.voxelSize = requireVoxlightTransform(*opacity, path, voxels.origin, voxels.frame);
    const std::vector<const openvdb::GridBase*> all = {albedo.get(),   normal.get(),    emission.get(),
                                                       opacity.get(),  occlusion.get(), solid.get(),
                                                       radiance.get(), axisPos.get(),   axisNeg.get()};
    for (const openvdb::GridBase* grid : all) {
        if (!grid) continue;
        glm::dvec3 translation;
        glm::dmat3 frame;
        if (requireVoxlightTransform(*grid, path, translation, frame) != voxels.voxelSize)
            throw InputError(path + ": grid '" + grid->getName() + "' has voxel size " +
                             std::to_string(grid->constTransform().voxelSize()[0]) + ", grid 'opacity' has " +
                             std::to_string(voxels.voxelSize));
        if (translation != voxels.origin || frame != voxels.frame)
            throw InputError(path + ": grid '" + grid->getName() + "' is placed otherwise than grid 'opacity'");
    }
    // A turned frame's h is the length of a matrix row: exact only up to rounding.
    if (auto size = set.metadata().getMetadata<openvdb::DoubleMetadata>(kMetaVoxelSize)) {
        if (!(std::abs(size->value() - voxels.voxelSize) <= 1e-12 * voxels.voxelSize))
            throw InputError(path + ": file metadata voxel_size " + std::to_string(size->value()) +
                             " disagrees with the grids' transform (" + std::to_string(voxels.voxelSize) + ")");
        voxels.voxelSize = size->value();
    }
    voxels.settings = stringMeta(set.metadata(), kMetaSettings);
    voxels.sourceScene = stringMeta(set.metadata(), kMetaSourceScene);

    voxels.coords = sortedActiveCoords(*opacity, path);
    const size_t n = voxels.coords.size();

    // Same active voxel count and every opacity voxel active ⇒ the same active set.
    auto requireSameTopology = [&](const auto& grid) {
        if (grid->activeVoxelCount() != n)
            throw InputError(path + ": grid '" + grid->getName() + "' has " +
                             std::to_string(grid->activeVoxelCount()) + " active voxels, grid 'opacity' has " +
                             std::to_string(n));
    };
    auto readChannel = [&](const auto& grid, auto& out, auto convert) {
        if (!grid) return;
        requireSameTopology(grid);
        out.resize(n);
        auto accessor = grid->getConstAccessor();
        for (size_t i = 0; i < n; ++i) {
            typename std::decay_t<decltype(*grid)>::ValueType value;
            if (!accessor.probeValue(toCoord(voxels.coords[i]), value))
                throw InputError(path + ": grid '" + grid->getName() + "' has no active voxel at " +
                                 coordText(voxels.coords[i]) + ", where grid 'opacity' has one");
            out[i] = convert(value);
        }
    };
    const auto asVec3 = [](const openvdb::Vec3f& v) { return fromVdb(v); };
    const auto asFloat = [](float v) { return v; };
    readChannel(albedo, voxels.albedo, asVec3);
    readChannel(normal, voxels.normal, asVec3);
    readChannel(emission, voxels.emission, asVec3);
    readChannel(opacity, voxels.opacity, asFloat);
    readChannel(occlusion, voxels.occlusion, asFloat);
    readChannel(radiance, voxels.radiance, asVec3);
    std::vector<vec3> pos, neg;
    readChannel(axisPos, pos, asVec3);
    readChannel(axisNeg, neg, asVec3);
    voxels.axisWeights.resize(n);
    for (size_t i = 0; i < n; ++i)
        voxels.axisWeights[i] = {pos[i].x, neg[i].x, pos[i].y, neg[i].y, pos[i].z, neg[i].z};

    voxels.solid.assign(n, 0);
    auto solidAccessor = solid->getConstAccessor();
    openvdb::Index64 solidFound = 0;
    for (size_t i = 0; i < n; ++i) {
        bool value = false;
        if (solidAccessor.probeValue(toCoord(voxels.coords[i]), value)) {
            ++solidFound;
            voxels.solid[i] = value ? 1 : 0;
        }
    }
    if (solidFound != solid->activeVoxelCount())
        throw InputError(path + ": grid 'solid' has " + std::to_string(solid->activeVoxelCount() - solidFound) +
                         " active voxels outside grid 'opacity'");
    return voxels;
}

ExtraGrid readExtraGrid(const std::string& path, const std::string& gridName) {
    const openvdb::GridBase::Ptr base = vdb_detail::readGrid(path, gridName);
    ExtraGrid out;
    out.name = gridName;
    out.voxelSize = requireVoxlightTransform(*base, path, out.translation, out.frame);
    if (auto scalar = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base)) {
        out.coords = sortedActiveCoords(*scalar, path);
        out.scalars.resize(out.coords.size());
        auto accessor = scalar->getConstAccessor();
        for (size_t i = 0; i < out.coords.size(); ++i) out.scalars[i] = accessor.getValue(toCoord(out.coords[i]));
    } else if (auto vector = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(base)) {
        out.coords = sortedActiveCoords(*vector, path);
        out.vectors.resize(out.coords.size());
        auto accessor = vector->getConstAccessor();
        for (size_t i = 0; i < out.coords.size(); ++i)
            out.vectors[i] = fromVdb(accessor.getValue(toCoord(out.coords[i])));
    } else {
        throw InputError(path + ": grid '" + gridName + "' has value type " + base->valueType() +
                         ", expected float or vec3s");
    }
    return out;
}

}  // namespace vl
