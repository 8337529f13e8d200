// `voxlight view`: a local web server for a bake's scene.glb and the viewer page
// (tools/viewer, three.js kept in the repository). It listens on 127.0.0.1 only, answers
// only requests whose Host is that address (a web page elsewhere cannot reach it through a
// name that resolves there), and serves files below two folders, the page's and the
// bake output's: a request path with `..`, or a link leading out, is refused.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vl {

struct ViewServerOptions {
    std::filesystem::path outputFolder;  // one bake's output folder, or a job's holding several
    std::filesystem::path pageFolder;    // the viewer page (tools/viewer)
    uint16_t port = 0;                   // 0: any free port
    // Set: the server accepts one POST /capture (the page's canvas as PNG, sent when the page
    // is opened with ?capture), writes it here and stops serving; or a POST /ready (?capture=page:
    // the page is drawn, its screenshot is the browser driver's to take), and stops serving.
    // The page's own errors arrive as POST /log and are kept (pageMessages()).
    std::filesystem::path captureFile;
};

// The file a request path names below root, or nothing when it names none there: a `..`
// segment, a backslash or NUL, a malformed %-escape, or a path that leads out of root
// through a link. The path is the URL's, %-escaped, without its query.
std::optional<std::filesystem::path> fileBelow(const std::filesystem::path& root, std::string_view urlPath);

// The folders below `folder` (itself as "", then up to two levels down, sorted) that hold
// a scene.glb: a job's output holds one per scene.
std::vector<std::string> sceneFoldersBelow(const std::filesystem::path& folder);

class ViewServer {
public:
    // Binds 127.0.0.1:port; Error naming the port when it is taken, InputError when the
    // output folder holds no scene.glb.
    explicit ViewServer(ViewServerOptions options);
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    uint16_t port() const { return port_; }
    std::string url() const;  // http://127.0.0.1:PORT/
    const std::vector<std::string>& scenes() const { return scenes_; }
    const std::filesystem::path& captureFile() const { return options_.captureFile; }

    // Answers requests until stop(), the capture's (or /ready's) arrival, or timeoutSeconds
    // (> 0) pass. Returns whether a capture or /ready arrived.
    bool serve(double timeoutSeconds = 0.0);
    void stop() { stopping_ = true; }
    std::vector<std::string> pageMessages() const;

private:
    void answer(int connection);

    ViewServerOptions options_;
    std::vector<std::string> scenes_;
    int listener_ = -1;
    uint16_t port_ = 0;
    std::atomic<bool> stopping_{false};
    std::atomic<bool> captured_{false};
    mutable std::mutex messagesMutex_;
    std::vector<std::string> messages_;
};

}  // namespace vl
