#include "bake/job_file.h"

#include "bake/output_names.h"
#include "core/settings_table.h"
#include "core/error.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vl {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string settingValue(const json& value) {
    if (value.is_string()) return value.get<std::string>();
    if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
    if (value.is_array()) {  // e.g. attenuation [K_c, K_l, K_q]
        std::string joined;
        for (const json& item : value) joined += (joined.empty() ? "" : ",") + settingValue(item);
        return joined;
    }
    return value.dump();
}

// A value as JSON writes it: a string quoted, its control characters escaped (a name or key
// in a message).
std::string asJson(const json& value) { return value.dump(-1, ' ', false, json::error_handler_t::replace); }

// The keys each object of a job file takes. A key not among them is refused (checkKeys), so a
// slip ("skyy") is an error, not a setting silently left out.
const std::vector<std::string> kJobKeys = {"output", "settings", "atlases", "sky", "scenes"};
const std::vector<std::string> kSceneKeys = {"path", "name", "output", "settings", "sky", "atlases", "lights", "cameras"};
// A light's keys, each with the types of light it is for (nullptr: every type).
struct LightKey {
    const char* name;
    const char* types;  // "point and spot": no type's name is part of another's
};
const LightKey kLightKeyTypes[] = {{"name", nullptr},
                                   {"type", nullptr},
                                   {"color", nullptr},
                                   {"intensity", nullptr},
                                   {"position", "point and spot"},
                                   {"range", "point and spot"},
                                   {"direction", "spot and directional"},
                                   {"angle", "directional"},
                                   {"innerConeAngle", "spot"},
                                   {"outerConeAngle", "spot"},
                                   {"bake", nullptr}};
const std::vector<std::string> kLightKeys = [] {
    std::vector<std::string> keys;
    for (const LightKey& key : kLightKeyTypes) keys.push_back(key.name);
    return keys;
}();
const std::vector<std::string> kCameraKeys = {"name", "position", "target", "up", "yfov"};
const std::vector<std::string> kSkyKeys = {"radiance", "image", "rotation", "intensity"};
const std::vector<std::string> kAtlasKeys = {"name", "meshes", "resolution"};

const std::vector<std::string>& bakeSettingNames() {
    static const std::vector<std::string> names = settingNames(bakeSettingsTable());
    return names;
}

// Keys that belong to another object of the job file, and where they go: the hint when a key
// is unknown where it stands but known there.
struct KeysElsewhere {
    const std::vector<std::string>* keys;
    const char* note;  // follows the key's name: "\"cones\" is a bake setting: ..."
};
KeysElsewhere inScene() { return {&kSceneKeys, "is a key of each scene: it goes in a scene of \"scenes\""}; }
KeysElsewhere inSettings() { return {&bakeSettingNames(), "is a bake setting: it goes in \"settings\""}; }
KeysElsewhere besideSettings(const std::vector<std::string>& keys) {
    return {&keys, "is a job-file key, not a bake setting: it goes beside \"settings\""};
}

// "unknown key "skyy" (did you mean "sky"?)": the closest key of the object itself, else a
// key of another object (exactly, then closely) with where it goes, else the keys it takes.
std::string unknownKey(const std::string& key, const std::vector<std::string>& known,
                       std::initializer_list<KeysElsewhere> elsewhere, const char* at = "") {
    const std::string message = "unknown key " + asJson(key) + at;
    for (const KeysElsewhere& other : elsewhere)
        if (std::find(other.keys->begin(), other.keys->end(), key) != other.keys->end())
            return message + " (" + asJson(key) + " " + other.note + ")";
    const std::string closest = closestName(key, known);
    if (!closest.empty()) return message + " (did you mean " + asJson(closest) + "?)";
    for (const KeysElsewhere& other : elsewhere) {
        const std::string near = closestName(key, *other.keys);
        if (!near.empty()) return message + " (did you mean " + asJson(near) + "? " + asJson(near) + " " + other.note + ")";
    }
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    return message + " (known: " + list + ")";
}

// Refuses the first key of `object` (an object) that is not in `known`, as InputError
// "<where>: unknown key …<at>".
void checkKeys(const json& object, const std::vector<std::string>& known, const std::string& where,
               std::initializer_list<KeysElsewhere> elsewhere = {}, const char* at = "") {
    for (const auto& entry : object.items())
        if (std::find(known.begin(), known.end(), entry.key()) == known.end())
            throw InputError(where + ": " + unknownKey(entry.key(), known, elsewhere, at));
}

// Why a folder name holds what no folder name should ("" when it does not): `slash` allows
// "/" (between the parts of a relative path).
std::string characterFault(const std::string& name, bool slash) {
    for (const char c : name) {
        if ((c == '/' && !slash) || c == '\\') return "it holds \"" + std::string(1, c) + "\"";
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "it holds a control character";
    }
    return "";
}

// Why `name` is one voxlight gives what it writes beside a scene's folder or in the output
// folder (output_names.h): "" when it is not.
std::string reservedFault(const std::string& name) {
    if (name == kClusterWorkFolder) return "a cluster bake keeps its work in \"" + name + "\"";
    if (name.find(kStagingInfix) != std::string::npos)
        return "a bake of <folder> is staged in \"<folder>" + std::string(kStagingInfix) + "…\"";
    const std::string lock = kLockSuffix;
    if (name.size() >= lock.size() && name.compare(name.size() - lock.size(), lock.size(), lock) == 0)
        return "a bake of <folder> is locked with \"<folder>" + lock + "\"";
    return "";
}

// Why `name` is not the name of one folder ("" when it is): a scene bakes into
// <output folder>/<name>, a folder of its own inside the output folder.
std::string folderNameFault(const std::string& name) {
    if (name.empty()) return "it is empty";
    if (name == ".") return "\".\" is the output folder itself";
    if (name == "..") return "\"..\" leads out of the output folder";
    const std::string fault = characterFault(name, false);
    return fault.empty() ? reservedFault(name) : fault;
}

// Why a scene's "output" is not a folder inside the output folder ("" when it is): a relative
// path of folder names ("levels/e1m1"; a trailing "/" aside).
std::string innerFolderFault(const std::string& folder) {
    if (folder.empty()) return "it is empty";
    if (folder.front() == '/') return "it is an absolute path";
    const std::string fault = characterFault(folder, true);
    if (!fault.empty()) return fault;
    const std::string parts = folder.back() == '/' ? folder.substr(0, folder.size() - 1) : folder;
    for (size_t begin = 0;;) {
        const size_t end = parts.find('/', begin);
        const std::string part = parts.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
        if (part == "..") return "\"..\" leads out of it";
        if (part.empty() || part == ".") return "it has an empty or \".\" part";
        if (const std::string reserved = reservedFault(part); !reserved.empty()) return reserved;
        if (end == std::string::npos) return "";
        begin = end + 1;
    }
}

// `folder` with links and ".." resolved (as far as it exists); InputError naming `where` when
// the file system will not say.
fs::path resolvedFolder(const std::string& folder, const std::string& where) {
    std::error_code error;
    fs::path resolved = fs::absolute(folder, error);
    if (!error) resolved = fs::weakly_canonical(resolved, error);
    if (error) throw InputError(where + ": cannot resolve the folder " + folder + ": " + error.message());
    return resolved;
}

// "settings": {name: value}: each name a bake setting of the one table (bakeSettingsTable),
// refused as SettingsError naming the place when unknown. `where` names the object.
void applySettings(BakeSettings& settings, const json& object, const std::string& where,
                   std::initializer_list<KeysElsewhere> elsewhere) {
    if (!object.is_object()) throw SettingsError(where + " must be an object of bake settings");
    for (const auto& [name, value] : object.items()) {
        const SettingSpec<BakeSettings>* spec = findSetting(bakeSettingsTable(), name);
        if (!spec) throw SettingsError(where + ": " + unknownKey(name, bakeSettingNames(), elsewhere));
        try {
            spec->apply(settings, settingValue(value));
        } catch (const SettingsError& e) {
            throw SettingsError(where + ": " + e.what());
        }
    }
}

vec3 readVec3(const json& value, const std::string& where) {
    if (!value.is_array() || value.size() != 3) throw InputError(where + " must be an array of 3 numbers");
    vec3 v;
    for (int i = 0; i < 3; ++i) {
        if (!value[static_cast<size_t>(i)].is_number()) throw InputError(where + " must be an array of 3 numbers");
        v[i] = value[static_cast<size_t>(i)].get<float>();
        if (!std::isfinite(v[i])) throw InputError(where + " is not finite");
    }
    return v;
}

Light readLight(const json& object, const std::string& where) {
    if (!object.is_object()) throw InputError(where + " must be an object");
    checkKeys(object, kLightKeys, where);
    Light light;
    light.name = object.value("name", "added light");
    const std::string type = object.value("type", "point");
    if (type == "point") light.type = LightType::Point;
    else if (type == "spot") light.type = LightType::Spot;
    else if (type == "directional") light.type = LightType::Directional;
    else throw InputError(where + ": type '" + type + "' is not point, spot or directional");
    // A key of another type's light would be read by none: a light missing its "type" (a point
    // light by default) with a spot's cone is refused, not baked as a point.
    for (const LightKey& key : kLightKeyTypes)
        if (key.types && object.contains(key.name) && std::string(key.types).find(type) == std::string::npos)
            throw InputError(where + ": \"" + key.name + "\" is for " + key.types + " lights, not a " + type + " light" +
                             (object.contains("type") ? "" : " (the default: give a \"type\")"));
    if (object.contains("color")) light.color = readVec3(object["color"], where + ".color");
    light.intensity = object.value("intensity", 1.0f);
    if (!(light.intensity >= 0.0f) || !std::isfinite(light.intensity))
        throw InputError(where + ": intensity must be finite and non-negative");
    light.range = object.value("range", 0.0f);
    if (light.type != LightType::Directional) {
        if (!object.contains("position")) throw InputError(where + ": a " + type + " light needs a position");
        light.position = readVec3(object["position"], where + ".position");
    }
    if (light.type != LightType::Point) {
        if (!object.contains("direction")) throw InputError(where + ": a " + type + " light needs a direction");
        const vec3 d = readVec3(object["direction"], where + ".direction");
        if (!(glm::length(d) > 0.0f)) throw InputError(where + ".direction is zero");
        light.direction = glm::normalize(d);
    }
    if (object.contains("angle")) {  // a sun's disk
        const float degrees = object["angle"].get<float>();
        if (!(degrees >= 0.0f && degrees <= 90.0f))
            throw InputError(where + ".angle: " + std::to_string(degrees) + " is outside 0..90 degrees");
        light.angularDiameter = degrees * kPi / 180.0f;
    }
    if (object.contains("bake")) {
        const nlohmann::json& mode = object["bake"];
        if (!mode.is_string() || !parseLightBake(mode.get<std::string>(), light.bake))
            throw InputError(where + ".bake: " + mode.dump() + " is not \"all\", \"indirect\" or \"shadowmask\"");
    }
    if (light.type == LightType::Spot) {
        light.innerConeAngle = object.value("innerConeAngle", 0.0f);
        light.outerConeAngle = object.value("outerConeAngle", 0.7853981634f);
        if (!(light.innerConeAngle >= 0.0f && light.innerConeAngle < light.outerConeAngle &&
              light.outerConeAngle <= 0.5f * kPi))
            throw InputError(where + ": cone angles must satisfy 0 ≤ inner < outer ≤ π/2");
    }
    return light;
}

// {"name": "hall", "position": [x, y, z], "target": [x, y, z], "up": [0, 1, 0], "yfov": 0.8}
// (yfov in radians, as glTF; up defaults to +Y).
Camera readCamera(const json& object, const std::string& where) {
    if (!object.is_object()) throw InputError(where + " must be an object");
    checkKeys(object, kCameraKeys, where);
    Camera camera;
    camera.name = object.value("name", "added camera");
    if (!object.contains("position") || !object.contains("target"))
        throw InputError(where + ": a camera needs a \"position\" and a \"target\"");
    camera.position = readVec3(object["position"], where + ".position");
    const vec3 forward = readVec3(object["target"], where + ".target") - camera.position;
    if (!(glm::length(forward) > 0.0f)) throw InputError(where + ": target equals position");
    camera.forward = glm::normalize(forward);
    const vec3 up = object.contains("up") ? readVec3(object["up"], where + ".up") : vec3(0.0f, 1.0f, 0.0f);
    const vec3 right = glm::cross(camera.forward, up);
    if (!(glm::length(right) > 1e-6f * glm::length(up))) throw InputError(where + ": up is parallel to the view direction");
    camera.up = glm::normalize(glm::cross(glm::normalize(right), camera.forward));
    if (object.contains("yfov")) {
        if (!object["yfov"].is_number()) throw InputError(where + ".yfov must be a number (radians)");
        camera.yfov = object["yfov"].get<float>();
    }
    if (!(camera.yfov > 0.0f && camera.yfov < kPi))
        throw InputError(where + ".yfov = " + std::to_string(camera.yfov) + " is outside (0, π) radians");
    return camera;
}

// {"name": "walls", "meshes": ["Floor", "BackWall"], "resolution": 512 or [1024, 512]}
AtlasGroup readAtlasGroup(const json& object, const std::string& where) {
    if (!object.is_object()) throw InputError(where + " must be an object");
    checkKeys(object, kAtlasKeys, where);
    AtlasGroup group;
    group.origin = where;
    if (!object.contains("name") || !object["name"].is_string()) throw InputError(where + " needs a \"name\" string");
    group.name = object["name"].get<std::string>();
    if (!object.contains("meshes") || !object["meshes"].is_array())
        throw InputError(where + " needs a \"meshes\" array of node or mesh names");
    for (const json& mesh : object["meshes"]) {
        if (!mesh.is_string()) throw InputError(where + ".meshes: " + mesh.dump() + " is not a name (a string)");
        group.meshes.push_back(mesh.get<std::string>());
    }
    if (object.contains("resolution")) {  // absent: lightmap-res
        const json& resolution = object["resolution"];
        const bool pair = resolution.is_array() && resolution.size() == 2;
        if (!resolution.is_number_integer() &&
            !(pair && resolution[0].is_number_integer() && resolution[1].is_number_integer()))
            throw InputError(where + ".resolution must be an integer or [width, height] integers, not " +
                             resolution.dump());
        const long long width = (pair ? resolution[0] : resolution).get<long long>();
        const long long height = (pair ? resolution[1] : resolution).get<long long>();
        if (width < 1 || height < 1 || width > kMaxLightmapResolution || height > kMaxLightmapResolution)
            throw SettingsError(where + ".resolution " + resolution.dump() + " is outside 1.." +
                                std::to_string(kMaxLightmapResolution) + " (the range of lightmap-res)");
        group.width = static_cast<int>(width);
        group.height = static_cast<int>(height);
    }
    return group;
}

std::vector<AtlasGroup> readAtlasGroups(const json& array, const std::string& where) {
    if (!array.is_array()) throw InputError(where + " must be an array of atlas groups");
    std::vector<AtlasGroup> groups;
    for (size_t i = 0; i < array.size(); ++i)
        groups.push_back(readAtlasGroup(array[i], where + "[" + std::to_string(i) + "]"));
    return groups;
}

json readJson(const std::string& path, const std::string& what) {
    std::ifstream in(path);
    if (!in) throw InputError(path + ": cannot open the " + what);
    try {
        return json::parse(in);
    } catch (const json::exception& e) {
        throw InputError(path + ": not valid JSON: " + e.what());
    }
}

// "sky": {"radiance": [r, g, b] (or one number), "image": path, "rotation": degrees,
// "intensity": scale}: the bake settings sky, sky-image (relative to the job file's folder),
// sky-rotation and sky-intensity. A radiance or an image is needed; rotation and intensity
// belong to an image. `where` names the object ("job.json: sky", "job.json: scenes[1].sky").
void readSky(const json& object, BakeSettings& settings, const std::string& where, const fs::path& base) {
    if (object.is_object()) checkKeys(object, kSkyKeys, where);
    if (!object.is_object() || !(object.contains("radiance") || object.contains("image")))
        throw InputError(where + ": \"sky\" must be an object with a \"radiance\" (W/(m²·sr): [r, g, b] or one number) "
                                 "or an \"image\" (an equirectangular .hdr or .exr)");
    if (!object.contains("image") && (object.contains("rotation") || object.contains("intensity")))
        throw InputError(where + ": \"rotation\" and \"intensity\" belong to an \"image\"");
    const auto apply = [&](const char* key, const char* setting, const std::string& text) {
        try {
            applySetting(bakeSettingsTable(), settings, setting, text);
        } catch (const SettingsError& e) {
            throw SettingsError(where + "." + key + ": " + e.what());
        }
    };
    if (object.contains("radiance")) {
        const json& radiance = object["radiance"];
        const vec3 r = radiance.is_number() ? vec3(radiance.get<float>()) : readVec3(radiance, where + ".radiance");
        std::ostringstream text;
        text << r.x << "," << r.y << "," << r.z;
        apply("radiance", "sky", text.str());
    }
    if (!object.contains("image")) return;
    if (!object["image"].is_string() || object["image"].get<std::string>().empty())
        throw InputError(where + ".image must be the path of an image file");
    const fs::path image = object["image"].get<std::string>();
    apply("image", "sky-image", image.is_absolute() ? image.string() : (base / image).lexically_normal().string());
    for (const char* key : {"rotation", "intensity"}) {
        if (!object.contains(key)) continue;
        if (!object[key].is_number()) throw InputError(where + "." + key + " must be a number");
        std::ostringstream text;
        text.precision(9);
        text << object[key].get<double>();
        apply(key, key == std::string("rotation") ? "sky-rotation" : "sky-intensity", text.str());
    }
}

}  // namespace

std::string sceneOutputName(const std::string& scenePath) { return fs::path(scenePath).stem().string(); }

std::vector<BakeJob> readJobFile(const std::string& path, const BakeSettings& defaults,
                                 const std::string& defaultOutputRoot, const SettingAssignments& command,
                                 const std::string& commandOutputRoot) {
    const json root = readJson(path, "job file");
    if (root.is_object()) checkKeys(root, kJobKeys, path, {inScene(), inSettings()}, " at the top level");
    if (!root.is_object() || !root.contains("scenes") || !root["scenes"].is_array() || root["scenes"].empty())
        throw InputError(path + ": a job file needs a non-empty \"scenes\" array");
    const fs::path base = fs::path(path).parent_path();
    auto resolve = [&](const std::string& p) { return fs::path(p).is_absolute() ? p : (base / p).lexically_normal().string(); };

    // A value of the wrong JSON type (a string where a number belongs) is the user's error:
    // report it with the place it was found, not as an internal one.
    std::string where = path;
    try {
        BakeSettings global = defaults;
        if (root.contains("settings"))
            applySettings(global, root["settings"], path + ": settings", {besideSettings(kJobKeys), inScene()});
        if (root.contains("atlases")) global.lightmap.atlases = readAtlasGroups(root["atlases"], path + ": atlases");
        if (root.contains("sky")) readSky(root["sky"], global, path + ": sky", base);
        if (root.contains("output") && !root["output"].is_string())
            throw InputError(path + ": \"output\" must be a string, the folder the scenes bake into");
        const std::string outputRoot = !commandOutputRoot.empty() ? commandOutputRoot
                                       : root.contains("output") ? resolve(root["output"].get<std::string>())
                                                                 : defaultOutputRoot;
        const fs::path resolvedRoot = resolvedFolder(outputRoot, path + ": output");

        std::vector<BakeJob> jobs;
        std::vector<fs::path> resolvedOutputs;  // per scene: two scenes never share a folder
        for (size_t i = 0; i < root["scenes"].size(); ++i) {
            const json& entry = root["scenes"][i];
            where = path + ": scenes[" + std::to_string(i) + "]";
            if (entry.is_object()) checkKeys(entry, kSceneKeys, where, {inSettings()});
            if (!entry.is_object() || !entry.contains("path") || !entry["path"].is_string())
                throw InputError(where + " needs a \"path\" string");
            BakeJob job;
            job.scenePath = resolve(entry["path"].get<std::string>());
            job.settings = global;
            if (entry.contains("settings"))
                applySettings(job.settings, entry["settings"], where + ".settings", {besideSettings(kSceneKeys)});
            if (entry.contains("sky")) readSky(entry["sky"], job.settings, where + ".sky", base);
            // Mesh names belong to one scene: a scene's list replaces the global one ([] for none).
            if (entry.contains("atlases"))
                job.settings.lightmap.atlases = readAtlasGroups(entry["atlases"], where + ".atlases");
            for (const auto& [name, value] : command) applySetting(bakeSettingsTable(), job.settings, name, value);
            job.settings.lightmap.validate();

            // The scene's folder: <output folder>/<name> (its file's stem by default), or its
            // "output" inside the output folder. Named by the file's text first, then resolved
            // (links, "..") and held inside the output folder, apart from every other scene's.
            if (entry.contains("name") && entry.contains("output"))
                throw InputError(where + ": \"name\" and \"output\" both give the scene's folder: keep one");
            if (entry.contains("output")) {
                const json& output = entry["output"];
                const std::string fault = output.is_string() ? innerFolderFault(output.get<std::string>()) : "not a string";
                if (!fault.empty())
                    throw InputError(where + ": \"output\": " + asJson(output) +
                                     " is not a folder inside the job's output folder (" + fault + ")");
                std::string folder = output.get<std::string>();
                if (folder.back() == '/') folder.pop_back();  // "<folder>.partial-…" stages beside it, not in it
                job.outputDir = (fs::path(outputRoot) / folder).lexically_normal().string();
            } else {
                const bool named = entry.contains("name");
                if (named && !entry["name"].is_string())
                    throw InputError(where + ": \"name\" must be a string, the name of the folder the scene bakes into");
                const std::string name = named ? entry["name"].get<std::string>() : sceneOutputName(job.scenePath);
                const std::string fault = folderNameFault(name);
                if (!fault.empty() && named)
                    throw InputError(where + ": \"name\": " + asJson(name) + " is not a folder name (" + fault +
                                     "): a scene bakes into the folder of its name, inside the job's output folder");
                if (!fault.empty())
                    throw InputError(where + ": its path gives the folder name " + asJson(name) + ", which is not one (" +
                                     fault + "): give the scene a \"name\"");
                job.outputDir = (fs::path(outputRoot) / name).string();
            }
            const fs::path resolved = resolvedFolder(job.outputDir, where);
            const fs::path relative = resolved.lexically_relative(resolvedRoot);
            if (relative.empty() || relative == "." || *relative.begin() == "..")
                throw InputError(where + ": its folder " + job.outputDir + " resolves to " + resolved.string() +
                                 ", outside the job's output folder " + resolvedRoot.string());
            // Nor into another scene's, nor around it: one's bake would mix with the other's.
            for (size_t other = 0; other < resolvedOutputs.size(); ++other) {
                const std::string scene = "scenes[" + std::to_string(other) + "]";
                if (resolvedOutputs[other] == resolved)
                    throw InputError(where + ": bakes into " + job.outputDir + ", as " + scene +
                                     " does: give one of them another \"name\"");
                const auto inside = [](const fs::path& inner, const fs::path& outer) {
                    const fs::path relative = inner.lexically_relative(outer);
                    return !relative.empty() && *relative.begin() != "..";
                };
                if (inside(resolved, resolvedOutputs[other]) || inside(resolvedOutputs[other], resolved))
                    throw InputError(where + ": its folder " + job.outputDir + " and the folder of " + scene +
                                     ", " + jobs[other].outputDir + ", lie one inside the other: keep them apart");
            }
            resolvedOutputs.push_back(resolved);

            if (entry.contains("lights")) {
                if (!entry["lights"].is_array()) throw InputError(where + ": \"lights\" must be an array");
                for (size_t l = 0; l < entry["lights"].size(); ++l)
                    job.addedLights.push_back(readLight(entry["lights"][l], where + ".lights[" + std::to_string(l) + "]"));
            }
            if (entry.contains("cameras")) {
                if (!entry["cameras"].is_array()) throw InputError(where + ": \"cameras\" must be an array");
                for (size_t c = 0; c < entry["cameras"].size(); ++c)
                    job.addedCameras.push_back(
                        readCamera(entry["cameras"][c], where + ".cameras[" + std::to_string(c) + "]"));
            }
            jobs.push_back(std::move(job));
        }
        return jobs;
    } catch (const json::exception& e) {
        throw InputError(where + ": " + e.what());
    }
}

std::vector<AtlasGroup> readAtlasFile(const std::string& path) {
    const json root = readJson(path, "atlas file");
    try {
        if (root.is_object()) checkKeys(root, kJobKeys, path, {inScene(), inSettings()}, " at the top level");
        if (root.is_object() && root.contains("atlases")) return readAtlasGroups(root["atlases"], path + ": atlases");
        return readAtlasGroups(root, path);
    } catch (const json::exception& e) {
        throw InputError(path + ": " + e.what());
    }
}

}  // namespace vl
