#include "bench/report.h"

#include "bake/voxel_size.h"
#include "bench/display_path.h"
#include "bench/format.h"
#include "core/text.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace vl {
namespace fs = std::filesystem;

namespace {

// The methods in the order the table and the plot show them, with their plot colours.
struct MethodStyle {
    const char* method;
    const char* title;
    const char* colour;
    int pointType;
};
const MethodStyle kMethods[] = {
    {"vct", "voxlight VCT bake", "#d62728", 7},
    {"path", "voxlight path tracer", "#1f77b4", 5},
    {"cycles", "Cycles (Blender, this run)", "#2ca02c", 9},
    {"cycles-files", "Cycles (reference files, timings.json)", "#7f7f7f", 13},
};

std::string pct(const BenchError& e) { return e.available ? fmt("%.1f%%", 100.0 * e.metrics.relativeRmse) : "—"; }

std::string settingsText(const BenchPointSpec& spec) {
    std::string out;
    for (const auto& [name, value] : spec.settings) out += (out.empty() ? "" : ";") + name + "=" + value;
    if (spec.spp > 0) out += (out.empty() ? "" : ";") + std::string("spp=") + std::to_string(spec.spp);
    return out;
}

std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string out = "\"";
    for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

std::string number(double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

void writeText(const fs::path& path, const std::string& text) {
    writeAtomically(path.string(), [&](const std::string& temp) {
        std::ofstream out(temp);
        out << text;
        if (!out) throw Error("cannot write " + temp);
    });
}

using Series = std::vector<std::pair<double, double>>;

// What a series rates: the lightmap, the image, or the lightmap-lit image (timed as its lightmap).
enum class Rated { Lightmap, Image, Lightmapped };

double secondsOf(const BenchPointResult& p, Rated rated) {
    return rated == Rated::Image ? p.imageSeconds : p.lightmapSeconds;
}

const BenchError& errorOf(const BenchPointResult& p, Rated rated) {
    return rated == Rated::Image ? p.image : rated == Rated::Lightmap ? p.lightmap : p.lightmapped;
}

// (time, relRMSE) of a method's points that measured both.
Series series(const BenchResult& r, const std::string& method, Rated rated, std::vector<size_t>* indices = nullptr) {
    Series s;
    for (size_t i = 0; i < r.points.size(); ++i) {
        const BenchPointResult& p = r.points[i];
        const double t = secondsOf(p, rated);
        const BenchError& e = errorOf(p, rated);
        if (p.spec.method != method || !p.ok || !(t > 0.0) || !e.available) continue;
        s.push_back({t, e.metrics.relativeRmse});
        if (indices) indices->push_back(i);
    }
    return s;
}

const BenchPointResult* findPoint(const BenchResult& r, const std::string& method, const std::string& label) {
    for (const BenchPointResult& p : r.points)
        if (p.spec.method == method && p.spec.label == label && p.ok) return &p;
    return nullptr;
}

// ---- CSV / JSON ----

void writeCsv(BenchResult& r) {
    std::ostringstream out;
    const auto& columns = benchCsvColumns();
    for (size_t i = 0; i < columns.size(); ++i) out << (i ? "," : "") << columns[i];
    out << '\n';
    std::map<std::pair<std::string, bool>, std::vector<size_t>> fronts;
    for (const MethodStyle& m : kMethods)
        for (bool image : {false, true}) {
            std::vector<size_t> idx;
            const Series s = series(r, m.method, image ? Rated::Image : Rated::Lightmap, &idx);
            for (size_t f : paretoFront(s)) fronts[{m.method, image}].push_back(idx[f]);
        }
    auto onFront = [&](size_t i, bool image) {
        const auto& v = fronts[{r.points[i].spec.method, image}];
        return std::find(v.begin(), v.end(), i) != v.end();
    };
    for (size_t i = 0; i < r.points.size(); ++i) {
        const BenchPointResult& p = r.points[i];
        std::vector<std::string> f;
        f.push_back(csvField(p.spec.method));
        f.push_back(csvField(p.spec.label));
        f.push_back(csvField(settingsText(p.spec)));
        f.push_back(p.ok ? "1" : "0");
        f.push_back(std::to_string(std::max(p.lightmapRuns.size(), p.imageRuns.size())));
        f.push_back(p.lightmapSeconds > 0 ? number(p.lightmapSeconds) : "");
        f.push_back(p.imageSeconds > 0 ? number(p.imageSeconds) : "");
        f.push_back(p.cpuSeconds > 0 ? number(p.cpuSeconds) : "");
        f.push_back(p.peakMemoryBytes > 0 ? number(p.peakMemoryBytes / 1048576.0) : "");
        for (const BenchError* e : {&p.lightmap, &p.lightmapIndirect, &p.image, &p.imageIndirect, &p.lightmapped}) {
            f.push_back(e->available ? number(e->metrics.relativeRmse) : "");
            f.push_back(e->available ? number(e->metrics.relMse) : "");
            f.push_back(e->available ? number(e->metrics.smape) : "");
        }
        f.push_back(onFront(i, false) ? "1" : "0");
        f.push_back(onFront(i, true) ? "1" : "0");
        for (size_t k = 0; k < f.size(); ++k) out << (k ? "," : "") << f[k];
        out << '\n';
    }
    writeText(fs::path(r.outputDir) / "bench.csv", out.str());
    r.files.push_back("bench.csv");
}

nlohmann::json errorJson(const BenchError& e) {
    if (!e.available) return nullptr;
    return {{"relative_rmse", e.metrics.relativeRmse}, {"rel_mse", e.metrics.relMse}, {"smape", e.metrics.smape},
            {"rmse", e.metrics.rmse}, {"pixels", e.metrics.pixels},
            {"mean_test", {e.metrics.meanTest[0], e.metrics.meanTest[1], e.metrics.meanTest[2]}},
            {"mean_reference", {e.metrics.meanReference[0], e.metrics.meanReference[1], e.metrics.meanReference[2]}}};
}

nlohmann::json nanToNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json scalingRunJson(const StageScalingRun& run) {
    nlohmann::json stages = nlohmann::json::object();
    for (const StageTime& t : run.stages) stages[t.stage] = t.seconds;
    return {{"label", run.label}, {"triangles", run.triangles}, {"resolution", run.resolution}, {"lightmap_res", run.lightmapResolution},
            {"threads", run.threads}, {"bakes", run.bakes}, {"ok", run.ok}, {"error", run.error}, {"voxels", run.voxels},
            {"gather_points", run.gatherPoints}, {"covered_texels", run.coveredTexels}, {"pixels", run.pixels},
            {"stage_seconds", stages}, {"total_seconds", run.totalSeconds()}, {"cpu_seconds", run.cpuSeconds}, {"other_cores", run.otherCores},
            {"peak_memory_bytes", run.peakMemoryBytes}};
}

nlohmann::json scalingJson(const StageScaling& s) {
    nlohmann::json runs = nlohmann::json::array(), growth = nlohmann::json::array(), speedups = nlohmann::json::array(),
                   findings = nlohmann::json::array();
    for (const StageScalingRun& run : s.runs) runs.push_back(scalingRunJson(run));
    auto labels = [&](const std::vector<size_t>& axis) {
        std::vector<std::string> out;
        for (size_t i : axis) out.push_back(s.runs[i].label);
        return out;
    };
    for (const StageGrowth& g : s.growth)
        growth.push_back({{"stage", g.stage}, {"work", g.work}, {"from", g.from}, {"to", g.to}, {"seconds", {g.seconds1, g.seconds2}},
                          {"work_amounts", {g.work1, g.work2}}, {"rated", g.rated},
                          {"exponent", g.rated ? nlohmann::json(g.exponent) : nlohmann::json(nullptr)},
                          {"flagged", g.flagged}, {"text", g.text}});
    for (const ThreadSpeedup& t : s.speedups)
        speedups.push_back({{"stage", t.stage}, {"one_thread_seconds", t.oneThreadSeconds},
                            {"all_threads_seconds", t.allThreadsSeconds}, {"speedup", t.speedup}});
    for (const ScalingFinding& f : s.findings) findings.push_back({{"text", f.text}, {"flagged", f.flagged}});
    return {{"threads", s.threads}, {"runs", runs}, {"resolution_axis", labels(s.resolutionAxis)},
            {"lightmap_axis", labels(s.lightmapAxis)}, {"triangle_axis", labels(s.triangleAxis)},
            {"texel_time_growth", s.texelTimeGrowth}, {"texel_time_growth_limit", kTexelTimeGrowthLimit},
            {"one_thread", s.oneThread ? scalingRunJson(*s.oneThread) : nlohmann::json(nullptr)},
            {"thread_speedup", speedups}, {"growth", growth}, {"findings", findings}, {"notes", s.notes},
            {"exponent_limit", kGrowthExponentLimit}, {"noise_floor_seconds", kScalingNoiseFloorSeconds}};
}

void writeJson(BenchResult& r, const nlohmann::json& headline) {
    nlohmann::json j;
    j["scene"] = displayPath(r.scenePath, r.outputDir);
    j["tool_version"] = VOXLIGHT_VERSION;
    j["threads"] = r.threads;
    j["repeats"] = r.repeats;
    j["reference"] = {{"description", r.reference.description},
                      {"lightmap_noise", nanToNull(r.reference.lightmapNoise)},
                      {"image_noise", nanToNull(r.reference.imageNoise)},
                      {"lightmap_spp", r.reference.lightmapSpp},
                      {"image_spp", r.reference.imageSpp}};
    j["notes"] = r.notes;
    j["headline"] = headline;
    nlohmann::json points = nlohmann::json::array();
    for (const BenchPointResult& p : r.points) {
        nlohmann::json settings = nlohmann::json::object();
        for (const auto& [name, value] : p.spec.settings) settings[name] = value;
        points.push_back({{"method", p.spec.method}, {"label", p.spec.label}, {"settings", settings}, {"spp", p.spec.spp},
                          {"ok", p.ok}, {"error", p.error}, {"note", p.note},
                          {"lightmap_seconds", p.lightmapSeconds}, {"image_seconds", p.imageSeconds},
                          {"cpu_seconds", p.cpuSeconds}, {"lightmap_runs", p.lightmapRuns}, {"image_runs", p.imageRuns},
                          {"cpu_runs", p.cpuRuns}, {"peak_memory_bytes", p.peakMemoryBytes},
                          {"voxel_size", p.voxelSize}, {"voxel_size_set_by", p.voxelSizeSetBy},
                          {"lightmap", errorJson(p.lightmap)}, {"lightmap_indirect", errorJson(p.lightmapIndirect)},
                          {"image", errorJson(p.image)}, {"image_indirect", errorJson(p.imageIndirect)},
                          {"lightmapped", errorJson(p.lightmapped)},
                          {"outputs", displayPath(p.outputDir, r.outputDir)}});
    }
    j["points"] = points;
    if (r.scaling) j["scaling"] = scalingJson(*r.scaling);
    writeText(fs::path(r.outputDir) / "bench.json", j.dump(2) + "\n");
    r.files.push_back("bench.json");
}

// ---- heat maps ----

// A perceptual ramp (inferno's anchors) in sRGB, 0 → 1.
vec3 ramp(float t) {
    static const vec3 anchors[] = {{0.0f, 0.0f, 0.016f}, {0.34f, 0.04f, 0.43f}, {0.73f, 0.21f, 0.33f},
                                   {0.98f, 0.55f, 0.04f}, {0.99f, 1.0f, 0.64f}};
    t = std::clamp(t, 0.0f, 1.0f) * 4.0f;
    const int i = std::min(3, static_cast<int>(t));
    return glm::mix(anchors[i], anchors[i + 1], t - static_cast<float>(i));
}

constexpr float kHeatScale = 0.5f;  // the PNG's full scale: 50% relative error

// Per-pixel |test − reference| (mean over RGB) / mean reference over the compared pixels.
void writeHeatMap(const Image& test, const Image& reference, const Image& mask, const fs::path& stem) {
    double mean = 0.0;
    size_t n = 0;
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x)
            if (mask.at(x, y) > 0.5f) {
                for (int c = 0; c < 3; ++c) mean += reference.at(x, y, std::min(c, reference.channels - 1));
                n += 3;
            }
    if (n == 0 || mean <= 0.0) return;
    mean /= static_cast<double>(n);
    Image error(reference.width, reference.height, 1), colour(reference.width, reference.height, 3);
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x) {
            if (!(mask.at(x, y) > 0.5f)) {
                colour.setRgb(x, y, vec3(srgbToLinear(0.25f)));  // not compared: grey
                continue;
            }
            double d = 0.0;
            for (int c = 0; c < 3; ++c)
                d += std::abs(test.at(x, y, std::min(c, test.channels - 1)) - reference.at(x, y, std::min(c, reference.channels - 1)));
            const float e = static_cast<float>(d / 3.0 / mean);
            error.at(x, y) = e;
            const vec3 srgb = ramp(e / kHeatScale);
            colour.setRgb(x, y, vec3(srgbToLinear(srgb.x), srgbToLinear(srgb.y), srgbToLinear(srgb.z)));
        }
    writeExr(error, stem.string() + ".exr", {"Y"});
    writePngSrgb(colour, stem.string() + ".png");
}

struct HeatMap {
    std::string method, label, lightmapPng, imagePng, lightmappedPng;
    std::string lightmapError, imageError, lightmappedError;
};

std::vector<HeatMap> writeHeatMaps(BenchResult& r, float excludeAbove) {
    std::vector<HeatMap> maps;
    const BenchPointResult* vct = findPoint(r, "vct", "default");
    if (!vct || !vct->lightmap.available) return maps;
    std::vector<const BenchPointResult*> chosen{vct};
    for (const MethodStyle& m : kMethods) {
        if (std::string(m.method) == "vct") continue;
        const BenchPointResult* best = nullptr;
        for (const BenchPointResult& p : r.points)
            if (p.spec.method == m.method && p.ok && p.lightmap.available &&
                (!best || std::abs(std::log(p.lightmap.metrics.relativeRmse / vct->lightmap.metrics.relativeRmse)) <
                              std::abs(std::log(best->lightmap.metrics.relativeRmse / vct->lightmap.metrics.relativeRmse))))
                best = &p;
        if (best) chosen.push_back(best);
    }
    const fs::path dir = fs::path(r.outputDir) / "heatmaps";
    fs::create_directories(dir);
    for (const BenchPointResult* p : chosen) {
        HeatMap h{p->spec.method, p->spec.label, "", "", "", pct(p->lightmap), pct(p->image), pct(p->lightmapped)};
        std::string stem = p->spec.method + "-" + p->spec.label;
        for (char& c : stem)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '.') c = '_';
        const fs::path base = fs::path(p->outputDir).is_absolute() ? fs::path(p->outputDir) : fs::path(r.outputDir) / p->outputDir;
        auto find = [&](const std::vector<std::string>& names) -> std::string {
            for (const std::string& n : names)
                if (!n.empty() && fs::exists(base / n)) return (base / n).string();
            return "";
        };
        const std::string n = std::to_string(p->spec.spp) + "spp";
        const std::string sceneStem = fs::path(r.scenePath).stem().string();
        const std::string lightmap = find({"lightmap.exr", sceneStem + "_lightmap_" + n + ".exr"});
        const std::string image = find({"image.exr", sceneStem + "_render_" + n + ".exr"});
        if (!lightmap.empty() && r.reference.hasLightmap) {
            writeHeatMap(readImage(lightmap), r.reference.lightmap, r.reference.mask, dir / (stem + "_lightmap"));
            h.lightmapPng = "heatmaps/" + stem + "_lightmap.png";
            r.files.push_back(h.lightmapPng);
        }
        Image imageMask;
        if (r.reference.hasImage) {
            imageMask = Image(r.reference.image.width, r.reference.image.height, 1, 1.0f);
            for (int y = 0; y < imageMask.height; ++y)
                for (int x = 0; x < imageMask.width; ++x)
                    for (int c = 0; c < std::min(3, r.reference.image.channels); ++c)
                        if (excludeAbove > 0.0f && r.reference.image.at(x, y, c) > excludeAbove) imageMask.at(x, y) = 0.0f;
        }
        if (!image.empty() && r.reference.hasImage && p->image.available) {
            writeHeatMap(readImage(image), r.reference.image, imageMask, dir / (stem + "_image"));
            h.imagePng = "heatmaps/" + stem + "_image.png";
            r.files.push_back(h.imagePng);
        }
        const std::string lightmapped = find({"image_lightmapped.exr"});
        if (!lightmapped.empty() && r.reference.hasImage && p->lightmapped.available) {
            writeHeatMap(readImage(lightmapped), r.reference.image, imageMask, dir / (stem + "_lightmapped"));
            h.lightmappedPng = "heatmaps/" + stem + "_lightmapped.png";
            r.files.push_back(h.lightmappedPng);
        }
        maps.push_back(h);
    }
    return maps;
}

// ---- plot ----

bool haveProgram(const std::string& name) {
    return std::system(("command -v " + name + " >/dev/null 2>&1").c_str()) == 0;
}

void writePlot(BenchResult& r, const BenchOptions& options) {
    const fs::path dir = fs::path(r.outputDir) / "plot";
    fs::create_directories(dir);
    std::ostringstream gp;
    gp << "# gnuplot script written by voxlight bench; run from the bench folder (this folder's parent): gnuplot "
          "plot/bench.gp\n";
    gp << "set terminal pngcairo size 2200,620 font 'sans,10' noenhanced\nset output 'bench.png'\n";
    gp << "set multiplot layout 1,3 title \"" << fs::path(r.scenePath).filename().string()
       << ": wall time (median) against relative RMSE vs the reference; lines join each method's Pareto front\"\n";
    gp << "set logscale xy\nset grid xtics ytics mxtics mytics lc rgb '#dddddd'\nset key top right box opaque\n";
    gp << "set xlabel 'seconds (wall, this machine)'\nset ylabel 'relative RMSE (%)'\n";
    const std::pair<Rated, const char*> panels[] = {
        {Rated::Lightmap, "lightmap (covered texels)"},
        {Rated::Image, "camera image (emitter excluded)"},
        {Rated::Lightmapped, "lightmap-lit image vs the reference image (time: the lightmap)"}};
    for (const auto& [rated, title] : panels) {
        gp << "set title '" << title << "'\n";
        std::vector<std::string> plots;
        for (const MethodStyle& m : kMethods) {
            std::vector<size_t> idx;
            const Series s = series(r, m.method, rated, &idx);
            if (s.empty()) continue;
            const std::string base = std::string(m.method) + (rated == Rated::Image         ? "_image"
                                                              : rated == Rated::Lightmap ? "_lightmap"
                                                                                         : "_lightmapped");
            std::ostringstream data, front;
            for (size_t i = 0; i < s.size(); ++i)
                data << number(s[i].first) << ' ' << number(100.0 * s[i].second) << " \"" << r.points[idx[i]].spec.label << "\"\n";
            for (size_t f : paretoFront(s)) front << number(s[f].first) << ' ' << number(100.0 * s[f].second) << '\n';
            writeText(dir / (base + ".dat"), data.str());
            writeText(dir / (base + "_pareto.dat"), front.str());
            const std::string colour = std::string("lc rgb '") + m.colour + "'";
            plots.push_back("'plot/" + base + "_pareto.dat' u 1:2 w l lw 2 " + colour + " notitle");
            plots.push_back("'plot/" + base + ".dat' u 1:2 w p pt " + std::to_string(m.pointType) + " ps 1.3 " + colour +
                            " title '" + m.title + "'");
            if (std::string(m.method) != "cycles-files")
                plots.push_back("'plot/" + base + ".dat' u 1:2:3 w labels left offset 0.7,0.4 font ',7' tc rgb '" + m.colour +
                                "' notitle");
        }
        if (plots.empty()) {
            gp << "set label 1 'no points' at graph 0.5,0.5 center\nplot [1:10] [1:10] NaN notitle\nunset label 1\n";
            continue;
        }
        gp << "plot ";
        for (size_t i = 0; i < plots.size(); ++i) gp << (i ? ", \\\n     " : "") << plots[i];
        gp << "\n";
    }
    gp << "unset multiplot\n";
    writeText(dir / "bench.gp", gp.str());
    if (!options.plot) return;
    if (!haveProgram("gnuplot")) {
        r.notes.push_back("no plot: gnuplot is not installed (Debian package gnuplot-nox; tools/install-deps.sh)");
        return;
    }
    const std::string command = "cd '" + r.outputDir + "' && gnuplot plot/bench.gp > plot/gnuplot.log 2>&1";
    if (std::system(command.c_str()) != 0 || !fs::exists(fs::path(r.outputDir) / "bench.png"))
        r.notes.push_back("gnuplot failed: see " + displayPath((dir / "gnuplot.log").string(), r.outputDir));
    else
        r.files.push_back("bench.png");
}

// ---- headline and Markdown ----

// "2.3×", "16×", "220×": two significant digits, never an exponent.
std::string timesText(double ratio) { return ratio < 100.0 ? fmt("%.2g×", ratio) : fmt("%.0f×", ratio); }

std::string reachText(const Reach& reach, double vctSeconds) {
    if (!reach.found) return "—";
    std::string s = secs(reach.seconds) + " s (" + timesText(reach.seconds / vctSeconds) + " the VCT time";
    if (reach.how != "interpolated") s += "; " + reach.how;
    return s + ")";
}

// "the VCT is 2.3× faster" / "5.8× slower": the other method's time to the VCT's error over
// the VCT's time.
std::string speedText(const Reach& reach, double vctSeconds) {
    const double ratio = reach.seconds / vctSeconds;
    return ratio >= 1.0 ? "**" + timesText(ratio) + " faster**" : "**" + timesText(1.0 / ratio) + " slower**";
}

// The default's voxel size against the points that change only the resolution, by error² ×
// time (lower is better): the figure a Monte Carlo method holds at any sample count, so the
// best point is the one that buys its accuracy cheapest.
nlohmann::json voxelSizeMerit(const BenchResult& r, const BenchPointResult& vct, std::ostringstream& md) {
    std::vector<const BenchPointResult*> sweep;
    for (const BenchPointResult& p : r.points)
        if (p.ok && p.spec.method == "vct" && p.voxelSize > 0.0 &&
            (&p == &vct || (p.spec.settings.size() == 1 && p.spec.settings[0].first == "resolution")))
            sweep.push_back(&p);
    std::sort(sweep.begin(), sweep.end(),
              [](const BenchPointResult* a, const BenchPointResult* b) { return a->voxelSize > b->voxelSize; });
    nlohmann::json j = {{"default_voxel_size", vct.voxelSize}, {"set_by", vct.voxelSizeSetBy}};
    md << "- **Voxel size**: the default chose " << lengthText(vct.voxelSize) << ", set by " << vct.voxelSizeSetBy
       << ".\n";
    if (sweep.size() < 2) return j;
    for (bool image : {false, true}) {
        auto merit = [&](const BenchPointResult& p) {
            const BenchError& e = image ? p.image : p.lightmap;
            const double t = image ? p.imageSeconds : p.lightmapSeconds;
            return e.available && t > 0.0 ? e.metrics.relativeRmse * e.metrics.relativeRmse * t : 0.0;
        };
        const BenchPointResult* best = nullptr;
        for (const BenchPointResult* p : sweep)
            if (merit(*p) > 0.0 && (!best || merit(*p) < merit(*best))) best = p;
        if (!best || !(merit(vct) > 0.0)) continue;
        const char* name = image ? "image" : "lightmap";
        md << "  - " << name << ", error² × time over the best point's, coarse to fine:";
        nlohmann::json points = nlohmann::json::array();
        for (const BenchPointResult* p : sweep) {
            const double ratio = merit(*p) / merit(*best);
            md << (p == sweep.front() ? " " : " / ") << p->spec.label << " (" << lengthText(p->voxelSize) << ") "
               << (merit(*p) > 0.0 ? fmt("%.2f", ratio) : "—");
            points.push_back({{"label", p->spec.label}, {"voxel_size", p->voxelSize}, {"merit_over_best", ratio}});
        }
        const double ratio = merit(vct) / merit(*best);
        md << "; the default is "
           << (best == &vct ? std::string("the best point")
                            : fmt("%.2f×", ratio) + " the best point's (" + best->spec.label + ")")
           << ".\n";
        j[name] = {{"points", points}, {"best", best->spec.label}, {"default_over_best", ratio}};
    }
    return j;
}

nlohmann::json headline(const BenchResult& r, std::string& markdown) {
    nlohmann::json h;
    const BenchPointResult* vct = findPoint(r, "vct", "default");
    if (!vct) return h;
    // The outputs the VCT default measured: the lightmap, the image, each with its error and time.
    struct Output {
        const char* name;
        const char* key;  // bench.json's
        Rated rated;
        const BenchError& error;
        const BenchError* indirect;
        double seconds;
    };
    std::vector<Output> outputs;
    for (const Output& o : {Output{"lightmap", "lightmap", Rated::Lightmap, vct->lightmap, &vct->lightmapIndirect, vct->lightmapSeconds},
                            Output{"image", "image", Rated::Image, vct->image, &vct->imageIndirect, vct->imageSeconds},
                            Output{"lightmap-lit image", "lightmapped", Rated::Lightmapped, vct->lightmapped, nullptr,
                                   vct->lightmapSeconds}})
        if (o.error.available && o.seconds > 0.0) outputs.push_back(o);
    if (outputs.empty()) return h;

    std::ostringstream md;
    h["vct_default"] = {{"cpu_seconds", vct->cpuSeconds}};
    md << "- **VCT default bake**:";
    for (size_t i = 0; i < outputs.size(); ++i) {
        const Output& o = outputs[i];
        h["vct_default"][std::string(o.key) + "_relative_rmse"] = o.error.metrics.relativeRmse;
        h["vct_default"][std::string(o.key) + "_seconds"] = o.seconds;
        md << (i ? ";" : "") << ' ' << o.name << " relative RMSE **" << pct(o.error) << "**";
        if (o.indirect) md << " in **" << secs(o.seconds) << " s** (indirect part " << pct(*o.indirect) << ")";
        else md << " (against the reference image, from the lightmap as it ships)";
    }
    md << "; the whole bake: " << secs(vct->cpuSeconds) << " CPU s.\n";
    for (const MethodStyle& m : kMethods) {
        if (std::string(m.method) == "vct") continue;
        std::ostringstream lines;
        for (const Output& o : outputs) {
            const Series s = series(r, m.method, o.rated);
            if (s.empty()) continue;
            const double e = o.error.metrics.relativeRmse, t = o.seconds;
            const Reach same = timeToReach(s, e);
            const Reach atTime = errorAtTime(s, t);
            h[m.method][o.key] = {
                {"seconds_to_reach_vct_error", same.found ? nlohmann::json(same.seconds) : nlohmann::json(nullptr)},
                {"how", same.how},
                {"time_ratio", same.found ? nlohmann::json(same.seconds / t) : nlohmann::json(nullptr)},
                {"error_at_vct_time", atTime.found ? nlohmann::json(atTime.seconds) : nlohmann::json(nullptr)},
                {"error_at_vct_time_how", atTime.how}};
            lines << "  - " << o.name << ": reaches " << pct(o.error) << " in " << reachText(same, t);
            if (same.found) lines << ": the VCT is " << speedText(same, t) << " at equal " << o.name << " error";
            if (atTime.found)
                lines << "; at the VCT's " << secs(t) << " s its error is " << fmt("%.1f%%", 100.0 * atTime.seconds) << " ("
                      << timesText(atTime.seconds / e) << " the VCT's"
                      << (atTime.how != "interpolated" ? "; " + atTime.how : "") << ")";
            lines << ".\n";
        }
        if (!lines.str().empty()) md << "- **" << m.title << "**\n" << lines.str();
    }
    h["voxel_size"] = voxelSizeMerit(r, *vct, md);
    markdown = md.str();
    return h;
}

std::string table(const BenchResult& r, bool markdown) {
    std::ostringstream out;
    if (markdown) {
        out << "| method | point | lightmap s | lightmap relRMSE | indirect relRMSE | image s | image relRMSE | "
               "lightmap-lit relRMSE | CPU s | peak MB |\n";
        out << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    } else {
        char line[256];
        std::snprintf(line, sizeof line, "%-13s %-32s %9s %8s %8s %9s %8s %8s %8s %8s\n", "method", "point", "lightmap",
                      "error", "indirect", "image", "error", "lm-lit", "CPU s", "peak MB");
        out << line;
    }
    for (const MethodStyle& m : kMethods)
        for (const BenchPointResult& p : r.points) {
            if (p.spec.method != m.method) continue;
            const std::string mem = p.peakMemoryBytes > 0 ? fmt("%.0f", p.peakMemoryBytes / 1048576.0) : "—";
            if (!p.ok) {
                if (markdown) out << "| " << p.spec.method << " | " << p.spec.label << " | failed: " << p.error << " |||||||\n";
                else out << p.spec.method << " " << p.spec.label << " FAILED: " << p.error << '\n';
                continue;
            }
            if (markdown) {
                out << "| " << p.spec.method << " | " << p.spec.label << " | " << secs(p.lightmapSeconds) << " | " << pct(p.lightmap)
                    << " | " << pct(p.lightmapIndirect) << " | " << secs(p.imageSeconds) << " | " << pct(p.image) << " | "
                    << pct(p.lightmapped) << " | " << secs(p.cpuSeconds) << " | " << mem << " |\n";
            } else {
                char line[512];
                std::snprintf(line, sizeof line, "%-13s %-32s %9s %8s %8s %9s %8s %8s %8s %8s\n", p.spec.method.c_str(),
                              p.spec.label.c_str(), secs(p.lightmapSeconds).c_str(), pct(p.lightmap).c_str(),
                              pct(p.lightmapIndirect).c_str(), secs(p.imageSeconds).c_str(), pct(p.image).c_str(),
                              pct(p.lightmapped).c_str(), secs(p.cpuSeconds).c_str(), mem.c_str());
                out << line;
            }
        }
    return out.str();
}

// Stage times to the millisecond below 0.1 s: the small stages are what the noise floor is about.
std::string stageSecs(double s) { return s > 0.0 && s < 0.1 ? fmt("%.3f", s) : secs(s); }

std::string scalingMarkdown(const StageScaling& s, const BenchOptions& options) {
    std::vector<std::string> stages;  // in the bake's order
    for (const StageScalingRun& run : s.runs)
        for (const StageTime& t : run.stages)
            if (std::find(stages.begin(), stages.end(), t.stage) == stages.end()) stages.push_back(t.stage);
    auto axisValues = [&](const std::vector<size_t>& axis, bool resolution) {
        std::string out;
        for (size_t i : axis)
            out += (out.empty() ? "" : " / ") + std::to_string(resolution ? s.runs[i].resolution : s.runs[i].lightmapResolution);
        return out;
    };
    const BakeSettings& base = options.base.settings;
    std::ostringstream md;
    md << "## How the stages scale\n\n";
    md << "Scene `" << fs::path(s.scenePath).filename().string() << "`, the bench's base settings with voxel resolution "
       << axisValues(s.resolutionAxis, true) << " (lightmap " << base.lightmap.width << "²) and lightmap resolution "
       << axisValues(s.lightmapAxis, false) << " (resolution "
       << (base.voxel.resolution > 0 ? std::to_string(base.voxel.resolution) : std::string("chosen from the scene"))
       << "), image "
       << base.imageWidth << "×" << base.imageHeight << ". Each run bakes in memory (no files) on " << s.threads
       << " threads, " << s.axes.repeats << " times (once when its first bake takes over "
       << fmt("%.0f", s.axes.repeatLimitSeconds)
       << " s); a stage's time is its fastest wall seconds (other load only adds time), CPU s that of the fastest "
          "bake, others the cores other processes used meanwhile (/proc/stat), peak MB the process's resident "
          "high-water mark during the run.";
    if (!s.triangleAxis.empty())
        md << " The triangle axis bakes generated rooms of 64 spheres (`triangles=N` runs), every mesh with its own "
              "TEXCOORD_1 cell, the same covered texels at every count, at resolution "
           << s.axes.triangleResolution << " and lightmap " << s.axes.triangleLightmapResolution << "².";
    md << "\n\n";
    md << "| run | voxels | gather points | covered texels | pixels |";
    for (const std::string& stage : stages) md << ' ' << stage << " |";
    md << " total | CPU s | others | peak MB |\n|---|---:|---:|---:|---:|";
    for (size_t i = 0; i < stages.size(); ++i) md << "---:|";
    md << "---:|---:|---:|---:|\n";
    for (const StageScalingRun& run : s.runs) {
        if (!run.ok) {
            md << "| " << run.label << " | failed: " << run.error << " |" << std::string(stages.size() + 7, '|') << "\n";
            continue;
        }
        md << "| " << run.label << " | " << run.voxels << " | " << run.gatherPoints << " | " << run.coveredTexels << " | "
           << run.pixels << " |";
        for (const std::string& stage : stages) md << ' ' << stageSecs(run.stageSeconds(stage)) << " |";
        md << ' ' << secs(run.totalSeconds()) << " | " << secs(run.cpuSeconds) << " | " << fmt("%.1f", run.otherCores)
           << " | " << fmt("%.0f", run.peakMemoryBytes / 1048576.0) << " |\n";
    }
    md << '\n';
    if (!s.speedups.empty()) {
        md << "The base settings on 1 thread and on " << s.threads << " (other processes used "
           << fmt("%.1f", s.oneThread->otherCores) << " cores during the one, ";
        for (const StageScalingRun& run : s.runs)
            if (run.resolution == s.oneThread->resolution && run.lightmapResolution == s.oneThread->lightmapResolution &&
                run.triangles == s.oneThread->triangles)
                md << fmt("%.1f", run.otherCores);
        md << " during the other):\n\n";
        md << "| stage | 1 thread s | " << s.threads << " threads s | speedup |\n|---|---:|---:|---:|\n";
        for (const ThreadSpeedup& t : s.speedups)
            md << "| " << t.stage << " | " << stageSecs(t.oneThreadSeconds) << " | " << stageSecs(t.allThreadsSeconds) << " | "
               << fmt("%.2f×", t.speedup) << " |\n";
        md << '\n';
    }
    md << "Each stage's time against its work between consecutive runs (voxels for the voxel stages, whose cones per "
          "voxel or gather point the settings fix; covered texels for lightmaps; pixels for images): exponent "
          "log(t₂/t₁) / log(w₂/w₁), 1 for a stage that scales with its work; **flagged** above "
       << fmt("%g", kGrowthExponentLimit) << ", and the bounces and the gather below " << fmt("%.0f%%", 100.0 * kThreadEfficiencyTarget)
       << " parallel efficiency:\n\n";
    for (const ScalingFinding& f : s.findings) md << "- " << (f.flagged ? "**flagged** " : "") << f.text << '\n';
    for (const std::string& note : s.notes) md << "- " << note << '\n';
    md << '\n';
    return md.str();
}

void writeMarkdown(BenchResult& r, const BenchOptions& options, const std::string& headlineText,
                   const std::vector<HeatMap>& maps) {
    std::ostringstream md;
    md << "## Speed against error\n\n";
    md << "Scene `" << fs::path(r.scenePath).filename().string() << "`, lightmap " << options.base.settings.lightmap.width
       << "², image " << options.base.settings.imageWidth << "×" << options.base.settings.imageHeight << ", on this machine's "
       << r.threads << " threads; every time is the median of " << r.repeats
       << " runs in one process (a run over " << fmt("%.0f", options.repeatLimitSeconds) << " s is timed once). Reference: "
       << r.reference.description << ". Errors are relative RMSE (RMSE / mean, RGB pooled) over the lightmap's covered "
          "texels and the image's pixels (the emitter, reference > "
       << fmt("%g", options.imageExcludeAbove) << ", excluded); bench.csv also has relMSE (ε = 10⁻²) and SMAPE. The "
          "lightmap-lit image is the camera lit by the point's lightmap as scene.glb carries it (albedo × lightmap + "
          "emission, what `voxlight view` shows), rated against the reference image over the same pixels and timed as "
          "its lightmap.\n\n";
    if (!headlineText.empty()) md << headlineText << '\n';
    if (std::find(r.files.begin(), r.files.end(), "bench.png") != r.files.end())
        md << "![wall time against relative RMSE, log axes](bench.png)\n\n";
    md << table(r, true) << '\n';
    md << "VCT times are the whole bake (load, voxelize, voxel light, bounces, mips, BVH, receivers, shading, EXR "
          "writes) without the other output's stage; the path tracer's are load, BVH, receivers and tracing. CPU s is "
          "the process CPU time of everything a point made (lightmap and image); the machine is shared, so wall time "
          "also carries other people's load.\n\n";
    if (!maps.empty()) {
        md << "Error heat maps (|test − reference| / mean reference; black 0, yellow ≥ "
           << fmt("%.0f%%", 100.0 * kHeatScale) << "; grey: not compared):\n\n";
        md << "| point | lightmap | image | lightmap-lit image |\n|---|---|---|---|\n";
        for (const HeatMap& h : maps)
            md << "| " << h.method << " " << h.label << " (" << h.lightmapError << " / " << h.imageError << " / "
               << h.lightmappedError << ") | " << (h.lightmapPng.empty() ? "—" : "![](" + h.lightmapPng + ")") << " | "
               << (h.imagePng.empty() ? "—" : "![](" + h.imagePng + ")") << " | "
               << (h.lightmappedPng.empty() ? "—" : "![](" + h.lightmappedPng + ")") << " |\n";
        md << '\n';
    }
    for (const std::string& note : r.notes) md << "- " << note << '\n';
    if (!r.notes.empty()) md << '\n';
    if (r.scaling) md << scalingMarkdown(*r.scaling, options);
    if (!options.commandLine.empty()) md << "Regenerate with `" << options.commandLine << "`.\n";
    writeText(fs::path(r.outputDir) / "bench.md", md.str());
    r.files.push_back("bench.md");
}

}  // namespace

const std::vector<std::string>& benchCsvColumns() {
    static const std::vector<std::string> columns = {
        "method", "label", "settings", "ok", "runs", "lightmap_seconds", "image_seconds", "cpu_seconds", "peak_memory_mb",
        "lightmap_relrmse", "lightmap_relmse", "lightmap_smape",
        "lightmap_indirect_relrmse", "lightmap_indirect_relmse", "lightmap_indirect_smape",
        "image_relrmse", "image_relmse", "image_smape",
        "image_indirect_relrmse", "image_indirect_relmse", "image_indirect_smape",
        "lightmapped_relrmse", "lightmapped_relmse", "lightmapped_smape",
        "lightmap_pareto", "image_pareto"};
    return columns;
}

std::vector<size_t> paretoFront(const std::vector<std::pair<double, double>>& timeError) {
    std::vector<size_t> order(timeError.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return timeError[a].first != timeError[b].first ? timeError[a].first < timeError[b].first
                                                        : timeError[a].second < timeError[b].second;
    });
    std::vector<size_t> front;
    double best = std::numeric_limits<double>::infinity();
    for (size_t i : order)
        if (timeError[i].second < best) {
            front.push_back(i);
            best = timeError[i].second;
        }
    return front;
}

namespace {

// Along the front (time up, error down): x → y on log-log axes; `xIsError` picks the direction.
Reach interpolateFront(const Series& s, double x, bool xIsError) {
    Reach reach;
    const std::vector<size_t> front = paretoFront(s);
    if (front.empty() || !(x > 0.0)) return reach;
    auto X = [&](size_t i) { return xIsError ? s[front[i]].second : s[front[i]].first; };
    auto Y = [&](size_t i) { return xIsError ? s[front[i]].first : s[front[i]].second; };
    reach.found = true;
    const size_t last = front.size() - 1;
    // Errors fall along the front, times rise: orient so X increases with i.
    const bool increasing = !xIsError;
    const double lo = increasing ? X(0) : X(last), hi = increasing ? X(last) : X(0);
    if (x >= lo && x <= hi && front.size() > 1) {
        for (size_t i = 0; i < last; ++i) {
            const double a = X(i), b = X(i + 1);
            if ((x - a) * (x - b) <= 0.0) {
                const double f = a == b ? 0.0 : std::log(x / a) / std::log(b / a);
                reach.seconds = std::exp(std::log(Y(i)) + f * std::log(Y(i + 1) / Y(i)));
                reach.how = "interpolated";
                return reach;
            }
        }
    }
    if (front.size() == 1 && x == X(0)) {
        reach.seconds = Y(0);
        reach.how = "interpolated";
        return reach;
    }
    if (xIsError) {
        if (x < X(last)) {  // better than its best point: Monte Carlo rate
            reach.seconds = Y(last) * std::pow(X(last) / x, 2.0);
            reach.how = "extrapolated (error ∝ 1/√time)";
        } else {
            reach.seconds = Y(0);
            reach.how = "at most (its fastest point is already better)";
        }
    } else {
        if (x > X(last)) {
            reach.seconds = Y(last) * std::sqrt(X(last) / x);
            reach.how = "extrapolated (error ∝ 1/√time)";
        } else {
            reach.seconds = Y(0) * std::sqrt(X(0) / x);
            reach.how = "extrapolated below its fastest point (error ∝ 1/√time)";
        }
    }
    return reach;
}

}  // namespace

Reach timeToReach(std::vector<std::pair<double, double>> timeError, double error) {
    return interpolateFront(timeError, error, true);
}

Reach errorAtTime(std::vector<std::pair<double, double>> timeError, double seconds) {
    return interpolateFront(timeError, seconds, false);
}

void writeBenchOutputs(BenchResult& result, const BenchOptions& options) {
    writeCsv(result);
    std::string headlineText;
    const nlohmann::json h = headline(result, headlineText);
    const std::vector<HeatMap> maps = writeHeatMaps(result, options.imageExcludeAbove);
    writePlot(result, options);
    writeJson(result, h);
    writeMarkdown(result, options, headlineText, maps);
    if (!options.quiet) {
        std::printf("%s", table(result, false).c_str());
        if (!headlineText.empty()) std::printf("\n%s", headlineText.c_str());
        for (const std::string& note : result.notes) std::printf("note: %s\n", note.c_str());
        std::printf("wrote %s/{bench.csv, bench.json, bench.md%s}\n", result.outputDir.c_str(),
                    std::find(result.files.begin(), result.files.end(), "bench.png") != result.files.end() ? ", bench.png" : "");
    }
}

}  // namespace vl
