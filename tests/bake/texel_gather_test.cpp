// The final gather in a lightmap's texel space (gather/texel_gather.h) against what a step in a
// floor must show under a uniform sky: its top, open to the whole sky, holds L at every texel up
// to its edge; the floor at its foot loses the sky the step's face hides, by quadrature; and the
// records' filter neither lifts the shaded foot onto the top nor darkens the top from it.
#include "bake/bake.h"
#include "receivers/receivers.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

constexpr float kStep = 0.03f;  // the step's height: under a voxel, as a skirting board or a rug's edge

// A black lower floor (x < 0), the step's black face (x = 0, facing −X) and its grey top (x > 0,
// at y = kStep), 2 m deep along Z, under a uniform sky. The top's light reaches neither the floor
// nor the face (both lie below its plane), and it sees only the sky: every texel's light is the
// sky's. The top is grey so the bake has voxel light to gather: a black scene has none and its
// lightmaps take the sky per sample, without records.
Scene blackStep() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f)), grey = addLambert(scene, vec3(0.5f));
    addQuad(scene, "lower", black, vec3(-1.5f, 0, -1), vec3(-1.5f, 0, 1), vec3(0, 0, 1), vec3(0, 0, -1));
    addQuad(scene, "face", black, vec3(0, 0, -1), vec3(0, 0, 1), vec3(0, kStep, 1), vec3(0, kStep, -1));
    addQuad(scene, "top", grey, vec3(0, kStep, -1), vec3(0, kStep, 1), vec3(1.5f, kStep, 1), vec3(1.5f, kStep, -1));
    return scene;
}

// The share of a uniform sky's irradiance that reaches the floor point (−d, 0, z) past the
// step's face: 1 − the face's form factor, ∫ cosθ_p cosθ_f / (π r²) dA by the midpoint rule.
double openShare(double d, double z) {
    const int n = 400;
    double hidden = 0.0;
    const double dz = 2.0 / n, dy = double(kStep) / n;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double fz = -1.0 + (i + 0.5) * dz - z, fy = (j + 0.5) * dy;
            const double r2 = d * d + fy * fy + fz * fz;
            hidden += (fy / std::sqrt(r2)) * (d / std::sqrt(r2)) / (M_PI * r2) * dz * dy;  // cos at the point, at the face
        }
    return 1.0 - hidden;
}

}  // namespace

TEST_CASE("A step under a uniform sky: its top holds L to its edge, its foot the sky its face leaves", "[bake]") {
    const Scene scene = blackStep();
    BakeSettings settings = quietSettings();
    settings.sky = vec3(1.0f);
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 128;  // 1.2 × 1.6 cm texels on the floors
    settings.gather.visibility = GatherVisibility::Rays;         // the texel gather's precondition
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    REQUIRE(result.gatherVisibility.visibility == GatherVisibility::Rays);
    Diagnostics quiet(false, false);
    const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, settings.lightmap, quiet);
    REQUIRE(result.lightmaps.size() == atlases.size());

    // The top: every texel L (all of the sky), the row at its edge too.
    double topWorst = 0.0, topEdgeSum = 0.0;
    size_t topTexels = 0, topEdgeTexels = 0;
    // The foot: texels within 15 cm of the face (|z| < 0.8, away from the face's ends), their
    // mean against the quadrature's mean at their own positions; beyond 30 cm each texel.
    double footBake = 0.0, footExact = 0.0, farWorst = 0.0;
    vec3 farWorstAt(0.0f);
    size_t footTexels = 0, farTexels = 0;
    for (size_t a = 0; a < atlases.size(); ++a) {
        const SurfaceSampleSet& set = atlases[a].receivers;
        const Image& total = result.lightmaps[a].total;
        for (int y = 0; y < set.height; ++y)
            for (int x = 0; x < set.width; ++x) {
                const size_t texel = size_t(y) * size_t(set.width) + size_t(x);
                if (!set.covered(texel)) continue;
                const vec3 p = set.samples[set.begin[texel]].position;
                if (set.samples[set.begin[texel]].normal.y < 0.9f) continue;  // the face
                const double value = total.at(x, y, 1);
                if (p.y > 0.5f * kStep && p.x > 0.0f) {  // the top
                    ++topTexels;
                    topWorst = std::max(topWorst, std::abs(value - 1.0));
                    if (p.x < 0.02f) {
                        ++topEdgeTexels;
                        topEdgeSum += value;
                    }
                } else if (p.y < 0.5f * kStep && std::abs(p.z) < 0.8f) {  // the lower floor
                    const double d = -double(p.x);
                    if (d < 0.15) {
                        ++footTexels;
                        footBake += value;
                        footExact += openShare(d, p.z);
                    } else if (d > 0.3) {
                        ++farTexels;
                        const double off = std::abs(value - openShare(d, p.z));
                        if (off > farWorst) {
                            farWorst = off;
                            farWorstAt = p;
                        }
                    }
                }
            }
    }
    REQUIRE(topTexels > 5000);
    REQUIRE(topEdgeTexels > 50);
    REQUIRE(footTexels > 500);
    REQUIRE(farTexels > 5000);
    INFO("top: worst " << topWorst << ", edge mean " << topEdgeSum / double(topEdgeTexels) << "; foot mean "
                       << footBake / double(footTexels) << " against " << footExact / double(footTexels)
                       << "; far worst " << farWorst << " at " << farWorstAt.x << ", " << farWorstAt.z);
    // The step is 3 cm, under a voxel: a gather shared across it would lower the top's edge
    // toward the foot's ~0.75 and lift the foot. Each record's fan of jittered rays sees the
    // open sky exactly (every ray escapes), so the top is L to rounding.
    CHECK(topWorst < 1e-3);
    CHECK(topEdgeSum / double(topEdgeTexels) == Approx(1.0).epsilon(1e-3));
    // The foot's mean: the shadow is steep over its first 3 cm, about one lattice step (2
    // texels here); the records there, read bilinearly and filtered, lift it (docs/accuracy.md:
    // contact shadows). The shadow must be there, within 5% of its mean.
    CHECK(footBake / double(footTexels) == Approx(footExact / double(footTexels)).epsilon(0.05));
    CHECK(footBake / double(footTexels) < 0.96);  // the far floor holds > 0.997
    // Far from the face the sky is all but whole: no texel is off by as much as one of its
    // record's 8 × 8 rays (1/64 of the sky), the records filtered.
    CHECK(farWorst < 1.0 / 64.0);
}

namespace {

constexpr float kBlockHalf = 0.3f, kBlockHeight = 0.3f;

// A grey floor [−1, 1]² (one chart, 64² texels of 3.125 cm) with a black block standing on it,
// [−0.3, 0.3] across x and z and 0.3 m high, its five faces wound outward and no bottom, under
// a uniform sky. Its faces lie 3 mm past the centres of the texels under its edges. Nothing lit
// reflects onto the floor, so a floor point's E/π is the share of the sky the block leaves it.
Scene blockOnAFloor() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f)), grey = addLambert(scene, vec3(0.5f));
    addQuad(scene, "floor", grey, vec3(-1, 0, -1), vec3(-1, 0, 1), vec3(1, 0, 1), vec3(1, 0, -1));
    const float s = kBlockHalf, h = kBlockHeight;
    addQuad(scene, "block top", black, vec3(-s, h, -s), vec3(-s, h, s), vec3(s, h, s), vec3(s, h, -s));
    addQuad(scene, "block +x", black, vec3(s, 0, -s), vec3(s, h, -s), vec3(s, h, s), vec3(s, 0, s));
    addQuad(scene, "block -x", black, vec3(-s, 0, -s), vec3(-s, 0, s), vec3(-s, h, s), vec3(-s, h, -s));
    addQuad(scene, "block +z", black, vec3(-s, 0, s), vec3(s, 0, s), vec3(s, h, s), vec3(-s, h, s));
    addQuad(scene, "block -z", black, vec3(-s, 0, -s), vec3(-s, h, -s), vec3(s, h, -s), vec3(s, 0, -s));
    return scene;
}

// The share of a uniform sky's irradiance that reaches the floor point (x, 0, z), x > 0.3 and
// |z| < 0.3, past the block's +x face (the only face it sees): 1 − the face's form factor,
// by the midpoint rule.
double openBesideBlock(double x, double z) {
    const int n = 300;
    const double d = x - kBlockHalf, dz = 2.0 * kBlockHalf / n, dy = double(kBlockHeight) / n;
    double hidden = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double fz = -kBlockHalf + (i + 0.5) * dz - z, fy = (j + 0.5) * dy;
            const double r2 = d * d + fy * fy + fz * fz;
            hidden += (fy / std::sqrt(r2)) * (d / std::sqrt(r2)) / (M_PI * r2) * dz * dy;
        }
    return 1.0 - hidden;
}

}  // namespace

TEST_CASE("A floor under a block: the texels under it hold their open neighbours' light, so its foot shows no dark "
          "line",
          "[bake]") {
    // A texel whose samples all lie under the block is inside closed geometry: nobody sees it,
    // but the bilinear read at the block's foot reaches it. It must hold its open neighbours'
    // light, not black. The read at the +x face's foot lies a tenth of the way from the texel
    // under the block to the open one, so black under the block would hold it near a tenth of
    // the sky there. Both gathers: records on the texels, and the voxel gather points.
    const LightmapGather gather = GENERATE(LightmapGather::Texels, LightmapGather::Points);
    const Scene scene = blockOnAFloor();
    BakeSettings settings = quietSettings();
    settings.sky = vec3(1.0f);
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 64;
    settings.gather.visibility = GatherVisibility::Rays;
    settings.gather.lightmapGather = gather;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    Diagnostics quiet(false, false);
    const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, settings.lightmap, quiet);
    size_t a = 0;
    while (a < atlases.size() && atlases[a].name.find("floor") == std::string::npos) ++a;
    REQUIRE(a < atlases.size());
    const SurfaceSampleSet& set = atlases[a].receivers;
    const BakedLightmap& floor = result.lightmaps[a];
    REQUIRE(set.width == 64);
    REQUIRE(set.height == 64);

    // A texel's samples (one a smooth surface it covers, at the mean of its part) all under the block.
    size_t under = 0;
    double darkest = 1.0;
    for (size_t texel = 0; texel < set.elementCount(); ++texel) {
        bool inside = set.sampleCount(texel) > 0;
        for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k) {
            const vec3 p = set.samples[k].position;
            inside = inside && std::abs(p.x) < kBlockHalf && std::abs(p.z) < kBlockHalf;
        }
        if (!inside) continue;
        ++under;
        darkest = std::min(darkest, double(floor.total.at(int(texel % 64), int(texel / 64), 1)));
    }
    // Texel centres 3 mm under the block's faces on both axes: the floor is one flat surface,
    // so each texel holds one sample at its centre, the diagonal's texels too.
    CHECK(under == 20 * 20);
    CHECK(floor.buriedTexels == under);
    CHECK(darkest > 0.3);  // the shadow at the foot is about half the sky

    // The bilinear read along the +x face's foot, 1 mm out (texel coordinates: x = 32 (x + 1) −
    // ½, y = 32 (1 − z) − ½), against the sky the face leaves there, in the middle rows.
    double read = 0.0, exact = 0.0;
    int points = 0;
    for (float z = -0.15f; z <= 0.15f; z += 0.01f, ++points) {
        const float x = kBlockHalf + 0.001f, u = 32.0f * (x + 1.0f) - 0.5f, v = 32.0f * (1.0f - z) - 0.5f;
        const int i = int(std::floor(u)), j = int(std::floor(v));
        const float fu = u - float(i), fv = v - float(j);
        const auto at = [&](int di, int dj) { return double(floor.total.at(i + di, j + dj, 1)); };
        read += (1 - fv) * ((1 - fu) * at(0, 0) + fu * at(1, 0)) + fv * ((1 - fu) * at(0, 1) + fu * at(1, 1));
        exact += openBesideBlock(x, z);
    }
    read /= points;
    exact /= points;
    INFO("the read at the face's foot " << read << " against the sky it leaves there, " << exact);
    CHECK(exact == Approx(0.5).margin(0.05));  // the face hides half the sky at its foot
    // The texels beside the foot hold the light 1.6 cm out, where the shadow is steep: above
    // the foot's own.
    CHECK(read == Approx(exact).epsilon(0.25));
}

TEST_CASE("The records' filter keeps a ceiling's light where a small bright spot makes its records' noise lopsided",
          "[bake]") {
    // A grey room 2 × 1 × 2 m with a lamp 3 cm over the middle of its floor: the floor's spot
    // under it is a few centimetres wide and holds most of the light the ceiling gets, so a
    // ceiling record's few rays that meet it read far more than the many that miss. Its noise is
    // lopsided: a record whose rays caught the spot is bright with a wide spread, one whose rays
    // missed it is dark with a narrow one. Each record's estimate is unbiased, and the filter
    // averages records, so the ceiling's mean must not move with the filter. Judged by the
    // record's own spread alone, the filter let the bright records take their neighbours' light
    // and the dark ones refuse theirs, and the mean fell.
    Scene scene;
    addRoom(scene, "", addLambert(scene, vec3(0.6f)), vec3(-1.0f, 0.0f, -1.0f), vec3(1.0f, 1.0f, 1.0f));
    scene.lights.push_back(pointLightAt(vec3(0.0f, 0.03f, 0.0f), 1.0f));
    BakeSettings settings = quietSettings();
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 64;
    settings.gather.visibility = GatherVisibility::Rays;
    settings.gather.texelGatherRays = 6;  // few rays: the spot is met by one record in several
    const auto ceilingIndirect = [&](int filterPasses) {
        settings.gather.lightmapFilterPasses = filterPasses;
        Diagnostics diagnostics(false, false);
        const BakeResult result = bake(scene, settings, diagnostics);
        for (const BakedLightmap& lightmap : result.lightmaps)
            if (lightmap.name.find("ceiling") != std::string::npos) {
                double sum = 0.0;
                size_t texels = 0;
                for (int y = 0; y < lightmap.mask.height; ++y)
                    for (int x = 0; x < lightmap.mask.width; ++x)
                        if (lightmap.mask.at(x, y, 0) > 0.5f) {
                            sum += lightmap.indirect.at(x, y, 1);
                            ++texels;
                        }
                REQUIRE(texels > 3000);
                return sum / double(texels);
            }
        FAIL("no ceiling lightmap");
        return 0.0;
    };
    const double unfiltered = ceilingIndirect(0), filtered = ceilingIndirect(3);
    INFO("the ceiling's mean indirect E/π: filtered " << filtered << ", unfiltered " << unfiltered);
    REQUIRE(unfiltered > 0.0);
    // The unfiltered mean's own noise, over some 200 records of 36 rays: well under 1%.
    CHECK(filtered == Approx(unfiltered).epsilon(0.01));
}
