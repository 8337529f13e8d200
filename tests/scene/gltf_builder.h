// Small glTF files for loader tests: binary data goes into one buffer, buffer views and
// accessors are declared from C++, the rest of the JSON (meshes, nodes, materials...) is
// written out as text by the test, so each test reads as the file it loads.
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace vl::test {

enum ComponentType : int {
    kByte = 5120,
    kUnsignedByte = 5121,
    kShort = 5122,
    kUnsignedShort = 5123,
    kUnsignedInt = 5125,
    kFloat = 5126,
};

inline std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t b0 = bytes[i];
        const uint32_t b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0u;
        const uint32_t b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0u;
        const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
        out += digits[(triple >> 18) & 63];
        out += digits[(triple >> 12) & 63];
        out += i + 1 < bytes.size() ? digits[(triple >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? digits[triple & 63] : '=';
    }
    return out;
}

inline std::vector<unsigned char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline std::string writeText(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

class GltfBuilder {
public:
    std::string asset = R"("asset": {"version": "2.0"})";

    // Appends bytes as a new buffer view (4-byte aligned); returns the view index.
    int view(const void* data, size_t bytes, size_t stride = 0) {
        while (bin_.size() % 4) bin_.push_back(0);
        const size_t offset = bin_.size();
        bin_.insert(bin_.end(), static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + bytes);
        std::string json = R"({"buffer": 0, "byteOffset": )" + std::to_string(offset) +
                           R"(, "byteLength": )" + std::to_string(bytes);
        if (stride) json += R"(, "byteStride": )" + std::to_string(stride);
        views_.push_back(json + "}");
        return static_cast<int>(views_.size()) - 1;
    }
    template <class T>
    int view(const std::vector<T>& values, size_t stride = 0) {
        return view(values.data(), values.size() * sizeof(T), stride);
    }
    // A buffer view written verbatim (for malformed ones).
    int rawView(const std::string& json) {
        views_.push_back(json);
        return static_cast<int>(views_.size()) - 1;
    }

    // `view` < 0: no bufferView. `extra`: further JSON members, e.g. R"("normalized": true)".
    int accessor(int view, int componentType, size_t count, const std::string& type, const std::string& extra = "",
                 size_t byteOffset = 0) {
        std::string json = "{";
        if (view >= 0) json += R"("bufferView": )" + std::to_string(view) + ", ";
        if (byteOffset) json += R"("byteOffset": )" + std::to_string(byteOffset) + ", ";
        json += R"("componentType": )" + std::to_string(componentType) + R"(, "count": )" + std::to_string(count) +
                R"(, "type": ")" + type + "\"";
        if (!extra.empty()) json += ", " + extra;
        accessors_.push_back(json + "}");
        return static_cast<int>(accessors_.size()) - 1;
    }

    int floats(const std::vector<float>& values, int components, const char* type) {
        return accessor(view(values), kFloat, values.size() / components, type);
    }
    int vec3(const std::vector<float>& xyz) { return floats(xyz, 3, "VEC3"); }
    int vec2(const std::vector<float>& uv) { return floats(uv, 2, "VEC2"); }
    int indices(const std::vector<uint16_t>& values) {
        return accessor(view(values), kUnsignedShort, values.size(), "SCALAR");
    }

    const std::vector<unsigned char>& bin() const { return bin_; }

    // The whole JSON; `bufferUri` empty = no uri (GLB's BIN chunk).
    std::string json(const std::string& members, const std::string& bufferUri) const {
        std::string out = "{" + asset;
        if (!bin_.empty()) {
            out += R"(, "buffers": [{"byteLength": )" + std::to_string(bin_.size());
            if (!bufferUri.empty()) out += R"(, "uri": ")" + bufferUri + "\"";
            out += "}]";
        }
        out += list("bufferViews", views_) + list("accessors", accessors_);
        if (!members.empty()) out += ", " + members;
        return out + "}";
    }

    // <dir>/<name>.gltf with its buffer in <name>.bin (or embedded as a data: URI).
    std::string writeGltf(const std::string& dir, const std::string& name, const std::string& members,
                          bool embedBuffer = false) const {
        const std::string uri = embedBuffer ? "data:application/octet-stream;base64," + base64(bin_) : name + ".bin";
        if (!embedBuffer) std::ofstream(dir + "/" + name + ".bin", std::ios::binary)
                              .write(reinterpret_cast<const char*>(bin_.data()), static_cast<std::streamsize>(bin_.size()));
        return writeText(dir + "/" + name + ".gltf", json(members, uri));
    }

    // <dir>/<name>.glb: header, JSON chunk (space padded), BIN chunk (zero padded).
    std::string writeGlb(const std::string& dir, const std::string& name, const std::string& members) const {
        std::string text = json(members, "");
        while (text.size() % 4) text += ' ';
        std::vector<unsigned char> bin = bin_;
        while (bin.size() % 4) bin.push_back(0);
        std::vector<unsigned char> out;
        const auto u32 = [&](uint32_t v) {
            unsigned char b[4];
            std::memcpy(b, &v, 4);
            out.insert(out.end(), b, b + 4);
        };
        const uint32_t total = 12 + 8 + static_cast<uint32_t>(text.size()) + (bin.empty() ? 0 : 8 + static_cast<uint32_t>(bin.size()));
        out.insert(out.end(), {'g', 'l', 'T', 'F'});
        u32(2);
        u32(total);
        u32(static_cast<uint32_t>(text.size()));
        u32(0x4E4F534Au);  // JSON
        out.insert(out.end(), text.begin(), text.end());
        if (!bin.empty()) {
            u32(static_cast<uint32_t>(bin.size()));
            u32(0x004E4942u);  // BIN
            out.insert(out.end(), bin.begin(), bin.end());
        }
        const std::string path = dir + "/" + name + ".glb";
        std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
        return path;
    }

private:
    static std::string list(const char* key, const std::vector<std::string>& items) {
        if (items.empty()) return "";
        std::string out = std::string(", \"") + key + "\": [";
        for (size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
        return out + "]";
    }

    std::vector<unsigned char> bin_;
    std::vector<std::string> views_;
    std::vector<std::string> accessors_;
};

// A unit quad in the XY plane facing +Z: (0,0) (1,0) (1,1) (0,1), two CCW triangles.
struct QuadAccessors {
    int position, normal, uv, indices;
};
inline QuadAccessors addQuad(GltfBuilder& b) {
    QuadAccessors q;
    q.position = b.vec3({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    q.normal = b.vec3({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
    q.uv = b.vec2({0, 1, 1, 1, 1, 0, 0, 0});
    q.indices = b.indices({0, 1, 2, 0, 2, 3});
    return q;
}
inline std::string quadMesh(const QuadAccessors& q, const std::string& extra = "") {
    return R"({"name": "Quad", "primitives": [{"attributes": {"POSITION": )" + std::to_string(q.position) +
           R"(, "NORMAL": )" + std::to_string(q.normal) + R"(, "TEXCOORD_0": )" + std::to_string(q.uv) +
           R"(}, "indices": )" + std::to_string(q.indices) + extra + "}]}";
}

}  // namespace vl::test
