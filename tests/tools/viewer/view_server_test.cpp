// voxlight view's server (viewer/view_server.h): it answers on 127.0.0.1 only, to requests
// naming that host, and serves nothing outside the page's and the output's folders.
#include "viewer/view_server.h"

#include "core/error.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <fstream>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

using namespace vl;
namespace fs = std::filesystem;

namespace {

void writeFile(const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << text;
}

struct Reply {
    int status = 0;
    std::string head, body;
};

// One raw HTTP/1.1 exchange: the request goes out exactly as written (no client normalises
// the `..` away, as a browser would).
Reply httpExchange(uint16_t port, const std::string& request, in_addr_t address = htonl(INADDR_LOOPBACK)) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = address;
    Reply reply;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
        ::close(fd);
        return reply;  // status 0: refused
    }
    ::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    std::string data;
    char buffer[4096];
    for (ssize_t got; (got = ::recv(fd, buffer, sizeof buffer, 0)) > 0;) data.append(buffer, size_t(got));
    ::close(fd);
    const size_t end = data.find("\r\n\r\n");
    if (data.rfind("HTTP/1.1 ", 0) != 0 || end == std::string::npos) return reply;
    reply.status = std::stoi(data.substr(9, 3));
    reply.head = data.substr(0, end);
    reply.body = data.substr(end + 4);
    return reply;
}

Reply get(uint16_t port, const std::string& path, const std::string& host = "") {
    const std::string named = host.empty() ? "127.0.0.1:" + std::to_string(port) : host;
    return httpExchange(port, "GET " + path + " HTTP/1.1\r\nHost: " + named + "\r\n\r\n");
}

// A bake output (scene.glb, bake.json), a secret beside it and a link out of it, in a folder
// of the test's own (ctest runs the test cases side by side: one shared folder raced).
struct Site {
    fs::path root, output;
    explicit Site(const std::string& name) {
        root = test::tempDir("view-server-" + name);
        fs::remove_all(root);
        output = root / "output";
        writeFile(output / "scene.glb", "glTF-bytes");
        writeFile(output / "bake.json", "{}");
        writeFile(root / "secret.txt", "the secret content");
        fs::create_symlink(root / "secret.txt", output / "link.txt");
    }
};

}  // namespace

TEST_CASE("The viewer's file lookup refuses every path that leaves its folder", "[view]") {
    const Site site("lookup");
    CHECK(fileBelow(site.output, "/scene.glb") == fs::canonical(site.output / "scene.glb"));
    CHECK(fileBelow(site.output, "/./scene%2Eglb") == fs::canonical(site.output / "scene.glb"));
    CHECK(fileBelow(site.output, "//scene.glb"));
    for (const char* path : {"/../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt", "/x/../scene.glb",
                             "/..\\secret.txt", "/scene.glb%00.png", "/%zz", "/%2", "/link.txt", "/", "/missing"}) {
        INFO(path);
        CHECK_FALSE(fileBelow(site.output, path));
    }
}

TEST_CASE("The viewer finds the scenes of one bake or of a job's output", "[view]") {
    const fs::path root = test::tempDir("view-scenes");
    fs::remove_all(root);
    writeFile(root / "scene.glb", "x");
    writeFile(root / "b" / "scene.glb", "x");
    writeFile(root / "a" / "scene.glb", "x");
    writeFile(root / "a" / "inner" / "scene.glb", "x");
    writeFile(root / "a" / "inner" / "deeper" / "scene.glb", "x");  // three levels down: not looked for
    writeFile(root / "c" / "bake.json", "{}");
    CHECK(sceneFoldersBelow(root) == std::vector<std::string>{"", "a", "a/inner", "b"});
    CHECK(sceneFoldersBelow(root / "c").empty());
}

TEST_CASE("voxlight view's server answers on 127.0.0.1 only and serves nothing outside its folders", "[view]") {
    const Site site("server");
    ViewServerOptions options;
    options.outputFolder = site.output;
    options.pageFolder = test::sourceDir() + "/tools/viewer";
    ViewServer server(options);
    REQUIRE(server.port() != 0);
    CHECK(server.url() == "http://127.0.0.1:" + std::to_string(server.port()) + "/");
    CHECK(server.scenes() == std::vector<std::string>{""});
    std::thread serving([&] { server.serve(60.0); });
    const uint16_t port = server.port();

    const Reply page = get(port, "/");
    CHECK(page.status == 200);
    CHECK(page.head.find("Content-Type: text/html") != std::string::npos);
    CHECK(page.body.find("voxlight view") != std::string::npos);
    const Reply three = get(port, "/vendor/three/build/three.module.js");
    CHECK(three.status == 200);
    CHECK(three.head.find("Content-Type: text/javascript") != std::string::npos);
    const Reply glb = get(port, "/scene/scene.glb");
    CHECK(glb.status == 200);
    CHECK(glb.body == "glTF-bytes");
    CHECK(glb.head.find("Content-Type: model/gltf-binary") != std::string::npos);
    CHECK(get(port, "/scenes.json").body == "{\"scenes\": [\"\"]}\n");
    const Reply head = httpExchange(port, "HEAD /scene/bake.json HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n");
    CHECK(head.status == 200);
    CHECK(head.body.empty());

    // Out of the output folder, out of the page folder, through a link, by any spelling.
    for (const char* path : {"/scene/../secret.txt", "/scene/%2e%2e/secret.txt", "/scene/..%2fsecret.txt",
                             "/scene/link.txt", "/../../../../etc/passwd", "/%2e%2e/%2e%2e/CMakeLists.txt",
                             "/scene/../../../etc/passwd", "/..%5c..%5cCMakeLists.txt"}) {
        INFO(path);
        const Reply reply = get(port, path);
        CHECK(reply.status == 404);
        CHECK(reply.body.find("the secret content") == std::string::npos);
        CHECK(reply.body.find("root:") == std::string::npos);
    }
    // A name other than 127.0.0.1 (a page elsewhere reaching it through DNS rebinding).
    CHECK(get(port, "/scene/scene.glb", "evil.example:" + std::to_string(port)).status == 403);
    CHECK(get(port, "/scene/scene.glb", "localhost:" + std::to_string(port)).status == 200);
    // Without a capture file nothing takes a POST; other methods are refused.
    CHECK(httpExchange(port, "POST /capture HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                             "\r\nContent-Length: 3\r\n\r\nabc").status == 405);
    CHECK(httpExchange(port, "DELETE /scene/scene.glb HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n")
              .status == 405);
    CHECK(httpExchange(port, "GET scene.glb HTTP/1.1\r\n\r\n").status == 400);

    // Not reachable on this machine's other addresses.
    ifaddrs* interfaces = nullptr;
    size_t tried = 0;
    if (::getifaddrs(&interfaces) == 0) {
        for (ifaddrs* i = interfaces; i; i = i->ifa_next) {
            if (!i->ifa_addr || i->ifa_addr->sa_family != AF_INET) continue;
            const in_addr_t address = reinterpret_cast<sockaddr_in*>(i->ifa_addr)->sin_addr.s_addr;
            if ((ntohl(address) >> 24) == 127) continue;
            ++tried;
            INFO(i->ifa_name);
            CHECK(httpExchange(port, "GET / HTTP/1.1\r\n\r\n", address).status == 0);
        }
        ::freeifaddrs(interfaces);
    }
    if (tried == 0) WARN("no address besides loopback to try here");
    server.stop();
    serving.join();
}

TEST_CASE("voxlight view says what is wrong with its folder or port", "[view]") {
    const Site site("errors");
    ViewServerOptions options;
    options.pageFolder = test::sourceDir() + "/tools/viewer";
    options.outputFolder = site.root / "nowhere";
    CHECK_THROWS_WITH(ViewServer(options), Catch::Contains("nowhere: no such folder"));
    options.outputFolder = site.root / "empty";
    fs::create_directories(options.outputFolder);
    CHECK_THROWS_WITH(ViewServer(options), Catch::Contains("holds no scene.glb"));
    options.outputFolder = site.output;
    const ViewServer first(options);
    options.port = first.port();
    CHECK_THROWS_WITH(ViewServer(options),
                      Catch::Contains("cannot listen on 127.0.0.1:" + std::to_string(first.port())) &&
                          Catch::Contains("--port 0"));
}
