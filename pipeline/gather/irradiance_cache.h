// Irradiance gathered where it is cheap and looked up where it is wanted (Ward's irradiance
// caching, on the voxel grid): takes the surface sides of a VoxelScene and a cell level L;
// gives gather points, one per surface side of every occupied cell of 2^L × 2^L × 2^L voxels,
// and interpolates the irradiance gathered at them (by cones here, by rays in
// gather/ray_gather.h) at any surface point.
//
// Why: indirect irradiance changes over the distance to the surfaces that send it, not over a
// voxel, so a gather per cell side serves the texels, pixel samples and voxel sides around it
// for the same error, and a lightmap or image of any size costs no more gathers
// (docs/decisions.md, "Gather points").
#pragma once

#include "cone/cone_trace.h"
#include "voxel/voxel_scene.h"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <cstdint>
#include <vector>

namespace vl {

class Progress;

struct GatherPoint {
    vec3 position{0.0f};  // local frame
    vec3 normal{0.0f};    // unit
    // The frame its cone set is laid out in: tangent (unit, ⊥ normal) and a turn about the
    // normal from it (see gatherFrame).
    vec3 tangent{1.0f, 0.0f, 0.0f};
    float turn = 0.0f;
    // In (0, 1]: √(its layer's share of the cell's cross-section), the share counted as the
    // distinct columns across the layer's axis that its open voxels fill, over 4^L (a layer two
    // voxels deep, or slanted, counts each column once; voxels under a block, which the point
    // leaves out, are not counted). Why: where a wall ends a surface inside a cell, the layer
    // there is a strip 1 to 8 voxels wide, and with equal masses the strip's point stood for
    // half a cell of surface beside it whatever its width, so a closed room's indirect power
    // depended on where its walls fell in their cells. Why the root: the share itself carries a
    // point's irradiance into the corners beyond it at full weight (docs/decisions.md, "Where
    // walls fall in the gather cells").
    float mass = 1.0f;
};

constexpr int kMaxGatherTurns = 16;
constexpr int kMaxCacheLevel = 16;  // cells of 2^16 voxels per axis

// The frame of a gather point's cone set, from where the point lies relative to the voxels'
// centre c (the middle of their bounding box) and nothing else, so that turning the scene a
// quarter turn about c turns every point's cones with it (the voxel hierarchy maps onto
// itself then too: voxelize.h anchorToVoxelGrid). r = p − c splits into a height r·n and a
// part r⊥ across the normal. The tangent points along r⊥; the turn is the R2 low-discrepancy
// sequence (Roberts 2018) over the cell-rounded |r⊥| and r·n, fract(u/φ₂ + v/φ₂²), φ₂ =
// 1.3247… (x³ = x + 1). Neighbouring points of a surface differ in one or the other, so
// their cone sets are turned apart and the few points a receiver interpolates see the bright
// regions between one point's cones through another's (random turns let neighbours
// coincide). A point on the axis through c along its normal (r⊥ ≈ 0) takes orthonormalBasis's
// tangent.
VL_HOSTDEV inline void gatherFrame(const vec3& p, const vec3& n, const vec3& centre, float cellSize, vec3& tangent,
                                   float& turn) {
    const vec3 r = p - centre;
    const float height = glm::dot(r, n);
    const vec3 across = r - height * n;
    const float radius = glm::length(across);
    if (radius > 1.0e-3f * cellSize) {
        tangent = across / radius;
    } else {
        vec3 bitangent;
        orthonormalBasis(n, tangent, bitangent);
    }
    const double v = floor(double(radius) / double(cellSize) + 0.5) * 0.7548776662466927 +
                     floor(double(height) / double(cellSize) + 0.5) * 0.5698402909980532;
    turn = static_cast<float>(v - floor(v));
}

using CellIndexGrid = nanovdb::NanoGrid<int32_t>;

// What the kernels read (host or device memory, as the owner placed it).
struct IrradianceCacheView {
    MipLevelView occupancy;                // level 0 of the radiance mips: what blocks a path (α ≥ ½)
    const CellIndexGrid* cells = nullptr;  // cell coordinate → its slot in cellBegin, −1 for none
    const uint32_t* cellBegin = nullptr;   // points of slot s: [cellBegin[s], cellBegin[s + 1])
    const GatherPoint* points = nullptr;
    const vec3* irradiance = nullptr;      // E per point (W/m²)
    // Points a point's receivers may take (IrradianceCache::link): of point q,
    // neighbours[neighbourBegin[q] … neighbourBegin[q + 1]); null before linking.
    const uint32_t* neighbourBegin = nullptr;
    const uint32_t* neighbours = nullptr;
    uint32_t pointCount = 0;
    float voxelSize = 0.0f;  // h
    int level = 0;           // L
    // > 0: the points gathered by n × n rays (gather/ray_gather.h), and a receiver no point
    // applies to gathers so too; 0: by cones.
    int raysPerAxis = 0;
    // Per level-0 voxel, the plane of its surface (unit normal, n·x at its surface's centroid;
    // a zero normal where the voxel's normals cancel): what a path must cross to be blocked
    // by it (clearPath). Null: every solid voxel blocks.
    const vec4* surfacePlanes = nullptr;
};

// Floor division of a voxel coordinate by the cell size 2^level.
VL_HOSTDEV inline int cellOf(int voxel, int level) { return voxel >> level; }  // arithmetic shift floors

// The signed axis (+X, −X, +Y, −Y, +Z, −Z) a normal is closest to; ties go to the lower axis.
VL_HOSTDEV inline int dominantAxisFace(const vec3& n) {
    int axis = 0;
    if (glm::abs(n.y) > glm::abs(n[axis])) axis = 1;
    if (glm::abs(n.z) > glm::abs(n[axis])) axis = 2;
    return 2 * axis + (n[axis] < 0.0f ? 1 : 0);
}

// A surface point lifted off its own surface: far enough along its unit normal n that the
// voxel holding the result touches no plane through p with that normal (a voxel box reaches
// ½‖n‖₁·h from its centre toward a plane, the lifted point's voxel centre lies within
// ½‖n‖₁·h of it).
VL_HOSTDEV inline vec3 liftOffSurface(const vec3& p, const vec3& n, float h) {
    return p + n * ((glm::abs(n.x) + glm::abs(n.y) + glm::abs(n.z) + 0.01f) * h);
}

// Whether level-0 voxel `voxel` of `occupancy` blocks a path (α ≥ ½: a solid wall).
VL_HOSTDEV inline bool blocksPath(const MipLevelView& occupancy, IndexLeafCache& leaves, const nanovdb::Coord& voxel) {
    const int32_t index = leaves.value(*occupancy.index, voxel);
    return index >= 0 && occupancy.texels[size_t(index) * size_t(occupancy.facesPerVoxel)].alpha >= 0.5f;
}

// Whether the segment a → b (world) crosses no voxel of `occupancy` with α ≥ ½ (a solid
// wall) besides the voxels holding its ends, sampled at most a voxel apart: consecutive
// samples then differ by at most a voxel along every axis, so none jumps over a layer of
// voxels one thick (a wall). With `planes` (IrradianceCacheView::surfacePlanes) a solid voxel
// blocks only a path whose ends lie on opposite sides of its surface's plane, or on it (and
// always where its normals cancel): a path along a room's corner runs inside the other
// wall's voxel layer without crossing that wall, and the receivers within half a voxel of
// the corner, finding no gather point they could see, fell back to cones and drew a dashed
// dark line down every corner of a room with thick walls.
VL_HOSTDEV inline bool clearPath(const MipLevelView& occupancy, float h, const vec3& a, const vec3& b,
                                 const vec4* planes = nullptr) {
    if (!occupancy.index) return true;
    const vec3 from = a / h, to = b / h;
    const float length = glm::length(to - from);
    const int steps = static_cast<int>(glm::ceil(length));
    const auto voxelAt = [](const vec3& x) {
        return nanovdb::Coord(int(glm::floor(x.x + 0.5f)), int(glm::floor(x.y + 0.5f)), int(glm::floor(x.z + 0.5f)));
    };
    const nanovdb::Coord first = voxelAt(from), final = voxelAt(to);
    nanovdb::Coord last = first;
    IndexLeafCache leaves;
    for (int k = 1; k < steps; ++k) {
        const nanovdb::Coord voxel = voxelAt(from + (to - from) * (float(k) / float(steps)));
        if (voxel == last || voxel == first || voxel == final) continue;
        last = voxel;
        const int32_t index = leaves.value(*occupancy.index, voxel);
        if (index < 0 || !(occupancy.texels[size_t(index) * size_t(occupancy.facesPerVoxel)].alpha >= 0.5f)) continue;
        if (!planes) return false;
        const vec4 plane = planes[index];
        const vec3 n(plane);
        if (!(glm::dot(n, n) > 0.25f)) return false;
        const float sa = glm::dot(n, a) - plane.w, sb = glm::dot(n, b) - plane.w;
        if (!((sa > 0.0f && sb > 0.0f) || (sa < 0.0f && sb < 0.0f))) return false;
    }
    return true;
}

// The interpolation weight of gather point q at surface point p with unit normal n,
// visibility and its mass aside; 0 where q does not apply. Every gather point q (normal n_q)
// of the 3 × 3 × 3 cells around p's cell that p can see (visitCachePoints) weighs
//   w_q = m_q · Π_axes max(0, 1 − |p_a − q_a| / H) · max(0, n·n_q) · max(0, 1 − |(p − q)·n_q| / H),
// H = 2^L·h: a tent one cell wide, facing the same way as p, lying in p's plane (the far side
// of a thin wall faces away; a shelf over a floor lies in another plane), and the irradiance is
// Σ w_q E_q / Σ w_q. m_q is the point's mass (GatherPoint::mass). The home a receiver takes its
// points through is chosen by this geometric part alone (a thin strip's own point should not
// lose it to a fuller layer's in the same cell); visitFromHome applies the masses.
VL_HOSTDEV inline float cacheWeight(const GatherPoint& q, const vec3& p, const vec3& n, float inverseCell) {
    // The tents along the axes first: most points a receiver's home links lie a cell or more
    // away on some axis, and their weight is 0 whatever they face.
    const vec3 d = p - q.position;
    const vec3 tent = vec3(1.0f) - glm::abs(d) * inverseCell;
    if (!(tent.x > 0.0f && tent.y > 0.0f && tent.z > 0.0f)) return 0.0f;
    const float facing = glm::dot(n, q.normal);
    if (!(facing > 0.0f)) return 0.0f;
    float w = facing * glm::max(0.0f, 1.0f - glm::abs(glm::dot(d, q.normal)) * inverseCell);
    for (int a = 0; a < 3; ++a) w *= tent[a];
    return w;
}

// Calls visit(point index, weight) for every point with weight > 0 at (p, n) that p sees;
// returns the weights' sum (0: no point applies). Why a visibility test: two rooms' floors in
// one plane, a wall between them, face the same way, and the dark room's floor by the wall
// took light from the lit room's floor points. Where no point applies (p by a wall it cannot
// see past, an isolated sliver) the caller gathers at p itself (cones, or rays where the points
// were gathered by rays: shade_element.h), so every receiver gets light.
//
// Visibility is tested once per receiver: its home point is the point of its own cell (else of
// the cells around) with the largest geometric weight (cacheWeight, no mass) and a clear path
// from p, and the points it takes are the home's neighbours (linked by IrradianceCache::link,
// which tested their paths from the home). A wall between p and a point a cell away nearly
// always stands between the home and that point too, and one test per receiver instead of one
// per point made the bounces' weights several times cheaper at the same lightmap error.
template <typename Visit>
VL_HOSTDEV inline float visitFromHome(const IrradianceCacheView& cache, uint32_t home, const vec3& p, const vec3& n,
                                      Visit&& visit);

template <typename Visit>
VL_HOSTDEV inline float visitCachePoints(const IrradianceCacheView& cache, const vec3& p, const vec3& n, Visit&& visit) {
    if (!cache.cells || cache.pointCount == 0 || !cache.neighbourBegin) return 0.0f;
    const float h = cache.voxelSize;
    const float inverseCell = 1.0f / ldexpf(h, cache.level);
    const vec3 voxel = glm::floor(p / h + vec3(0.5f));
    constexpr float kIndexLimit = 1.0e9f;
    if (!(glm::abs(voxel.x) < kIndexLimit && glm::abs(voxel.y) < kIndexLimit && glm::abs(voxel.z) < kIndexLimit))
        return 0.0f;
    const ivec3 centre(cellOf(int(voxel.x), cache.level), cellOf(int(voxel.y), cache.level),
                       cellOf(int(voxel.z), cache.level));
    IndexLeafCache cells;
    const vec3 lifted = liftOffSurface(p, n, h);
    // The home: own cell first (ring 0), then the cells around (ring 1); within a ring the
    // geometrically heaviest points first (ties: the lower index), each tried until one is
    // seen, at most kHomeTries paths in all.
    constexpr int kHomeTries = 4;
    constexpr int kMaxCandidates = 64;
    uint32_t candidate[kMaxCandidates];
    float weight[kMaxCandidates];
    uint32_t home = ~0u;
    int tries = 0;
    for (int ring = 0; ring <= 1 && home == ~0u; ++ring) {
        int count = 0;
        for (int dz = -ring; dz <= ring; ++dz)
            for (int dy = -ring; dy <= ring; ++dy)
                for (int dx = -ring; dx <= ring; ++dx) {
                    if (ring == 1 && dx == 0 && dy == 0 && dz == 0) continue;
                    const int32_t slot = cells.value(*cache.cells, nanovdb::Coord(centre.x + dx, centre.y + dy, centre.z + dz));
                    if (slot < 0) continue;
                    for (uint32_t q = cache.cellBegin[slot]; q < cache.cellBegin[slot + 1] && count < kMaxCandidates; ++q) {
                        const float w = cacheWeight(cache.points[q], p, n, inverseCell);
                        if (w > 0.0f) {
                            candidate[count] = q;
                            weight[count++] = w;
                        }
                    }
                }
        for (; tries < kHomeTries && home == ~0u; ++tries) {
            int best = -1;
            for (int k = 0; k < count; ++k)
                if (weight[k] > 0.0f && (best < 0 || weight[k] > weight[best] ||
                                         (weight[k] == weight[best] && candidate[k] < candidate[best])))
                    best = k;
            if (best < 0) break;
            const GatherPoint& q = cache.points[candidate[best]];
            if (clearPath(cache.occupancy, h, lifted, liftOffSurface(q.position, q.normal, h), cache.surfacePlanes))
                home = candidate[best];
            weight[best] = 0.0f;  // tried
        }
    }
    return visitFromHome(cache, home, p, n, visit);
}

// visitCachePoints from a home already known (~0u: none): the home's neighbours (itself
// among them) with weight > 0 at (p, n).
template <typename Visit>
VL_HOSTDEV inline float visitFromHome(const IrradianceCacheView& cache, uint32_t home, const vec3& p, const vec3& n,
                                      Visit&& visit) {
    if (home == ~0u || !cache.neighbourBegin) return 0.0f;
    const float inverseCell = 1.0f / ldexpf(cache.voxelSize, cache.level);
    float total = 0.0f;
    for (uint32_t k = cache.neighbourBegin[home]; k < cache.neighbourBegin[home + 1]; ++k) {
        const uint32_t q = cache.neighbours[k];
        const float w = cacheWeight(cache.points[q], p, n, inverseCell) * cache.points[q].mass;
        if (!(w > 0.0f)) continue;
        visit(q, w);
        total += w;
    }
    return total;
}

// The irradiance at a gather point: `turns` cone sets (coneTraceIrradiance) turned by
// point.turn + t/turns, t = 0 … turns − 1, averaged. Each set tiles the hemisphere with
// gaps between its cones; the turned copies look into them.
VL_HOSTDEV inline vec3 gatherAtPoint(const MipView& mips, const GatherPoint& point, const ConeSet& set,
                                     const ConeSettings& settings, int turns) {
    vec3 sum(0.0f);
    for (int t = 0; t < turns; ++t) {
        float turn = point.turn + float(t) / float(turns);
        turn -= glm::floor(turn);
        sum += coneTraceIrradiance(mips, point.position, point.normal, set, settings, nullptr, turn, &point.tangent);
    }
    return sum / float(turns);
}

// Interpolated irradiance at (p, n); false when no gather point applies.
VL_HOSTDEV inline bool interpolateIrradiance(const IrradianceCacheView& cache, const vec3& p, const vec3& n, vec3& E) {
    vec3 sum(0.0f);
    const float total = visitCachePoints(cache, p, n, [&](uint32_t q, float w) { sum += w * cache.irradiance[q]; });
    if (!(total > 0.0f)) return false;
    E = sum / total;
    return true;
}

struct GatherScene;

class IrradianceCache {
public:
    IrradianceCache() = default;
    // The gather points of `voxels`' surface sides at cell level `level` (0 … 16; SettingsError
    // outside). Error when normals or axis weights do not match the voxel count.
    //
    // A voxel's sides (voxel_scene.h voxelSides) are grouped by the cell the voxel lies in
    // (cell C holds voxels 2^L·C … 2^L·C + 2^L − 1, as mip level L in radiance_mips.h) and by
    // the signed axis their normal is closest to: a cell holding a floor and a wall has a point
    // for each, a thin wall one for each of its sides. A point sits at the mean centre of its
    // voxels, facing the normalised mean of their side normals.
    //
    // With `enclosed` (what rays meet), a point lies on the open part of its layer, the part
    // whose probe rays do not mostly meet the backs of surfaces (shade_element.h isBuried). A
    // cell a block's foot crosses holds floor on both sides of its wall, and the mean of all of
    // it fell under the block, or beside its wall: the receivers around took that point's
    // darkness (docs/decisions.md, "Gather points on open surface"). Each quarter of a layer is
    // probed at the mean of its surface points; where the quarters disagree, every voxel of the
    // layer is.
    IrradianceCache(const VoxelScene& voxels, int level, const GatherScene* enclosed = nullptr);
    // SettingsError for a level outside 0 … 16.
    static void checkLevel(int level);

    int level() const { return level_; }
    double voxelSize() const { return voxelSize_; }
    const std::vector<GatherPoint>& points() const { return points_; }
    const std::vector<vec3>& irradiance() const { return irradiance_; }
    // Cone-traced irradiance at every point (gatherAtPoint with `turns` turned sets, 1 …
    // kMaxGatherTurns, else SettingsError), TBB-parallel, the same bytes at any thread count.
    // `progress` advances once per point.
    void gather(const MipView& mips, const ConeSettings& settings, int turns = 1, Progress* progress = nullptr);
    // Irradiance computed elsewhere (a GPU launcher), one per point.
    void setIrradiance(std::vector<vec3> irradiance);
    // How the points were gathered: by n × n rays (n > 0) or by cones (0), for the receivers
    // no point applies to (IrradianceCacheView::raysPerAxis).
    void setRaysPerAxis(int raysPerAxis) { raysPerAxis_ = raysPerAxis; }
    // Finds each point's neighbours: the points of the 3 × 3 × 3 cells around its own that
    // face its way (n·n_q > 0) and that it sees (clearPath between both lifted off their
    // surfaces, through level 0 of `mips`), itself included. Receivers interpolate from
    // these (visitCachePoints); before linking no point applies.
    void link(const MipView& mips);
    // `mips`: the radiance mips of the same voxels, whose level 0 tells what blocks the
    // path between a receiver and a gather point.
    IrradianceCacheView view(const MipView& mips) const;
    const CellIndexGrid* cellGrid() const { return cells_.grid<int32_t>(); }
    const std::vector<uint32_t>& cellBegin() const { return cellBegin_; }
    // The point of the layer that side k (voxelSides order) of voxel i belongs to, at slot
    // 6·i + k; ~0u for slots with no side.
    const std::vector<uint32_t>& sidePoints() const { return sidePoints_; }
    size_t memoryBytes() const;

private:
    int level_ = 0;
    double voxelSize_ = 0.0;
    std::vector<GatherPoint> points_;
    std::vector<uint32_t> cellBegin_;
    std::vector<vec3> irradiance_;
    std::vector<ivec3> cellCoords_;  // per cell slot
    std::vector<uint32_t> neighbourBegin_, neighbours_;
    std::vector<vec4> surfacePlanes_;  // per voxel (IrradianceCacheView::surfacePlanes)
    std::vector<uint32_t> sidePoints_;  // per voxel side slot (sidePoints())
    int raysPerAxis_ = 0;
    nanovdb::GridHandle<nanovdb::HostBuffer> cells_;
};

}  // namespace vl
