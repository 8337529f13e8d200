// The viewer page rendered by headless Chromium (WebGL on its SwiftShader software renderer):
// `voxlight view --screenshot` and the test that holds the page to the bake's own image.
#pragma once

#include "viewer/view_server.h"

#include <string>
#include <vector>

namespace vl {

// The Chromium on PATH (chromium, chromium-browser, google-chrome), or "" when none.
std::string findChromium();

struct BrowserCapture {
    std::string chromium;         // the browser to run (findChromium())
    std::string scene;            // one of server.scenes()
    int camera = 0;               // the glTF camera, in the file's order
    std::string mode = "lit";     // lit | lightmap | albedo
    double exposureStops = 0.0;
    bool threeMaterials = false;  // three.js' own materials (tools/viewer/moz_lightmap.js)
    // Spheres lit by the scene's irradiance volume: "x,y,z,r" (world metres), optionally
    // ",albedo" or ",r,g,b" (linear), as the page's ?sphere takes them.
    std::vector<std::string> spheres;
    int width = 1280, height = 720;
    // false: the canvas alone, as the page drew it (exact pixels: the test compares them);
    // true: the whole page with its controls, as a user sees it (Chromium's screenshot).
    bool wholePage = false;
    double timeoutSeconds = 120.0;
};

// Runs Chromium on the page with ?capture, serves it until the page posts its canvas or says it
// is drawn (then Chromium's screenshot of it is taken through the DevTools protocol), writes the
// PNG to the server's capture file and stops the browser. Error, with the page's own messages,
// when the browser exits or the time passes first. The server must have a capture file.
void captureInBrowser(ViewServer& server, const BrowserCapture& capture);

}  // namespace vl
