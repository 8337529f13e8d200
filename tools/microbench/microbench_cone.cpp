// Cone-tracing throughput: irradiance gathers per second for 6/16/32 cones, mip build and
// one voxel bounce, on a closed box of radiating walls (the Cornell-box situation: every
// cone ends on a wall). Run: build/microbench/microbench_cone
#include "gather/bounces.h"
#include "cone/cone_trace.h"

#include <benchmark/benchmark.h>

using namespace vl;

namespace {

// Closed box, interior n³, walls one voxel thick, radiance 1, inward normals, albedo ½.
VoxelScene closedBox(int n) {
    VoxelScene scene;
    scene.voxelSize = 1.0 / n;
    for (int x = -1; x <= n; ++x)
        for (int y = -1; y <= n; ++y)
            for (int z = -1; z <= n; ++z) {
                const ivec3 c(x, y, z);
                vec3 inward(0.0f);
                for (int a = 0; a < 3; ++a) inward[a] = c[a] < 0 ? 1.0f : c[a] >= n ? -1.0f : 0.0f;
                if (inward == vec3(0.0f)) continue;
                scene.coords.push_back(c);
                scene.normal.push_back(glm::normalize(inward));
                scene.radiance.push_back(vec3(1.0f));
                scene.albedo.push_back(vec3(0.5f));
                scene.opacity.push_back(1.0f);
                scene.solid.push_back(1);
                scene.axisWeights.push_back({});
            }
    return scene;
}

void BM_MipBuild(benchmark::State& state) {
    const VoxelScene box = closedBox(int(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(buildRadianceMips(box).levelCount());
    state.counters["voxels"] = double(box.size());
}

void BM_Irradiance(benchmark::State& state) {
    static const VoxelScene box = closedBox(128);
    static const RadianceMips mips = buildRadianceMips(box);
    const MipView view = mips.view();
    ConeSettings settings;
    settings.coneCount = int(state.range(0));
    const ConeSet& set = coneSet(settings.coneCount);
    size_t i = 0;
    for (auto _ : state) {
        // Receivers spread over the floor, facing up.
        const vec3 p = vec3(float(i % 128), float((i / 128) % 128), -1.0f) * float(box.voxelSize);
        benchmark::DoNotOptimize(coneTraceIrradiance(view, p, vec3(0, 0, 1), set, settings));
        i += 97;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}

void BM_Bounce(benchmark::State& state) {
    const VoxelScene box = closedBox(int(state.range(0)));
    ConeSettings settings;
    settings.coneCount = 6;
    for (auto _ : state) {
        VoxelScene copy = box;
        propagateBounces(copy, BounceSettings{1, 0, BounceTail::None, settings});
        benchmark::DoNotOptimize(copy.radiance.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * box.size()));
}

}  // namespace

BENCHMARK(BM_MipBuild)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Irradiance)->Arg(6)->Arg(16)->Arg(32)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Bounce)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
