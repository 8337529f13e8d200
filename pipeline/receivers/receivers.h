// Receivers: the surface points a bake (cone tracing) or the reference path tracer lights.
//
// Lightmaps: every mesh with TEXCOORD_1 rasterised in texel space, a texel's covered sub-texel
// points kept as one sample per triangle (buildLightmapReceivers), in one shared atlas unless
// atlas groups name meshes for images of their own (AtlasGroup). Camera: per pixel, the
// surfaces an n × n grid of primary rays hits, and the emission seen directly
// (buildCameraReceivers).
#pragma once

#include "core/diagnostics.h"
#include "core/image.h"
#include "scene/scene.h"
#include "trace/camera.h"
#include "trace/surface_samples.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vl {

class Bvh;
class TraceScene;

constexpr int kMaxLightmapResolution = 16384;
// `lightmap-res auto`: texels at least this fine, in voxels: the bake's indirect light varies
// no faster than its voxels (its direct light is traced per texel, and sharpens with a finer
// lightmap-texel).
constexpr double kAutoTexelPerVoxel = 0.5;

// Atlas groups: meshes that share one TEXCOORD_1 layout (Blender's lightmap pack over a set
// of objects) bake into their own image at their own resolution; the meshes no group names
// stay in the shared atlas "lightmap". A group names meshes as a user sees them: a name
// selects every scene mesh whose glTF node name, glTF mesh name (all its primitives and
// instances) or full "<mesh>/<primitive>" name it equals; Blender writes object names as
// node names and mesh data names as mesh names, and the two often differ.
struct AtlasGroup {
    std::string name;                 // the image's name and file stem: letters, digits, '-', '_'
    std::vector<std::string> meshes;  // node, mesh or "<mesh>/<primitive>" names (see above)
    std::vector<uint32_t> meshIndices;  // a group the bake makes (generated UVs): these meshes, by index
    int width = 0;                    // texels; 0 × 0: the shared atlas's resolution (lightmap-res)
    int height = 0;
    std::string origin;               // where it was declared ("job.json: atlases[0]"), for messages
};

struct LightmapSettings {
    int width = 256;
    int height = 256;
    // The shared atlas's (and each atlas group's without a resolution of its own) size chosen
    // by the bake instead (`lightmap-res auto`): the smallest power-of-two square that holds
    // its charts at texels of kAutoTexelPerVoxel voxels or finer (unwrap/lightmap_uvs.h).
    bool autoResolution = false;
    // Metres per texel (`lightmap-texel`, 0: none): overrides width, height and autoResolution;
    // each atlas is then the smallest square, a multiple of 4 texels a side, that holds its
    // charts at that texel.
    double texelSize = 0.0;
    int subsamplesPerAxis = 4;     // n: sub-texel probe grid n × n (1 = texel centres only), 1..8
    bool samplePerTriangle = true; // one sample per (texel, triangle) at its covered points' centroid
    bool atlasPerMesh = false;     // each mesh its own image instead of one shared atlas
    std::vector<AtlasGroup> atlases;  // groups baked into their own images; excludes atlasPerMesh

    // SettingsError naming the setting, or the atlas group and where it was declared. Checks
    // what needs no scene; buildLightmapReceivers checks the mesh names against the scene.
    void validate() const;
    // Texels of the shared atlas and every group's image, for the memory budget.
    double maxTexels() const;
};

struct LightmapAtlas {
    std::string name;              // "lightmap" for the shared atlas; the group's name; the mesh name per mesh
    std::vector<uint32_t> meshes;  // indices into Scene::meshes baked into this image
    SurfaceSampleSet receivers;    // per texel; weights sum to 1 on covered texels
    Image mask;                    // 1 channel: 1 covered, 0 padding
    size_t coveredTexels = 0;
    size_t overlappingProbes = 0;  // sub-texel points covered by more than one triangle
};

// What a lightmap bake checks of its atlas groups against the scene, cheaply, so a bake can
// refuse them before any work: every name selects a mesh, no mesh is in two groups, and
// "lightmap" names a group only when no mesh is left for the shared atlas (SettingsError
// naming the group and where it was declared).
void checkAtlasGroups(const Scene& scene, const LightmapSettings& settings);

// The side of a square atlas holding `meshes`' own TEXCOORD_1 at `texel` metres per texel on
// average (their 3D area over their uv area), rounded up to a multiple of 4 (or to a power of
// two) within 16..maxSide; 0 where they cover no uv area.
int atlasSideForTexel(const Scene& scene, const std::vector<uint32_t>& meshes, double texel, bool powerOfTwo, int maxSide);

// The shared atlas's and the size-less atlas groups' sizes for authored TEXCOORD_1 where the
// settings ask for a texel size (lightmap-texel, or `lightmap-res auto` with autoTexel), into
// `settings`; a texel size that needs more than maxSide a side gets maxSide, with a warning.
void sizeAuthoredAtlases(const Scene& scene, LightmapSettings& settings, double autoTexel, Diagnostics& diagnostics);

// What generated lightmap UVs are for (bake.cpp): the meshes the shared atlas would bake (with
// triangles, not emitting, named by no group) that have no TEXCOORD_1, and whether some of its
// meshes have one of their own. Nothing for one image per mesh.
struct MeshesWithoutUv1 {
    std::vector<uint32_t> meshes;
    bool othersHaveUv1 = false;
};
MeshesWithoutUv1 sharedAtlasMeshesWithoutUv1(const Scene& scene, const LightmapSettings& settings);

// Lightmaps: every mesh with TEXCOORD_1 is rasterised in texel space. glTF's v runs down
// from the top of the image, so texel (x, y) (row y from the top) spans u ∈ [x, x+1)/W,
// v ∈ [y, y+1)/H. Each texel is probed on an n × n grid of sub-texel points; a point inside
// a triangle (top-left rule on shared edges, so no point counts twice on a seam) is
// covered. A texel keeps either every covered point or, by default, one sample per triangle
// at the centroid of that triangle's covered points, weighted by their share: a texel a
// chart edge crosses averages its triangles. Texels with no covered point are padding
// (mask 0), for dilation. All meshes with TEXCOORD_1 share one atlas (one image), as a
// Blender export does; emitter meshes are not baked, and a mesh without TEXCOORD_1 is
// skipped with a warning naming it.
//
// Global triangle ids follow gatherTriangles (mesh-major, every triangle). The shared atlas
// comes first when it has meshes, then the groups in the order given; a group left with no
// mesh to bake (none has TEXCOORD_1, or all emit) is reported and makes no image.
std::vector<LightmapAtlas> buildLightmapReceivers(const Scene& scene, const LightmapSettings& settings,
                                                  Diagnostics& diagnostics);

struct CameraReceivers {
    SurfaceSampleSet receivers;  // per pixel; weights 1/n² per hit
    Image emission;              // RGB: emitted radiance and the sky seen directly, pixel mean
    Image albedo;                // RGB: base colour, pixel mean (background 0)
    Image mask;                  // 1 channel: fraction of the pixel's rays that hit a surface
};

// Camera: per pixel, an n × n grid of pinhole primary rays (a G-buffer): the surface each
// ray hits, its normal turned toward the camera, weighted 1/n² (a pixel that partly sees
// the background sums to less than 1), and the emission seen directly.
//
// emissionSubsamplesPerAxis > subsamplesPerAxis samples the directly seen emission on that
// finer grid (primary rays only); otherwise emission uses the shading grid.
// samplePerTriangle: the rays of a pixel that hit the same triangle make one sample at their
// hits' centroid (normal and albedo their means, weight their share), as a lightmap texel
// keeps one sample per triangle: the n × n rays still find the pixel's edges, but a pixel
// inside one surface is shaded once.
CameraReceivers buildCameraReceivers(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                                     int subsamplesPerAxis = 1, int emissionSubsamplesPerAxis = 0,
                                     bool samplePerTriangle = false);

}  // namespace vl
