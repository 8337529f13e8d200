#include "cluster/voxel_state.h"

#include "cluster/unit_file.h"
#include "core/error.h"
#include "gather/gather.h"
#include "lighting/surface_points.h"
#include "voxel/voxelize.h"

#include <type_traits>

namespace vl::cluster {
namespace {

using nlohmann::json;

json atlasJson(const AtlasGroup& group) {
    return {{"name", group.name},   {"meshes", group.meshes}, {"mesh_indices", group.meshIndices},
            {"width", group.width}, {"height", group.height}, {"origin", group.origin}};
}

AtlasGroup atlasFrom(const json& j) {
    AtlasGroup group;
    group.name = j.at("name").get<std::string>();
    group.meshes = j.at("meshes").get<std::vector<std::string>>();
    group.meshIndices = j.at("mesh_indices").get<std::vector<uint32_t>>();
    group.width = j.at("width").get<int>();
    group.height = j.at("height").get<int>();
    group.origin = j.at("origin").get<std::string>();
    return group;
}

// The voxels' channels and the gathered irradiance, in the order the file stores them: the
// writer and the reader both walk this one list (`v` const or not).
template <typename Voxels, typename Irradiance, typename Visit>
void forEachArray(Voxels& v, Irradiance& irradiance, Visit&& visit) {
    visit(v.coords);
    visit(v.albedo);
    visit(v.normal);
    visit(v.axisWeights);
    visit(v.emission);
    visit(v.surfaceOffset);
    visit(v.opacity);
    visit(v.solid);
    visit(v.radiance);
    visit(v.faceRadiance);
    visit(v.occlusion);
    visit(irradiance);
}

}  // namespace

void writeVoxelState(const VoxelStages& stages, size_t triangles, const std::vector<std::string>& sceneWarnings,
                     double loadSeconds, const std::vector<std::string>& stageWarnings, const std::string& path) {
    const BakeResult& r = stages.result;
    const VoxelScene& v = r.voxels;
    UnitFile file;
    json& h = file.header;
    h["kind"] = "voxel state";
    h["tool_version"] = VOXLIGHT_VERSION;
    h["voxel_size"] = v.voxelSize;
    h["origin"] = {v.origin.x, v.origin.y, v.origin.z};
    for (int c = 0; c < 3; ++c) h["frame"].push_back({v.frame[c].x, v.frame[c].y, v.frame[c].z});
    const VoxelSizeChoice& c = r.voxelSizeChoice;
    h["choice"] = {{"voxel_size", c.voxelSize}, {"along_longest", c.voxelsAlongLongest}, {"set_by", c.setBy},
                   {"warnings", c.warnings}};
    const FreePaths& f = c.freePaths;
    h["choice"]["free_paths"] = {f.rays, f.hits, f.singleSidedBacks, f.mean, f.median};
    for (const LightClearance& clearance : c.clearances)
        h["choice"]["clearances"].push_back({{"light", clearance.light}, {"metres", clearance.metres}});
    for (const StageTime& s : r.stages) h["stages"].push_back({{"stage", s.stage}, {"seconds", s.seconds}});
    h["gather_points"] = r.gatherPoints;
    h["bright_patches"] = r.brightPatches;
    h["gather_visibility"] = {{"visibility", toString(r.gatherVisibility.visibility)},
                              {"set_by", r.gatherVisibility.setBy},
                              {"probe_hits", r.gatherVisibility.probe.hits},
                              {"probe_backs", r.gatherVisibility.probe.singleSidedBacks}};
    if (r.lightmapUvs) {
        const LightmapUvReport& u = *r.lightmapUvs;
        h["lightmap_uvs"] = {{"width", u.width},         {"height", u.height},           {"meshes", u.meshes},
                             {"charts", u.charts},       {"texel_size", u.texelSize},    {"occupancy", u.occupancy},
                             {"max_stretch", u.maxStretch}, {"mean_stretch", u.meanStretch}, {"seconds", u.seconds},
                             {"grown_charts", u.grownCharts}, {"asked_texel_size", u.askedTexelSize},
                             {"merged_across_creases", u.mergedAcrossCreases},
                             {"small_charts", json::array()}};
        for (const SmallCharts& small : u.smallCharts)
            h["lightmap_uvs"]["small_charts"].push_back({{"mesh", small.mesh}, {"charts", small.charts}});
    }
    h["lightmap"] = {{"width", stages.lightmap.width}, {"height", stages.lightmap.height}, {"atlases", json::array()}};
    for (const AtlasGroup& group : stages.lightmap.atlases) h["lightmap"]["atlases"].push_back(atlasJson(group));
    h["gathered"] = r.gatherPoints > 0;
    h["gather_level"] = stages.indirect.cache.level();
    h["on_gpu"] = stages.onGpu;
    h["triangles"] = triangles;
    h["load_seconds"] = loadSeconds;
    h["scene_warnings"] = sceneWarnings;
    h["stage_warnings"] = stageWarnings;
    h["mesh_count"] = r.generatedLayouts.size();

    forEachArray(v, stages.indirect.cache.irradiance(), [&](const auto& array) { file.add(array); });
    // Per mesh, the layout glTF out writes: its source, and for meshes given generated UVs
    // their split vertices (indices into the primitive), uv1 and triangles.
    for (const GeneratedLayout& layout : r.generatedLayouts) {
        h["layouts"].push_back({{"mesh", layout.source.mesh},
                                {"primitive", layout.source.primitive},
                                {"node", layout.source.node},
                                {"mirrored", layout.source.mirrored}});
        file.add(layout.source.vertices);
        file.add(layout.uv1);
        file.add(layout.indices);
    }
    writeUnitFile(file, path);
}

VoxelState readVoxelState(const std::string& path) {
    const UnitFile file = readUnitFile(path);
    const json& h = file.header;
    if (h.value("kind", "") != "voxel state") throw InputError(path + ": not a voxel state");
    if (h.value("tool_version", "") != VOXLIGHT_VERSION)
        throw InputError(path + ": written by voxlight " + h.value("tool_version", "?") + ", this is " + VOXLIGHT_VERSION);
    if (!h.contains("frame") || !h.contains("choice") || !h.at("choice").contains("free_paths"))
        throw InputError(path + ": written by a build of voxlight " + VOXLIGHT_VERSION +
                         " from before the grid turned with the scene (no frame): bake its voxel unit again");
    VoxelState state;
    BakeResult& r = state.result;
    VoxelScene& v = r.voxels;
    v.voxelSize = h.at("voxel_size").get<double>();
    v.origin = glm::dvec3(h.at("origin")[0].get<double>(), h.at("origin")[1].get<double>(), h.at("origin")[2].get<double>());
    for (int c = 0; c < 3; ++c)
        v.frame[c] = glm::dvec3(h.at("frame")[c][0].get<double>(), h.at("frame")[c][1].get<double>(),
                                h.at("frame")[c][2].get<double>());
    const json& c = h.at("choice");
    r.voxelSizeChoice.voxelSize = c.at("voxel_size").get<double>();
    r.voxelSizeChoice.voxelsAlongLongest = c.at("along_longest").get<int>();
    r.voxelSizeChoice.setBy = c.at("set_by").get<std::string>();
    r.voxelSizeChoice.warnings = c.at("warnings").get<std::vector<std::string>>();
    const json& f = c.at("free_paths");
    r.voxelSizeChoice.freePaths = {f[0].get<int>(), f[1].get<int>(), f[2].get<int>(), f[3].get<double>(),
                                   f[4].get<double>()};
    if (c.contains("clearances"))
        for (const json& clearance : c["clearances"])
            r.voxelSizeChoice.clearances.push_back({clearance.at("light").get<std::string>(), clearance.at("metres").get<double>()});
    if (h.contains("stages"))
        for (const json& s : h["stages"]) r.stages.push_back({s.at("stage").get<std::string>(), s.at("seconds").get<double>()});
    r.gatherPoints = h.at("gather_points").get<size_t>();
    r.brightPatches = h.at("bright_patches").get<size_t>();
    const json& g = h.at("gather_visibility");
    r.gatherVisibility.visibility = parseGatherVisibility(g.at("visibility").get<std::string>());
    r.gatherVisibility.setBy = g.at("set_by").get<std::string>();
    r.gatherVisibility.probe.hits = g.at("probe_hits").get<uint64_t>();
    r.gatherVisibility.probe.singleSidedBacks = g.at("probe_backs").get<uint64_t>();
    if (h.contains("lightmap_uvs")) {
        const json& u = h["lightmap_uvs"];
        LightmapUvReport uvs;
        uvs.width = u.at("width").get<int>();
        uvs.height = u.at("height").get<int>();
        uvs.meshes = u.at("meshes").get<size_t>();
        uvs.charts = u.at("charts").get<size_t>();
        uvs.texelSize = u.at("texel_size").get<double>();
        uvs.occupancy = u.at("occupancy").get<double>();
        uvs.maxStretch = u.at("max_stretch").get<double>();
        uvs.meanStretch = u.at("mean_stretch").get<double>();
        uvs.seconds = u.at("seconds").get<double>();
        uvs.grownCharts = u.value("grown_charts", uvs.charts);
        uvs.askedTexelSize = u.value("asked_texel_size", 0.0);
        uvs.mergedAcrossCreases = u.value("merged_across_creases", false);
        for (const json& small : u.value("small_charts", json::array()))
            uvs.smallCharts.push_back({small.at("mesh").get<std::string>(), small.at("charts").get<size_t>()});
        r.lightmapUvs = uvs;
    }
    state.lightmap.width = h.at("lightmap").at("width").get<int>();
    state.lightmap.height = h.at("lightmap").at("height").get<int>();
    for (const json& group : h.at("lightmap").at("atlases")) state.lightmap.atlases.push_back(atlasFrom(group));
    state.gathered = h.at("gathered").get<bool>();
    state.gatherLevel = h.at("gather_level").get<int>();
    state.onGpu = h.at("on_gpu").get<bool>();
    state.triangles = h.at("triangles").get<size_t>();
    state.loadSeconds = h.at("load_seconds").get<double>();
    state.sceneWarnings = h.at("scene_warnings").get<std::vector<std::string>>();
    state.stageWarnings = h.at("stage_warnings").get<std::vector<std::string>>();

    size_t next = 0;
    forEachArray(v, state.gatheredIrradiance, [&](auto& array) {
        array = file.take<typename std::decay_t<decltype(array)>::value_type>(next++, path);
    });
    const size_t meshes = h.at("mesh_count").get<size_t>();
    for (size_t m = 0; m < meshes; ++m) {
        const json& l = h.at("layouts").at(m);
        GeneratedLayout layout;
        layout.source.mesh = l.at("mesh").get<int>();
        layout.source.primitive = l.at("primitive").get<int>();
        layout.source.node = l.at("node").get<int>();
        layout.source.mirrored = l.at("mirrored").get<bool>();
        layout.source.vertices = file.take<uint32_t>(next + 3 * m, path);
        layout.uv1 = file.take<vec2>(next + 3 * m + 1, path);
        layout.indices = file.take<uint32_t>(next + 3 * m + 2, path);
        r.generatedLayouts.push_back(std::move(layout));
    }
    const size_t n = v.coords.size();
    for (size_t size : {v.albedo.size(), v.normal.size(), v.axisWeights.size(), v.opacity.size(), v.solid.size(),
                        v.radiance.size(), v.faceRadiance.size()})
        if (size != n) throw InputError(path + ": its voxel channels differ in length");
    return state;
}

Scene receiverScene(Scene loaded, const VoxelState& state) {
    Scene scene = std::move(loaded);
    // The voxel unit's turn, to the last bit (the state keeps doubles), then its anchor.
    const VoxelScene& voxels = state.result.voxels;
    if (voxels.frame != scene.frame) scene.turnFrame(voxels.frame);
    anchorToVoxelGrid(scene, voxels.voxelSize);
    if (scene.origin != voxels.origin)
        throw InputError(scene.sourcePath + ": lies otherwise than in the voxel unit's state: the scene changed");
    const std::vector<GeneratedLayout>& layouts = state.result.generatedLayouts;
    if (!layouts.empty() && layouts.size() != scene.meshes.size())
        throw InputError(scene.sourcePath + ": has " + std::to_string(scene.meshes.size()) +
                         " meshes, the voxel unit's state " + std::to_string(layouts.size()) + ": the scene changed");
    for (size_t m = 0; m < layouts.size(); ++m) {
        const GeneratedLayout& layout = layouts[m];
        if (layout.uv1.empty()) continue;
        // The generated UVs split vertices: vertex k is the loaded mesh's vertex vertices[k].
        const Mesh& original = scene.meshes[m];
        Mesh mesh = original.withoutVertices();
        for (uint32_t old : layout.source.vertices) {
            if (old >= original.positions.size())
                throw InputError(scene.sourcePath + ": mesh '" + original.name + "' changed since its voxel unit ran");
            mesh.appendVertexOf(original, old);
        }
        mesh.source.vertices = layout.source.vertices;
        mesh.uv1 = layout.uv1;
        mesh.indices = layout.indices;
        scene.meshes[m] = std::move(mesh);
    }
    return scene;
}

IndirectLight restoreIndirectLight(const VoxelState& state, const ReceiverScene& tracing, const BakeSettings& settings) {
    const VoxelScene& voxels = state.result.voxels;
    const TraceSceneView view = tracing.traceScene.view();
    const GatherInputs inputs = gatherInputs(settings);
    const VoxelSurfacePoints points = gatherNeedsSurfacePoints(settings.gather, inputs, view.lightCount > 0)
                                          ? voxelSurfacePoints(voxels, view, settings.lighting.surfacePoints)
                                          : VoxelSurfacePoints{};
    return vl::restoreIndirectLight(voxels, state.result.gatherVisibility,
                                    state.gathered ? &state.gatheredIrradiance : nullptr, points,
                                    GatherScene{tracing.bvh.view(), view}, settings.gather, inputs);
}

}  // namespace vl::cluster
