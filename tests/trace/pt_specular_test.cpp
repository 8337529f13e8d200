// Specular paths end to end: a camera looking at an emitter through a mirror or through a
// glass slab. After a delta lobe the emitter hit takes MIS weight 1, so a perfect mirror
// shows the emitter exactly; a non-absorbing slab of index n at normal incidence passes
// (1 − R)/(1 + R) of the radiance (incoherent sum over its internal reflections, R = F₀).
#include "pt_scenes.h"

#include "trace/camera.h"
#include "trace/path_tracer.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

// A quad facing +Z at depth z, spanning [-h, h]².
Mesh wall(const std::string& name, float z, float h, int material, bool facePlusZ) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {{-h, -h, z}, {h, -h, z}, {h, h, z}, {-h, h, z}};
    const vec3 n(0, 0, facePlusZ ? 1.0f : -1.0f);
    mesh.normals.assign(4, n);
    mesh.indices = facePlusZ ? std::vector<uint32_t>{0, 1, 2, 0, 2, 3} : std::vector<uint32_t>{0, 2, 1, 0, 3, 2};
    return mesh;
}

CameraModel narrowCamera(vec3 position, vec3 forward) {
    Camera c;
    c.position = position;
    c.forward = forward;
    c.up = vec3(0, 1, 0);
    c.yfov = 0.02f;  // every ray within 0.6° of the axis: normal incidence for Fresnel
    return makeCameraModel(c, 8, 8);
}

}  // namespace

TEST_CASE("A perfect mirror shows the emitter behind the camera exactly", "[trace]") {
    Scene scene;
    scene.sourcePath = "mirror";
    Material mirror;
    mirror.name = "mirror";
    mirror.baseColorFactor = vec4(1.0f);
    mirror.metallic = 1.0f;
    mirror.roughness = 0.0f;
    scene.materials.push_back(mirror);
    scene.materials.push_back(lambert("light", vec3(0.0f), vec3(3.0f, 2.0f, 1.0f)));
    scene.meshes.push_back(wall("mirror", -1.0f, 2.0f, 0, true));
    scene.meshes.push_back(wall("light", 1.0f, 2.0f, 1, false));  // behind the camera, facing it
    TraceFixture f(std::move(scene));
    PathTracerSettings settings;
    settings.samplesPerPixel = 4;
    settings.quiet = true;
    const TraceResult r = renderCamera(f.trace, f.bvh, narrowCamera(vec3(0.0f), vec3(0, 0, -1)), settings);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            REQUIRE(r.beauty.at(x, y, 0) == Approx(3.0f).epsilon(1e-6));
            REQUIRE(r.beauty.at(x, y, 2) == Approx(1.0f).epsilon(1e-6));
            REQUIRE(r.direct.at(x, y, 1) == Approx(2.0f).epsilon(1e-6));  // scattered once: direct
        }
}

TEST_CASE("A glass slab transmits one minus R over one plus R at normal incidence", "[trace]") {
    for (float ior : {1.5f, 2.0f}) {
        Scene scene;
        scene.sourcePath = "slab";
        Material glass;
        glass.name = "glass";
        glass.baseColorFactor = vec4(1.0f);
        glass.metallic = 0.0f;
        glass.transmission = 1.0f;
        glass.ior = ior;
        glass.doubleSided = true;
        scene.materials.push_back(glass);
        scene.materials.push_back(lambert("light", vec3(0.0f), vec3(1.0f)));
        // A closed slab between z = −1.2 and −1 (front, back and four sides).
        const float h = 3.0f;
        scene.meshes.push_back(wall("front", -1.0f, h, 0, true));
        scene.meshes.push_back(wall("back", -1.2f, h, 0, false));
        Mesh sides;
        sides.name = "sides";
        sides.material = 0;
        const vec3 c[8] = {{-h, -h, -1.2f}, {h, -h, -1.2f}, {h, h, -1.2f}, {-h, h, -1.2f},
                           {-h, -h, -1.0f}, {h, -h, -1.0f}, {h, h, -1.0f}, {-h, h, -1.0f}};
        const int quads[4][4] = {{0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
        for (const auto& q : quads) {
            const vec3 n = glm::normalize(glm::cross(c[q[1]] - c[q[0]], c[q[2]] - c[q[0]]));
            for (int k : {0, 1, 2, 0, 2, 3}) {
                sides.indices.push_back(static_cast<uint32_t>(sides.positions.size()));
                sides.positions.push_back(c[q[k]]);
                sides.normals.push_back(n);
            }
        }
        scene.meshes.push_back(sides);
        scene.meshes.push_back(wall("light", -3.0f, 20.0f, 1, true));  // behind the slab, facing the camera
        TraceFixture f(std::move(scene));
        PathTracerSettings settings;
        settings.samplesPerPixel = 256;
        settings.quiet = true;
        settings.path.maxBounces = 200;  // delta paths bounce inside the slab
        const TraceResult r = renderCamera(f.trace, f.bvh, narrowCamera(vec3(0.0f), vec3(0, 0, -1)), settings);
        const double R = std::pow((ior - 1.0) / (ior + 1.0), 2.0);
        const double expected = (1.0 - R) / (1.0 + R);
        double sum = 0.0, var = 0.0;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                sum += r.beauty.at(x, y, 0);
                var += r.variance.at(x, y, 0);
            }
        const double mean = sum / 64.0, sigma = std::sqrt(var) / 64.0;
        INFO("ior " << ior << " mean " << mean << " expected " << expected << " sigma " << sigma);
        REQUIRE(std::abs(mean - expected) <= 4.0 * sigma + 1e-4);
        REQUIRE(sigma < 0.01);
    }
}
