// voxlight bench [scene.gltf | job.json] [-o dir]: speed against error (tools/bench/run.h).
// Default scene: the Cycles Cornell quad of ../shared/reference, compared with Cycles' 4096-spp
// lightmap and render, with the lower-spp Cycles files as a second Cycles curve; without
// ../shared, the project's scenes/cornell_box.gltf against a path-traced reference.
#include "tools/voxlight/commands.h"

#include "bake/job_file.h"
#include "bench/display_path.h"
#include "bench/run.h"
#include "core/error.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <utility>

namespace vl::cli {
namespace {
namespace fs = std::filesystem;

struct BenchCliOptions {
    std::string input;
    std::string output;
    std::vector<std::pair<std::string, std::string>> settings;
    std::vector<std::string> vctPoints;  // "name=value;name=value" each
    std::vector<int> pathSpp;
    bool full = false;
    int repeats = 3;
    double repeatLimit = 30.0;
    BenchReferenceFiles reference;
    bool pathTracedReference = false;
    BenchReferenceSettings referenceSettings;
    float excludeAbove = 5.0f;
    std::string blender;
    std::vector<int> cyclesSpp = {16, 64, 256};
    bool noCyclesFiles = false;
    bool noPlot = false;
    bool quiet = false;
    bool scaling = false;    // --scaling: even when --methods leaves out vct
    bool noScaling = false;
    std::vector<size_t> scalingTriangles;  // --scaling-triangles: the triangle axis (empty: none)
    std::vector<std::string> methods;  // empty = all
    std::string commandLine;
};

std::string sharedReferenceDir() { return std::string(VOXLIGHT_SOURCE_DIR) + "/../shared/reference"; }

bool sameFile(const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

std::vector<std::pair<std::string, std::string>> parsePointSettings(const std::string& text) {
    std::vector<std::pair<std::string, std::string>> settings;
    std::istringstream in(text);
    std::string item;
    while (std::getline(in, item, ';')) {
        if (item.empty()) continue;
        const size_t eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
            throw SettingsError("vct: '" + item + "' in '" + text + "' is not name=value");
        settings.emplace_back(item.substr(0, eq), item.substr(eq + 1));
    }
    return settings;
}

BenchOptions plan(const BenchCliOptions& o) {
    BenchOptions options;
    BakeSettings settings;
    for (const auto& [name, value] : o.settings) applySetting(bakeSettingsTable(), settings, name, value);
    settings.quiet = true;
    validateBakeSettings(settings);

    const std::string refDir = sharedReferenceDir();
    std::string input = o.input;
    if (input.empty())
        input = fs::exists(refDir + "/cornell_quad.gltf") ? refDir + "/cornell_quad.gltf" : defaultScenePath();
    if (fs::path(input).extension() == ".json") {
        std::vector<BakeJob> jobs = readJobFile(input, settings, "output", o.settings);
        if (jobs.empty()) throw InputError(input + ": the job file names no scene");
        options.base = std::move(jobs.front());
        if (jobs.size() > 1)
            std::fprintf(stderr, "bench: %s names %zu scenes; benching the first, %s\n", input.c_str(), jobs.size(),
                         options.base.scenePath.c_str());
    } else {
        options.base.scenePath = input;
        options.base.settings = settings;
    }
    options.base.settings.quiet = true;
    options.base.outputDir =
        o.output.empty() ? "output/" + sceneOutputName(options.base.scenePath) + "/bench" : o.output;

    options.reference = o.reference;
    // The Cycles Cornell boxes compare with Cycles' own references unless told otherwise.
    for (const std::string variant : {"quad", "point"}) {
        const std::string scene = refDir + "/cornell_" + variant + ".gltf";
        if (o.pathTracedReference || options.reference.any() || !sameFile(options.base.scenePath, scene)) continue;
        const std::string cycles = refDir + "/cycles/cornell_" + variant;
        options.reference.lightmap = cycles + "_lightmap_4096spp.exr";
        options.reference.lightmapDirect = cycles + "_lightmap_direct_4096spp.exr";
        options.reference.lightmapMask = cycles + "_lightmap_mask.exr";
        options.reference.image = cycles + "_render_4096spp.exr";
        if (!o.noCyclesFiles) options.cyclesFilesDir = refDir + "/cycles";
    }
    options.referenceSettings = o.referenceSettings;
    options.full = o.full;
    options.repeats = o.repeats;
    options.repeatLimitSeconds = o.repeatLimit;
    options.imageExcludeAbove = o.excludeAbove;
    options.blender = o.blender;
    options.cyclesScript = std::string(VOXLIGHT_SOURCE_DIR) + "/tools/bench/cycles_bake.py";
    options.cyclesSpp = o.cyclesSpp;
    // The stage scaling is about the VCT bake: on unless the run leaves the bake out.
    const bool vctWanted = o.methods.empty() || std::find(o.methods.begin(), o.methods.end(), "vct") != o.methods.end();
    options.scaling = o.scaling || (!o.noScaling && vctWanted) || !o.scalingTriangles.empty();
    options.scalingAxes.triangles = o.scalingTriangles;
    options.plot = !o.noPlot;
    options.quiet = o.quiet;
    options.commandLine = o.commandLine;
    if (!o.vctPoints.empty() || !o.pathSpp.empty()) {
        const std::vector<BenchPointSpec> sweep = benchSweep(o.full);
        for (const std::string& text : o.vctPoints)
            options.points.push_back({"vct", text.empty() ? "default" : text, parsePointSettings(text), 0});
        if (o.vctPoints.empty())
            for (const BenchPointSpec& p : sweep)
                if (p.method == "vct") options.points.push_back(p);
        for (int spp : o.pathSpp) {
            if (spp < 1) throw SettingsError("path-spp: " + std::to_string(spp) + " must be at least 1");
            options.points.push_back({"path", "spp=" + std::to_string(spp), {}, spp});
        }
        if (o.pathSpp.empty())
            for (const BenchPointSpec& p : sweep)
                if (p.method == "path") options.points.push_back(p);
    }
    if (!o.methods.empty()) {
        for (const std::string& m : o.methods)
            if (m != "vct" && m != "path" && m != "cycles")
                throw SettingsError("methods: '" + m + "' is not one of vct, path, cycles");
        const auto wanted = [&](const std::string& m) { return std::find(o.methods.begin(), o.methods.end(), m) != o.methods.end(); };
        if (options.points.empty()) options.points = benchSweep(o.full);
        std::vector<BenchPointSpec> kept;
        for (const BenchPointSpec& p : options.points)
            if (wanted(p.method)) kept.push_back(p);
        options.points = kept;
        options.pointsGiven = true;
        if (!wanted("cycles")) {
            options.blender = "none";
            options.cyclesFilesDir.clear();
        }
    }
    return options;
}

// This process's command line (for the report's "regenerate with"), the binary as build/voxlight
// and paths as run from the repository's root (never relative to the bench folder: the line is
// not run there).
std::string commandLine() {
    std::ifstream in("/proc/self/cmdline", std::ios::binary);
    std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::string> args;
    for (size_t start = 0; start < all.size();) {
        const size_t end = all.find('\0', start);
        args.push_back(all.substr(start, end == std::string::npos ? std::string::npos : end - start));
        if (end == std::string::npos) break;
        start = end + 1;
    }
    std::string line = "build/voxlight";
    for (size_t i = 1; i < args.size(); ++i) {
        const size_t eq = args[i].rfind("--", 0) == 0 ? args[i].find('=') : std::string::npos;  // --name=value
        const std::string arg = eq == std::string::npos ? displayPath(args[i], "")
                                                        : args[i].substr(0, eq + 1) + displayPath(args[i].substr(eq + 1), "");
        const bool plain = !arg.empty() && arg.find_first_of(" ;'\"$`\\*?()<>|&") == std::string::npos;
        line += " " + (plain ? arg : "'" + arg + "'");
    }
    return line;
}

}  // namespace

void addBenchCommand(CLI::App& app) {
    auto o = std::make_shared<BenchCliOptions>();
    auto* cmd = app.add_subcommand(
        "bench", "speed against error: VCT settings, path-tracer spp (and Cycles when Blender is installed) against one "
                 "reference, then how each bake stage scales; writes bench.csv, bench.json, bench.png, heat maps and bench.md");
    cmd->add_option("input", o->input,
                    "scene (.gltf, .glb) or job file (.json: its first scene and settings); default: the Cycles Cornell "
                    "quad of ../shared/reference, else scenes/cornell_box.gltf");
    cmd->add_option("-o,--output", o->output, "output folder (default output/<scene name>/bench)");
    cmd->add_flag("--full", o->full, "the full sweep (more values per setting, path tracer 4..1024 spp)");
    cmd->add_option("--repeats", o->repeats, "runs per point; times are their median (default 3)");
    cmd->add_option("--repeat-limit", o->repeatLimit, "a point whose first run takes longer (s) is timed once (default 30)");
    cmd->add_option("--vct", o->vctPoints,
                    "a VCT point as 'name=value;name=value' of bake settings ('' = the defaults); replaces the VCT sweep")
        ->allow_extra_args(false);
    cmd->add_option("--path-spp", o->pathSpp, "path-tracer spp points; replace the default 16 64 256");
    cmd->add_option("--reference-lightmap", o->reference.lightmap, "reference lightmap EXR (E/π, total)");
    cmd->add_option("--reference-lightmap-direct", o->reference.lightmapDirect, "its direct part (indirect = total − direct)");
    cmd->add_option("--reference-mask", o->reference.lightmapMask, "covered-texel mask EXR (default: our rasteriser's)");
    cmd->add_option("--reference-image", o->reference.image, "reference render EXR of the first camera (total)");
    cmd->add_option("--reference-image-direct", o->reference.imageDirect, "its direct part");
    cmd->add_flag("--path-traced-reference", o->pathTracedReference,
                  "path-trace the reference even for the Cycles Cornell boxes");
    cmd->add_option("--reference-noise", o->referenceSettings.targetNoise,
                    "target relative noise of a path-traced reference (default 0.02)");
    cmd->add_option("--reference-max-spp", o->referenceSettings.maxSpp, "spp cap of a path-traced reference (default 4096)");
    cmd->add_option("--reference-budget", o->referenceSettings.budgetSeconds,
                    "seconds a path-traced lightmap or image reference may take, estimated from its pilot (default 300)");
    cmd->add_option("--cache-dir", o->referenceSettings.cacheDir, "cache of path-traced references (default output/bench-cache)");
    cmd->add_option("--exclude-above", o->excludeAbove,
                    "image pixels whose reference exceeds this in a channel are not compared: the emitter (default 5; 0 = none)");
    cmd->add_option("--blender", o->blender, "Blender executable for the Cycles peer (default: blender on the PATH; none = off)");
    cmd->add_option("--cycles-spp", o->cyclesSpp, "Cycles peer spp points (default 16 64 256)");
    cmd->add_flag("--no-cycles-files", o->noCyclesFiles, "leave out the precomputed lower-spp Cycles files");
    cmd->add_option("--methods", o->methods, "only these methods: vct path cycles (default all)")->delimiter(',');
    auto* scaling = cmd->add_flag("--scaling", o->scaling,
                                  "time every stage against voxel resolution 64/128/256, lightmap resolution "
                                  "256/512/1024 and 1 thread against all, each the fastest of 3 bakes (default: on unless --methods "
                                  "leaves out vct)");
    auto* noScaling = cmd->add_flag("--no-scaling", o->noScaling, "leave out the stage scaling")->excludes(scaling);
    cmd->add_option("--scaling-triangles", o->scalingTriangles,
                    "add the stage scaling's triangle axis: a generated room of 64 spheres of about each of these many "
                    "triangles (e.g. 30000 300000 3000000), baked at resolution 128 and lightmap 2048², the same covered "
                    "texels at every count")
        ->check(CLI::Range(size_t(100), size_t(100000000)))
        ->excludes(noScaling);
    cmd->add_flag("--no-plot", o->noPlot, "write the gnuplot script and data but do not run gnuplot");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress or table output");
    for (const auto& spec : bakeSettingsTable()) {
        const std::string name = spec.name;
        cmd->add_option_function<std::string>(
               "--" + name, [o, name](const std::string& value) { o->settings.emplace_back(name, value); }, spec.help)
            ->group("Bake settings (the base every VCT point varies)");
    }
    cmd->callback([o] {
        o->commandLine = commandLine();
        runBench(plan(*o));
    });
}

}  // namespace vl::cli
