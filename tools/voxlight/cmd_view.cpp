// `voxlight view output/<scene>`: serves the bake's scene.glb with the viewer page on
// 127.0.0.1 and prints the address; `--screenshot shot.png` renders the page once in headless
// Chromium instead (from a glTF camera, at a size) and writes what it drew (the canvas, or with
// --whole-page the page and its controls).
#include "tools/voxlight/commands.h"

#include "core/error.h"
#include "viewer/browser_capture.h"
#include "viewer/view_server.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace vl::cli {

namespace {

struct ViewOptions {
    std::string folder = "output";
    int port = 0;
    std::string screenshot;
    BrowserCapture capture;
    std::string size = "1280x720";
};

std::string pageFolder() { return std::string(VOXLIGHT_SOURCE_DIR) + "/tools/viewer"; }

void parseSize(const std::string& text, BrowserCapture& capture) {
    int width = 0, height = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 || x != 'x' || width < 1 ||
        height < 1 || width > 8192 || height > 8192)
        throw SettingsError("view: --size '" + text + "': expected WIDTHxHEIGHT, each 1 to 8192");
    capture.width = width;
    capture.height = height;
}

void runView(ViewOptions& options) {
    if (options.port < 0 || options.port > 65535)
        throw SettingsError("view: --port " + std::to_string(options.port) + ": expected 0 to 65535 (0: any free port)");
    ViewServerOptions server;
    server.outputFolder = options.folder;
    server.pageFolder = pageFolder();
    server.port = static_cast<uint16_t>(options.port);
    if (options.screenshot.empty()) {
        ViewServer view(server);
        std::printf("voxlight view: %s (%zu scene%s) at %s\n  open it in a browser; Ctrl-C stops the server\n",
                    options.folder.c_str(), view.scenes().size(), view.scenes().size() == 1 ? "" : "s",
                    view.url().c_str());
        std::fflush(stdout);
        view.serve();
        return;
    }
    parseSize(options.size, options.capture);
    if (options.capture.mode != "lit" && options.capture.mode != "lightmap" && options.capture.mode != "albedo")
        throw SettingsError("view: --mode '" + options.capture.mode + "': expected lit, lightmap or albedo");
    if (std::filesystem::path(options.screenshot).extension() != ".png")
        throw SettingsError("view: --screenshot " + options.screenshot + ": the page is captured as PNG (name it .png)");
    server.captureFile = std::filesystem::absolute(options.screenshot);
    ViewServer view(server);
    if (options.capture.scene.empty()) options.capture.scene = view.scenes().front();
    else if (std::find(view.scenes().begin(), view.scenes().end(), options.capture.scene) == view.scenes().end())
        throw InputError("view: --scene " + options.capture.scene + ": no scene.glb at " +
                         (std::filesystem::path(options.folder) / options.capture.scene).string());
    options.capture.chromium = findChromium();
    captureInBrowser(view, options.capture);
    std::printf("wrote %s (%dx%d, camera %d, %s)\n", options.screenshot.c_str(), options.capture.width,
                options.capture.height, options.capture.camera, options.capture.mode.c_str());
}

}  // namespace

void addViewCommand(CLI::App& app) {
    auto options = std::make_shared<ViewOptions>();
    auto* cmd = app.add_subcommand("view", "Show a bake's scene.glb with its lightmaps in the browser (three.js)");
    cmd->add_option("folder", options->folder,
                    "a bake's output folder, or a job's holding several scenes (default output)");
    cmd->add_option("--port", options->port, "port on 127.0.0.1 (default 0: any free port, printed)");
    cmd->add_option("--screenshot", options->screenshot,
                    "render the page once in headless Chromium and write the canvas to this .png instead of serving");
    cmd->add_option("--scene", options->capture.scene, "with --screenshot: which scene folder (default the first)");
    cmd->add_option("--camera", options->capture.camera,
                    "with --screenshot: the glTF camera, in the file's order (default 0; -1: the whole scene)");
    cmd->add_option("--mode", options->capture.mode, "with --screenshot: lit | lightmap | albedo (default lit)");
    cmd->add_option("--exposure", options->capture.exposureStops, "with --screenshot: exposure in stops (default 0)");
    cmd->add_option("--sphere", options->capture.spheres,
                    "with --screenshot: a sphere lit by the irradiance volume, x,y,z,r in world metres, optionally "
                    ",albedo or ,r,g,b (repeatable; the page's ?sphere)");
    cmd->add_option("--size", options->size, "with --screenshot: WIDTHxHEIGHT (default 1280x720)");
    cmd->add_flag("--whole-page", options->capture.wholePage,
                  "with --screenshot: the page with its controls, not the canvas alone");
    cmd->add_option("--timeout", options->capture.timeoutSeconds,
                    "with --screenshot: seconds to wait for the page (default 120)");
    cmd->callback([options] { runView(*options); });
}

}  // namespace vl::cli
