// The irradiance volume: takes a baked scene's receiver gather (gather/gather.h) and the scene;
// gives a grid of irradiance probes over the scene's bounds, in the world frame, each holding per
// colour channel the irradiance over normals as E(n)/π ≈ A + B·n (spherical harmonics to L1),
// and whether it lies in open space. What moves through a baked room (an avatar, a picked-up
// globe) is lit from it; scene.glb carries it as VOXLIGHT_irradiance_volume
// (docs/irradiance-volume.md).
//
// Why these parts: the lightmaps' own light, read the same way (fans of rays reading the voxels'
// light, the lights at their hits, the sky, the emitters), so an object and the floor under it
// agree. The punctual lights' direct light is a delta in direction, which a six-normal fit
// gets wrong by a third of its mean (a sun's: E/6 where SH's projection is E/4); it is
// projected exactly instead.
#pragma once

#include "export/gltf_export.h"
#include "gather/gather.h"
#include "receivers/receiver_scene.h"
#include "scene/scene.h"

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace vl {

struct IrradianceVolumeSettings {
    double spacing = 0.0;  // metres between probes along each axis; 0: no volume
    int raysPerAxis = 8;   // each probe's fans (six, along ±x, ±y, ±z): n × n rays
};

// Suns (directional lights) a volume keeps apart, each as its visibility per probe: a sun's
// light is one direction, whose cosine a probe's L1 smooths to a quarter of its contrast, so an
// object in a sun patch would show a terminator far softer than the sun's. A reader draws each
// one on what moves exactly, E·max(0, n·ω)/π times the visibility interpolated. A sun the engine
// draws (LightBake::Indirect, Shadowmask) is kept too: its direct light is in no probe, and its
// visibility there is what moving objects need of it (Unity's probe occlusion). Past four, suns
// of mode all go into A and B as the point lights do; engine-drawn ones are left to the engine.
constexpr int kVolumeSuns = 4;

// A probe is inside geometry when at least this share of the rays it sends hits surfaces from
// behind: it sits inside a closed solid, a wall's thickness, or under a floor.
constexpr float kProbeBackfaceShare = 0.25f;
// The rays of that test: directions spread evenly over the sphere (a Fibonacci lattice).
constexpr int kProbeInsideRays = 64;

struct IrradianceVolume {
    glm::dvec3 origin{0.0};   // world position of probe (0, 0, 0)
    glm::dvec3 spacing{0.0};  // metres between probes along world x, y, z
    glm::ivec3 counts{0};
    // Per probe, in the order of index(): A (RGB E/π, the lightmap's convention), B along world
    // x, y and z (RGB each), and 1 for a probe in open space, 0 for one inside geometry.
    std::vector<vec3> mean;
    std::vector<std::array<vec3, 3>> gradient;
    std::vector<uint8_t> valid;
    // The suns kept apart (kVolumeSuns at most): each its direction of travel (world, unit)
    // and E/π facing it; per probe, how much of each it sees (0..1, channel s for sun s).
    struct Sun {
        vec3 direction{0.0f, -1.0f, 0.0f};
        vec3 irradiance{0.0f};
        bool drawnByEngine = false;  // its bake mode indirect or shadowmask: the lightmaps hold none of its direct light
    };
    std::vector<Sun> suns;
    std::vector<std::array<float, kVolumeSuns>> sunVisibility;

    bool empty() const { return mean.empty(); }
    size_t probeCount() const { return mean.size(); }
    // Probe (i, j, k) along x, y, z: slabs of constant y, rows of constant z within them. The
    // images of scene.glb lay the probes out the same way (row j·nz + k, column i).
    size_t index(int i, int j, int k) const {
        return (size_t(j) * size_t(counts.z) + size_t(k)) * size_t(counts.x) + size_t(i);
    }
    glm::dvec3 position(int i, int j, int k) const { return origin + glm::dvec3(i, j, k) * spacing; }
};

// The world bounding box of a scene's geometry (world = origin + frame · local); lo > hi when
// it has none.
struct WorldBox {
    glm::dvec3 lo{std::numeric_limits<double>::infinity()}, hi{-std::numeric_limits<double>::infinity()};
    bool empty() const { return !(lo.x <= hi.x); }
};
WorldBox worldBox(const Scene& scene);

// Where the probes lie: at the centres of cells `spacing` wide over `box`, centred on it, at
// least one per axis. Counts zero for an empty box or a spacing not above 0. SettingsError,
// naming `sceneName` and the setting, past kMaxVolumeProbes.
struct VolumeGrid {
    glm::dvec3 origin{0.0}, spacing{0.0};
    glm::ivec3 counts{0};
    size_t probes() const { return size_t(counts.x) * size_t(counts.y) * size_t(counts.z); }
};
VolumeGrid volumeGrid(const WorldBox& box, double spacing, const std::string& sceneName);
// How many probes volumeGrid would place (any number: nothing is refused).
double volumeProbeCount(const WorldBox& box, double spacing);

// The probes over the world bounding box of `scene`'s geometry (centred on it, `spacing`
// apart, at least one per axis), each lit by `gather` (ReceiverGather::openPoints for six
// normals, plus the punctual lights the lightmaps hold, exactly) and tested for open space.
// `scene` and `tracing` are the bake's (its local frame; world = origin + frame · local).
// SettingsError past kMaxVolumeProbes. TBB-parallel; the same bytes at any thread count.
// Progress on stderr unless `quiet`.
IrradianceVolume bakeIrradianceVolume(const Scene& scene, const ReceiverScene& tracing, const ReceiverGather& gather,
                                      const IrradianceVolumeSettings& settings, bool quiet = true);

// E/π at a world point for a world unit normal, as a viewer reads it: A, B and the suns'
// visibility trilinear over the valid probes of the point's cell (all eight where none is
// valid; clamped to the grid), then the non-linear reconstruction of docs/irradiance-volume.md
// per channel, plus each sun's E·max(0, n·ω)/π times its visibility.
vec3 volumeIrradiance(const IrradianceVolume& volume, const glm::dvec3& point, const vec3& normal);

// The volume as scene.glb carries it (export/gltf_export.h ExportedIrradianceVolume): B/A
// clamped to ±2 per channel, the most a light of any directions gives (a single direction's).
ExportedIrradianceVolume encodeIrradianceVolume(const IrradianceVolume& volume);

// Back from those bytes (A through RGBM, B/A to 8 bits), for tests and readers of scene.glb.
IrradianceVolume decodeIrradianceVolume(const ExportedIrradianceVolume& encoded);

}  // namespace vl
