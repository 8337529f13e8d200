// The CUDA backend (issue 7). On a machine without a GPU (CI): the device choice falls back
// to the CPU and says why, --device cuda is a clear error, and the per-element functions the
// GPU threads run (trace/path_elements.h, gather/shade_element.h, shared with the CPU stages)
// are run element by element on the host and checked bit for bit against the stages' images,
// together with the array lengths the launchers copy. On a GPU machine: CPU and GPU agree on the Cornell box
// within the tolerances written in cuda/launchers.h (these tests skip with a message
// elsewhere).
#include "bake/bake.h"
#include "receivers/receivers.h"
#include "gather/shade_element.h"
#include "gather/shade_receivers.h"
#include "cone/radiance_mips.h"
#include "core/error.h"
#include "cuda/device.h"
#include "cuda/device_choice.h"
#include "cuda/launchers.h"
#include "cuda/view_extents.h"
#include "lighting/lighting.h"
#include "lighting/lighting_kernels.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "trace/bvh.h"
#include "trace/path_elements.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"
#include "voxel/voxelize.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <iostream>
#include <sstream>

using namespace vl;

namespace {

// The project's Cornell box, voxelized, lit, with its BVH, trace scene and lightmap atlas.
struct Cornell {
    Scene scene;
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene trace;
    VoxelScene voxels;
    std::vector<LightmapAtlas> atlases;
};

const Cornell& cornell() {
    static const Cornell c = [] {
        Cornell out;
        LoadOptions load;
        load.echoWarnings = false;
        out.scene = loadGltf(test::sourceDir() + "/scenes/cornell_box.gltf", load);
        out.triangles = gatherTriangles(out.scene);
        out.bvh = Bvh::build(out.triangles);
        out.trace = TraceScene::build(out.scene, out.triangles);
        VoxelSettings voxel;
        voxel.resolution = 32;
        out.voxels = voxelize(out.scene, voxel);
        lightVoxels(out.scene, out.voxels, LightingSettings{});
        LightmapSettings lightmap;
        lightmap.width = lightmap.height = 24;
        Diagnostics diagnostics(false, false);
        out.atlases = buildLightmapReceivers(out.scene, lightmap, diagnostics);
        return out;
    }();
    return c;
}

CameraModel cornellCamera(int size) {
    const Cornell& c = cornell();
    REQUIRE(!c.scene.cameras.empty());
    return makeCameraModel(c.scene.cameras[0], size, size);
}

bool sameBits(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.channels == b.channels &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

// lightVoxels' kernel runner on the host: the loop a GPU launcher replaces, one voxel at a time.
void hostVoxelRunner(const lighting::LightingView& view, uint32_t count, bool hierarchical,
                     lighting::VoxelLighting* results, lighting::KernelStats& stats) {
    lighting::IndexAccessor accessor = view.grid->getAccessor();
    for (uint32_t i = 0; i < count; ++i)
        results[i] = hierarchical ? lighting::shadeVoxel<true>(view, accessor, i, stats)
                                  : lighting::shadeVoxel<false>(view, accessor, i, stats);
}

size_t seenEmitterSamples = 0;
void countingVoxelRunner(const lighting::LightingView& view, uint32_t count, bool hierarchical,
                         lighting::VoxelLighting* results, lighting::KernelStats& stats) {
    seenEmitterSamples = cuda::emitterSampleCount(view);
    hostVoxelRunner(view, count, hierarchical, results, stats);
}

bool gpuUsable() { return cuda::probeDevice().usable; }

#define VL_SKIP_WITHOUT_GPU()                                                                     \
    do {                                                                                          \
        if (!gpuUsable()) {                                                                       \
            VL_SKIP("no GPU: " << cuda::probeDevice().description);                               \
        }                                                                                         \
    } while (0)

// The deterministic kernels' tolerance (cuda/launchers.h): per element within
// 1e-3·max(|cpu|, mean |cpu|) for at least 99.5 % of the values, means within 0.1 %.
void checkDeterministicAgreement(const std::vector<float>& gpu, const std::vector<float>& cpu, const char* what) {
    REQUIRE(gpu.size() == cpu.size());
    double meanGpu = 0.0, meanCpu = 0.0, meanAbs = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        REQUIRE(std::isfinite(gpu[i]));
        meanGpu += gpu[i];
        meanCpu += cpu[i];
        meanAbs += std::fabs(cpu[i]);
    }
    meanGpu /= double(cpu.size());
    meanCpu /= double(cpu.size());
    meanAbs /= double(cpu.size());
    size_t close = 0;
    for (size_t i = 0; i < cpu.size(); ++i)
        if (std::fabs(gpu[i] - cpu[i]) <= 1e-3 * std::max<double>(std::fabs(cpu[i]), meanAbs)) ++close;
    INFO(what << ": " << close << " of " << cpu.size() << " values within 1e-3; means " << meanGpu << " (GPU) vs "
              << meanCpu << " (CPU)");
    CHECK(double(close) >= 0.995 * double(cpu.size()));
    CHECK(std::fabs(meanGpu - meanCpu) <= 1e-3 * std::fabs(meanCpu));
}

std::vector<float> flatten(const std::vector<vec3>& v) {
    std::vector<float> out;
    for (const vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
    return out;
}

}  // namespace

TEST_CASE("Device choices parse and a wrong one names the option", "[cuda]") {
    CHECK(cuda::parseDeviceChoice("cpu") == cuda::DeviceChoice::Cpu);
    CHECK(cuda::parseDeviceChoice("cuda") == cuda::DeviceChoice::Cuda);
    CHECK(cuda::parseDeviceChoice("auto") == cuda::DeviceChoice::Auto);
    CHECK_THROWS_AS(cuda::parseDeviceChoice("gpu"), SettingsError);
    CHECK_THROWS_WITH(cuda::parseDeviceChoice("gpu"), "device 'gpu': expected cpu, cuda or auto");
    std::ostringstream messages;
    CHECK_FALSE(cuda::resolveDevice(cuda::DeviceChoice::Cpu, messages));
    CHECK(messages.str().empty());
}

TEST_CASE("Without a usable GPU auto runs on the CPU and says why", "[cuda]") {
    const cuda::DeviceStatus status = cuda::probeDevice();
    if (status.usable) {
        VL_SKIP("this machine has a GPU (" << status.description << ")");
    }
    REQUIRE_FALSE(status.description.empty());
    std::ostringstream messages;
    CHECK_FALSE(cuda::resolveDevice(cuda::DeviceChoice::Auto, messages));
    CHECK(messages.str() == "running on the CPU: " + status.description + "\n");
}

TEST_CASE("Without a usable GPU --device cuda and every launcher are clear errors", "[cuda]") {
    const cuda::DeviceStatus status = cuda::probeDevice();
    if (status.usable) {
        VL_SKIP("this machine has a GPU (" << status.description << ")");
    }
    std::ostringstream messages;
    CHECK_THROWS_WITH(cuda::resolveDevice(cuda::DeviceChoice::Cuda, messages), "--device cuda: " + status.description);
    const std::string expected = "CUDA: " + status.description;
    const Cornell& c = cornell();
    PathTracerSettings settings;
    settings.samplesPerPixel = 1;
    settings.quiet = true;
    CHECK_THROWS_WITH(cuda::renderCameraCuda(c.trace, c.bvh, cornellCamera(4), settings), expected);
    CHECK_THROWS_WITH(cuda::traceIrradianceCuda(c.trace, c.bvh, c.atlases.front().receivers, settings), expected);
    CHECK_THROWS_WITH(cuda::shadeReceiversCuda(c.atlases.front().receivers, c.trace.view(), c.bvh.view(), nullptr,
                                               nullptr, ConeSettings{}, DirectLightSettings{}, true),
                      expected);
    CHECK_THROWS_WITH(cuda::gatherIrradianceCuda({GatherPoint{}}, MipView{}, ConeSettings{}, 1), expected);
    VoxelScene voxels = c.voxels;
    CHECK_THROWS_WITH(cuda::lightVoxelsCuda(c.scene, voxels, LightingSettings{}), expected);
    CHECK(voxels.radiance == c.voxels.radiance);  // nothing was touched
}

TEST_CASE("The GPU camera kernel run on the host equals renderCamera bit for bit", "[cuda]") {
    const Cornell& c = cornell();
    const CameraModel camera = cornellCamera(12);
    PathTracerSettings settings;
    settings.samplesPerPixel = 6;
    settings.seed = 7;
    settings.quiet = true;
    const TraceResult cpu = renderCamera(c.trace, c.bvh, camera, settings);
    const PathKernelSettings k = pathKernelSettings(settings, kCameraSalt);  // what the launcher passes
    TraceResult host;
    for (Image* image : {&host.beauty, &host.direct, &host.indirect, &host.albedo, &host.variance})
        *image = Image(camera.width, camera.height, 3);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const PathEstimate e = cameraPixel(c.trace.view(), c.bvh.view(), camera, k, x, y);
            host.beauty.setRgb(x, y, e.beauty);
            host.direct.setRgb(x, y, e.direct);
            host.indirect.setRgb(x, y, e.indirect);
            host.albedo.setRgb(x, y, e.albedo);
            host.variance.setRgb(x, y, e.variance);
        }
    double sum = 0.0;
    for (float v : cpu.beauty.pixels) sum += v;
    REQUIRE(sum > 0.0);  // the comparison is not between two black images
    CHECK(sameBits(host.beauty, cpu.beauty));
    CHECK(sameBits(host.direct, cpu.direct));
    CHECK(sameBits(host.indirect, cpu.indirect));
    CHECK(sameBits(host.albedo, cpu.albedo));
    CHECK(sameBits(host.variance, cpu.variance));
}

TEST_CASE("The GPU lightmap path kernel run on the host equals traceIrradiance bit for bit", "[cuda]") {
    const Cornell& c = cornell();
    const SurfaceSampleSet& receivers = c.atlases.front().receivers;
    PathTracerSettings settings;
    settings.samplesPerPixel = 4;
    settings.quiet = true;
    const TraceResult cpu = traceIrradiance(c.trace, c.bvh, receivers, settings);
    const PathKernelSettings k = pathKernelSettings(settings, kReceiverSalt);
    Image beauty(receivers.width, receivers.height, 3), variance(receivers.width, receivers.height, 3);
    for (size_t e = 0; e < receivers.elementCount(); ++e) {
        const PathEstimate p = receiverElementPaths(c.trace.view(), c.bvh.view(),
                                                                receivers.samples.data() + receivers.begin[e],
                                                                receivers.sampleCount(e), e, k);
        beauty.setRgb(int(e % receivers.width), int(e / receivers.width), p.beauty);
        variance.setRgb(int(e % receivers.width), int(e / receivers.width), p.variance);
    }
    double sum = 0.0;
    for (float v : cpu.beauty.pixels) sum += v;
    REQUIRE(sum > 0.0);
    CHECK(sameBits(beauty, cpu.beauty));
    CHECK(sameBits(variance, cpu.variance));
}

TEST_CASE("The GPU receiver kernel run on the host equals shadeReceivers bit for bit", "[cuda]") {
    const Cornell& c = cornell();
    const SurfaceSampleSet& receivers = c.atlases.front().receivers;
    const RadianceMips mips = buildRadianceMips(c.voxels);
    const MipView mipView = mips.view();
    const ConeSettings cone;
    const DirectLightSettings direct;
    IrradianceCache cache(c.voxels, 2);
    cache.link(mipView);
    cache.gather(mipView, cone);
    const IrradianceCacheView cacheView = cache.view(mipView);
    const ConeSet& set = coneSet(cone.coneCount);
    // Both ways to the indirect light: interpolated from the gather points, and gathered by
    // every sample's own cones (no cache).
    for (const IrradianceCacheView* gathered : {&cacheView, static_cast<const IrradianceCacheView*>(nullptr)}) {
        INFO((gathered ? "interpolated" : "own cones"));
        const ReceiverLighting cpu =
            shadeReceivers(receivers, c.trace.view(), c.bvh.view(), &mipView, gathered, cone, direct, true);
        ReceiverLighting host;
        for (Image* image : {&host.direct, &host.indirect, &host.directRadiance, &host.indirectRadiance})
            *image = Image(receivers.width, receivers.height, 3);
        for (size_t e = 0; e < receivers.elementCount(); ++e) {
            const ElementLighting l = shadeReceiverElement(c.trace.view(), c.bvh.view(), &mipView, gathered, set, cone,
                                                           direct, receivers.samples.data(), receivers.begin[e],
                                                           receivers.begin[e + 1], true);
            const int x = int(e % receivers.width), y = int(e / receivers.width);
            host.direct.setRgb(x, y, l.direct);
            host.indirect.setRgb(x, y, l.indirect);
            host.directRadiance.setRgb(x, y, l.directRadiance);
            host.indirectRadiance.setRgb(x, y, l.indirectRadiance);
        }
        double direct0 = 0.0, indirect0 = 0.0;
        for (float v : cpu.direct.pixels) direct0 += v;
        for (float v : cpu.indirect.pixels) indirect0 += v;
        REQUIRE(direct0 > 0.0);
        REQUIRE(indirect0 > 0.0);
        CHECK(sameBits(host.direct, cpu.direct));
        CHECK(sameBits(host.indirect, cpu.indirect));
        CHECK(sameBits(host.directRadiance, cpu.directRadiance));
        CHECK(sameBits(host.indirectRadiance, cpu.indirectRadiance));
    }
}

TEST_CASE("lightVoxels with a kernel runner gives the TBB loop's bits and stats", "[cuda]") {
    const Cornell& c = cornell();
    // The box's light is uniform: sampled per voxel, it has no fixed samples to copy. With a
    // white emissive texture it keeps the same light and gets fixed samples.
    Scene textured = c.scene;
    Texture white;
    white.name = "white";
    white.image = Image(1, 1, 4);
    for (int k = 0; k < 4; ++k) white.image.at(0, 0, k) = 1.0f;
    textured.textures.push_back(white);
    int texturedEmitters = 0;
    for (Material& m : textured.materials)
        if (m.emissive()) {
            m.emissiveTexture.texture = static_cast<int>(textured.textures.size()) - 1;
            ++texturedEmitters;
        }
    REQUIRE(texturedEmitters > 0);
    for (const Scene* scene : {&c.scene, static_cast<const Scene*>(&textured)}) {
        for (const VisibilityTraversal traversal : {VisibilityTraversal::Hdda, VisibilityTraversal::Dda}) {
            LightingSettings settings;
            settings.traversal = traversal;
            VoxelScene cpu = c.voxels, host = c.voxels;
            const LightingStats a = lightVoxels(*scene, cpu, settings);
            seenEmitterSamples = 0;
            const LightingStats b = lightVoxels(*scene, host, settings, nullptr, &countingVoxelRunner);
            REQUIRE(a.voxelLightEvaluations > 0);
            CHECK(b.voxelLightEvaluations == a.voxelLightEvaluations);
            CHECK(b.visibilitySteps == a.visibilitySteps);
            CHECK(host.radiance == cpu.radiance);
            CHECK(host.occlusion == cpu.occlusion);
            // The launcher copies this many fixed emitter samples: all of them.
            CHECK((a.emitterSamples > 0) == (scene == &textured));
            CHECK(seenEmitterSamples == a.emitterSamples);
        }
    }
}

TEST_CASE("The array lengths the launchers copy are the owners' lengths", "[cuda]") {
    const Cornell& c = cornell();
    CHECK(cuda::leafSlotCount(c.bvh.view()) == c.bvh.triangleIds.size());
    CHECK(3 * cuda::leafSlotCount(c.bvh.view()) == c.bvh.vertices.size());
    CHECK(cuda::texelFloatCount(c.trace.view()) == c.trace.texels.size());
    const RadianceMips mips = buildRadianceMips(c.voxels);
    const MipView view = mips.view();
    REQUIRE(view.levelCount > 1);
    for (int k = 0; k < view.levelCount; ++k) CHECK(cuda::mipTexelCount(view.levels[k]) == mips.level(k).texels.size());
}

// ---- On a GPU machine: CPU and GPU agree (tolerances in cuda/launchers.h). ----

TEST_CASE("GPU voxel lighting agrees with the CPU on the Cornell box", "[cuda][gpu]") {
    VL_SKIP_WITHOUT_GPU();
    const Cornell& c = cornell();
    VoxelScene gpu = c.voxels;
    const LightingStats stats = cuda::lightVoxelsCuda(c.scene, gpu, LightingSettings{});
    CHECK(stats.voxels == c.voxels.size());
    checkDeterministicAgreement(flatten(gpu.radiance), flatten(c.voxels.radiance), "radiance");
    checkDeterministicAgreement(gpu.occlusion, c.voxels.occlusion, "occlusion");
}

TEST_CASE("GPU receiver shading agrees with the CPU on the Cornell lightmap", "[cuda][gpu]") {
    VL_SKIP_WITHOUT_GPU();
    const Cornell& c = cornell();
    const SurfaceSampleSet& receivers = c.atlases.front().receivers;
    const RadianceMips mips = buildRadianceMips(c.voxels);
    const MipView mipView = mips.view();
    const ReceiverLighting cpu =
        shadeReceivers(receivers, c.trace.view(), c.bvh.view(), &mipView, nullptr, ConeSettings{}, DirectLightSettings{}, true);
    const ReceiverLighting gpu = cuda::shadeReceiversCuda(receivers, c.trace.view(), c.bvh.view(), &mipView, nullptr,
                                                          ConeSettings{}, DirectLightSettings{}, true);
    checkDeterministicAgreement(gpu.direct.pixels, cpu.direct.pixels, "direct");
    checkDeterministicAgreement(gpu.indirect.pixels, cpu.indirect.pixels, "indirect");

    // The gather points' cones, and texels interpolating them.
    IrradianceCache cache(c.voxels, 2);
    cache.link(mipView);
    cache.gather(mipView, ConeSettings{});
    const std::vector<vec3> gathered = cuda::gatherIrradianceCuda(cache.points(), mipView, ConeSettings{}, 1);
    REQUIRE(gathered.size() == cache.irradiance().size());
    std::vector<float> gpuPoints, cpuPoints;
    for (size_t q = 0; q < gathered.size(); ++q)
        for (int ch = 0; ch < 3; ++ch) {
            gpuPoints.push_back(gathered[q][ch]);
            cpuPoints.push_back(cache.irradiance()[q][ch]);
        }
    checkDeterministicAgreement(gpuPoints, cpuPoints, "gather points");
    const IrradianceCacheView cacheView = cache.view(mipView);
    const ReceiverLighting cpuCached = shadeReceivers(receivers, c.trace.view(), c.bvh.view(), &mipView, &cacheView,
                                                      ConeSettings{}, DirectLightSettings{}, true);
    const ReceiverLighting gpuCached = cuda::shadeReceiversCuda(receivers, c.trace.view(), c.bvh.view(), &mipView,
                                                                &cacheView, ConeSettings{}, DirectLightSettings{}, true);
    checkDeterministicAgreement(gpuCached.indirect.pixels, cpuCached.indirect.pixels, "interpolated indirect");
}

namespace {

// Path tracing tolerance: per channel, |mean_gpu − mean_cpu| ≤ 1 % of the CPU mean + 4 standard
// errors of the difference (each image's mean has variance Σ var / n²).
void checkPathAgreement(const TraceResult& gpu, const TraceResult& cpu, const char* what) {
    REQUIRE(gpu.nonFiniteSamples == cpu.nonFiniteSamples);
    const size_t n = size_t(cpu.beauty.width) * size_t(cpu.beauty.height);
    for (int ch = 0; ch < 3; ++ch) {
        double meanGpu = 0.0, meanCpu = 0.0, varianceOfMeans = 0.0;
        for (size_t i = 0; i < n; ++i) {
            meanGpu += gpu.beauty.pixels[3 * i + ch];
            meanCpu += cpu.beauty.pixels[3 * i + ch];
            varianceOfMeans += gpu.variance.pixels[3 * i + ch] + cpu.variance.pixels[3 * i + ch];
        }
        meanGpu /= double(n);
        meanCpu /= double(n);
        const double sigma = std::sqrt(varianceOfMeans) / double(n);
        INFO(what << " channel " << ch << ": GPU mean " << meanGpu << ", CPU mean " << meanCpu << ", sigma " << sigma);
        CHECK(meanCpu > 0.0);
        CHECK(std::fabs(meanGpu - meanCpu) <= 0.01 * meanCpu + 4.0 * sigma);
    }
}

}  // namespace

TEST_CASE("GPU path tracing agrees with the CPU on the Cornell reference", "[cuda][gpu]") {
    VL_SKIP_WITHOUT_GPU();
    const Cornell& c = cornell();
    PathTracerSettings settings;
    settings.samplesPerPixel = 64;
    settings.quiet = true;
    const CameraModel camera = cornellCamera(64);
    checkPathAgreement(cuda::renderCameraCuda(c.trace, c.bvh, camera, settings),
                       renderCamera(c.trace, c.bvh, camera, settings), "camera");
    const SurfaceSampleSet& receivers = c.atlases.front().receivers;
    checkPathAgreement(cuda::traceIrradianceCuda(c.trace, c.bvh, receivers, settings),
                       traceIrradiance(c.trace, c.bvh, receivers, settings), "lightmap");
}

// ---- The bake's --device setting (bake.h) on a machine without a GPU. ----

namespace {

BakeSettings tinyBake(cuda::DeviceChoice device) {
    BakeSettings settings;
    settings.voxel.resolution = 16;
    settings.lightmap.width = settings.lightmap.height = 16;
    settings.outputs.images = false;
    settings.outputs.grids = false;
    settings.quiet = true;
    settings.device = device;
    return settings;
}

// Captures what a call writes to std::cerr.
template <typename F>
std::string stderrOf(F&& work) {
    std::ostringstream captured;
    std::streambuf* previous = std::cerr.rdbuf(captured.rdbuf());
    try {
        work();
    } catch (...) {
        std::cerr.rdbuf(previous);
        throw;
    }
    std::cerr.rdbuf(previous);
    return captured.str();
}

}  // namespace

TEST_CASE("A bake with device auto and no GPU says why and gives the CPU bake", "[cuda]") {
    const cuda::DeviceStatus status = cuda::probeDevice();
    if (status.usable) {
        VL_SKIP("this machine has a GPU (" << status.description << ")");
    }
    const Cornell& c = cornell();
    Diagnostics diagnostics(false, false);
    BakeResult cpu = bake(c.scene, tinyBake(cuda::DeviceChoice::Cpu), diagnostics);
    BakeResult fallback;
    const std::string said =
        stderrOf([&] { fallback = bake(c.scene, tinyBake(cuda::DeviceChoice::Auto), diagnostics); });
    CHECK(said == "running on the CPU: " + status.description + "\n");
    REQUIRE(cpu.lightmaps.size() == fallback.lightmaps.size());
    REQUIRE_FALSE(cpu.lightmaps.empty());
    for (size_t i = 0; i < cpu.lightmaps.size(); ++i) CHECK(sameBits(cpu.lightmaps[i].total, fallback.lightmaps[i].total));
}

TEST_CASE("A bake with device cuda and no GPU fails before any work with the reason", "[cuda]") {
    const cuda::DeviceStatus status = cuda::probeDevice();
    if (status.usable) {
        VL_SKIP("this machine has a GPU (" << status.description << ")");
    }
    Diagnostics diagnostics(false, false);
    CHECK_THROWS_WITH(bake(cornell().scene, tinyBake(cuda::DeviceChoice::Cuda), diagnostics),
                      "--device cuda: " + status.description);
}

TEST_CASE("The bake settings table takes device cpu, cuda and auto", "[cuda]") {
    BakeSettings settings;
    CHECK(settings.device == cuda::DeviceChoice::Cpu);
    applySetting(bakeSettingsTable(), settings, "device", "auto");
    CHECK(settings.device == cuda::DeviceChoice::Auto);
    CHECK_THAT(describeBakeSettings(settings), Catch::Matchers::Contains("device=auto"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "device", "gpu"),
                      Catch::Matchers::Contains("device 'gpu'"));
}
