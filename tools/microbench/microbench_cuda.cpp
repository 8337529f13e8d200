// GPU against CPU, kernel by kernel, on one scene (default: the project's Cornell box):
// voxel direct lighting, bake receiver shading (exact direct + cones) of the lightmap atlas
// and a camera image, and path tracing of a camera image and the lightmap. Each kernel runs
// on the CPU with 2 threads (the CI machine) and with every core, then on the GPU, in the
// same run; the table gives wall seconds, the speed-ups over both CPU runs and the largest
// relative difference of the image means (the agreement the tests check is in
// cuda/launchers.h). GPU timings include the copies to and from the device. Without a
// usable GPU it prints the CPU columns and says why.
//
// Run: build/microbench/microbench_cuda [scene.gltf] [--resolution N] [--lightmap-res N] [--size N] [--spp N]
#include "receivers/receivers.h"
#include "gather/shade_receivers.h"
#include "cone/radiance_mips.h"
#include "core/error.h"
#include "cuda/device.h"
#include "cuda/launchers.h"
#include "lighting/lighting.h"
#include "scene/gltf_loader.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"
#include "voxel/voxelize.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <tuple>
#include <vector>

using namespace vl;

namespace {

double seconds(const std::function<void()>& work) {
    const auto start = std::chrono::steady_clock::now();
    work();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double mean(const std::vector<float>& values) {
    double sum = 0.0;
    for (float v : values) sum += v;
    return values.empty() ? 0.0 : sum / double(values.size());
}

std::vector<float> flatten(const std::vector<vec3>& v) {
    std::vector<float> out;
    out.reserve(3 * v.size());
    for (const vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
    return out;
}

// One kernel: runs `cpu` at 2 threads and at every core, `gpu` when usable; each returns the
// values whose mean is compared.
void row(const char* name, bool gpuUsable, const std::function<std::vector<float>()>& cpu,
         const std::function<std::vector<float>()>& gpu) {
    std::vector<float> cpuValues, gpuValues;
    double cpu2, cpuAll, gpuSeconds = 0.0;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        cpu2 = seconds([&] { cpuValues = cpu(); });
    }
    cpuAll = seconds([&] { cpuValues = cpu(); });
    if (!gpuUsable) {
        std::printf("%-28s %10.3f %10.3f %10s\n", name, cpu2, cpuAll, "-");
        return;
    }
    gpu();  // first call pays for context creation and module loading
    gpuSeconds = seconds([&] { gpuValues = gpu(); });
    const double a = mean(cpuValues), b = mean(gpuValues);
    std::printf("%-28s %10.3f %10.3f %10.4f %9.1fx %9.1fx %12.2e\n", name, cpu2, cpuAll, gpuSeconds, cpu2 / gpuSeconds,
                cpuAll / gpuSeconds, a != 0.0 ? std::fabs(b - a) / std::fabs(a) : std::fabs(b));
}

}  // namespace

int main(int argc, char** argv) {
    std::string scenePath = std::string(VOXLIGHT_SOURCE_DIR) + "/scenes/cornell_box.gltf";
    int resolution = 128, lightmapRes = 256, size = 256, spp = 64;
    for (int i = 1; i < argc; ++i) {
        const auto value = [&](int& out) {
            if (i + 1 >= argc) throw SettingsError(std::string(argv[i]) + " needs a value");
            out = std::atoi(argv[++i]);
        };
        if (!std::strcmp(argv[i], "--resolution")) value(resolution);
        else if (!std::strcmp(argv[i], "--lightmap-res")) value(lightmapRes);
        else if (!std::strcmp(argv[i], "--size")) value(size);
        else if (!std::strcmp(argv[i], "--spp")) value(spp);
        else scenePath = argv[i];
    }
    try {
        const cuda::DeviceStatus device = cuda::probeDevice();
        std::printf("scene %s, resolution %d, lightmap %d, image %d x %d, %d spp; %d CPU threads\n", scenePath.c_str(),
                    resolution, lightmapRes, size, size, spp, tbb::info::default_concurrency());
        std::printf("GPU: %s%s\n", device.usable ? "" : "none (", (device.description + (device.usable ? "" : ")")).c_str());

        LoadOptions load;
        load.echoWarnings = false;
        const Scene scene = loadGltf(scenePath, load);
        const SceneTriangles triangles = gatherTriangles(scene);
        const Bvh bvh = Bvh::build(triangles);
        const TraceScene trace = TraceScene::build(scene, triangles);
        VoxelSettings voxelSettings;
        voxelSettings.resolution = resolution;
        const VoxelScene voxels = voxelize(scene, voxelSettings);
        LightmapSettings lightmap;
        lightmap.width = lightmap.height = lightmapRes;
        Diagnostics diagnostics(false, false);
        const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, lightmap, diagnostics);
        if (atlases.empty()) throw InputError(scenePath + ": no mesh has TEXCOORD_1: no lightmap to shade");
        const SurfaceSampleSet& texels = atlases.front().receivers;
        Camera camera = scene.cameras.empty() ? defaultCamera(scene.bounds(), 1.0f) : scene.cameras.front();
        const CameraModel model = makeCameraModel(camera, size, size);
        const CameraReceivers pixels = buildCameraReceivers(trace, bvh, model, 2);

        VoxelScene lit = voxels;
        lightVoxels(scene, lit, LightingSettings{});
        const RadianceMips mips = buildRadianceMips(lit);
        const MipView mipView = mips.view();
        PathTracerSettings pathSettings;
        pathSettings.samplesPerPixel = spp;
        pathSettings.quiet = true;

        std::printf("\n%-28s %10s %10s %10s %10s %10s %12s\n", "kernel", "CPU 2 thr s", "CPU all s", "GPU s",
                    "vs 2 thr", "vs all", "mean rel diff");
        row("voxel direct light", device.usable,
            [&] { VoxelScene v = voxels; lightVoxels(scene, v, LightingSettings{}); return flatten(v.radiance); },
            [&] { VoxelScene v = voxels; cuda::lightVoxelsCuda(scene, v, LightingSettings{}); return flatten(v.radiance); });
        for (const auto& [name, receivers, lightmap] :
             {std::tuple<const char*, const SurfaceSampleSet*, bool>{"receivers: lightmap", &texels, true},
              {"receivers: image", &pixels.receivers, false}}) {
            row(name, device.usable,
                [&] { return shadeReceivers(*receivers, trace.view(), bvh.view(), &mipView, nullptr, ConeSettings{}, DirectLightSettings{}, lightmap).indirect.pixels; },
                [&] { return cuda::shadeReceiversCuda(*receivers, trace.view(), bvh.view(), &mipView, nullptr, ConeSettings{}, DirectLightSettings{}, lightmap).indirect.pixels; });
        }
        row("path tracing: image", device.usable, [&] { return renderCamera(trace, bvh, model, pathSettings).beauty.pixels; },
            [&] { return cuda::renderCameraCuda(trace, bvh, model, pathSettings).beauty.pixels; });
        row("path tracing: lightmap", device.usable,
            [&] { return traceIrradiance(trace, bvh, texels, pathSettings).beauty.pixels; },
            [&] { return cuda::traceIrradianceCuda(trace, bvh, texels, pathSettings).beauty.pixels; });
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
