#include "viewer/browser_capture.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <exception>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <poll.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace vl {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::string urlEscaped(const std::string& text) {
    static const char* hex = "0123456789ABCDEF";
    std::string out;
    for (const unsigned char c : text) {
        if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~' || c == '/') {
            out += static_cast<char>(c);
        } else {
            out += '%';
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

std::string base64Decoded(const std::string& text) {
    std::string out;
    uint32_t bits = 0;
    int count = 0;
    for (const char c : text) {
        int value = -1;
        if (c >= 'A' && c <= 'Z') value = c - 'A';
        else if (c >= 'a' && c <= 'z') value = c - 'a' + 26;
        else if (c >= '0' && c <= '9') value = c - '0' + 52;
        else if (c == '+') value = 62;
        else if (c == '/') value = 63;
        if (value < 0) continue;  // '=' padding
        bits = (bits << 6) | static_cast<uint32_t>(value);
        if ((count += 6) >= 8) {
            count -= 8;
            out += static_cast<char>((bits >> count) & 0xFF);
        }
    }
    return out;
}

// Chromium's DevTools protocol over --remote-debugging-pipe: JSON messages, each ended by NUL,
// commands on the browser's fd 3, answers and events on its fd 4.
class DevTools {
public:
    DevTools(int toBrowser, int fromBrowser) : out_(toBrowser), in_(fromBrowser) {}
    ~DevTools() {
        ::close(out_);
        ::close(in_);
    }

    Json call(const std::string& method, const Json& params = Json::object(), const std::string& session = "") {
        const int id = nextId_++;
        Json message{{"id", id}, {"method", method}, {"params", params}};
        if (!session.empty()) message["sessionId"] = session;
        const std::string text = message.dump() + '\0';
        for (size_t sent = 0; sent < text.size();) {
            const ssize_t n = ::write(out_, text.data() + sent, text.size() - sent);
            if (n <= 0) throw Error("view: the browser closed its DevTools pipe (" + method + ")");
            sent += static_cast<size_t>(n);
        }
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        for (;;) {
            const size_t end = pending_.find('\0');
            if (end != std::string::npos) {
                const Json reply = Json::parse(pending_.substr(0, end), nullptr, false);
                pending_.erase(0, end + 1);
                if (reply.is_discarded() || !reply.contains("id") || reply["id"] != id) continue;  // an event
                if (reply.contains("error"))
                    throw Error("view: the browser refused " + method + ": " + reply["error"].value("message", "?"));
                return reply.value("result", Json::object());
            }
            if (std::chrono::steady_clock::now() > deadline)
                throw Error("view: the browser did not answer " + method + " within 60 s");
            pollfd waiting{in_, POLLIN, 0};
            if (::poll(&waiting, 1, 200) <= 0) continue;
            char buffer[65536];
            const ssize_t got = ::read(in_, buffer, sizeof buffer);
            if (got <= 0) throw Error("view: the browser closed its DevTools pipe (" + method + ")");
            pending_.append(buffer, static_cast<size_t>(got));
        }
    }

private:
    int out_, in_;
    int nextId_ = 1;
    std::string pending_;
};

struct Browser {
    pid_t pid = -1;
    int toBrowser = -1, fromBrowser = -1;
};

// The browser runs in its own process group, so stopping it stops its renderer and GPU
// processes too; its DevTools pipe is on its fds 3 and 4.
Browser startBrowser(const std::vector<std::string>& arguments) {
    int commands[2], answers[2];
    if (::pipe2(commands, O_CLOEXEC) != 0 || ::pipe2(answers, O_CLOEXEC) != 0)
        throw Error("view: cannot make the pipes to talk to " + arguments[0]);
    std::vector<char*> argv;
    for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) throw Error("view: cannot start " + arguments[0]);
    if (pid == 0) {
        ::setpgid(0, 0);
        const int null = ::open("/dev/null", O_RDWR);
        ::dup2(null, STDIN_FILENO);
        ::dup2(null, STDOUT_FILENO);
        ::dup2(null, STDERR_FILENO);
        ::dup2(commands[0], 3);
        ::dup2(answers[1], 4);
        ::execvp(argv[0], argv.data());
        ::_exit(127);
    }
    ::close(commands[0]);
    ::close(answers[1]);
    return {pid, commands[1], answers[0]};
}

// The browser's first tab, once it exists.
std::string pageTarget(DevTools& devTools) {
    for (int attempt = 0; attempt < 100; ++attempt) {
        const Json targets = devTools.call("Target.getTargets");
        for (const Json& target : targets.value("targetInfos", Json::array()))
            if (target.value("type", "") == "page") return target.value("targetId", "");
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw Error("view: the browser opened no page");
}

}  // namespace

std::string findChromium() {
    const char* path = std::getenv("PATH");
    std::istringstream folders(path ? path : "/usr/bin:/bin");
    std::string folder;
    std::vector<std::string> searched;
    while (std::getline(folders, folder, ':')) searched.push_back(folder);
    for (const char* name : {"chromium", "chromium-browser", "google-chrome"})
        for (const std::string& dir : searched) {
            const fs::path candidate = fs::path(dir) / name;
            if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
        }
    return "";
}

void captureInBrowser(ViewServer& server, const BrowserCapture& capture) {
    if (capture.chromium.empty())
        throw Error("view: no Chromium to render the page with (tools/install-deps.sh installs Debian's chromium)");
    std::ostringstream url;
    url << server.url() << "?capture" << (capture.wholePage ? "=page" : "") << "&scene=" << urlEscaped(capture.scene)
        << "&camera=" << capture.camera << "&mode=" << urlEscaped(capture.mode) << "&exposure=" << capture.exposureStops
        << "&width=" << capture.width << "&height=" << capture.height << (capture.threeMaterials ? "&material=three" : "");
    for (const std::string& sphere : capture.spheres) url << "&sphere=" << urlEscaped(sphere);
    char profileTemplate[] = "/tmp/voxlight-chromium-XXXXXX";
    if (!::mkdtemp(profileTemplate)) throw Error("view: cannot make a browser profile folder in /tmp");
    const std::string profile = profileTemplate;
    std::vector<std::string> arguments{capture.chromium,
                                       "--headless=new",
                                       "--remote-debugging-pipe",
                                       "--use-angle=swiftshader",
                                       "--enable-unsafe-swiftshader",
                                       "--user-data-dir=" + profile,
                                       "--no-first-run",
                                       "--no-default-browser-check",
                                       "--disable-extensions",
                                       "--disable-background-networking",
                                       "--hide-scrollbars",
                                       "--disable-dev-shm-usage",  // a container's /dev/shm is small or absent
                                       "--force-device-scale-factor=1"};
    // Chromium's sandbox refuses to run as root (CI and the fresh-machine check run as root).
    if (::geteuid() == 0) arguments.push_back("--no-sandbox");
    arguments.push_back("about:blank");
    const Browser browser = startBrowser(arguments);
    DevTools devTools(browser.toBrowser, browser.fromBrowser);
    // A browser that exits (a crash, a missing library) ends the wait at once.
    std::atomic<bool> browserExited{false};
    int browserStatus = 0;
    std::thread watcher([&] {
        ::waitpid(browser.pid, &browserStatus, 0);
        browserExited = true;
        server.stop();
    });
    // The server answers while the browser navigates: Page.navigate returns only once the
    // page's first response has arrived.
    std::atomic<bool> captured{false};
    std::exception_ptr failure, serving;
    std::thread serverThread([&] {
        try {
            captured = server.serve(capture.timeoutSeconds);
        } catch (...) {
            serving = std::current_exception();
        }
    });
    try {
        const std::string session =
            devTools.call("Target.attachToTarget", {{"targetId", pageTarget(devTools)}, {"flatten", true}})
                .value("sessionId", "");
        devTools.call("Emulation.setDeviceMetricsOverride",
                      {{"width", capture.width}, {"height", capture.height}, {"deviceScaleFactor", 1}, {"mobile", false}},
                      session);
        devTools.call("Page.navigate", {{"url", url.str()}}, session);
        serverThread.join();
        if (serving) std::rethrow_exception(serving);
        if (captured && capture.wholePage) {
            const std::string png =
                base64Decoded(devTools.call("Page.captureScreenshot", {{"format", "png"}}, session).value("data", ""));
            writeAtomically(server.captureFile().string(), [&](const std::string& temp) {
                std::ofstream out(temp, std::ios::binary);
                out.write(png.data(), static_cast<std::streamsize>(png.size()));
                if (!out) throw Error("view: cannot write " + server.captureFile().string());
            });
        }
    } catch (...) {
        failure = std::current_exception();
        server.stop();
        if (serverThread.joinable()) serverThread.join();
    }
    const bool exitedFirst = browserExited;
    ::kill(-browser.pid, SIGTERM);
    for (int i = 0; i < 50 && !browserExited; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (!browserExited) ::kill(-browser.pid, SIGKILL);
    watcher.join();
    ::kill(-browser.pid, SIGKILL);  // its helper processes, should any outlive it
    std::error_code ignored;
    fs::remove_all(profile, ignored);
    std::string messages;
    for (const std::string& message : server.pageMessages()) messages += "\n  page: " + message;
    if (failure) {
        try {
            std::rethrow_exception(failure);
        } catch (const Error& error) {
            throw Error(error.what() + messages);
        }
    }
    if (!captured) {
        std::ostringstream why;
        why << "view: the page did not render in " << capture.chromium << " (" << url.str() << "): "
            << (exitedFirst ? "the browser exited first (wait status " + std::to_string(browserStatus) + ")"
                            : "no capture within the time given");
        if (!exitedFirst) why << " (" << capture.timeoutSeconds << " s)";
        why << (messages.empty() ? "; the page reported nothing" : messages);
        throw Error(why.str());
    }
}

}  // namespace vl
