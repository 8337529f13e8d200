// Rays per second of the voxlight BVH (closest hit and any hit) against Embree 3's
// single-ray queries (rtcIntersect1 / rtcOccluded1) on the same rays, in the same run.
//
//   build/microbench/microbench_rays [scene.glb] [--width W] [--height H] [--repeats N]
//
// Default scene: ../shared/scenes/interior-zdm2-godot/zdm2.glb. Rays: primary rays of a
// pinhole camera at a viewpoint inside the level, cosine-distributed secondary rays from
// the primary hit points, shadow segments from the primary hits to points inside the level.
// Each query set runs on 1 and 2 threads (tbb::global_control); the best of N repeats is
// reported (the machine is shared: the best run is the least disturbed one). Both
// libraries' answers are compared: hit/miss and t must agree for ≥ 99.9% of rays.
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "scene/gltf_loader.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/ray_offset.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#if VOXLIGHT_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

using namespace vl;

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Timing {
    double wall = 1e30;  // best wall-clock seconds
    double cpu = 1e30;   // best CPU seconds of the calling thread (meaningful on 1 thread)
};

double threadCpuSeconds() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Best of `repeats` runs of fn on `threads` threads. On a shared machine the wall time
// includes time the thread was descheduled; on one thread (TBB then runs everything on the
// calling thread) its CPU time does not, so 1-thread figures use CPU time.
Timing bestTime(int threads, int repeats, const std::function<void()>& fn) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    Timing best;
    for (int r = 0; r < repeats; ++r) {
        const auto start = Clock::now();
        const double cpuStart = threadCpuSeconds();
        fn();
        best.cpu = std::min(best.cpu, threadCpuSeconds() - cpuStart);
        best.wall = std::min(best.wall, secondsSince(start));
    }
    return best;
}

template <typename F>
void forEachRay(size_t count, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

vec3 geometricNormal(const SceneTriangles& tris, uint32_t triangle) {
    const vec3* v = &tris.vertices[3 * size_t(triangle)];
    return glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
}

// A point inside the level: among candidates on a grid over the scene bounds, the one
// whose rays in all directions hit a front face (seen from inside a room, not from inside
// a wall or outside), preferring the most open space (largest mean hit distance).
struct Viewpoint {
    vec3 position;
    float score;
};

std::vector<Viewpoint> insidePoints(const Bvh& bvh, const SceneTriangles& tris, int wanted) {
    const Aabb box = bvh.bounds();
    std::vector<Viewpoint> found;
    const int grid = 12, probes = 96;
    for (int z = 0; z < grid; ++z)
        for (int y = 0; y < grid; ++y)
            for (int x = 0; x < grid; ++x) {
                const vec3 p = box.lower + box.extent() * (vec3(float(x), float(y), float(z)) + 0.5f) / float(grid);
                int front = 0;
                float distance = 0.0f;
                for (int k = 0; k < probes; ++k) {
                    Pcg32 rng = Pcg32::forItem(uint64_t(k), 0, 99);
                    Ray ray;
                    ray.origin = p;
                    ray.direction = sampleUniformSphere(vec2(rng.next1D(), rng.next1D()));
                    Hit hit;
                    if (!intersectClosest(bvh.view(), ray, hit)) break;
                    if (glm::dot(geometricNormal(tris, hit.triangle), ray.direction) >= 0.0f) break;
                    ++front;
                    distance += hit.t;
                }
                if (front == probes) found.push_back({p, distance / float(probes)});
            }
    std::sort(found.begin(), found.end(), [](const Viewpoint& a, const Viewpoint& b) { return a.score > b.score; });
    if (found.size() > size_t(wanted)) found.resize(size_t(wanted));
    return found;
}

struct RaySet {
    std::string name;
    std::vector<Ray> rays;
    bool shadow;  // any-hit query
};

struct Result {
    std::vector<uint8_t> hit;
    std::vector<float> t;  // closest-hit only
    void resize(size_t n) {
        hit.assign(n, 0);
        t.assign(n, 0.0f);
    }
};

#if VOXLIGHT_HAVE_EMBREE
std::atomic<int64_t> embreeBytes{0};
int64_t embreePeakBytes = 0;

bool embreeMemoryMonitor(void*, ssize_t bytes, bool) {
    const int64_t now = embreeBytes += bytes;
    embreePeakBytes = std::max(embreePeakBytes, now);
    return true;
}

RTCRayHit toEmbree(const Ray& ray) {
    RTCRayHit rh;
    std::memset(&rh, 0, sizeof rh);
    rh.ray.org_x = ray.origin.x;
    rh.ray.org_y = ray.origin.y;
    rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x;
    rh.ray.dir_y = ray.direction.y;
    rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = ray.tMin;
    rh.ray.tfar = ray.tMax;
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    return rh;
}
#endif

}  // namespace

int main(int argc, char** argv) {
    std::string path = std::string(VOXLIGHT_SOURCE_DIR) + "/../shared/scenes/interior-zdm2-godot/zdm2.glb";
    int width = 1024, height = 768, repeats = 5;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--width" && i + 1 < argc) width = std::atoi(argv[++i]);
        else if (arg == "--height" && i + 1 < argc) height = std::atoi(argv[++i]);
        else if (arg == "--repeats" && i + 1 < argc) repeats = std::atoi(argv[++i]);
        else if (arg.rfind("--", 0) != 0) path = arg;
        else {
            std::fprintf(stderr, "usage: microbench_rays [scene.glb] [--width W] [--height H] [--repeats N]\n");
            return 2;
        }
    }

    try {
        auto start = Clock::now();
        const Scene scene = loadGltf(path);
        const double loadSeconds = secondsSince(start);
        const SceneTriangles tris = gatherTriangles(scene);
        const size_t triangleCount = tris.vertices.size() / 3;
        std::printf("scene %s: %zu triangles, %zu meshes (loaded in %.2f s)\n", path.c_str(), triangleCount,
                    scene.meshes.size(), loadSeconds);

        BvhSettings settings;
        if (const char* env = std::getenv("VL_BVH_TRAVERSAL_COST")) settings.traversalCost = float(std::atof(env));
        if (const char* env = std::getenv("VL_BVH_MAX_LEAF")) settings.maxLeafSize = std::atoi(env);
        Bvh bvh;
        const Timing build1 = bestTime(1, 3, [&] { bvh = Bvh::build(tris, settings); });
        const Timing build2 = bestTime(2, 3, [&] { bvh = Bvh::build(tris, settings); });
        std::printf("voxlight BVH build: %.3f s on 1 thread (CPU time), %.3f s on 2 threads (wall)\n", build1.cpu,
                    build2.wall);
        std::printf("voxlight BVH: %zu nodes, %.1f MiB (%.1f bytes/triangle)\n", bvh.nodes.size(),
                    double(bvh.memoryBytes()) / (1 << 20), double(bvh.memoryBytes()) / double(triangleCount));
        BvhView view = bvh.view();
        // VL_BVH_BINARY=1 traverses the binary nodes instead of the 4-wide ones.
        if (std::getenv("VL_BVH_BINARY") != nullptr) view.wideNodes = nullptr;

        // Viewpoint, camera, and the points shadow rays go to.
        const std::vector<Viewpoint> inside = insidePoints(bvh, tris, 16);
        if (inside.empty()) throw Error("no point inside the level found: is " + path + " an interior?");
        const vec3 eye = inside.front().position;
        std::printf("viewpoint (%.2f, %.2f, %.2f), %zu inside points for lights\n", eye.x, eye.y, eye.z, inside.size());
        // Look along the horizontal direction with the longest free distance.
        vec3 forward(1, 0, 0);
        float longest = -1.0f;
        for (int k = 0; k < 16; ++k) {
            const float phi = 2.0f * kPi * float(k) / 16.0f;
            Ray probe;
            probe.origin = eye;
            probe.direction = vec3(std::cos(phi), 0.0f, std::sin(phi));
            Hit hit;
            const float d = intersectClosest(view, probe, hit) ? hit.t : 1e30f;
            if (d > longest) {
                longest = d;
                forward = probe.direction;
            }
        }
        const vec3 right = glm::normalize(glm::cross(forward, vec3(0, 1, 0)));
        const vec3 up = glm::cross(right, forward);
        const float tanHalf = std::tan(0.5f * 1.2f);

        RaySet primary{"primary (closest)", std::vector<Ray>(size_t(width) * height), false};
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const float sx = (2.0f * (float(x) + 0.5f) / float(width) - 1.0f) * tanHalf * float(width) / float(height);
                const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / float(height)) * tanHalf;
                Ray& ray = primary.rays[size_t(y) * width + x];
                ray.origin = eye;
                ray.direction = glm::normalize(forward + sx * right + sy * up);
            }
        Result primaryHits;
        primaryHits.resize(primary.rays.size());
        std::vector<Hit> firstHits(primary.rays.size());
        forEachRay(primary.rays.size(), [&](size_t i) {
            primaryHits.hit[i] = intersectClosest(view, primary.rays[i], firstHits[i]);
        });

        RaySet secondary{"secondary (closest)", {}, false};
        RaySet shadow{"shadow (any hit)", {}, true};
        for (size_t i = 0; i < primary.rays.size(); ++i) {
            if (!primaryHits.hit[i]) continue;
            const Ray& in = primary.rays[i];
            const Hit& h = firstHits[i];
            const vec3 p = in.at(h.t);
            vec3 n = geometricNormal(tris, h.triangle);
            if (glm::dot(n, in.direction) > 0.0f) n = -n;
            const vec3 origin = offsetRayOrigin(p, n, view.extent);
            Pcg32 rng = Pcg32::forItem(i, 0, 1);
            vec3 t, b;
            orthonormalBasis(n, t, b);
            const vec3 local = sampleCosineHemisphere(vec2(rng.next1D(), rng.next1D()));
            Ray out;
            out.origin = origin;
            out.direction = glm::normalize(local.x * t + local.y * b + local.z * n);
            secondary.rays.push_back(out);
            // A shadow segment to a jittered point near one of the inside points.
            const vec3 light = inside[rng.nextU32() % inside.size()].position +
                               0.2f * (vec3(rng.next1D(), rng.next1D(), rng.next1D()) - 0.5f);
            Ray s;
            s.origin = origin;
            s.direction = light - origin;  // t ∈ (0, 1) spans the segment
            s.tMax = 1.0f;
            shadow.rays.push_back(s);
        }

        std::vector<RaySet*> sets = {&primary, &secondary, &shadow};
        std::printf("\nMrays/s; 1T = one thread, by its CPU time; 2T = two threads, wall clock; best of %d.\n"
                    "ratio = voxlight time / embree time (1.00 = as fast as embree)\n",
                    repeats);
        std::vector<Result> ours(sets.size());
        std::printf("\n%-22s %9s %8s | %12s %12s", "query", "rays", "hit %", "voxlight 1T", "voxlight 2T");
#if VOXLIGHT_HAVE_EMBREE
        std::printf(" | %12s %12s | %7s %7s", "embree 1T", "embree 2T", "ratio1T", "ratio2T");
#endif
        std::printf("\n");

#if VOXLIGHT_HAVE_EMBREE
        RTCDevice device = rtcNewDevice(nullptr);
        rtcSetDeviceMemoryMonitorFunction(device, embreeMemoryMonitor, nullptr);
        RTCScene escene = rtcNewScene(device);
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                                tris.vertices.size()));
        std::memcpy(vb, tris.vertices.data(), tris.vertices.size() * sizeof(vec3));
        unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                      RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                                      triangleCount));
        for (size_t i = 0; i < 3 * triangleCount; ++i) ib[i] = unsigned(i);
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(escene, geometry);
        rtcReleaseGeometry(geometry);
        const int64_t beforeBuild = embreeBytes.load();
        start = Clock::now();
        rtcCommitScene(escene);
        const double embreeBuild = secondsSince(start);
        std::vector<Result> theirs(sets.size());
#endif

        for (size_t s = 0; s < sets.size(); ++s) {
            const RaySet& set = *sets[s];
            const size_t n = set.rays.size();
            ours[s].resize(n);
            Timing mine[2];
#if VOXLIGHT_HAVE_EMBREE
            Timing embree[2];
#endif
            for (int threads : {1, 2}) {
                mine[threads - 1] = bestTime(threads, repeats, [&] {
                    if (set.shadow) {
                        forEachRay(n, [&](size_t i) { ours[s].hit[i] = intersectAny(view, set.rays[i]); });
                    } else {
                        forEachRay(n, [&](size_t i) {
                            Hit hit;
                            ours[s].hit[i] = intersectClosest(view, set.rays[i], hit);
                            ours[s].t[i] = hit.t;
                        });
                    }
                });
#if VOXLIGHT_HAVE_EMBREE
                theirs[s].resize(n);
                embree[threads - 1] = bestTime(threads, repeats, [&] {
                    forEachRay(n, [&](size_t i) {
                        RTCIntersectContext context;
                        rtcInitIntersectContext(&context);
                        RTCRayHit rh = toEmbree(set.rays[i]);
                        if (set.shadow) {
                            rtcOccluded1(escene, &context, &rh.ray);
                            theirs[s].hit[i] = rh.ray.tfar < 0.0f;  // -inf marks occluded
                        } else {
                            rtcIntersect1(escene, &context, &rh);
                            theirs[s].hit[i] = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                            theirs[s].t[i] = rh.ray.tfar;
                        }
                    });
                });
#endif
            }
            size_t hits = 0;
            for (uint8_t h : ours[s].hit) hits += h;
            std::printf("%-22s %9zu %7.1f%% | %12.2f %12.2f", set.name.c_str(), n, 100.0 * double(hits) / double(n),
                        double(n) / mine[0].cpu * 1e-6, double(n) / mine[1].wall * 1e-6);
#if VOXLIGHT_HAVE_EMBREE
            std::printf(" | %12.2f %12.2f | %7.2f %7.2f", double(n) / embree[0].cpu * 1e-6,
                        double(n) / embree[1].wall * 1e-6, mine[0].cpu / embree[0].cpu, mine[1].wall / embree[1].wall);
#endif
            std::printf("\n");
        }

#if VOXLIGHT_HAVE_EMBREE
        std::printf("\nembree BVH build (its own threads): %.3f s, %.1f MiB\n", embreeBuild,
                    double(embreeBytes.load() - beforeBuild) / (1 << 20));
        std::printf("agreement with embree (hit/miss, and t within 1e-4 relative for closest hits):\n");
        bool allAgree = true;
        for (size_t s = 0; s < sets.size(); ++s) {
            const size_t n = sets[s]->rays.size();
            size_t same = 0, hitMismatch = 0, tMismatch = 0;
            for (size_t i = 0; i < n; ++i) {
                const bool a = ours[s].hit[i], b = theirs[s].hit[i];
                bool ok = a == b;
                if (!ok) ++hitMismatch;
                if (ok && a && !sets[s]->shadow) {
                    const float ta = ours[s].t[i], tb = theirs[s].t[i];
                    ok = std::abs(ta - tb) <= 1e-4f * std::max(ta, tb) + 1e-6f;
                    if (!ok) ++tMismatch;
                }
                same += ok;
            }
            const double fraction = double(same) / double(n);
            allAgree = allAgree && fraction >= 0.999;
            std::printf("  %-22s %.4f%% agree (%zu hit/miss and %zu t differences)\n", sets[s]->name.c_str(),
                        100.0 * fraction, hitMismatch, tMismatch);
        }
        rtcReleaseScene(escene);
        rtcReleaseDevice(device);
        if (!allAgree) {
            std::fprintf(stderr, "FAIL: fewer than 99.9%% of rays agree with embree\n");
            return 1;
        }
#else
        std::printf("\n(built without Embree 3: no comparison)\n");
#endif
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "microbench_rays: %s\n", e.what());
        return 1;
    }
}
