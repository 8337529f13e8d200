// The scene every stage reads: world-space triangle meshes (the node hierarchy already
// applied), materials, textures, punctual lights and cameras, in glTF's units converted
// as DESIGN.md states: metres, +Y up, punctual intensity ÷ 683 (W/sr; W/m² for
// directional lights), emission = emissiveFactor × emissiveStrength as radiance W/(m²·sr).
#pragma once

#include "core/aabb.h"
#include "core/image.h"
#include "core/math.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vl {

enum class WrapMode { Repeat, ClampToEdge, MirroredRepeat };

struct Texture {
    std::string name;   // the image's name or URI, for messages
    Image image;        // RGBA float; colour textures already sRGB-decoded to linear
    WrapMode wrapS = WrapMode::Repeat;
    WrapMode wrapT = WrapMode::Repeat;
    bool nearest = false;  // magnification filter NEAREST; bilinear otherwise
};

// KHR_texture_transform: uv' = T · R · S · uv.
struct TextureTransform {
    vec2 offset{0.0f};
    vec2 scale{1.0f};
    float rotation = 0.0f;
};

struct TextureRef {
    int texture = -1;  // index into Scene::textures; -1 = none
    int texCoord = 0;  // which TEXCOORD_n set (0 or 1)
    TextureTransform transform;
    bool valid() const { return texture >= 0; }
};

enum class AlphaMode { Opaque, Mask, Blend };

struct Material {
    std::string name;
    vec4 baseColorFactor{1.0f};
    TextureRef baseColorTexture;
    vec3 emissiveFactor{0.0f};
    float emissiveStrength = 1.0f;  // KHR_materials_emissive_strength
    TextureRef emissiveTexture;
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    bool doubleSided = false;
    float metallic = 1.0f;
    float roughness = 1.0f;
    float transmission = 0.0f;  // KHR_materials_transmission
    float ior = 1.5f;           // KHR_materials_ior

    vec3 emission() const { return emissiveFactor * emissiveStrength; }
    bool emissive() const { return maxComponent(emission()) > 0.0f; }
};

// One glTF primitive instance in world space. Triangles only, counter-clockwise seen from
// the front (winding already flipped for transforms with a negative determinant).
struct Mesh {
    std::string name;          // "<mesh name>/<primitive index>" (node name when the mesh has none)
    std::string node;          // name of the glTF node that places it (what Blender calls the object)
    // The glTF mesh and primitive it was read from (glTF out writes its lightmap to that
    // primitive's material); −1 for a mesh made in code.
    struct Source {
        int mesh = -1;
        int primitive = -1;
        int node = -1;          // the node that places this instance
        bool mirrored = false;  // its transform mirrors: the loader swapped two corners of each triangle
        // Each vertex's index in the glTF primitive where the vertices were split after
        // loading (generated lightmap UVs); empty: the primitive's own order.
        std::vector<uint32_t> vertices;
    } source;
    int material = -1;         // index into Scene::materials; -1 = the glTF default material
    std::vector<vec3> positions;
    std::vector<vec3> normals;   // unit length, one per position (area-weighted when the file has none)
    std::vector<vec2> uv0;       // empty when absent
    std::vector<vec2> uv1;       // empty when absent: the lightmap set
    std::vector<vec4> colors;    // COLOR_0, empty when absent
    std::vector<uint32_t> indices;  // 3 per triangle

    size_t triangleCount() const { return indices.size() / 3; }
    // The mesh's name, node, source (but its vertex map) and material, without vertices or
    // triangles: what splitting its vertices starts from.
    Mesh withoutVertices() const {
        Mesh out;
        out.name = name;
        out.node = node;
        out.source = source;
        out.source.vertices.clear();
        out.material = material;
        return out;
    }
    // Appends a copy of vertex v of `from` (position and every attribute `from` has but uv1,
    // which a new vertex is given by who splits it).
    void appendVertexOf(const Mesh& from, uint32_t v) {
        positions.push_back(from.positions[v]);
        if (!from.normals.empty()) normals.push_back(from.normals[v]);
        if (!from.uv0.empty()) uv0.push_back(from.uv0[v]);
        if (!from.colors.empty()) colors.push_back(from.colors[v]);
    }
};

enum class LightType { Point, Spot, Directional };

// What a punctual light's bake holds (docs/light-bake-modes.md): its direct and indirect light
// (All), or its indirect light alone (Indirect), the engine drawing its direct light per pixel
// with its own shadows, sharp at any texel size; or its indirect light and, in one channel of
// the shadowmask, its visibility per texel (Shadowmask), the engine drawing its unshadowed
// direct light times the mask. Unset: the bake's setting decides (BakeSettings::lightBake).
enum class LightBake { Unset, All, Indirect, Shadowmask };

// "all", "indirect", "shadowmask" (Unset: "all"), as job files, settings and glTF write them.
const char* lightBakeName(LightBake mode);
// The mode a name gives; false for any other text.
bool parseLightBake(const std::string& name, LightBake& mode);

// A shadowmask image is RGBA: one channel per shadowmask light, four at most (as Unity's).
constexpr int kShadowmaskChannels = 4;
// A shadowmask texel none of whose samples faces its light, before it is filled from its
// neighbours (lightmap/dilate.h fillUnseenShadowmask).
constexpr float kShadowmaskUnseen = -1.0f;

// glTF punctual intensities are photometric (cd, lx); Blender's exporter multiplies watts
// per steradian by 683 lm/W, so dividing by it gives back radiometric units (DESIGN.md). The
// loader divides, glTF out multiplies.
constexpr double kLumensPerWatt = 683.0;

struct Light {
    std::string name;
    LightType type = LightType::Point;
    vec3 color{1.0f};
    float intensity = 1.0f;         // W/sr (point, spot) or W/m² (directional), after ÷ 683
    float range = 0.0f;             // 0 = infinite
    float innerConeAngle = 0.0f;    // radians (spot)
    float outerConeAngle = 0.7853981634f;
    vec3 position{0.0f};            // world space
    vec3 direction{0.0f, 0.0f, -1.0f};  // unit, the direction the light travels (node −Z)
    // A directional light's disk as seen from the scene (Cycles' sun "angle"), radians: its
    // irradiance comes evenly from a cone of this diameter, so shadows have penumbrae. 0: a
    // single direction. glTF has none; a job file's light sets it ("angle", degrees).
    float angularDiameter = 0.0f;
    LightBake bake = LightBake::Unset;
    int sourceLight = -1;  // its KHR_lights_punctual index; -1: not from the file (a job file's)
    int maskChannel = -1;  // Shadowmask: its channel of the shadowmask (resolveLightBake); else -1

    vec3 radiantIntensity() const { return color * intensity; }
};

struct Camera {
    std::string name;
    vec3 position{0.0f};
    vec3 forward{0.0f, 0.0f, -1.0f};  // unit
    vec3 up{0.0f, 1.0f, 0.0f};        // unit, orthogonal to forward
    float yfov = 0.8f;                // radians
    float aspectRatio = 0.0f;         // width / height; 0 = take it from the image size
    float apertureRadius = 0.0f;      // thin lens (metres); 0 = pinhole
    float focusDistance = 1.0f;       // metres along forward
};

// An equirectangular HDR image of the sky, linear RGB W/(m²·sr), rows from the top
// (trace/sky.h: its mapping, Blender's).
struct SkyImage {
    std::string path;  // for messages
    int width = 0, height = 0;
    std::vector<vec3> texels;
};

// Light from beyond the scene in every direction not blocked by it: a uniform radiance
// W/(m²·sr) (Cycles' world colour) plus, optionally, an image turned by `rotationDegrees`
// counterclockwise seen from above and scaled by `intensity` (Cycles' environment texture
// and background strength). glTF has none; a job file's or the command line's sky settings
// give it (bake_settings.h).
struct Sky {
    vec3 radiance{0.0f};
    std::shared_ptr<const SkyImage> image;
    float rotationDegrees = 0.0f;
    float intensity = 1.0f;
    bool present() const { return maxComponent(radiance) > 0.0f || (image && intensity > 0.0f); }
    // The mean over all directions (each pixel by its solid angle): one colour for viewers.
    vec3 meanRadiance() const;
};

// The image at `path` (.hdr, .exr or anything OpenImageIO reads; 8- and 16-bit files decoded
// from sRGB, as Blender reads them) as a sky: InputError naming
// the file and the pixel for a missing or unreadable file, fewer than three channels' worth
// of colour (one channel is grey), or a negative or non-finite value.
std::shared_ptr<const SkyImage> loadSkyImage(const std::string& path);

// Positions, directions and lengths are in metres in the scene's local frame: world =
// origin + frame · local, origin the centre of the geometry's bounding box, found in double
// precision before anything is rounded to float, frame a rotation (the identity until a bake
// turns the scene into its own frame: scene/own_frame.h). Why: float holds a
// position 10 km from the world origin to 1 mm, and voxels anchored at the world origin fell
// at other offsets inside their walls when the scene moved; in the local frame a translated
// scene is the same floats, and a turned one the same up to rounding.
struct Scene {
    std::string sourcePath;  // the file it came from, for messages
    std::string name;        // file stem, used for output folders
    glm::dvec3 origin{0.0};  // world position of the local frame's origin
    glm::dmat3 frame{1.0};   // the local frame's axes in world space (columns), a rotation
    std::vector<Mesh> meshes;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<Light> lights;
    std::vector<Camera> cameras;
    Sky sky;
    std::vector<std::string> warnings;  // also printed when raised; repeated in reports
    size_t degenerateTrianglesDropped = 0;

    Aabb bounds() const;
    size_t triangleCount() const;
    bool hasEmitters() const;  // any triangle with an emissive material
    // The material of a mesh; the glTF default material for -1.
    const Material& materialOf(const Mesh& mesh) const;
    // Re-expresses every position relative to `newOrigin` (world space) instead of `origin`:
    // for grids made in another frame (a .vdb whose translation is not this scene's origin).
    void moveOrigin(const glm::dvec3& newOrigin);
    // Re-expresses every position and direction in the frame whose axes are `newFrame`'s
    // columns (a rotation, world space) about the same origin: the scene stays where it is in
    // the world.
    void turnFrame(const glm::dmat3& newFrame);
};

}  // namespace vl
