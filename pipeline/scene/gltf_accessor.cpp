#include "scene/gltf_accessor.h"

#include "core/error.h"

#include <algorithm>
#include <cstring>

namespace vl::gltf {
namespace {

int componentSize(int componentType) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;  // INT and DOUBLE are not glTF 2.0 accessor types
    }
}

template <class T>
T load(const unsigned char* p) {
    T value;
    std::memcpy(&value, p, sizeof(T));
    return value;
}

// glTF 2.0 §3.11: normalized signed values map as max(c / (2^(b-1) - 1), -1).
float decodeFloat(const unsigned char* p, int componentType, bool normalized) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const float c = load<int8_t>(p);
        return normalized ? std::max(c / 127.0f, -1.0f) : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
        const float c = load<uint8_t>(p);
        return normalized ? c / 255.0f : c;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        const float c = load<int16_t>(p);
        return normalized ? std::max(c / 32767.0f, -1.0f) : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        const float c = load<uint16_t>(p);
        return normalized ? c / 65535.0f : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        const double c = load<uint32_t>(p);
        return static_cast<float>(normalized ? c / 4294967295.0 : c);
    }
    default: return load<float>(p);
    }
}

uint32_t decodeUint(const unsigned char* p, int componentType) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return load<uint8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return load<uint16_t>(p);
    default: return load<uint32_t>(p);
    }
}

// Where `count` elements of `elementSize` bytes, `stride` apart, start `offset` bytes into a
// range of `available` bytes: true when they all fit (without overflowing size_t).
bool fits(size_t offset, size_t count, size_t stride, size_t elementSize, size_t available) {
    if (offset > available) return false;
    if (count == 0) return true;
    const size_t room = available - offset;
    if (elementSize > room) return false;
    return (count - 1) <= (room - elementSize) / stride;
}

// An accessor resolved to bytes: base == nullptr means "no bufferView" (all zeros).
struct Layout {
    const unsigned char* base = nullptr;
    size_t stride = 0;
    size_t count = 0;
    int componentType = 0;
    int componentSize = 0;
    int components = 0;
    bool normalized = false;
};

std::string accessorName(const tinygltf::Model& model, int index) {
    std::string name = "accessor " + std::to_string(index);
    if (index >= 0 && static_cast<size_t>(index) < model.accessors.size() && !model.accessors[index].name.empty())
        name += " ('" + model.accessors[index].name + "')";
    return name;
}

Layout resolve(const tinygltf::Model& model, int index, const std::string& where) {
    const std::string what = where + ": " + accessorName(model, index);
    if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
        throw InputError(what + " does not exist (the file has " + std::to_string(model.accessors.size()) +
                         " accessors)");
    const tinygltf::Accessor& accessor = model.accessors[static_cast<size_t>(index)];

    Layout layout;
    layout.componentType = accessor.componentType;
    layout.componentSize = componentSize(accessor.componentType);
    layout.components = vectorComponents(accessor.type);
    layout.normalized = accessor.normalized;
    layout.count = accessor.count;
    if (layout.componentSize == 0)
        throw InputError(what + " has unsupported componentType " + std::to_string(accessor.componentType));
    if (layout.components == 0)
        throw InputError(what + " has type " + std::to_string(accessor.type) + ", not SCALAR or VEC2..VEC4");
    if (layout.count > kMaxAccessorCount)
        throw InputError(what + " has count " + std::to_string(layout.count) + ", more than the " +
                         std::to_string(kMaxAccessorCount) + " elements this loader accepts");

    const size_t elementSize = static_cast<size_t>(layout.componentSize) * layout.components;
    layout.stride = elementSize;
    if (accessor.bufferView < 0) {  // zeros (spec 3.6.2.4), possibly with sparse values
        // Not backed by file bytes, so only this bound keeps a hostile count from allocating gigabytes.
        if (layout.count > kMaxUnbackedAccessorCount)
            throw InputError(what + " has no bufferView and count " + std::to_string(layout.count) + ", more than the " +
                             std::to_string(kMaxUnbackedAccessorCount) + " zero elements this loader accepts");
        return layout;
    }

    const auto [bytes, length] = bufferViewBytes(model, accessor.bufferView, what);
    const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(accessor.bufferView)];
    if (view.byteStride != 0) {
        if (view.byteStride < elementSize)
            throw InputError(what + ": bufferView " + std::to_string(accessor.bufferView) + " byteStride " +
                             std::to_string(view.byteStride) + " is smaller than one element (" +
                             std::to_string(elementSize) + " bytes)");
        layout.stride = view.byteStride;
    }
    if (!fits(accessor.byteOffset, layout.count, layout.stride, elementSize, length))
        throw InputError(what + " (byteOffset " + std::to_string(accessor.byteOffset) + ", count " +
                         std::to_string(layout.count) + ", stride " + std::to_string(layout.stride) +
                         ") does not fit in bufferView " + std::to_string(accessor.bufferView) + " (" +
                         std::to_string(length) + " bytes)");
    layout.base = bytes + accessor.byteOffset;
    return layout;
}

// Calls store(element, component, bytePointer) for every component the accessor holds,
// the sparse substitutes after the dense values.
template <class Store>
void forEachComponent(const tinygltf::Model& model, int index, const Layout& layout, const std::string& where,
                      Store store) {
    if (layout.base)
        for (size_t i = 0; i < layout.count; ++i)
            for (int c = 0; c < layout.components; ++c)
                store(i, c, layout.base + i * layout.stride + static_cast<size_t>(c) * layout.componentSize);

    const tinygltf::Accessor& accessor = model.accessors[static_cast<size_t>(index)];
    if (!accessor.sparse.isSparse) return;
    const std::string what = where + ": " + accessorName(model, index) + " sparse";
    const auto& sparse = accessor.sparse;
    if (sparse.count < 1 || static_cast<size_t>(sparse.count) > layout.count)
        throw InputError(what + " count " + std::to_string(sparse.count) + " is not in [1, " +
                         std::to_string(layout.count) + "]");
    const size_t count = static_cast<size_t>(sparse.count);

    const int indexType = sparse.indices.componentType;
    const int indexSize = componentSize(indexType);
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        throw InputError(what + " indices have componentType " + std::to_string(indexType) +
                         ", not an unsigned integer type");
    const auto [indexBytes, indexLength] = bufferViewBytes(model, sparse.indices.bufferView, what + " indices");
    if (sparse.indices.byteOffset < 0 ||
        !fits(static_cast<size_t>(sparse.indices.byteOffset), count, indexSize, indexSize, indexLength))
        throw InputError(what + " indices (byteOffset " + std::to_string(sparse.indices.byteOffset) +
                         ") do not fit in bufferView " + std::to_string(sparse.indices.bufferView));

    const size_t elementSize = static_cast<size_t>(layout.componentSize) * layout.components;
    const auto [valueBytes, valueLength] = bufferViewBytes(model, sparse.values.bufferView, what + " values");
    if (sparse.values.byteOffset < 0 ||
        !fits(static_cast<size_t>(sparse.values.byteOffset), count, elementSize, elementSize, valueLength))
        throw InputError(what + " values (byteOffset " + std::to_string(sparse.values.byteOffset) +
                         ") do not fit in bufferView " + std::to_string(sparse.values.bufferView));

    const unsigned char* indices = indexBytes + sparse.indices.byteOffset;
    const unsigned char* values = valueBytes + sparse.values.byteOffset;
    for (size_t k = 0; k < count; ++k) {
        const uint32_t target = decodeUint(indices + k * indexSize, indexType);
        if (target >= layout.count)
            throw InputError(what + " index " + std::to_string(target) + " (entry " + std::to_string(k) +
                             ") is out of range: the accessor has " + std::to_string(layout.count) + " elements");
        for (int c = 0; c < layout.components; ++c)
            store(target, c, values + k * elementSize + static_cast<size_t>(c) * layout.componentSize);
    }
}

}  // namespace

int vectorComponents(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;
    }
}

std::pair<const unsigned char*, size_t> bufferViewBytes(const tinygltf::Model& model, int view,
                                                        const std::string& where) {
    const std::string what = where + ": bufferView " + std::to_string(view);
    if (view < 0 || static_cast<size_t>(view) >= model.bufferViews.size())
        throw InputError(what + " does not exist (the file has " + std::to_string(model.bufferViews.size()) +
                         " buffer views)");
    const tinygltf::BufferView& bufferView = model.bufferViews[static_cast<size_t>(view)];
    const int buffer = bufferView.buffer;
    if (buffer < 0 || static_cast<size_t>(buffer) >= model.buffers.size())
        throw InputError(what + " refers to buffer " + std::to_string(buffer) + ", which does not exist");
    const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(buffer)].data;
    const std::string& uri = model.buffers[static_cast<size_t>(buffer)].uri;
    const std::string bufferName = "buffer " + std::to_string(buffer) + (uri.empty() || uri.rfind("data:", 0) == 0
                                                                             ? std::string()
                                                                             : " ('" + uri + "')");
    if (data.empty() && bufferView.byteLength > 0)
        throw InputError(what + ": " + bufferName + " is missing or empty");
    if (!fits(bufferView.byteOffset, 1, 1, bufferView.byteLength, data.size()))
        throw InputError(what + " (byteOffset " + std::to_string(bufferView.byteOffset) + ", byteLength " +
                         std::to_string(bufferView.byteLength) + ") lies outside " + bufferName + " (" +
                         std::to_string(data.size()) + " bytes)");
    return {data.data() + bufferView.byteOffset, bufferView.byteLength};
}

FloatArray readFloatAccessor(const tinygltf::Model& model, int accessor, std::initializer_list<int> allowedComponents,
                             const std::string& where) {
    const Layout layout = resolve(model, accessor, where);
    if (std::find(allowedComponents.begin(), allowedComponents.end(), layout.components) == allowedComponents.end())
        throw InputError(where + ": " + accessorName(model, accessor) + " has " + std::to_string(layout.components) +
                         " components per element, which this attribute cannot use");
    FloatArray out;
    out.count = layout.count;
    out.components = layout.components;
    out.values.assign(layout.count * layout.components, 0.0f);
    forEachComponent(model, accessor, layout, where, [&](size_t i, int c, const unsigned char* p) {
        out.values[i * layout.components + c] = decodeFloat(p, layout.componentType, layout.normalized);
    });
    return out;
}

std::vector<uint32_t> readIndexAccessor(const tinygltf::Model& model, int accessor, const std::string& where) {
    const Layout layout = resolve(model, accessor, where);
    const std::string what = where + ": index " + accessorName(model, accessor);
    if (layout.components != 1) throw InputError(what + " is not SCALAR");
    if (layout.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        layout.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        layout.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        throw InputError(what + " has componentType " + std::to_string(layout.componentType) +
                         ", not an unsigned integer type");
    std::vector<uint32_t> out(layout.count, 0u);
    forEachComponent(model, accessor, layout, where,
                     [&](size_t i, int, const unsigned char* p) { out[i] = decodeUint(p, layout.componentType); });
    return out;
}

}  // namespace vl::gltf
