#include "voxel/vdb_inspect.h"

#include "core/error.h"
#include "voxel/vdb_detail.h"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace vl {

namespace {

// Grid types whose values inspect can show (PointDataGrid and PointIndexGrid hold point
// indices, not values; MaskGrid holds no value but its activity).
using ValueGridTypes = openvdb::TypeList<openvdb::FloatGrid, openvdb::DoubleGrid, openvdb::Int32Grid,
                                         openvdb::Int64Grid, openvdb::BoolGrid, openvdb::MaskGrid,
                                         openvdb::Vec3SGrid, openvdb::Vec3DGrid, openvdb::Vec3IGrid>;

template <typename T>
struct IsVec3 : std::false_type {};
template <typename T>
struct IsVec3<openvdb::math::Vec3<T>> : std::true_type {};

template <typename GridT>
constexpr bool isMask() {
    return std::is_same_v<GridT, openvdb::MaskGrid>;
}

// Calls f(value, voxelCount) for every active value; a tile counts once per voxel it covers.
template <typename GridT, typename F>
void forEachActiveValue(const GridT& grid, F&& f) {
    for (auto it = grid.cbeginValueOn(); it; ++it) f(*it, it.getVoxelCount());
}

template <typename ValueT>
double scalarOf(const ValueT& value) {
    if constexpr (IsVec3<ValueT>::value) {
        const double x = value[0], y = value[1], z = value[2];
        return std::sqrt(x * x + y * y + z * z);
    } else {
        return static_cast<double>(value);
    }
}

template <typename ValueT>
bool finite(const ValueT& value) {
    if constexpr (IsVec3<ValueT>::value) {
        return std::isfinite(double(value[0])) && std::isfinite(double(value[1])) && std::isfinite(double(value[2]));
    } else {
        return std::isfinite(static_cast<double>(value));
    }
}

int binOf(double v, double lo, double hi, int bins) {
    if (!(hi > lo)) return 0;
    // Multiply before dividing so that a value on a bin edge (often a round number) lands
    // exactly on it rather than a rounding error below.
    const int b = static_cast<int>(std::floor((v - lo) * bins / (hi - lo)));
    return std::clamp(b, 0, bins - 1);
}

template <typename GridT>
GridValueStats valueStats(const GridT& grid, int bins) {
    using ValueT = typename GridT::ValueType;
    GridValueStats stats;
    if constexpr (isMask<GridT>()) {
        return stats;
    } else {
        constexpr bool vector = IsVec3<ValueT>::value;
        stats.ofMagnitude = vector;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0;
        uint64_t count = 0;
        std::array<double, 3> cmin{lo, lo, lo}, cmax{hi, hi, hi};
        forEachActiveValue(grid, [&](const ValueT& value, openvdb::Index64 voxels) {
            if (!finite(value)) {
                stats.nonFinite += voxels;
                return;
            }
            const double s = scalarOf(value);
            lo = std::min(lo, s);
            hi = std::max(hi, s);
            sum += s * static_cast<double>(voxels);
            count += voxels;
            if constexpr (vector)
                for (int c = 0; c < 3; ++c) {
                    cmin[c] = std::min(cmin[c], double(value[c]));
                    cmax[c] = std::max(cmax[c], double(value[c]));
                }
        });
        if (count == 0) return stats;
        stats.available = true;
        stats.min = lo;
        stats.max = hi;
        stats.mean = sum / static_cast<double>(count);
        if (vector) {
            stats.componentMin = cmin;
            stats.componentMax = cmax;
        }
        stats.histogram.assign(static_cast<size_t>(std::max(bins, 1)), 0);
        forEachActiveValue(grid, [&](const ValueT& value, openvdb::Index64 voxels) {
            if (finite(value)) stats.histogram[binOf(scalarOf(value), lo, hi, int(stats.histogram.size()))] += voxels;
        });
        return stats;
    }
}

template <typename GridT>
uint64_t valueBytes() {
    using ValueT = typename GridT::ValueType;
    if constexpr (std::is_same_v<ValueT, bool> || isMask<GridT>()) return 1;
    else return sizeof(ValueT);
}

std::array<double, 3> toArray(const openvdb::Vec3d& v) { return {v[0], v[1], v[2]}; }

std::vector<std::pair<std::string, std::string>> metadataText(const openvdb::MetaMap& meta, bool skipStandard) {
    std::vector<std::pair<std::string, std::string>> out;
    for (auto it = meta.beginMeta(); it != meta.endMeta(); ++it) {
        const std::string& key = it->first;
        // Shown elsewhere in GridInfo, or bookkeeping of the file format.
        if (skipStandard && (key == openvdb::GridBase::META_GRID_NAME || key == openvdb::GridBase::META_GRID_CLASS ||
                             key.rfind("file_", 0) == 0))
            continue;
        out.emplace_back(key, it->second ? it->second->str() : std::string());
    }
    return out;
}

GridInfo describeGrid(const openvdb::GridBase& grid, int bins) {
    GridInfo info;
    info.name = grid.getName();
    info.valueType = grid.valueType();
    info.gridClass = openvdb::GridBase::gridClassToString(grid.getGridClass());
    const auto& transform = grid.constTransform();
    info.voxelSize = toArray(transform.voxelSize());
    info.linearTransform = transform.isLinear();
    info.activeVoxels = grid.activeVoxelCount();
    info.memoryBytes = grid.memUsage();
    const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    info.empty = info.activeVoxels == 0 || box.empty();
    uint64_t bytesPerValue = 0;
    grid.apply<ValueGridTypes>([&](const auto& typed) {
        using GridT = std::decay_t<decltype(typed)>;
        bytesPerValue = valueBytes<GridT>();
        info.stats = valueStats(typed, bins);
    });
    if (!info.empty) {
        for (int a = 0; a < 3; ++a) {
            info.indexMin[a] = box.min()[a];
            info.indexMax[a] = box.max()[a];
        }
        const openvdb::BBoxd world =
            transform.indexToWorld(openvdb::BBoxd(box.min().asVec3d() - 0.5, box.max().asVec3d() + 0.5));
        info.worldMin = toArray(world.min());
        info.worldMax = toArray(world.max());
        info.denseBytes = static_cast<uint64_t>(box.volume()) * bytesPerValue;
    }
    info.metadata = metadataText(grid, true);
    return info;
}

// ---- slices ---------------------------------------------------------------------------

vec3 viridis(double t) {
    // sRGB samples of matplotlib's viridis at t = 0, 1/8, …, 1.
    static const float stops[9][3] = {{0.267f, 0.005f, 0.329f}, {0.278f, 0.176f, 0.482f}, {0.231f, 0.322f, 0.545f},
                                      {0.173f, 0.447f, 0.557f}, {0.129f, 0.569f, 0.549f}, {0.157f, 0.682f, 0.502f},
                                      {0.369f, 0.788f, 0.384f}, {0.678f, 0.863f, 0.188f}, {0.992f, 0.906f, 0.145f}};
    const double x = std::clamp(t, 0.0, 1.0) * 8.0;
    const int i = std::min(static_cast<int>(x), 7);
    const float f = static_cast<float>(x - i);
    vec3 out;
    for (int c = 0; c < 3; ++c) out[c] = srgbToLinear(stops[i][c] + f * (stops[i + 1][c] - stops[i][c]));
    return out;
}

const vec3 kNonFiniteColour(1.0f, 0.0f, 1.0f);

// How a grid's values become colours; fixed per grid, so all its slices compare.
struct ColourScale {
    double lo = 0.0, hi = 0.0;   // scalars: viridis range
    bool signedVectors = false;  // vectors: centre on grey
    double vectorScale = 1.0;    // vectors: divide components by this
};

template <typename GridT>
ColourScale colourScaleOf(const GridT& grid) {
    using ValueT = typename GridT::ValueType;
    ColourScale scale;
    if constexpr (IsVec3<ValueT>::value) {
        double maxAbs = 0.0;
        forEachActiveValue(grid, [&](const ValueT& v, openvdb::Index64) {
            if (!finite(v)) return;
            for (int c = 0; c < 3; ++c) {
                scale.signedVectors = scale.signedVectors || v[c] < 0;
                maxAbs = std::max(maxAbs, std::abs(double(v[c])));
            }
        });
        scale.vectorScale = std::max(maxAbs, 1.0);
    } else if constexpr (!isMask<GridT>()) {
        forEachActiveValue(grid, [&](const ValueT& v, openvdb::Index64) {
            if (!finite(v)) return;
            scale.lo = std::min(scale.lo, double(v));
            scale.hi = std::max(scale.hi, double(v));
        });
    }
    return scale;
}

template <typename ValueT>
vec3 colourOf(const ValueT& value, const ColourScale& scale) {
    if (!finite(value)) return kNonFiniteColour;
    if constexpr (IsVec3<ValueT>::value) {
        vec3 c;
        for (int i = 0; i < 3; ++i) {
            const double v = double(value[i]) / scale.vectorScale;
            c[i] = static_cast<float>(scale.signedVectors ? 0.5 + 0.5 * v : v);
        }
        return c;
    } else {
        const double v = static_cast<double>(value);
        return viridis(scale.hi > scale.lo ? (v - scale.lo) / (scale.hi - scale.lo) : 0.0);
    }
}

const char* axisName(SliceAxis axis) { return axis == SliceAxis::X ? "x" : axis == SliceAxis::Y ? "y" : "z"; }

template <typename GridT>
Image sliceOf(const GridT& grid, const openvdb::CoordBBox& box, SliceAxis axis, int index) {
    using ValueT = typename GridT::ValueType;
    const ColourScale scale = colourScaleOf(grid);
    const openvdb::Coord lo = box.min(), hi = box.max();
    const openvdb::Coord extent = hi - lo + openvdb::Coord(1);
    // (column axis, row axis, rows increase upwards)
    int colAxis = 0, rowAxis = 1;
    bool rowsUp = true;
    switch (axis) {
    case SliceAxis::X: colAxis = 2; rowAxis = 1; rowsUp = true; break;
    case SliceAxis::Y: colAxis = 0; rowAxis = 2; rowsUp = false; break;
    case SliceAxis::Z: colAxis = 0; rowAxis = 1; rowsUp = true; break;
    }
    constexpr int64_t kMaxPixels = int64_t(1) << 26;
    if (int64_t(extent[colAxis]) * extent[rowAxis] > kMaxPixels)
        throw SettingsError("grid '" + grid.getName() + "' spans " + std::to_string(extent[colAxis]) + " x " +
                            std::to_string(extent[rowAxis]) + " voxels, too large for a slice image");
    Image image(extent[colAxis], extent[rowAxis], 3);
    auto accessor = grid.getConstAccessor();
    for (int row = 0; row < image.height; ++row) {
        for (int col = 0; col < image.width; ++col) {
            openvdb::Coord c;
            c[int(axis)] = index;
            c[colAxis] = lo[colAxis] + col;
            c[rowAxis] = rowsUp ? hi[rowAxis] - row : lo[rowAxis] + row;
            ValueT value;
            if (!accessor.probeValue(c, value)) {
                image.setRgb(col, row, inactiveSliceColour(col, row));
            } else if constexpr (isMask<GridT>()) {
                image.setRgb(col, row, viridis(1.0));
            } else {
                image.setRgb(col, row, colourOf(value, scale));
            }
        }
    }
    return image;
}

}  // namespace

vec3 inactiveSliceColour(int column, int row) { return vec3(((column + row) & 1) ? 0.03f : 0.12f); }

VdbFileInfo inspectVoxelFile(const std::string& path, int histogramBins) {
    VdbFileInfo info;
    info.path = path;
    const openvdb::MetaMap::Ptr metadata = vdb_detail::forEachGrid(
        path, [&](const openvdb::GridBase& grid) { info.grids.push_back(describeGrid(grid, histogramBins)); });
    info.metadata = metadataText(*metadata, false);
    return info;
}

Image sliceImage(const std::string& path, const std::string& gridName, SliceAxis axis, int index) {
    const openvdb::GridBase::Ptr grid = vdb_detail::readGrid(path, gridName);
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    if (grid->activeVoxelCount() == 0 || box.empty())
        throw InputError(path + ": grid '" + gridName + "' has no active voxels to slice");
    const int a = static_cast<int>(axis);
    if (index < box.min()[a] || index > box.max()[a])
        throw SettingsError("slice " + std::string(axisName(axis)) + "=" + std::to_string(index) +
                            " is outside grid '" + gridName + "' of " + path + " (active " + axisName(axis) +
                            " range " + std::to_string(box.min()[a]) + ".." + std::to_string(box.max()[a]) + ")");
    Image image;
    const bool known = grid->apply<ValueGridTypes>([&](const auto& typed) { image = sliceOf(typed, box, axis, index); });
    if (!known)
        throw InputError(path + ": grid '" + gridName + "' has value type " + grid->valueType() +
                         ", which has no values to show");
    return image;
}

}  // namespace vl
