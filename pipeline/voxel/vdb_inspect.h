// What is in a .vdb file — ours or any other program's — and pictures of its slices; the
// engine of `voxlight inspect`. Free of OpenVDB types.
#pragma once

#include "core/image.h"
#include "core/math.h"

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vl {

// Statistics over a grid's active values (active tiles count once per voxel they cover).
// Scalar grids (float, double, int, bool): of the value. Vector grids: of the magnitude |v|,
// with the per-component range beside it. Non-finite values are counted, not included.
struct GridValueStats {
    bool available = false;      // false for value-less grids (mask, points, empty grids)
    bool ofMagnitude = false;    // true for vector grids: min/max/mean/histogram are of |v|
    double min = 0.0;
    double max = 0.0;
    double mean = 0.0;
    // Equal-width bins over [min, max]; bin b holds values in [min + b·w, min + (b+1)·w), the
    // last bin also holds max. When min == max every value falls in bin 0.
    std::vector<uint64_t> histogram;
    std::array<double, 3> componentMin{};  // vector grids only
    std::array<double, 3> componentMax{};
    uint64_t nonFinite = 0;      // NaN or Inf values, left out of everything above
};

struct GridInfo {
    std::string name;
    std::string valueType;       // OpenVDB's name: float, double, int32, bool, vec3s, mask, ...
    std::string gridClass;       // level set, fog volume, staggered, unknown
    std::array<double, 3> voxelSize{};  // world size of one voxel per axis
    bool linearTransform = true;  // false for frustum or other non-linear maps
    uint64_t activeVoxels = 0;
    bool empty = true;           // no active voxels: the bounding boxes are meaningless
    std::array<int, 3> indexMin{}, indexMax{};          // active bbox, inclusive voxel indices
    std::array<double, 3> worldMin{}, worldMax{};        // world extent of those voxels' boxes
    uint64_t memoryBytes = 0;    // OpenVDB's memUsage() of the loaded grid
    uint64_t denseBytes = 0;     // bbox voxel count × value size (bool and mask: 1 byte)
    GridValueStats stats;
    std::vector<std::pair<std::string, std::string>> metadata;  // the grid's own metadata, as text
};

struct VdbFileInfo {
    std::string path;
    std::vector<std::pair<std::string, std::string>> metadata;  // file-level, as text
    std::vector<GridInfo> grids;
};

inline constexpr int kInspectHistogramBins = 10;

// Reads every grid of the file. InputError naming the file for a missing or non-VDB file,
// or naming the grid when one cannot be read (an unregistered grid type).
VdbFileInfo inspectVoxelFile(const std::string& path, int histogramBins = kInspectHistogramBins);

enum class SliceAxis { X = 0, Y = 1, Z = 2 };

// One index plane of a grid as a linear RGB image covering the grid's whole active bbox on
// the other two axes (so every slice of a grid has the same size):
//   X slice: columns = z (increasing to the right), rows = y (increasing upwards);
//   Y slice: columns = x, rows = z (increasing downwards: seen from +Y);
//   Z slice: columns = x, rows = y (increasing upwards).
// Vectors are shown as colours: unchanged when every component of the grid lies in [0, 1],
// divided by the largest component when above, and 0.5 + 0.5·v/m for signed grids (m the
// largest |component|, at least 1). Scalars go through viridis over [min(0, grid min),
// max(0, grid max)]. Inactive voxels are a checkerboard of two dark greys alternating
// voxel by voxel, so they stand apart from zero (black, grey or viridis purple).
// InputError naming the file for a missing file or grid, a value-less grid type or an empty
// grid; SettingsError for an index outside the grid's active bbox.
Image sliceImage(const std::string& path, const std::string& gridName, SliceAxis axis, int index);

// The checkerboard colours of inactive voxels, for tests and legends.
vec3 inactiveSliceColour(int column, int row);

}  // namespace vl
