// The bench's Cycles peer hands Blender what glTF cannot carry: the sky. A stand-in for
// Blender records the command line tools/bench/cycles_bake.py would get.
#include "bench/cycles_peer.h"
#include "core/error.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

// A "blender" that writes its arguments and the script's cycles.json into --out.
fs::path fakeBlender(const fs::path& dir) {
    const fs::path script = dir / "blender";
    std::ofstream(script) << R"(#!/bin/sh
out=
prev=
for a in "$@"; do [ "$prev" = "--out" ] && out=$a; prev=$a; done
printf '%s\n' "$@" > "$out/args.txt"
echo '{"cpu_seconds": 1.0}' > "$out/cycles.json"
)";
    fs::permissions(script, fs::perms::owner_all);
    return script;
}

std::string argumentsOf(const BenchOptions& options, const CyclesPeer& peer) {
    BenchPointResult p;
    p.spec = {"cycles", "spp=4", {}, 4};
    runCyclesPoint(options, peer, p, [](BenchPointResult&, const fs::path&) {});
    std::ifstream in(fs::path(options.base.outputDir) / p.outputDir / "args.txt");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace

TEST_CASE("The bench's Cycles peer gives Blender the sky: a uniform world or an image, turned and scaled", "[bench]") {
    const fs::path dir = tempDir("cycles-peer");
    CyclesPeer peer;
    peer.available = true;
    peer.blender = fakeBlender(dir).string();
    peer.script = (fs::path(sourceDir()) / "tools/bench/cycles_bake.py").string();
    BenchOptions options;
    options.base.scenePath = "scene.gltf";
    options.base.outputDir = (dir / "bench").string();

    CHECK(argumentsOf(options, peer).find("--sky") == std::string::npos);  // no sky: a black world

    options.base.settings.sky = vec3(0.6f, 0.75f, 1.0f);
    CHECK(argumentsOf(options, peer).find("--sky\n0.6,0.75,1\n") != std::string::npos);

    options.base.settings.sky = vec3(0.0f);
    options.base.settings.skyImage = "skies/noon.exr";
    options.base.settings.skyRotation = 30.0f;
    options.base.settings.skyIntensity = 2.0f;
    const std::string image = argumentsOf(options, peer);
    CHECK(image.find("--sky-image\n" + fs::absolute("skies/noon.exr").string() + "\n") != std::string::npos);
    CHECK(image.find("--sky-rotation\n30\n--sky-intensity\n2\n") != std::string::npos);

    options.base.settings.sky = vec3(1.0f);  // Cycles' world takes one or the other
    CHECK_THROWS_WITH(argumentsOf(options, peer), Catch::Contains("uniform sky or a sky image, not both"));
}
