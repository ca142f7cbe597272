// glTF loader, accessors: each accessor's elements located in its buffer view (or zero-filled,
// or patched by sparse values), checked against their use, and read as floats or integers.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "internal.hpp"

namespace reprise::server::gltf_loader {

namespace {

// An accessor without a bufferView is zero-filled in memory; its count is otherwise unbounded.
constexpr uint64_t max_unbacked_count = uint64_t(1) << 24;

unsigned kind_of(int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return normalized ? 0 : F32;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return normalized ? 0 : U32;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? U8N : U8;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return normalized ? U16N : U16;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return normalized ? I8N : I8;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return normalized ? I16N : I16;
        default:
            return 0;
    }
}

size_t kind_size(unsigned kind) {
    if (kind & (F32 | U32)) return 4;
    if (kind & (U16 | I16 | U16N | I16N)) return 2;
    return 1;
}

std::string kind_name(unsigned kind) {
    switch (kind) {
        case F32:
            return "FLOAT";
        case U8:
            return "UNSIGNED_BYTE";
        case U16:
            return "UNSIGNED_SHORT";
        case U32:
            return "UNSIGNED_INT";
        case I8:
            return "BYTE";
        case I16:
            return "SHORT";
        case U8N:
            return "normalized UNSIGNED_BYTE";
        case U16N:
            return "normalized UNSIGNED_SHORT";
        case I8N:
            return "normalized BYTE";
        case I16N:
            return "normalized SHORT";
        default:
            return "?";
    }
}

std::string kind_list(unsigned kinds) {
    std::string list;
    for (unsigned bit = 1; bit & all_kinds; bit <<= 1) {
        if (!(kinds & bit)) continue;
        if (!list.empty()) list += ", ";
        list += kind_name(bit);
    }
    return list;
}

std::string describe_component(const tg::Accessor& a) {
    const unsigned kind = kind_of(a.componentType, a.normalized);
    if (kind) return kind_name(kind);
    return "componentType " + std::to_string(a.componentType) + (a.normalized ? " normalized" : "");
}

std::string type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return "SCALAR";
        case TINYGLTF_TYPE_VEC2:
            return "VEC2";
        case TINYGLTF_TYPE_VEC3:
            return "VEC3";
        case TINYGLTF_TYPE_VEC4:
            return "VEC4";
        case TINYGLTF_TYPE_MAT2:
            return "MAT2";
        case TINYGLTF_TYPE_MAT3:
            return "MAT3";
        case TINYGLTF_TYPE_MAT4:
            return "MAT4";
        default:
            return "type " + std::to_string(type);
    }
}

// An accessor's elements in memory: `count` elements of `components` values each, `stride`
// bytes apart. Zero-filled and sparse accessors are materialised in `storage`.
struct Elements {
    const uint8_t* data = nullptr;
    size_t stride = 0;
    size_t count = 0;
    size_t components = 0;
    unsigned kind = 0;
    std::vector<uint8_t> storage;
};

// Whether `count` elements of `element` bytes, `stride` apart from `offset`, end within
// `length` bytes, without overflowing.
bool span_fits(uint64_t offset, uint64_t count, uint64_t stride, uint64_t element,
               uint64_t length) {
    if (count == 0) return offset <= length;
    if (offset > length || element > length - offset) return false;
    return count - 1 <= (length - offset - element) / stride;
}

}  // namespace

Status check_buffer_views(const Gltf& g) {
    for (size_t i = 0; i < g.model.bufferViews.size(); ++i) {
        const tg::BufferView& view = g.model.bufferViews[i];
        const std::string field = item("bufferViews", i);
        REPRISE_TRY(
            check_index(g, field + ".buffer", view.buffer, g.model.buffers.size(), "buffers"));
        const size_t size = g.model.buffers[size_t(view.buffer)].data.size();
        if (!span_fits(view.byteOffset, 1, 1, view.byteLength, size))
            return g.fail(field, "byteOffset " + std::to_string(view.byteOffset) +
                                     " + byteLength " + std::to_string(view.byteLength) +
                                     " exceeds the " + std::to_string(size) + " bytes of buffers[" +
                                     std::to_string(view.buffer) + "]");
        if (view.byteStride != 0 &&
            (view.byteStride < 4 || view.byteStride > 252 || view.byteStride % 4))
            return g.fail(field + ".byteStride",
                          std::to_string(view.byteStride) + " is not a multiple of 4 in [4, 252]");
    }
    return ok();
}

namespace {

Status locate_in_view(const Gltf& g, const tg::Accessor& a, const std::string& name, size_t element,
                      Elements& out) {
    REPRISE_TRY(check_index(g, name + ".bufferView", a.bufferView, g.model.bufferViews.size(),
                            "bufferViews"));
    const tg::BufferView& view = g.model.bufferViews[size_t(a.bufferView)];
    const size_t stride = view.byteStride ? view.byteStride : element;
    if (stride < element)
        return g.fail(name, "elements of " + std::to_string(element) +
                                " bytes do not fit the byteStride " + std::to_string(stride) +
                                " of bufferViews[" + std::to_string(a.bufferView) + "]");
    if (!span_fits(a.byteOffset, a.count, stride, element, view.byteLength))
        return g.fail(name, "byteOffset " + std::to_string(a.byteOffset) + " + count " +
                                std::to_string(a.count) + " x stride " + std::to_string(stride) +
                                " exceeds the byteLength " + std::to_string(view.byteLength) +
                                " of bufferViews[" + std::to_string(a.bufferView) + "]");
    out.data = g.model.buffers[size_t(view.buffer)].data.data() + view.byteOffset + a.byteOffset;
    out.stride = stride;
    return ok();
}

Status zero_fill(const Gltf& g, const tg::Accessor& a, const std::string& name, size_t element,
                 Elements& out) {
    if (a.count > max_unbacked_count)
        return g.fail(name, "count " + std::to_string(a.count) +
                                " without a bufferView exceeds the limit of " +
                                std::to_string(max_unbacked_count));
    out.storage.assign(a.count * element, 0);
    out.data = out.storage.data();
    out.stride = element;
    return ok();
}

// Copies elements that live in a buffer into `storage`, so that sparse values can patch them.
void make_dense(Elements& e, size_t element) {
    if (e.data == e.storage.data()) return;
    e.storage.resize(e.count * element);
    for (size_t i = 0; i < e.count; ++i)
        std::memcpy(e.storage.data() + i * element, e.data + i * e.stride, element);
    e.data = e.storage.data();
    e.stride = element;
}

uint32_t component_uint(const uint8_t* p, unsigned kind) {
    if (kind == U8) return p[0];
    if (kind == U16) {
        uint16_t v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    uint32_t v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

Status sparse_span(const Gltf& g, const std::string& field, int view_index, int offset,
                   size_t count, size_t element, const uint8_t*& out) {
    REPRISE_TRY(check_index(g, field + ".bufferView", view_index, g.model.bufferViews.size(),
                            "bufferViews"));
    const tg::BufferView& view = g.model.bufferViews[size_t(view_index)];
    if (offset < 0 || !span_fits(uint64_t(offset), count, element, element, view.byteLength))
        return g.fail(field, "byteOffset " + std::to_string(offset) + " + " +
                                 std::to_string(count) + " x " + std::to_string(element) +
                                 " bytes exceeds the byteLength " +
                                 std::to_string(view.byteLength) + " of bufferViews[" +
                                 std::to_string(view_index) + "]");
    out = g.model.buffers[size_t(view.buffer)].data.data() + view.byteOffset + size_t(offset);
    return ok();
}

Status apply_sparse(const Gltf& g, const tg::Accessor& a, const std::string& name, size_t element,
                    Elements& out) {
    const auto& sparse = a.sparse;
    const std::string field = name + ".sparse";
    if (sparse.count < 1 || size_t(sparse.count) > a.count)
        return g.fail(field + ".count", std::to_string(sparse.count) +
                                            " is not in [1, accessor count " +
                                            std::to_string(a.count) + "]");
    const size_t n = size_t(sparse.count);
    const unsigned index_kind = kind_of(sparse.indices.componentType, false) & (U8 | U16 | U32);
    if (!index_kind)
        return g.fail(
            field + ".indices.componentType",
            std::to_string(sparse.indices.componentType) + " is not an unsigned integer type");
    const uint8_t* indices = nullptr;
    const uint8_t* values = nullptr;
    REPRISE_TRY(sparse_span(g, field + ".indices", sparse.indices.bufferView,
                            sparse.indices.byteOffset, n, kind_size(index_kind), indices));
    REPRISE_TRY(sparse_span(g, field + ".values", sparse.values.bufferView,
                            sparse.values.byteOffset, n, element, values));
    make_dense(out, element);
    uint32_t previous = 0;
    for (size_t k = 0; k < n; ++k) {
        const uint32_t index = component_uint(indices + k * kind_size(index_kind), index_kind);
        if (index >= a.count)
            return g.fail(field + ".indices", "index " + std::to_string(index) +
                                                  " >= accessor count " + std::to_string(a.count));
        if (k > 0 && index <= previous)
            return g.fail(field + ".indices",
                          "not strictly increasing at element " + std::to_string(k));
        std::memcpy(out.storage.data() + size_t(index) * element, values + k * element, element);
        previous = index;
    }
    return ok();
}

Status locate(const Gltf& g, int index, const Use& use, Elements& out) {
    REPRISE_TRY(check_index(g, use.field, index, g.model.accessors.size(), "accessors"));
    const tg::Accessor& a = g.model.accessors[size_t(index)];
    const std::string name = item("accessors", size_t(index));
    if (a.type != use.type)
        return g.fail(use.field, name + " has type " + type_name(a.type) + ", expected " +
                                     type_name(use.type));
    const unsigned kind = kind_of(a.componentType, a.normalized);
    if (!(kind & use.kinds))
        return g.fail(use.field, name + " has " + describe_component(a) + ", expected " +
                                     kind_list(use.kinds));
    if (a.count == 0) return g.fail(name, "count is 0");
    out.kind = kind;
    out.count = a.count;
    out.components = size_t(tg::GetNumComponentsInType(uint32_t(use.type)));
    const size_t element = kind_size(kind) * out.components;
    if (a.bufferView >= 0)
        REPRISE_TRY(locate_in_view(g, a, name, element, out));
    else
        REPRISE_TRY(zero_fill(g, a, name, element, out));
    if (a.sparse.isSparse) REPRISE_TRY(apply_sparse(g, a, name, element, out));
    return ok();
}

float component_float(const uint8_t* p, unsigned kind) {
    auto load = [p](auto v) {
        std::memcpy(&v, p, sizeof v);
        return v;
    };
    switch (kind) {
        case F32:
            return load(float{});
        case U8:
            return float(p[0]);
        case U16:
            return float(load(uint16_t{}));
        case U32:
            return float(load(uint32_t{}));
        case I8:
            return float(load(int8_t{}));
        case I16:
            return float(load(int16_t{}));
        case U8N:
            return float(p[0]) / 255.0f;
        case U16N:
            return float(load(uint16_t{})) / 65535.0f;
        case I8N:
            return std::max(float(load(int8_t{})) / 127.0f, -1.0f);
        case I16N:
            return std::max(float(load(int16_t{})) / 32767.0f, -1.0f);
        default:
            return 0.0f;
    }
}

}  // namespace

// All values of an accessor as floats, flattened; every value must be finite.
Status read_floats(const Gltf& g, int index, const Use& use, std::vector<float>& out) {
    Elements e;
    REPRISE_TRY(locate(g, index, use, e));
    const size_t size = kind_size(e.kind);
    out.resize(e.count * e.components);
    for (size_t i = 0; i < e.count; ++i) {
        for (size_t c = 0; c < e.components; ++c) {
            const float v = component_float(e.data + i * e.stride + c * size, e.kind);
            if (!std::isfinite(v))
                return g.fail(use.field, item("accessors", size_t(index)) + " element " +
                                             std::to_string(i) + " is not finite (" +
                                             std::to_string(v) + ")");
            out[i * e.components + c] = v;
        }
    }
    return ok();
}

Status read_uints(const Gltf& g, int index, const Use& use, std::vector<uint32_t>& out) {
    Elements e;
    REPRISE_TRY(locate(g, index, use, e));
    const size_t size = kind_size(e.kind);
    out.resize(e.count * e.components);
    for (size_t i = 0; i < e.count; ++i)
        for (size_t c = 0; c < e.components; ++c)
            out[i * e.components + c] = component_uint(e.data + i * e.stride + c * size, e.kind);
    return ok();
}

}  // namespace reprise::server::gltf_loader
