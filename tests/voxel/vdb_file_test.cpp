// VoxelScene → .vdb → VoxelScene must be the identity, and the file must say what it holds.
#include "core/allocation_limit.h"
#include "core/error.h"
#include "support/paths.h"
#include "voxel/vdb_file.h"
#include "voxel/vdb_inspect.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <tuple>

using namespace vl;
using Catch::Matchers::Contains;

namespace {

// A few hundred voxels on a sheared slab that crosses the origin (negative coords too), with
// values that exercise the float range: tiny, huge, subnormal, negative.
VoxelScene syntheticScene(bool optionalChannels) {
    VoxelScene s;
    s.voxelSize = 0.0125;
    s.sourceScene = "/scenes/synthetic.gltf";
    s.settings = "resolution=64 fill_interior=0";
    for (int x = -6; x < 6; ++x)
        for (int y = -3; y < 2; ++y)
            for (int z = x - 2; z < x + 3; ++z) s.coords.emplace_back(x, y, z);
    std::sort(s.coords.begin(), s.coords.end(),
              [](const ivec3& a, const ivec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
    const size_t n = s.coords.size();
    for (size_t i = 0; i < n; ++i) {
        const float t = static_cast<float>(i) / static_cast<float>(n);
        s.albedo.emplace_back(t, 1.0f - t, 0.1f + 0.3f * t);
        s.normal.push_back(normalize(vec3(std::sin(3.0f * t), std::cos(5.0f * t), t - 0.5f)));
        s.axisWeights.push_back({t, 1.0f - t, 0.25f, 0.0f, 3.5f * t, 1e-30f});
        s.opacity.push_back(i == 7 ? 1e-40f /* subnormal */ : 0.001f + 0.999f * t);
        s.solid.push_back(i % 3 == 0 ? 1 : 0);
        if (optionalChannels) {
            s.emission.emplace_back(i % 17 == 0 ? 3.0e4f : 0.0f, 0.0f, t * 12.5f);
            s.radiance.emplace_back(t * 0.7f, 1.0f / (1.0f + t), 3.4e38f * t);
            s.occlusion.push_back(1.0f - t * t);
        }
    }
    return s;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool sameBits(const vec3& a, const vec3& b) { return sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z); }

template <typename T>
size_t countMismatches(const std::vector<T>& a, const std::vector<T>& b) {
    size_t bad = 0;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) bad += sameBits(a[i], b[i]) ? 0 : 1;
    return bad + (a.size() > b.size() ? a.size() - b.size() : b.size() - a.size());
}

template <typename E, typename F>
std::string messageOf(F&& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    return "(no exception of the expected type)";
}

std::map<std::string, const GridInfo*> byName(const VdbFileInfo& info) {
    std::map<std::string, const GridInfo*> out;
    for (const GridInfo& g : info.grids) out[g.name] = &g;
    return out;
}
// Pointers into a temporary would dangle (ASan found two such uses): keep the info alive.
std::map<std::string, const GridInfo*> byName(VdbFileInfo&&) = delete;

std::string metaValue(const VdbFileInfo& info, const std::string& key) {
    for (const auto& [k, v] : info.metadata)
        if (k == key) return v;
    return "(absent)";
}

}  // namespace

TEST_CASE("A VoxelScene written to .vdb reads back bit for bit", "[voxel]") {
    const VoxelScene scene = syntheticScene(true);
    REQUIRE(scene.size() == 300);
    const std::string path = test::tempDir("vdb_file") + "/roundtrip.vdb";
    writeVoxelFile(scene, path);
    const VoxelScene back = readVoxelFile(path);

    CHECK(back.voxelSize == scene.voxelSize);
    CHECK(back.sourceScene == scene.sourceScene);
    CHECK(back.settings == scene.settings);
    REQUIRE(back.coords == scene.coords);
    CHECK(countMismatches(back.albedo, scene.albedo) == 0);
    CHECK(countMismatches(back.normal, scene.normal) == 0);
    CHECK(countMismatches(back.emission, scene.emission) == 0);
    CHECK(countMismatches(back.radiance, scene.radiance) == 0);
    CHECK(countMismatches(back.opacity, scene.opacity) == 0);
    CHECK(countMismatches(back.occlusion, scene.occlusion) == 0);
    CHECK(back.solid == scene.solid);
    REQUIRE(back.axisWeights.size() == scene.axisWeights.size());
    size_t axisMismatches = 0;
    for (size_t i = 0; i < scene.size(); ++i)
        for (int f = 0; f < 6; ++f) axisMismatches += sameBits(back.axisWeights[i][f], scene.axisWeights[i][f]) ? 0 : 1;
    CHECK(axisMismatches == 0);
}

TEST_CASE("A turned scene's grids carry its frame and origin, and read back with them", "[voxel]") {
    // The bake turns a scene into its own frame (scene/own_frame.h): the grids' transform
    // turns them back, so another tool shows the voxels where the scene is.
    VoxelScene scene = syntheticScene(false);
    const double c = std::cos(0.6), s = std::sin(0.6);
    scene.frame = glm::dmat3(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);  // 0.6 rad about +Z
    scene.origin = glm::dvec3(1.0e4, 2.5, -3.0);
    const std::string path = test::tempDir("vdb_file") + "/turned.vdb";
    ExtraGrid mip;
    mip.name = "radiance_mip1";
    mip.voxelSize = 2.0 * scene.voxelSize;
    mip.coords = {ivec3(0), ivec3(1, -2, 3)};
    mip.vectors = {vec3(1.0f), vec3(0.5f)};
    mip.translation = scene.origin + scene.frame * glm::dvec3(0.5 * scene.voxelSize);
    mip.frame = scene.frame;
    writeVoxelFile(scene, path, {mip});
    const VoxelScene back = readVoxelFile(path);
    CHECK(back.voxelSize == scene.voxelSize);
    CHECK(back.origin == scene.origin);
    for (int k = 0; k < 3; ++k) CHECK(glm::distance(back.frame[k], scene.frame[k]) <= 1e-15);
    CHECK(back.coords == scene.coords);
    const ExtraGrid mipBack = readExtraGrid(path, "radiance_mip1");
    CHECK(mipBack.voxelSize == Approx(mip.voxelSize).epsilon(1e-14));
    CHECK(glm::distance(mipBack.translation, mip.translation) <= 1e-9);
    for (int k = 0; k < 3; ++k) CHECK(glm::distance(mipBack.frame[k], mip.frame[k]) <= 1e-15);
    // OpenVDB itself places the voxels there: the active voxels' world box, by OpenVDB's
    // transform, is the box of origin + frame · (corner · h) over the index box's corners.
    const VdbFileInfo info = inspectVoxelFile(path);
    const GridInfo* opacity = nullptr;
    for (const GridInfo& g : info.grids)
        if (g.name == "opacity") opacity = &g;
    REQUIRE(opacity != nullptr);
    glm::dvec3 lower(1e300), upper(-1e300);
    for (int corner = 0; corner < 8; ++corner) {
        glm::dvec3 index;
        for (int a = 0; a < 3; ++a)
            index[a] = (corner >> a & 1) ? opacity->indexMax[a] + 0.5 : opacity->indexMin[a] - 0.5;
        const glm::dvec3 world = scene.origin + scene.frame * (index * scene.voxelSize);
        lower = glm::min(lower, world);
        upper = glm::max(upper, world);
    }
    for (int a = 0; a < 3; ++a) {
        CHECK(opacity->worldMin[a] == Approx(lower[a]).margin(1e-9));
        CHECK(opacity->worldMax[a] == Approx(upper[a]).margin(1e-9));
    }
    // An unturned scene keeps the scale-translate transform of every file before frames.
    const std::string plain = test::tempDir("vdb_file") + "/plain.vdb";
    writeVoxelFile(syntheticScene(false), plain);
    CHECK(readVoxelFile(plain).frame == glm::dmat3(1.0));
}

TEST_CASE("Writing the same scene twice gives the same bytes", "[voxel]") {
    const VoxelScene scene = syntheticScene(true);
    const std::string dir = test::tempDir("vdb_file");
    const auto bytesOf = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    writeVoxelFile(scene, dir + "/first.vdb");
    writeVoxelFile(scene, dir + "/second.vdb");
    const std::string first = bytesOf(dir + "/first.vdb");
    REQUIRE(first.size() > 1000);
    CHECK(first == bytesOf(dir + "/second.vdb"));
    // A different scene gets a different file identity (the UUID in the header).
    VoxelScene other = scene;
    other.opacity[0] = 0.5f;
    writeVoxelFile(other, dir + "/third.vdb");
    CHECK(bytesOf(dir + "/third.vdb").substr(21, 36) != first.substr(21, 36));
    CHECK(readVoxelFile(dir + "/second.vdb").opacity == scene.opacity);
}

TEST_CASE("The .vdb carries the DESIGN.md grid names and file metadata", "[voxel]") {
    const VoxelScene scene = syntheticScene(true);
    const std::string path = test::tempDir("vdb_file") + "/names.vdb";
    writeVoxelFile(scene, path);
    const VdbFileInfo info = inspectVoxelFile(path);
    const auto grids = byName(info);
    const std::map<std::string, std::string> expectedTypes = {
        {"albedo", "vec3s"},   {"normal", "vec3s"},    {"emission", "vec3s"},
        {"opacity", "float"},  {"occlusion", "float"}, {"solid", "bool"},
        {"radiance", "vec3s"}, {"axis_weights_pos", "vec3s"}, {"axis_weights_neg", "vec3s"}};
    REQUIRE(grids.size() == expectedTypes.size());
    const size_t solidCount = static_cast<size_t>(std::count(scene.solid.begin(), scene.solid.end(), uint8_t(1)));
    for (const auto& [name, type] : expectedTypes) {
        INFO("grid " << name);
        REQUIRE(grids.count(name) == 1);
        const GridInfo& g = *grids.at(name);
        CHECK(g.valueType == type);
        CHECK(g.voxelSize[0] == scene.voxelSize);
        CHECK(g.voxelSize[2] == scene.voxelSize);
        CHECK(g.activeVoxels == (name == "solid" ? solidCount : scene.size()));
        // The slab spans x ∈ [−6, 5], y ∈ [−3, 1], z ∈ [−8, 7]; solid voxels (every third) too.
        CHECK(g.indexMin == std::array<int, 3>{-6, -3, -8});
        CHECK(g.indexMax == std::array<int, 3>{5, 1, 7});
        CHECK(g.worldMin[0] == Approx(-6.5 * scene.voxelSize));
        CHECK(g.worldMax[2] == Approx(7.5 * scene.voxelSize));
    }
    CHECK(grids.at("opacity")->gridClass == "fog volume");
    CHECK(metaValue(info, "voxel_size") == "0.0125");
    CHECK(metaValue(info, "settings") == scene.settings);
    CHECK(metaValue(info, "source_scene") == scene.sourceScene);
    CHECK(metaValue(info, "voxlight_version") == VOXLIGHT_VERSION);
}

TEST_CASE("Optional channels are not written when absent and read back empty", "[voxel]") {
    const VoxelScene scene = syntheticScene(false);
    const std::string path = test::tempDir("vdb_file") + "/no_optional.vdb";
    writeVoxelFile(scene, path);
    const VdbFileInfo info = inspectVoxelFile(path);
    const auto grids = byName(info);
    CHECK(grids.count("emission") == 0);
    CHECK(grids.count("radiance") == 0);
    CHECK(grids.count("occlusion") == 0);
    CHECK(grids.size() == 6);
    const VoxelScene back = readVoxelFile(path);
    CHECK(back.emission.empty());
    CHECK(back.radiance.empty());
    CHECK(back.occlusion.empty());
    CHECK(back.coords == scene.coords);
    CHECK(countMismatches(back.albedo, scene.albedo) == 0);
}

TEST_CASE("Extra grids keep their own voxel size and values", "[voxel]") {
    const VoxelScene scene = syntheticScene(false);
    ExtraGrid mip1{"radiance_mip1", scene.voxelSize * 2.0, {}, {}, {}};
    ExtraGrid alpha1{"opacity_mip1", scene.voxelSize * 2.0, {}, {}, {}};
    for (int i = 0; i < 40; ++i) {
        mip1.coords.emplace_back(i / 8 - 2, i % 8, -i);
        mip1.vectors.emplace_back(0.1f * i, 1.0f / (i + 1), -2.0f * i);
        alpha1.coords.emplace_back(i, -i, 3);
        alpha1.scalars.push_back(0.025f * static_cast<float>(i));
    }
    // Read back sorted by (x, y, z): the mip coords above are already in that order except z.
    const std::string path = test::tempDir("vdb_file") + "/extra.vdb";
    writeVoxelFile(scene, path, {mip1, alpha1});

    const ExtraGrid vectors = readExtraGrid(path, "radiance_mip1");
    CHECK(vectors.voxelSize == scene.voxelSize * 2.0);
    REQUIRE(vectors.coords.size() == mip1.coords.size());
    CHECK(vectors.scalars.empty());
    size_t mismatches = 0;
    for (size_t i = 0; i < mip1.coords.size(); ++i) {
        const auto it = std::find(vectors.coords.begin(), vectors.coords.end(), mip1.coords[i]);
        REQUIRE(it != vectors.coords.end());
        mismatches += sameBits(vectors.vectors[size_t(it - vectors.coords.begin())], mip1.vectors[i]) ? 0 : 1;
    }
    CHECK(mismatches == 0);
    CHECK(std::is_sorted(vectors.coords.begin(), vectors.coords.end(), [](const ivec3& a, const ivec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    }));

    const ExtraGrid scalars = readExtraGrid(path, "opacity_mip1");
    CHECK(scalars.coords == alpha1.coords);  // already sorted by x
    CHECK(countMismatches(scalars.scalars, alpha1.scalars) == 0);

    // The scene itself is untouched by the extras.
    CHECK(readVoxelFile(path).coords == scene.coords);
    const VdbFileInfo info = inspectVoxelFile(path);
    const auto grids = byName(info);
    CHECK(grids.at("radiance_mip1")->voxelSize[1] == scene.voxelSize * 2.0);
}

TEST_CASE("Writing refuses inconsistent scenes and leaves no file behind", "[voxel]") {
    const std::string dir = test::tempDir("vdb_file_bad_write");
    const std::string path = dir + "/bad.vdb";
    std::filesystem::remove(path);

    VoxelScene nan = syntheticScene(true);
    nan.radiance[5].y = std::numeric_limits<float>::quiet_NaN();
    const std::string nanMessage = messageOf<Error>([&] { writeVoxelFile(nan, path); });
    CHECK_THAT(nanMessage, Contains("radiance") && Contains("(-6, -2, -8)"));

    VoxelScene shortChannel = syntheticScene(false);
    shortChannel.opacity.pop_back();
    CHECK_THAT(messageOf<Error>([&] { writeVoxelFile(shortChannel, path); }), Contains("opacity"));

    VoxelScene unsorted = syntheticScene(false);
    std::swap(unsorted.coords[3], unsorted.coords[4]);
    CHECK_THAT(messageOf<Error>([&] { writeVoxelFile(unsorted, path); }), Contains("sorted"));

    const VoxelScene good = syntheticScene(false);
    ExtraGrid clash{"albedo", good.voxelSize, {ivec3(0)}, {1.0f}, {}};
    CHECK_THAT(messageOf<Error>([&] { writeVoxelFile(good, path, {clash}); }), Contains("albedo"));

    CHECK_FALSE(std::filesystem::exists(path));
    // No temporary left over either: the folder holds nothing.
    CHECK(std::filesystem::directory_iterator(dir) == std::filesystem::directory_iterator());
}

TEST_CASE("Reading bad .vdb input names the file and the grid", "[voxel]") {
    const std::string dir = test::tempDir("vdb_file_bad_read");

    const std::string missing = dir + "/does_not_exist.vdb";
    const std::string missingMessage = messageOf<InputError>([&] { readVoxelFile(missing); });
    CHECK_THAT(missingMessage, Contains(missing) && Contains("no such file"));
    CHECK_THAT(messageOf<InputError>([&] { inspectVoxelFile(missing); }), Contains(missing));

    const std::string garbage = dir + "/garbage.vdb";
    std::ofstream(garbage) << "this is not an OpenVDB file, just some text that is long enough\n";
    CHECK_THAT(messageOf<InputError>([&] { readVoxelFile(garbage); }),
               Contains(garbage) && Contains("not a readable OpenVDB file"));
    CHECK_THAT(messageOf<InputError>([&] { inspectVoxelFile(garbage); }), Contains(garbage));
    CHECK_THAT(messageOf<InputError>([&] { sliceImage(garbage, "albedo", SliceAxis::Z, 0); }), Contains(garbage));

    // A real file cut in half.
    const std::string whole = dir + "/whole.vdb";
    writeVoxelFile(syntheticScene(true), whole);
    const std::string truncated = dir + "/truncated.vdb";
    {
        std::ifstream in(whole, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::ofstream(truncated, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 2));
    }
    CHECK_THAT(messageOf<InputError>([&] { readVoxelFile(truncated); }), Contains(truncated));

    // tools/fuzz/fuzz_vdb's findings. Lengths that OpenVDB allocates (and, for a metadata
    // string, fills) before reading them are refused before they are allocated, naming the size
    // claimed (a 10 kB file's 2.5 GB metadata name); a root node claiming 2^32 tiles stops at
    // the file's end (OpenVDB read past it, then failed on a block); a raw block longer than
    // its leaf is refused (OpenVDB 10.0 wrote it past the leaf's buffer: voxel/vdb_blocks.cpp;
    // this test runs under ASan in CI).
    const std::string data = test::sourceDir() + "/tests/voxel/data/";
    for (const auto& [file, says] : {std::pair<std::string, std::string>{"blosc_claims_2e48.vdb",
                                                                         "claims a block of 281474976710656 bytes"},
                                     {"metadata_claims_2.5GB.vdb", "claims a block of 2560137369 bytes"},
                                     {"root_tiles_past_its_end.vdb", "it ends, or cannot be read, before its grids do"},
                                     {"raw_block_longer_than_its_leaf.vdb", "raw bytes for a node of 224"}}) {
        const std::string claims = data + file;
        if (!AllocationLimit::enforced && says.find("claims a block") != std::string::npos) continue;  // TSan's build
        CHECK_THAT(messageOf<InputError>([&] { readVoxelFile(claims); }),
                   Contains(claims) && Contains("not a readable OpenVDB file") && Contains(says));
        CHECK_THAT(messageOf<InputError>([&] { inspectVoxelFile(claims); }), Contains(claims) && Contains(says));
    }

    // A grid that is not there.
    const std::string absent = messageOf<InputError>([&] { sliceImage(whole, "density", SliceAxis::X, 0); });
    CHECK_THAT(absent, Contains(whole) && Contains("'density'") && Contains("'albedo'"));
    CHECK_THAT(messageOf<InputError>([&] { readExtraGrid(whole, "radiance_mip3"); }),
               Contains(whole) && Contains("radiance_mip3"));
    CHECK_THAT(messageOf<InputError>([&] { readExtraGrid(whole, "solid"); }),
               Contains("'solid'") && Contains("bool"));
}
