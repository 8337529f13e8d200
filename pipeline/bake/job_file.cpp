#include "bake/job_file.h"

#include "core/error.h"

#include <nlohmann/json.hpp>

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

void applySettings(BakeSettings& settings, const json& object, const std::string& where) {
    if (!object.is_object()) throw SettingsError(where + ": \"settings\" must be an object");
    for (const auto& [name, value] : object.items()) {
        try {
            applySetting(bakeSettingsTable(), settings, name, settingValue(value));
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
    Light light;
    light.name = object.value("name", "added light");
    const std::string type = object.value("type", "point");
    if (type == "point") light.type = LightType::Point;
    else if (type == "spot") light.type = LightType::Spot;
    else if (type == "directional") light.type = LightType::Directional;
    else throw InputError(where + ": type '" + type + "' is not point, spot or directional");
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
    if (object.contains("angle")) {
        if (light.type != LightType::Directional) throw InputError(where + ": \"angle\" (a sun's disk) is for directional lights");
        const float degrees = object["angle"].get<float>();
        if (!(degrees >= 0.0f && degrees <= 90.0f))
            throw InputError(where + ".angle: " + std::to_string(degrees) + " is outside 0..90 degrees");
        light.angularDiameter = degrees * kPi / 180.0f;
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
    for (const auto& entry : object.items())
        if (entry.key() != "name" && entry.key() != "position" && entry.key() != "target" && entry.key() != "up" &&
            entry.key() != "yfov")
            throw InputError(where + ": unknown key \"" + entry.key() + "\" (known: name, position, target, up, yfov)");
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
    for (const auto& entry : object.items())
        if (entry.key() != "name" && entry.key() != "meshes" && entry.key() != "resolution")
            throw InputError(where + ": unknown key \"" + entry.key() + "\" (known: name, meshes, resolution)");
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
// belong to an image.
void readSky(const json& object, BakeSettings& settings, const std::string& where, const fs::path& base) {
    if (!object.is_object() || !(object.contains("radiance") || object.contains("image")))
        throw InputError(where + ": \"sky\" must be an object with a \"radiance\" (W/(m²·sr): [r, g, b] or one number) "
                                 "or an \"image\" (an equirectangular .hdr or .exr)");
    for (const auto& [key, value] : object.items())
        if (key != "radiance" && key != "image" && key != "rotation" && key != "intensity")
            throw InputError(where + ".sky: unknown key \"" + key + "\" (known: radiance, image, rotation, intensity)");
    if (!object.contains("image") && (object.contains("rotation") || object.contains("intensity")))
        throw InputError(where + ".sky: \"rotation\" and \"intensity\" belong to an \"image\"");
    const auto apply = [&](const char* key, const char* setting, const std::string& text) {
        try {
            applySetting(bakeSettingsTable(), settings, setting, text);
        } catch (const SettingsError& e) {
            throw SettingsError(where + ".sky." + key + ": " + e.what());
        }
    };
    if (object.contains("radiance")) {
        const json& radiance = object["radiance"];
        const vec3 r = radiance.is_number() ? vec3(radiance.get<float>()) : readVec3(radiance, where + ".sky.radiance");
        std::ostringstream text;
        text << r.x << "," << r.y << "," << r.z;
        apply("radiance", "sky", text.str());
    }
    if (!object.contains("image")) return;
    if (!object["image"].is_string() || object["image"].get<std::string>().empty())
        throw InputError(where + ".sky.image must be the path of an image file");
    const fs::path image = object["image"].get<std::string>();
    apply("image", "sky-image", image.is_absolute() ? image.string() : (base / image).lexically_normal().string());
    for (const char* key : {"rotation", "intensity"}) {
        if (!object.contains(key)) continue;
        if (!object[key].is_number()) throw InputError(where + ".sky." + key + " must be a number");
        std::ostringstream text;
        text.precision(9);
        text << object[key].get<double>();
        apply(key, key == std::string("rotation") ? "sky-rotation" : "sky-intensity", text.str());
    }
}

}  // namespace

std::string sceneOutputName(const std::string& scenePath) { return fs::path(scenePath).stem().string(); }

std::vector<BakeJob> readJobFile(const std::string& path, const BakeSettings& defaults,
                                 const std::string& defaultOutputRoot) {
    const json root = readJson(path, "job file");
    if (!root.is_object() || !root.contains("scenes") || !root["scenes"].is_array() || root["scenes"].empty())
        throw InputError(path + ": a job file needs a non-empty \"scenes\" array");
    const fs::path base = fs::path(path).parent_path();
    auto resolve = [&](const std::string& p) { return fs::path(p).is_absolute() ? p : (base / p).lexically_normal().string(); };

    // A value of the wrong JSON type (a string where a number belongs) is the user's error:
    // report it with the place it was found, not as an internal one.
    std::string where = path;
    try {
        BakeSettings global = defaults;
        if (root.contains("settings")) applySettings(global, root["settings"], path);
        if (root.contains("atlases")) global.lightmap.atlases = readAtlasGroups(root["atlases"], path + ": atlases");
        if (root.contains("sky")) readSky(root["sky"], global, path, base);
        const std::string outputRoot = root.contains("output") ? resolve(root["output"].get<std::string>()) : defaultOutputRoot;

        std::vector<BakeJob> jobs;
        for (size_t i = 0; i < root["scenes"].size(); ++i) {
            const json& entry = root["scenes"][i];
            where = path + ": scenes[" + std::to_string(i) + "]";
            if (!entry.is_object() || !entry.contains("path") || !entry["path"].is_string())
                throw InputError(where + " needs a \"path\" string");
            BakeJob job;
            job.scenePath = resolve(entry["path"].get<std::string>());
            job.settings = global;
            if (entry.contains("settings")) applySettings(job.settings, entry["settings"], where);
            if (entry.contains("sky")) readSky(entry["sky"], job.settings, where, base);
            // Mesh names belong to one scene: a scene's list replaces the global one ([] for none).
            if (entry.contains("atlases"))
                job.settings.lightmap.atlases = readAtlasGroups(entry["atlases"], where + ".atlases");
            job.settings.lightmap.validate();
            const std::string name = entry.value("name", sceneOutputName(job.scenePath));
            job.outputDir = entry.contains("output") ? resolve(entry["output"].get<std::string>())
                                                     : (fs::path(outputRoot) / name).string();
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
        if (root.is_object() && root.contains("atlases")) return readAtlasGroups(root["atlases"], path + ": atlases");
        return readAtlasGroups(root, path);
    } catch (const json::exception& e) {
        throw InputError(path + ": " + e.what());
    }
}

}  // namespace vl
