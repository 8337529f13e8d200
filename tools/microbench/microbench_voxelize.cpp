// Voxelization speed and memory beside OpenVDB's own tools::meshToVolume (unsigned
// distance, narrow band of 1 voxel: about the voxels a conservative voxelization touches)
// on the same triangles at the same voxel size, in one run.
//
//   build/microbench/microbench_voxelize [scene.glb] [resolution ...]
// Default: ../shared/scenes/interior-zdm2-godot/zdm2.glb at resolutions 256 and 512.
// Each timing is the best of a few repetitions (wall clock, all TBB threads).
#include "scene/gltf_loader.h"
#include "voxel/voxelize.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

template <typename F>
double bestSeconds(int repetitions, F&& run) {
    double best = 1e30;
    for (int r = 0; r < repetitions; ++r) {
        const auto start = std::chrono::steady_clock::now();
        run();
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return best;
}

double mib(double bytes) { return bytes / (1024.0 * 1024.0); }

}  // namespace

int main(int argc, char** argv) {
    std::string path = std::string(VOXLIGHT_SOURCE_DIR) + "/../shared/scenes/interior-zdm2-godot/zdm2.glb";
    std::vector<int> resolutions;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        if (arg.find_first_not_of("0123456789") == std::string::npos) resolutions.push_back(std::atoi(arg.c_str()));
        else path = arg;
    }
    if (resolutions.empty()) resolutions = {256, 512};

    openvdb::initialize();
    vl::Scene scene;
    try {
        scene = vl::loadGltf(path);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "microbench_voxelize: %s\n", e.what());
        return 1;
    }

    // The cost of texture sampling, on the same geometry: every mesh under a 256² checker
    // (bilinear), projected from above with a 2 m period.
    vl::Scene textured = scene;
    {
        vl::Texture checker;
        checker.name = "checker";
        checker.image = vl::Image(256, 256, 4, 1.0f);
        for (int y = 0; y < 256; ++y)
            for (int x = 0; x < 256; ++x)
                checker.image.setRgb(x, y, ((x / 16 + y / 16) % 2) ? vl::vec3(0.8f) : vl::vec3(0.2f, 0.3f, 0.4f));
        textured.textures = {checker};
        vl::Material material;
        material.name = "checker";
        material.baseColorTexture.texture = 0;
        textured.materials = {material};
        for (vl::Mesh& mesh : textured.meshes) {
            mesh.material = 0;
            mesh.uv0.clear();
            for (const vl::vec3& p : mesh.positions) mesh.uv0.push_back(vl::vec2(p.x, p.z) * 0.5f);
        }
    }

    // The same triangles for OpenVDB, in world space.
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    for (const vl::Mesh& mesh : scene.meshes) {
        const auto base = static_cast<uint32_t>(points.size());
        for (const vl::vec3& p : mesh.positions) points.emplace_back(p.x, p.y, p.z);
        for (size_t t = 0; t < mesh.triangleCount(); ++t)
            triangles.emplace_back(base + mesh.indices[3 * t], base + mesh.indices[3 * t + 1], base + mesh.indices[3 * t + 2]);
    }
    const vl::Aabb box = scene.bounds();
    const vl::vec3 extent = box.extent();
    std::printf("scene %s: %zu triangles, %zu meshes, extent %.3f x %.3f x %.3f m, emitters: %s, threads: %d\n",
                path.c_str(), triangles.size(), scene.meshes.size(), extent.x, extent.y, extent.z,
                scene.hasEmitters() ? "yes" : "no", tbb::info::default_concurrency());

    std::printf("%-6s %-15s %9s %12s %11s %11s %11s %10s %10s\n", "res", "method", "time s", "tris/s",
                "active vox", "fragments", "MiB used", "MiB dense", "used/dense");
    for (int resolution : resolutions) {
        vl::VoxelSettings settings;
        settings.resolution = resolution;
        const double h = vl::voxelSizeFor(scene, settings);
        const int repetitions = 3;

        struct Variant {
            const char* name;
            const vl::Scene* scene;
            int samples;
            bool fillInterior;
        };
        for (const Variant& variant :
             {Variant{"voxlight", &scene, 4, false}, Variant{"vl tex s=4", &textured, 4, false},
              Variant{"vl tex s=1", &textured, 1, false}, Variant{"vl fill", &scene, 4, true}}) {
            settings.texelSamples = variant.samples;
            settings.fillInterior = variant.fillInterior;
            vl::VoxelizeStats stats;
            size_t active = 0;
            const double seconds = bestSeconds(repetitions, [&] {
                const vl::VoxelScene voxels = vl::voxelize(*variant.scene, settings, nullptr, &stats);
                active = voxels.size();
            });
            const std::string name = variant.name;
            std::printf("%-6d %-15s %9.3f %12.0f %11zu %11zu %11.1f %10.1f %10.4f\n", resolution, name.c_str(), seconds,
                        double(triangles.size()) / seconds, active, stats.fragments, mib(stats.channelBytes),
                        mib(stats.denseBytes), stats.channelBytes / stats.denseBytes);
        }

        const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(h);
        openvdb::FloatGrid::Ptr grid;
        const double vdbSeconds = bestSeconds(repetitions, [&] {
            grid = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*transform, points, triangles, {},
                                                                                 1.0f);
        });
        const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
        const double dense = double(bbox.volume()) * sizeof(float);
        std::printf("%-6d %-15s %9.3f %12.0f %11llu %11s %11.1f %10.1f %10.4f\n", resolution, "meshToVolume", vdbSeconds,
                    double(triangles.size()) / vdbSeconds, static_cast<unsigned long long>(grid->activeVoxelCount()),
                    "-", mib(double(grid->memUsage())), mib(dense), double(grid->memUsage()) / dense);
        std::printf("%-6d voxel size %.5f m\n", resolution, h);
    }
    std::printf("voxlight: the scene's own materials; vl tex: under a checker texture, s = texelSamples;\n"
                "vl fill: with fillInterior (closed meshes made solid through their depth).\n"
                "voxlight MiB: coords + albedo, normal, six axis weights, (emission), opacity, solid as arrays;\n"
                "dense: the same channels over the active bounding box. meshToVolume: one float grid (memUsage)\n"
                "against a dense float array over its active bounding box.\n");
    return 0;
}
