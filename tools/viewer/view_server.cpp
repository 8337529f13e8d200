#include "viewer/view_server.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <algorithm>
#include <arpa/inet.h>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <netinet/in.h>
#include <poll.h>
#include <sstream>
#include <sys/socket.h>
#include <sys/time.h>
#include <thread>
#include <unistd.h>

namespace vl {

namespace fs = std::filesystem;

namespace {

constexpr size_t kMaxHeaderBytes = 16 * 1024;
constexpr size_t kMaxCaptureBytes = 256u << 20;  // a 8192² RGBA PNG fits with room
constexpr int kReceiveTimeoutSeconds = 10;      // a connection that sends nothing is dropped

int hexValue(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

std::optional<std::string> percentDecoded(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (size_t i = 0; i < text.size(); ++i) {
        if (text[i] != '%') {
            out += text[i];
            continue;
        }
        if (i + 2 >= text.size()) return std::nullopt;
        const int high = hexValue(text[i + 1]), low = hexValue(text[i + 2]);
        if (high < 0 || low < 0) return std::nullopt;
        out += static_cast<char>(high * 16 + low);
        i += 2;
    }
    return out;
}

bool isBelow(const fs::path& path, const fs::path& root) {
    const auto [rootEnd, pathAt] = std::mismatch(root.begin(), root.end(), path.begin(), path.end());
    return rootEnd == root.end();
}

std::string contentType(const fs::path& file) {
    const std::string extension = file.extension().string();
    if (extension == ".html") return "text/html; charset=utf-8";
    if (extension == ".js" || extension == ".mjs") return "text/javascript; charset=utf-8";
    if (extension == ".css") return "text/css; charset=utf-8";
    if (extension == ".json") return "application/json";
    if (extension == ".glb") return "model/gltf-binary";
    if (extension == ".png") return "image/png";
    if (extension == ".jpg" || extension == ".jpeg") return "image/jpeg";
    return "application/octet-stream";
}

struct Request {
    std::string method;
    std::string path;  // %-escaped, without query or fragment
    std::string host;
    size_t contentLength = 0;
    std::string body;
};

void sendAll(int connection, std::string_view bytes) {
    while (!bytes.empty()) {
        const ssize_t sent = ::send(connection, bytes.data(), bytes.size(), MSG_NOSIGNAL);
        if (sent <= 0) return;  // the browser went away: nothing to tell it
        bytes.remove_prefix(static_cast<size_t>(sent));
    }
}

void respond(int connection, int status, std::string_view reason, const std::string& type, std::string_view body,
             bool headOnly = false) {
    std::ostringstream head;
    head << "HTTP/1.1 " << status << ' ' << reason << "\r\n"
         << "Content-Type: " << type << "\r\n"
         << "Content-Length: " << body.size() << "\r\n"
         << "Cache-Control: no-store\r\n"
         << "X-Content-Type-Options: nosniff\r\n"
         << "Connection: close\r\n\r\n";
    sendAll(connection, head.str());
    if (!headOnly) sendAll(connection, body);
}

void respondText(int connection, int status, std::string_view reason, const std::string& text) {
    respond(connection, status, reason, "text/plain; charset=utf-8", text + "\n");
}

// Reads the request head and, for a POST, its body. Nothing when the connection closes,
// times out or sends a head past kMaxHeaderBytes.
std::optional<Request> readRequest(int connection, size_t maxBody) {
    std::string data;
    char buffer[8192];
    size_t headEnd = std::string::npos;
    while ((headEnd = data.find("\r\n\r\n")) == std::string::npos) {
        if (data.size() > kMaxHeaderBytes) return std::nullopt;
        const ssize_t got = ::recv(connection, buffer, sizeof buffer, 0);
        if (got <= 0) return std::nullopt;
        data.append(buffer, static_cast<size_t>(got));
    }
    Request request;
    std::istringstream head(data.substr(0, headEnd));
    std::string line, target, version;
    std::getline(head, line);
    std::istringstream requestLine(line);
    requestLine >> request.method >> target >> version;
    if (target.empty() || target[0] != '/' || version.rfind("HTTP/1.", 0) != 0) return request;  // path empty: 400
    request.path = target.substr(0, target.find_first_of("?#"));
    while (std::getline(head, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string name = line.substr(0, colon);
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
        std::string value = line.substr(colon + 1);
        value.erase(0, value.find_first_not_of(" \t"));
        if (name == "host") request.host = value;
        if (name == "content-length") {
            try {
                request.contentLength = std::stoull(value);
            } catch (const std::exception&) {
                request.contentLength = maxBody + 1;
            }
        }
    }
    if (request.method != "POST") return request;
    if (request.contentLength > maxBody) return request;  // refused by the caller, body unread
    request.body = data.substr(headEnd + 4);
    while (request.body.size() < request.contentLength) {
        const ssize_t got = ::recv(connection, buffer, sizeof buffer, 0);
        if (got <= 0) return std::nullopt;
        request.body.append(buffer, static_cast<size_t>(got));
    }
    request.body.resize(request.contentLength);
    return request;
}

std::string jsonString(const std::string& text) {
    std::string out = "\"";
    for (const char c : text) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) continue;
        out += c;
    }
    return out + "\"";
}

}  // namespace

std::optional<fs::path> fileBelow(const fs::path& root, std::string_view urlPath) {
    const std::optional<std::string> decoded = percentDecoded(urlPath);
    if (!decoded || decoded->find('\0') != std::string::npos || decoded->find('\\') != std::string::npos)
        return std::nullopt;
    fs::path file = root;
    std::istringstream segments(*decoded);
    std::string segment;
    while (std::getline(segments, segment, '/')) {
        if (segment.empty() || segment == ".") continue;
        if (segment == "..") return std::nullopt;
        file /= segment;
    }
    std::error_code error;
    const fs::path realRoot = fs::canonical(root, error);
    if (error) return std::nullopt;
    const fs::path realFile = fs::canonical(file, error);
    if (error || !isBelow(realFile, realRoot) || !fs::is_regular_file(realFile, error)) return std::nullopt;
    return realFile;
}

std::vector<std::string> sceneFoldersBelow(const fs::path& folder) {
    std::vector<std::string> found;
    std::error_code error;
    if (fs::is_regular_file(folder / "scene.glb", error)) found.emplace_back();
    for (fs::recursive_directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
        if (it.depth() >= 1) it.disable_recursion_pending();
        if (it->is_directory(error) && fs::is_regular_file(it->path() / "scene.glb", error))
            found.push_back(fs::relative(it->path(), folder).generic_string());
    }
    std::sort(found.begin(), found.end());
    return found;
}

ViewServer::ViewServer(ViewServerOptions options) : options_(std::move(options)) {
    if (!fs::is_directory(options_.outputFolder))
        throw InputError("view: " + options_.outputFolder.string() + ": no such folder");
    if (!fs::is_regular_file(options_.pageFolder / "index.html"))
        throw Error("view: the viewer page is missing: " + (options_.pageFolder / "index.html").string());
    scenes_ = sceneFoldersBelow(options_.outputFolder);
    if (scenes_.empty())
        throw InputError("view: " + options_.outputFolder.string() +
                         " holds no scene.glb, nor do the folders in it (a bake writes one unless --gltf false)");
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (listener_ < 0) throw Error(std::string("view: cannot open a socket: ") + std::strerror(errno));
    const int yes = 1;
    ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(options_.port);
    if (::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(listener_, 64) != 0) {
        const std::string why = std::strerror(errno);
        ::close(listener_);
        throw Error("view: cannot listen on 127.0.0.1:" + std::to_string(options_.port) + ": " + why +
                    " (--port 0 takes any free port)");
    }
    socklen_t length = sizeof address;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);
}

ViewServer::~ViewServer() {
    if (listener_ >= 0) ::close(listener_);
}

std::string ViewServer::url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/"; }

std::vector<std::string> ViewServer::pageMessages() const {
    std::lock_guard lock(messagesMutex_);
    return messages_;
}

bool ViewServer::serve(double timeoutSeconds) {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeoutSeconds);
    // One detached thread a connection (a browser keeps several open); serve() returns once the
    // last has answered, so none outlives the server.
    std::atomic<int> open{0};
    while (!stopping_ && !captured_ && (timeoutSeconds <= 0.0 || Clock::now() < deadline)) {
        pollfd waiting{listener_, POLLIN, 0};
        if (::poll(&waiting, 1, 100) <= 0) continue;
        const int connection = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
        if (connection < 0) continue;
        const timeval receiveTimeout{kReceiveTimeoutSeconds, 0};
        ::setsockopt(connection, SOL_SOCKET, SO_RCVTIMEO, &receiveTimeout, sizeof receiveTimeout);
        ++open;
        std::thread([this, connection, &open] {
            answer(connection);
            ::close(connection);
            --open;
        }).detach();
    }
    while (open > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return captured_;
}

void ViewServer::answer(int connection) {
    const bool capturing = !options_.captureFile.empty();
    const std::optional<Request> request = readRequest(connection, capturing ? kMaxCaptureBytes : 0);
    if (!request) return;
    if (request->path.empty()) return respondText(connection, 400, "Bad Request", "malformed request");
    const std::string port = std::to_string(port_);
    if (request->host != "127.0.0.1:" + port && request->host != "localhost:" + port)
        return respondText(connection, 403, "Forbidden", "this server answers only http://127.0.0.1:" + port + "/");

    if (request->method == "POST") {
        if (!capturing || (request->path != "/capture" && request->path != "/ready" && request->path != "/log"))
            return respondText(connection, 405, "Method Not Allowed", "nothing here takes a POST");
        if (request->contentLength > kMaxCaptureBytes)
            return respondText(connection, 413, "Payload Too Large", "capture too large");
        if (request->path == "/log") {
            std::lock_guard lock(messagesMutex_);
            messages_.push_back(request->body);
            return respond(connection, 204, "No Content", "text/plain", "");
        }
        if (request->path == "/ready") {  // the page is drawn: the browser's driver takes the screenshot
            respond(connection, 204, "No Content", "text/plain", "");
            captured_ = true;
            return;
        }
        writeAtomically(options_.captureFile.string(), [&](const std::string& temp) {
            std::ofstream out(temp, std::ios::binary);
            out.write(request->body.data(), static_cast<std::streamsize>(request->body.size()));
            if (!out) throw Error("view: cannot write " + options_.captureFile.string());
        });
        respond(connection, 204, "No Content", "text/plain", "");
        captured_ = true;
        return;
    }
    if (request->method != "GET" && request->method != "HEAD")
        return respondText(connection, 405, "Method Not Allowed", "only GET and HEAD");
    const bool headOnly = request->method == "HEAD";

    if (request->path == "/scenes.json") {
        std::string body = "{\"scenes\": [";
        for (size_t i = 0; i < scenes_.size(); ++i) body += (i ? ", " : "") + jsonString(scenes_[i]);
        return respond(connection, 200, "OK", "application/json", body + "]}\n", headOnly);
    }
    constexpr std::string_view kScenePrefix = "/scene/";
    const bool inScene = request->path.rfind(kScenePrefix, 0) == 0;
    const std::string_view below = inScene ? std::string_view(request->path).substr(kScenePrefix.size())
                                           : std::string_view(request->path);
    const std::optional<fs::path> file =
        fileBelow(inScene ? options_.outputFolder : options_.pageFolder, below == "/" ? "index.html" : below);
    if (!file) return respondText(connection, 404, "Not Found", "not found: " + request->path);
    std::ifstream in(*file, std::ios::binary);
    std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) return respondText(connection, 500, "Internal Server Error", "cannot read " + request->path);
    respond(connection, 200, "OK", contentType(*file), body, headOnly);
}

}  // namespace vl
