// Job files: many scenes in one batch, settings globally or per scene, lights and cameras
// added to scenes that have none, a choice of outputs. Relative paths resolve against the job
// file. The format, with an example, is next to readJobFile; the user's side is in
// docs/usage.md, "Job files".
#pragma once

#include "bake/bake_job.h"

#include <string>
#include <utility>
#include <vector>

namespace vl {

// A job file:
// {
//   "output": "output",                       // root folder for scenes without "output"
//   "settings": { "resolution": 128, "lightmap-res": 512 },   // any bake setting, for all
//   "atlases": [ { "name": "walls", "meshes": ["Floor", "BackWall"], "resolution": 1024 } ],
//   "sky": { "radiance": [0.6, 0.75, 1.0] },  // a uniform sky, W/(m²·sr), for all (the `sky` setting)
//   "scenes": [
//     { "path": "scenes/cornell_box.gltf" },
//     { "path": "level.glb", "name": "level",   // its folder in "output"; or "output": "levels/e1m1"
//       "settings": { "cones": 32, "images": false }, "sky": { "radiance": 0 },  // replaces the global sky
//       "atlases": [ { "name": "props", "meshes": ["Chair"], "resolution": [512, 256] } ],  // replaces the global list
//       "lights": [ { "name": "lamp", "type": "point", "position": [1, 2, 3],
//                     "color": [1, 1, 1], "intensity": 5 } ],      // W/sr (W/m² directional)
//       "cameras": [ { "name": "hall", "position": [0, 1.6, 4], "target": [0, 1, 0],
//                      "up": [0, 1, 0], "yfov": 0.8 } ] }            // radians; up defaults to +Y
//   ]
// }
//
// Every key of every object is one of those above (a light also takes "direction", "range",
// "angle", "innerConeAngle", "outerConeAngle", each for the types it belongs to, and "bake":
// "all" or "indirect", its bake mode, scene.h LightBake; "settings"
// takes the bake settings): another is refused, naming the file, the place and the closest
// known key. A scene bakes into <output>/<name> (name: its file's stem by default) or into its
// "output", a relative path inside the job's output folder; a name is one folder's name (no
// "/", "\", "..", control characters, nor a name of output_names.h), and each scene's folder,
// links resolved, lies inside the output folder, neither another scene's nor inside or around
// one.
//
// Each scene starts from `defaults`; the file's global and per-scene settings apply on top,
// then `command`, the settings the command line gave (name, value): what the user typed last
// wins over the file (a job baked at another lightmap-res without editing it). The scenes bake
// under the file's "output" (relative to the file), else `defaultOutputRoot`; a non-empty
// `commandOutputRoot` (the command's -o) wins over both, as the command's settings do. InputError /
// SettingsError name the file and the scene. It reads only: a refused job file leaves nothing
// written.
using SettingAssignments = std::vector<std::pair<std::string, std::string>>;
std::vector<BakeJob> readJobFile(const std::string& path, const BakeSettings& defaults,
                                 const std::string& defaultOutputRoot, const SettingAssignments& command = {},
                                 const std::string& commandOutputRoot = "");

// Atlas groups (LightmapSettings::atlases) from a JSON file holding a job file's "atlases"
// array, or from a job file's top-level "atlases", for commands that take no job file.
std::vector<AtlasGroup> readAtlasFile(const std::string& path);

// The folder name a scene bakes into: its file stem.
std::string sceneOutputName(const std::string& scenePath);

}  // namespace vl
