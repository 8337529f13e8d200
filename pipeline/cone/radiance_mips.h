// The radiance mip chain that cones sample: takes a lit VoxelScene (faceRadiance, or
// radiance where there is none; opacity, solid, axis weights), gives per level a sparse
// NanoVDB index grid (coord → texel index, −1 outside) over plain texel arrays, and a plain
// view of them for the kernels in cone_trace.h.
//
// Every level keeps per voxel one texel per direction of travel, its children composited
// front to back along it, so a wall one voxel thick stays opaque at every level to the cones
// that cross it (MipTexel says how a level is made). The radiance channels are the light
// voxels reflect: emission never enters the mips, so cones never count an emitter that the
// receiver's exact direct term already holds.
#pragma once

#include "core/math.h"
#include "voxel/vdb_file.h"
#include "voxel/voxel_scene.h"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <array>
#include <vector>

namespace vl {

using MipIndexGrid = nanovdb::NanoGrid<int32_t>;

// Opacity cap: a solid voxel lets 10⁻³ through per voxel length, so σ stays finite.
constexpr float kMaxMipOpacity = 0.999f;

// Every level keeps per voxel one texel per direction of travel (+X, −X, +Y, −Y, +Z, −Z):
// (α-premultiplied radiance, α, coverage). Coverage is the part of α that shows a surface:
// a cone's colour is radiance / coverage (cone_trace.h), its opacity comes from α.
//  - Level 0 is the voxels: α = opacity (1 for a solid voxel). The texel for travel d shows
//    the face looking back at the cone (travel +X: face −X), its radiance from faceRadiance,
//    with coverage c_f·α, c_f = w_f / max_g w_g (the face's share of the voxel's largest
//    axis weight). A face without surface (w_f = 0) shows nothing and covers nothing, yet the
//    voxel keeps its α: looking at a floor at 45°, the blend of its top face (coverage 1) and
//    its empty side face (coverage 0) shows the top's radiance, not half of it, and a one-
//    sided or double-sided wall lit on one side shows nothing to the dark side (the isotropic
//    radiance of one voxel holding both sides leaked through every thin wall). Without
//    faceRadiance every face shows `radiance` with coverage α (isotropic, as before).
//  - Level k voxel I (size 2^k·h) has the 8 children 2I + {0,1}³ at level k−1 and is active
//    when any child is. Its texel for travel along an axis composites the children front to
//    back in pairs along that axis (c = c_f + (1−α_f)c_b, α = α_f + (1−α_f)α_b, coverage
//    alike), then averages the 4 pairs (Crassin et al. 2011, anisotropic voxels). Why not
//    the plain average: a wall one voxel thick averages to α = 2^−k at level k, so every
//    cone wider than a voxel sees through walls (a closed box of radiance L gathers a few
//    percent of π·L). Composited along the travel axis the wall keeps α = 1 for cones
//    crossing it and coverage for cones running along it. A uniform medium of opacity α₀
//    gets α_k = 1 − (1 − α₀)^(2^k): Beer–Lambert at every level.
//    A wall at a slant to the axis steps from one voxel into the next along it, so some of
//    a voxel's columns hold it and the rest lie in the voxel behind; where a voxel shows
//    surface to the travel, its columns emptier than its fullest one take the voxel behind
//    them (one step of the level, `behind`) front to back as well (radiance_mips.cpp
//    makeParent says why).
//  - `values`: the plain average of the children's isotropic (α·radiance, α) (level 0: the
//    voxels' `radiance`), empty children zero, so Σ value·volume is the same at every level.
//    This is the isotropic mip written to grids.vdb.
// Each texel also stores its optical depth σ = −ln(1 − min(α, 1 − 10⁻³)) per voxel length;
// cone_trace.h interpolates σ rather than α for opacity (see there).
// Levels are built until one has at most 8 voxels or spans at most 2 voxels on every axis
// (at most MipView::kMaxLevels).
struct MipTexel {
    vec3 radiance = vec3(0.0f);  // α-premultiplied (coverage-premultiplied at level 0)
    float alpha = 0.0f;
    float density = 0.0f;        // σ = −ln(1 − min(α, kMaxMipOpacity))
    float coverage = 0.0f;       // the part of α that shows a surface; colour = radiance / coverage
};

VL_HOSTDEV inline float opticalDepth(float alpha) {
    return -logf(1.0f - glm::clamp(alpha, 0.0f, kMaxMipOpacity));
}

// Directions of travel of the texels, in this order.
enum MipFace { kFacePosX, kFaceNegX, kFacePosY, kFaceNegY, kFacePosZ, kFaceNegZ, kFaceCount };

struct MipLevelView {
    const MipIndexGrid* index = nullptr;
    const MipTexel* texels = nullptr;  // texel of voxel i, face f: texels[i·facesPerVoxel + f]
    int facesPerVoxel = 6;             // one texel per direction of travel at every level
    // mipIndexPosition(p) = p·inverseVoxelSize − centreOffset at this level, precomputed
    // for the kernels (what a cone step would otherwise recompute with ldexp).
    float voxelSize = 0.0f;         // 2^k·h
    float inverseVoxelSize = 0.0f;  // 1 / (2^k·h)
    float centreOffset = 0.0f;      // (1 − 2^−k)/2
};

// The leaf of an index grid (a mip level's, the gather cells') that the last lookup landed
// in: consecutive cone samples and the eight corners of a trilinear sample mostly share a
// leaf. Also remembers where there is no leaf (index grids have no active tiles, so every
// voxel there is −1).
struct IndexLeafCache {
    using Leaf = nanovdb::NanoLeaf<int32_t>;
    const Leaf* leaf = nullptr;
    nanovdb::Coord origin = nanovdb::Coord::max();

    VL_HOSTDEV const Leaf* find(const MipIndexGrid& grid, const nanovdb::Coord& ijk) {
        const nanovdb::Coord o(ijk[0] & ~int32_t(Leaf::MASK), ijk[1] & ~int32_t(Leaf::MASK), ijk[2] & ~int32_t(Leaf::MASK));
        if (!(o == origin)) {
            origin = o;
            leaf = grid.tree().root().probeLeaf(ijk);
        }
        return leaf;
    }
    VL_HOSTDEV int32_t value(const MipIndexGrid& grid, const nanovdb::Coord& ijk) {
        const Leaf* l = find(grid, ijk);
        return l ? l->getValue(Leaf::CoordToOffset(ijk)) : -1;
    }
};

// What a kernel needs: per-level grids and texel arrays (host or device memory, as the
// owner placed them), the level-0 voxel size and the world box the level-0 voxels cover.
struct MipView {
    static constexpr int kMaxLevels = 16;
    MipLevelView levels[kMaxLevels] = {};
    int levelCount = 0;
    float voxelSize = 0.0f;      // h (metres) of level 0
    vec3 boundsMin = vec3(0.0f);  // world box of the level-0 voxels' extents
    vec3 boundsMax = vec3(0.0f);

    // The middle of that box: a point that turns with the scene (voxelize.h anchorToVoxelGrid).
    VL_HOSTDEV vec3 centre() const { return 0.5f * (boundsMin + boundsMax); }
};

// Index convention. Level 0 follows voxel_scene.h: voxel i centred at i·h. A level-k voxel
// covers level-0 voxels 2^k·I … 2^k·I + 2^k − 1, so its centre is their centroid,
// (2^k·I + (2^k − 1)/2)·h — not 2^k·I·h. Each level's NanoVDB map carries that translation,
// and mipIndexPosition() applies it, so a level-k parent's centre is exactly the corner
// shared by its 8 children at level k−1.
//
// Index-space position of world point p at `level`, with voxel centres at integers.
VL_HOSTDEV inline vec3 mipIndexPosition(const vec3& p, float voxelSize, int level) {
    const float levelVoxelSize = ldexpf(voxelSize, level);
    const float centreOffset = 0.5f - ldexpf(0.5f, -level);  // (1 − 2^−k)/2 in level-k voxels
    return p / levelVoxelSize - vec3(centreOffset);
}

// World centre of voxel `coord` at `level`.
VL_HOSTDEV inline vec3 mipVoxelCentre(const ivec3& coord, float voxelSize, int level) {
    const float levelVoxelSize = ldexpf(voxelSize, level);
    const float centreOffset = 0.5f - ldexpf(0.5f, -level);
    return (vec3(coord) + vec3(centreOffset)) * levelVoxelSize;
}

struct MipLevel {
    double voxelSize = 0.0;          // 2^k·h
    vec3 centreOffset = vec3(0.0f);  // world position of voxel (0,0,0)'s centre: (2^k − 1)/2·h
    std::vector<ivec3> coords;       // sorted by (x, y, z)
    std::vector<vec4> values;        // isotropic (α·radiance, α), parallel to coords
    std::vector<MipTexel> texels;    // facesPerVoxel per voxel
    int facesPerVoxel = 6;
    // Level k > 0: per voxel its 8 children at level k − 1 (slot x + 2y + 4z, −1 absent).
    std::vector<std::array<int32_t, 8>> children;
    // Level k > 0: per voxel and direction of travel (MipFace order), the voxel one step
    // further along it (−1 absent).
    std::vector<std::array<int32_t, 6>> behind;
};

class RadianceMips {
public:
    int levelCount() const { return static_cast<int>(levels_.size()); }
    double voxelSize() const { return voxelSize_; }
    const glm::dvec3& origin() const { return origin_; }
    const glm::dmat3& frame() const { return frame_; }
    const MipLevel& level(int k) const { return levels_.at(static_cast<size_t>(k)); }
    const MipIndexGrid* indexGrid(int k) const;
    MipView view() const;
    size_t memoryBytes() const;  // index grids and texel arrays of all levels
    // New radiance on the same voxels (what the bounces do once per bounce): the texels and
    // values of the levels there are recomputed, the topology and index grids kept. The same
    // result as building them anew (buildRadianceMips, or buildLevelZeroMips for level 0
    // alone) with the same checks.
    void relight(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                 const std::vector<FaceRadiance>& faceRadiance);
    // The coarser levels of mips built with level 0 alone (buildLevelZeroMips), from level 0's
    // radiance as it is now: then the same as buildRadianceMips of that radiance. Nothing
    // where they are there.
    void addParentLevels();

private:
    friend RadianceMips buildMips(const VoxelScene&, const std::vector<vec3>&, const std::vector<FaceRadiance>*, bool);
    void addIndexGrids();  // of the levels that have none yet
    double voxelSize_ = 0.0;
    glm::dvec3 origin_{0.0};  // the voxels' frame (VoxelScene::origin, frame), for the file's grids
    glm::dmat3 frame_{1.0};
    vec3 boundsMin_ = vec3(0.0f), boundsMax_ = vec3(0.0f);
    std::vector<MipLevel> levels_;
    std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> grids_;
};

// Mips of voxels.faceRadiance (with voxels.radiance as the isotropic values), or of
// voxels.radiance alone, isotropic, when faceRadiance is empty. Error when radiance, opacity
// or solid (or faceRadiance, when given, and axis weights with it) do not match the voxel
// count (radiance is missing before the lighting stage has run), the voxel size is not
// positive, or a coordinate is beyond ±2^20; InputError when a radiance is negative, NaN or
// Inf or an opacity is outside [0, 1] (naming the voxel). An empty scene gives zero levels;
// cones through it gather nothing.
RadianceMips buildRadianceMips(const VoxelScene& voxels);
// The same topology with another isotropic radiance channel (parallel to voxels.coords).
RadianceMips buildRadianceMips(const VoxelScene& voxels, const std::vector<vec3>& radiance);
// The same topology with other face radiances (parallel to voxels.coords); `radiance` their
// isotropic mean (faceWeightedMean), for `values`.
RadianceMips buildRadianceMips(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                               const std::vector<FaceRadiance>& faceRadiance);

// Level 0 alone: all that the gathers by rays read (a ray reads the voxels it hits, never a
// coarser level), without the coarser levels' share of the mips' time (docs/decisions.md,
// "Cone marching"); the lightmap is the same bytes. addParentLevels adds them where cones or
// grids.vdb want them.
RadianceMips buildLevelZeroMips(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                                const std::vector<FaceRadiance>& faceRadiance);

// Who reads a bake's mips: cones (every level), or only rays (level 0: the gathers by rays
// and the receivers their points do not reach).
enum class MipReaders { Cones, RaysOnly };
// The mips of voxels.radiance (and faceRadiance) as `readers` need them: level 0 alone for
// RaysOnly where the voxels have face radiance, buildRadianceMips otherwise.
RadianceMips buildRadianceMipsFor(const VoxelScene& voxels, MipReaders readers);

// Grids for grids.vdb: per level k, `radiance_mip<k>` (Vec3, the isotropic α-premultiplied
// radiance) and `opacity_mip<k>` (float α), voxel size 2^k·h, level k's voxel I centred in
// world space at the voxels' origin + frame·(I·2^k·h + MipLevel::centreOffset).
std::vector<ExtraGrid> mipGridsForFile(const RadianceMips& mips);

}  // namespace vl
