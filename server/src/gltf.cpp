// glTF 2.0 into a Scene. tinygltf parses the JSON, the buffers and the images; it leaves
// ranges, types, finiteness and the node graph unchecked, so everything the renderer uses is
// validated here, and the Scene is only written once the whole file has passed.
#include "reprise/server/gltf.hpp"

#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <numbers>
#include <numeric>
#include <span>
#include <string_view>

namespace reprise::server {
namespace {

namespace tg = tinygltf;

// tinygltf takes lengths as 32-bit unsigned integers.
constexpr uint64_t max_file_bytes = std::numeric_limits<uint32_t>::max();
// An accessor without a bufferView is zero-filled in memory; its count is otherwise unbounded.
constexpr uint64_t max_unbacked_count = uint64_t(1) << 24;

constexpr std::string_view supported_required_extensions[] = {"KHR_mesh_quantization"};

std::string item(std::string_view array, size_t index) {
    return std::string(array) + "[" + std::to_string(index) + "]";
}

std::string count_of(size_t n, std::string_view what) {
    return std::to_string(n) + " " + std::string(what);
}

// The loaded model and the file name every message starts with.
struct Gltf {
    std::string file;
    const tg::Model& model;
    std::string warnings;    // tinygltf's, quoted when an image failed to load
    bool quantized = false;  // KHR_mesh_quantization widens the allowed attribute types

    Status fail(const std::string& field, const std::string& problem) const {
        return Status::error(file + ": " + field + ": " + problem);
    }
};

Status check_index(const Gltf& g, const std::string& field, int index, size_t size,
                   std::string_view array) {
    if (index >= 0 && size_t(index) < size) return ok();
    return g.fail(
        field, "index " + std::to_string(index) + " out of range (" + count_of(size, array) + ")");
}

// ---------------------------------------------------------------------------------------------
// Accessors

// An accessor's component type together with its `normalized` flag, as one bit.
constexpr unsigned F32 = 1u << 0;
constexpr unsigned U8 = 1u << 1;
constexpr unsigned U16 = 1u << 2;
constexpr unsigned U32 = 1u << 3;
constexpr unsigned I8 = 1u << 4;
constexpr unsigned I16 = 1u << 5;
constexpr unsigned U8N = 1u << 6;
constexpr unsigned U16N = 1u << 7;
constexpr unsigned I8N = 1u << 8;
constexpr unsigned I16N = 1u << 9;
constexpr unsigned all_kinds = (1u << 10) - 1;

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

// How an accessor is used: where (for messages), with which type and component kinds.
struct Use {
    std::string field;
    int type = TINYGLTF_TYPE_SCALAR;
    unsigned kinds = F32;
};

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

template <class V>
std::vector<V> group(const std::vector<float>& flat) {
    static_assert(sizeof(V) % sizeof(float) == 0);
    std::vector<V> out(flat.size() * sizeof(float) / sizeof(V));
    std::memcpy(static_cast<void*>(out.data()), flat.data(), out.size() * sizeof(V));
    return out;
}

template <class V>
Status read_vectors(const Gltf& g, int index, const Use& use, std::vector<V>& out) {
    REPRISE_ASSERT(size_t(tg::GetNumComponentsInType(uint32_t(use.type))) * sizeof(float) ==
                   sizeof(V));
    std::vector<float> flat;
    REPRISE_TRY(read_floats(g, index, use, flat));
    out = group<V>(flat);
    return ok();
}

// ---------------------------------------------------------------------------------------------
// Attribute rules (glTF 2.0 §3.7.2.1, widened by KHR_mesh_quantization)

unsigned position_kinds(const Gltf& g) {
    return F32 | (g.quantized ? I8 | I8N | U8 | U8N | I16 | I16N | U16 | U16N : 0);
}
unsigned normal_kinds(const Gltf& g) {
    return F32 | (g.quantized ? I8N | I16N : 0);
}
unsigned texcoord_kinds(const Gltf& g) {
    return F32 | U8N | U16N | (g.quantized ? I8 | I8N | U8 | I16 | I16N | U16 : 0);
}
unsigned target_kinds(const Gltf& g) {
    return F32 | (g.quantized ? I8 | I8N | I16 | I16N : 0);
}

int attribute(const std::map<std::string, int>& attributes, const std::string& name) {
    const auto it = attributes.find(name);
    return it == attributes.end() ? -1 : it->second;
}

Status check_count(const Gltf& g, const std::string& field, size_t count, size_t vertices) {
    if (count == vertices) return ok();
    return g.fail(field, "count " + std::to_string(count) + " differs from the POSITION count " +
                             std::to_string(vertices));
}

// Unit normals; false when one cannot be normalised (zero length).
bool normalize_all(std::vector<glm::vec3>& normals) {
    for (glm::vec3& n : normals) {
        const float length = glm::length(n);
        if (!(length > 1e-12f) || !std::isfinite(length)) return false;
        n /= length;
    }
    return true;
}

// ---------------------------------------------------------------------------------------------
// Textures and materials

Status expand_to_rgba(const Gltf& g, size_t index, const tg::Image& image, Texture& out) {
    const std::string field = item("images", index);
    if (image.image.empty() || image.width < 1 || image.height < 1) {
        std::string problem = "could not be loaded or decoded";
        if (!g.warnings.empty()) problem += " (" + g.warnings + ")";
        return g.fail(field, problem);
    }
    if ((image.bits != 8 && image.bits != 16) || image.component < 1 || image.component > 4)
        return g.fail(field, "decoded to " + std::to_string(image.component) + " components of " +
                                 std::to_string(image.bits) + " bits, expected 1 to 4 of 8 or 16");
    const size_t pixels = size_t(image.width) * size_t(image.height);
    const size_t channels = size_t(image.component);
    const size_t bytes = size_t(image.bits / 8);
    if (image.image.size() != pixels * channels * bytes)
        return g.fail(field, "decoded data has " + std::to_string(image.image.size()) +
                                 " bytes, expected " + std::to_string(pixels * channels * bytes));
    auto channel = [&](size_t p, size_t c) -> uint8_t {
        const uint8_t* v = image.image.data() + (p * channels + c) * bytes;
        if (bytes == 1) return v[0];
        uint16_t wide;
        std::memcpy(&wide, v, sizeof wide);
        return uint8_t((unsigned(wide) + 128u) / 257u);
    };
    out.width = image.width;
    out.height = image.height;
    out.pixels.resize(pixels);
    for (size_t p = 0; p < pixels; ++p) {
        const uint8_t first = channel(p, 0);
        switch (channels) {
            case 1:
                out.pixels[p] = {first, first, first, 255};
                break;
            case 2:
                out.pixels[p] = {first, first, first, channel(p, 1)};
                break;
            case 3:
                out.pixels[p] = {first, channel(p, 1), channel(p, 2), 255};
                break;
            default:
                out.pixels[p] = {first, channel(p, 1), channel(p, 2), channel(p, 3)};
                break;
        }
    }
    return ok();
}

void apply_sampler(const tg::Sampler& sampler, Texture& out) {
    out.repeat = sampler.wrapS != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE &&
                 sampler.wrapT != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    out.nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
}

// Scene textures are only the ones materials use; `remap` maps glTF texture indices to them.
struct TextureTable {
    std::vector<Texture> textures;
    std::vector<int> remap;
};

Status convert_texture(const Gltf& g, const std::string& field, int index, TextureTable& table,
                       int& out) {
    REPRISE_TRY(check_index(g, field, index, g.model.textures.size(), "textures"));
    const size_t t = size_t(index);
    if (table.remap[t] >= 0) {
        out = table.remap[t];
        return ok();
    }
    const tg::Texture& texture = g.model.textures[t];
    const std::string name = item("textures", t);
    out = -1;
    if (texture.source < 0) return ok();  // no image reprise can decode: untextured
    REPRISE_TRY(check_index(g, name + ".source", texture.source, g.model.images.size(), "images"));
    Texture converted;
    REPRISE_TRY(expand_to_rgba(g, size_t(texture.source), g.model.images[size_t(texture.source)],
                               converted));
    if (texture.sampler >= 0) {
        REPRISE_TRY(check_index(g, name + ".sampler", texture.sampler, g.model.samplers.size(),
                                "samplers"));
        apply_sampler(g.model.samplers[size_t(texture.sampler)], converted);
    }
    out = table.remap[t] = int(table.textures.size());
    table.textures.push_back(std::move(converted));
    return ok();
}

// Roughness to a Blinn-Phong lobe of similar width (Walter et al.'s alpha = roughness^2).
void apply_roughness(float roughness, Material& out) {
    const float r = std::clamp(roughness, 0.01f, 1.0f);
    out.specular = 0.04f + 0.5f * (1.0f - r);
    out.shininess = std::clamp(2.0f / (r * r * r * r) - 2.0f, 2.0f, 512.0f);
}

Status convert_material(const Gltf& g, size_t index, TextureTable& table, Material& out) {
    const tg::Material& material = g.model.materials[index];
    const tg::PbrMetallicRoughness& pbr = material.pbrMetallicRoughness;
    const std::string field = item("materials", index) + ".pbrMetallicRoughness";
    if (pbr.baseColorFactor.size() != 4)
        return g.fail(field + ".baseColorFactor",
                      "has " + std::to_string(pbr.baseColorFactor.size()) + " values, expected 4");
    for (size_t c = 0; c < 4; ++c) {
        if (!std::isfinite(pbr.baseColorFactor[c]))
            return g.fail(field + ".baseColorFactor", "is not finite");
        out.base_color[int(c)] = std::clamp(float(pbr.baseColorFactor[c]), 0.0f, 1.0f);
    }
    if (!std::isfinite(pbr.roughnessFactor))
        return g.fail(field + ".roughnessFactor", "is not finite");
    apply_roughness(float(pbr.roughnessFactor), out);
    const tg::TextureInfo& info = pbr.baseColorTexture;
    if (info.index >= 0) {
        if (info.texCoord != 0 && info.texCoord != 1)
            return g.fail(
                field + ".baseColorTexture.texCoord",
                std::to_string(info.texCoord) + " (only TEXCOORD_0 and TEXCOORD_1 are supported)");
        REPRISE_TRY(convert_texture(g, field + ".baseColorTexture.index", info.index, table,
                                    out.base_color_texture));
        out.texcoord = info.texCoord;
    }
    out.double_sided = material.doubleSided;
    return ok();
}

// ---------------------------------------------------------------------------------------------
// Meshes

enum class Topology { Triangles, Strip, Fan, Unsupported };

Status topology_of(const Gltf& g, const std::string& field, int mode, Topology& out) {
    switch (mode) {
        case TINYGLTF_MODE_TRIANGLES:
            out = Topology::Triangles;
            return ok();
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            out = Topology::Strip;
            return ok();
        case TINYGLTF_MODE_TRIANGLE_FAN:
            out = Topology::Fan;
            return ok();
        case TINYGLTF_MODE_POINTS:
        case TINYGLTF_MODE_LINE:
        case TINYGLTF_MODE_LINE_LOOP:
        case TINYGLTF_MODE_LINE_STRIP:
            out = Topology::Unsupported;
            return ok();
        default:
            return g.fail(field + ".mode", std::to_string(mode) + " is not a glTF primitive mode");
    }
}

// Strips and fans into a triangle list, in the winding order glTF 2.0 §3.7.2.1 defines.
std::vector<uint32_t> to_triangle_list(const std::vector<uint32_t>& v, Topology topology) {
    if (topology == Topology::Triangles) return v;
    std::vector<uint32_t> list;
    if (v.size() < 3) return list;
    list.reserve((v.size() - 2) * 3);
    for (size_t i = 0; i + 2 < v.size(); ++i) {
        if (topology == Topology::Strip && i % 2 == 0)
            list.insert(list.end(), {v[i], v[i + 1], v[i + 2]});
        if (topology == Topology::Strip && i % 2 == 1)
            list.insert(list.end(), {v[i], v[i + 2], v[i + 1]});
        if (topology == Topology::Fan) list.insert(list.end(), {v[i + 1], v[i + 2], v[0]});
    }
    return list;
}

Status read_indices(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, Topology topology, std::vector<uint32_t>& out) {
    std::vector<uint32_t> raw;
    if (p.indices >= 0) {
        REPRISE_TRY(read_uints(g, p.indices,
                               {field + ".indices", TINYGLTF_TYPE_SCALAR, U8 | U16 | U32}, raw));
        for (const uint32_t index : raw)
            if (index >= vertices)
                return g.fail(field + ".indices", "index " + std::to_string(index) +
                                                      " >= vertex count " +
                                                      std::to_string(vertices));
    } else {
        raw.resize(vertices);
        std::iota(raw.begin(), raw.end(), 0u);
    }
    if (topology == Topology::Triangles && raw.size() % 3 != 0)
        return g.fail(p.indices >= 0 ? field + ".indices" : field + ".attributes.POSITION",
                      std::to_string(raw.size()) + " vertices do not make whole TRIANGLES");
    out = to_triangle_list(raw, topology);
    return ok();
}

Status read_normals(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, std::vector<glm::vec3>& out) {
    const int index = attribute(p.attributes, "NORMAL");
    if (index < 0) return ok();
    const std::string name = field + ".attributes.NORMAL";
    REPRISE_TRY(read_vectors(g, index, {name, TINYGLTF_TYPE_VEC3, normal_kinds(g)}, out));
    REPRISE_TRY(check_count(g, name, out.size(), vertices));
    if (!normalize_all(out)) out.clear();  // zero normals: the renderer computes flat ones
    return ok();
}

Status read_texcoords(const Gltf& g, const tg::Primitive& p, const std::string& field,
                      size_t vertices, int set, std::vector<glm::vec2>& out) {
    const std::string attr = "TEXCOORD_" + std::to_string(set);
    const int index = attribute(p.attributes, attr);
    if (index < 0) return ok();
    const std::string name = field + ".attributes." + attr;
    REPRISE_TRY(read_vectors(g, index, {name, TINYGLTF_TYPE_VEC2, texcoord_kinds(g)}, out));
    return check_count(g, name, out.size(), vertices);
}

Status normalize_weights(const Gltf& g, const std::string& field, std::vector<glm::vec4>& weights) {
    for (size_t i = 0; i < weights.size(); ++i) {
        glm::vec4& w = weights[i];
        const float sum = w.x + w.y + w.z + w.w;
        if (w.x < 0 || w.y < 0 || w.z < 0 || w.w < 0 || !(sum > 0.0f))
            return g.fail(field, "vertex " + std::to_string(i) +
                                     " has negative weights or weights that sum to 0");
        w /= sum;
    }
    return ok();
}

Status read_skinning(const Gltf& g, const tg::Primitive& p, const std::string& field,
                     size_t vertices, Primitive& out) {
    const int joints = attribute(p.attributes, "JOINTS_0");
    const int weights = attribute(p.attributes, "WEIGHTS_0");
    if (joints < 0 && weights < 0) return ok();
    if (joints < 0 || weights < 0)
        return g.fail(field + ".attributes", "JOINTS_0 and WEIGHTS_0 must come together");
    const std::string joints_name = field + ".attributes.JOINTS_0";
    const std::string weights_name = field + ".attributes.WEIGHTS_0";
    std::vector<uint32_t> flat;
    REPRISE_TRY(read_uints(g, joints, {joints_name, TINYGLTF_TYPE_VEC4, U8 | U16}, flat));
    REPRISE_TRY(check_count(g, joints_name, flat.size() / 4, vertices));
    out.joints.resize(vertices);
    for (size_t i = 0; i < vertices; ++i)
        out.joints[i] =
            glm::u16vec4(flat[4 * i], flat[4 * i + 1], flat[4 * i + 2], flat[4 * i + 3]);
    REPRISE_TRY(read_vectors(g, weights, {weights_name, TINYGLTF_TYPE_VEC4, F32 | U8N | U16N},
                             out.weights));
    REPRISE_TRY(check_count(g, weights_name, out.weights.size(), vertices));
    return normalize_weights(g, weights_name, out.weights);
}

Status read_targets(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, bool keep_normals, std::vector<MorphTarget>& out) {
    out.resize(p.targets.size());
    for (size_t t = 0; t < p.targets.size(); ++t) {
        const std::string name = field + "." + item("targets", t);
        const int positions = attribute(p.targets[t], "POSITION");
        const int normals = attribute(p.targets[t], "NORMAL");
        if (positions >= 0) {
            REPRISE_TRY(read_vectors(g, positions,
                                     {name + ".POSITION", TINYGLTF_TYPE_VEC3, target_kinds(g)},
                                     out[t].positions));
            REPRISE_TRY(check_count(g, name + ".POSITION", out[t].positions.size(), vertices));
        }
        if (normals >= 0) {
            REPRISE_TRY(read_vectors(g, normals,
                                     {name + ".NORMAL", TINYGLTF_TYPE_VEC3, target_kinds(g)},
                                     out[t].normals));
            REPRISE_TRY(check_count(g, name + ".NORMAL", out[t].normals.size(), vertices));
            if (!keep_normals) out[t].normals.clear();
        }
    }
    return ok();
}

// A textured material reads a UV set; the primitive must have it.
Status check_material(const Gltf& g, const tg::Primitive& p, const std::string& field,
                      const std::vector<Material>& materials, const Primitive& out) {
    if (p.material < 0) return ok();
    REPRISE_TRY(check_index(g, field + ".material", p.material, materials.size(), "materials"));
    const Material& material = materials[size_t(p.material)];
    if (material.base_color_texture < 0) return ok();
    const auto& uv = material.texcoord == 0 ? out.uv0 : out.uv1;
    if (!uv.empty()) return ok();
    return g.fail(field, "materials[" + std::to_string(p.material) +
                             "] is textured through TEXCOORD_" + std::to_string(material.texcoord) +
                             ", which the primitive lacks");
}

Status convert_primitive(const Gltf& g, const tg::Primitive& p, const std::string& field,
                         const std::vector<Material>& materials, Primitive& out, bool& skipped) {
    Topology topology = Topology::Unsupported;
    REPRISE_TRY(topology_of(g, field, p.mode, topology));
    skipped = topology == Topology::Unsupported;
    if (skipped) return ok();
    const int positions = attribute(p.attributes, "POSITION");
    if (positions < 0) return g.fail(field + ".attributes", "no POSITION");
    REPRISE_TRY(read_vectors(
        g, positions, {field + ".attributes.POSITION", TINYGLTF_TYPE_VEC3, position_kinds(g)},
        out.positions));
    const size_t vertices = out.positions.size();
    REPRISE_TRY(read_normals(g, p, field, vertices, out.normals));
    REPRISE_TRY(read_texcoords(g, p, field, vertices, 0, out.uv0));
    REPRISE_TRY(read_texcoords(g, p, field, vertices, 1, out.uv1));
    REPRISE_TRY(read_skinning(g, p, field, vertices, out));
    REPRISE_TRY(read_targets(g, p, field, vertices, !out.normals.empty(), out.targets));
    REPRISE_TRY(read_indices(g, p, field, vertices, topology, out.indices));
    REPRISE_TRY(check_material(g, p, field, materials, out));
    out.material = p.material;
    return ok();
}

Status convert_mesh(const Gltf& g, size_t index, const std::vector<Material>& materials, Mesh& out,
                    size_t& skipped) {
    const tg::Mesh& mesh = g.model.meshes[index];
    const std::string field = item("meshes", index);
    if (mesh.primitives.empty())
        return g.fail(field + ".primitives", "none (at least one is required)");
    const size_t targets = mesh.primitives[0].targets.size();
    out.name = mesh.name;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const std::string name = field + "." + item("primitives", p);
        if (mesh.primitives[p].targets.size() != targets)
            return g.fail(name + ".targets",
                          count_of(mesh.primitives[p].targets.size(), "morph targets") +
                              ", but primitives[0] has " + std::to_string(targets));
        Primitive primitive;
        bool unsupported = false;
        REPRISE_TRY(
            convert_primitive(g, mesh.primitives[p], name, materials, primitive, unsupported));
        if (unsupported)
            ++skipped;
        else
            out.primitives.push_back(std::move(primitive));
    }
    if (!mesh.weights.empty() && mesh.weights.size() != targets)
        return g.fail(field + ".weights", count_of(mesh.weights.size(), "weights") + " for " +
                                              count_of(targets, "morph targets"));
    out.weights.assign(targets, 0.0f);
    for (size_t w = 0; w < mesh.weights.size(); ++w) {
        if (!std::isfinite(mesh.weights[w])) return g.fail(field + ".weights", "not finite");
        out.weights[w] = float(mesh.weights[w]);
    }
    return ok();
}

// ---------------------------------------------------------------------------------------------
// Skins, cameras, nodes

Status convert_skin(const Gltf& g, size_t index, Skin& out) {
    const tg::Skin& skin = g.model.skins[index];
    const std::string field = item("skins", index);
    if (skin.joints.empty()) return g.fail(field + ".joints", "empty");
    for (size_t j = 0; j < skin.joints.size(); ++j)
        REPRISE_TRY(check_index(g, field + "." + item("joints", j), skin.joints[j],
                                g.model.nodes.size(), "nodes"));
    if (skin.skeleton >= 0)
        REPRISE_TRY(
            check_index(g, field + ".skeleton", skin.skeleton, g.model.nodes.size(), "nodes"));
    out.joints = skin.joints;
    if (skin.inverseBindMatrices < 0) {
        out.inverse_bind.assign(skin.joints.size(), glm::mat4(1.0f));
        return ok();
    }
    const std::string name = field + ".inverseBindMatrices";
    REPRISE_TRY(read_vectors(g, skin.inverseBindMatrices, {name, TINYGLTF_TYPE_MAT4, F32},
                             out.inverse_bind));
    if (out.inverse_bind.size() < skin.joints.size())
        return g.fail(name, count_of(out.inverse_bind.size(), "matrices") + " for " +
                                count_of(skin.joints.size(), "joints"));
    out.inverse_bind.resize(skin.joints.size());
    return ok();
}

bool finite_positive(double v) {
    return std::isfinite(v) && v > 0.0;
}

Status convert_perspective(const Gltf& g, const std::string& field, const tg::PerspectiveCamera& c,
                           CameraModel& out) {
    if (!finite_positive(c.yfov) || c.yfov >= std::numbers::pi)
        return g.fail(field + ".yfov", std::to_string(c.yfov) + " is not in (0, pi)");
    if (!finite_positive(c.znear))
        return g.fail(field + ".znear", std::to_string(c.znear) + " is not > 0");
    if (c.zfar != 0.0 && !(std::isfinite(c.zfar) && c.zfar > c.znear))
        return g.fail(field + ".zfar", std::to_string(c.zfar) + " is not > znear");
    if (c.aspectRatio != 0.0 && !finite_positive(c.aspectRatio))
        return g.fail(field + ".aspectRatio", std::to_string(c.aspectRatio) + " is not > 0");
    out.perspective = true;
    out.yfov = float(c.yfov);
    out.aspect = float(c.aspectRatio);
    out.znear = float(c.znear);
    out.zfar = float(c.zfar);
    return ok();
}

Status convert_orthographic(const Gltf& g, const std::string& field,
                            const tg::OrthographicCamera& c, CameraModel& out) {
    if (!std::isfinite(c.xmag) || c.xmag == 0.0)
        return g.fail(field + ".xmag", "is 0 or not finite");
    if (!std::isfinite(c.ymag) || c.ymag == 0.0)
        return g.fail(field + ".ymag", "is 0 or not finite");
    if (!std::isfinite(c.znear) || c.znear < 0.0)
        return g.fail(field + ".znear", std::to_string(c.znear) + " is not >= 0");
    if (!std::isfinite(c.zfar) || c.zfar <= c.znear)
        return g.fail(field + ".zfar", std::to_string(c.zfar) + " is not > znear");
    out.perspective = false;
    out.xmag = float(c.xmag);
    out.ymag = float(c.ymag);
    out.znear = float(c.znear);
    out.zfar = float(c.zfar);
    return ok();
}

Status convert_camera(const Gltf& g, size_t index, CameraModel& out) {
    const tg::Camera& camera = g.model.cameras[index];
    const std::string field = item("cameras", index);
    if (camera.type == "perspective")
        return convert_perspective(g, field + ".perspective", camera.perspective, out);
    if (camera.type == "orthographic")
        return convert_orthographic(g, field + ".orthographic", camera.orthographic, out);
    return g.fail(field + ".type",
                  "\"" + camera.type + "\" is neither perspective nor orthographic");
}

Status read_numbers(const Gltf& g, const std::string& field, const std::vector<double>& in,
                    size_t size, float* out) {
    if (in.empty()) return ok();
    if (in.size() != size)
        return g.fail(field, count_of(in.size(), "values") + ", expected " + std::to_string(size));
    for (size_t i = 0; i < size; ++i) {
        if (!std::isfinite(in[i]))
            return g.fail(field, "value " + std::to_string(i) + " is not finite");
        out[i] = float(in[i]);
    }
    return ok();
}

Status convert_transform(const Gltf& g, const tg::Node& node, const std::string& field, Node& out) {
    REPRISE_TRY(read_numbers(g, field + ".translation", node.translation, 3,
                             glm::value_ptr(out.translation)));
    REPRISE_TRY(read_numbers(g, field + ".scale", node.scale, 3, glm::value_ptr(out.scale)));
    REPRISE_TRY(read_numbers(g, field + ".matrix", node.matrix, 16, glm::value_ptr(out.matrix)));
    out.has_matrix = !node.matrix.empty();
    float xyzw[4] = {0, 0, 0, 1};
    REPRISE_TRY(read_numbers(g, field + ".rotation", node.rotation, 4, xyzw));
    const glm::quat rotation(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
    const float length = glm::length(rotation);
    if (!(length > 1e-6f) || !std::isfinite(length))
        return g.fail(field + ".rotation", "is not a rotation (length 0)");
    out.rotation = rotation / length;
    return ok();
}

Status check_skinned_mesh(const Gltf& g, const std::string& field, const Mesh& mesh,
                          const Skin& skin) {
    for (const Primitive& p : mesh.primitives)
        for (const glm::u16vec4& j : p.joints)
            for (int c = 0; c < 4; ++c)
                if (size_t(j[c]) >= skin.joints.size())
                    return g.fail(field, "mesh joint " + std::to_string(j[c]) +
                                             " >= skin joint count " +
                                             std::to_string(skin.joints.size()));
    return ok();
}

Status convert_node(const Gltf& g, size_t index, const Scene& scene, Node& out) {
    const tg::Node& node = g.model.nodes[index];
    const std::string field = item("nodes", index);
    out.name = node.name;
    for (size_t c = 0; c < node.children.size(); ++c)
        REPRISE_TRY(check_index(g, field + "." + item("children", c), node.children[c],
                                g.model.nodes.size(), "nodes"));
    out.children = node.children;
    REPRISE_TRY(convert_transform(g, node, field, out));
    if (node.camera >= 0)
        REPRISE_TRY(
            check_index(g, field + ".camera", node.camera, scene.cameras.size(), "cameras"));
    if (node.skin >= 0)
        REPRISE_TRY(check_index(g, field + ".skin", node.skin, scene.skins.size(), "skins"));
    if (node.mesh >= 0)
        REPRISE_TRY(check_index(g, field + ".mesh", node.mesh, scene.meshes.size(), "meshes"));
    out.camera = node.camera;
    out.skin = node.skin;
    out.mesh = node.mesh;
    if (node.mesh >= 0 && node.skin >= 0)
        REPRISE_TRY(check_skinned_mesh(g, field + ".skin", scene.meshes[size_t(node.mesh)],
                                       scene.skins[size_t(node.skin)]));
    if (node.weights.empty()) return ok();
    const size_t targets = node.mesh >= 0 ? scene.meshes[size_t(node.mesh)].weights.size() : 0;
    if (node.weights.size() != targets)
        return g.fail(field + ".weights", count_of(node.weights.size(), "weights") + " for " +
                                              count_of(targets, "morph targets") + " of its mesh");
    out.weights.resize(targets);
    return read_numbers(g, field + ".weights", node.weights, targets, out.weights.data());
}

// Every node has at most one parent and the children lists are acyclic. `parent` gets -1 for
// roots.
Status check_hierarchy(const Gltf& g, const std::vector<Node>& nodes, std::vector<int>& parent) {
    parent.assign(nodes.size(), -1);
    for (size_t i = 0; i < nodes.size(); ++i) {
        for (const int child : nodes[i].children) {
            int& p = parent[size_t(child)];
            if (p >= 0)
                return g.fail(item("nodes", size_t(child)), "is a child of both nodes[" +
                                                                std::to_string(p) + "] and nodes[" +
                                                                std::to_string(i) + "]");
            p = int(i);
        }
    }
    std::vector<bool> reached(nodes.size(), false);
    std::vector<int> stack;
    for (size_t i = 0; i < nodes.size(); ++i)
        if (parent[i] < 0) stack.push_back(int(i));
    while (!stack.empty()) {
        const int n = stack.back();
        stack.pop_back();
        reached[size_t(n)] = true;
        for (const int child : nodes[size_t(n)].children) stack.push_back(child);
    }
    for (size_t i = 0; i < nodes.size(); ++i)
        if (!reached[i])
            return g.fail(item("nodes", i),
                          "is its own ancestor (the children lists form a cycle)");
    return ok();
}

Status choose_roots(const Gltf& g, const std::vector<int>& parent, std::vector<int>& roots,
                    std::string& name) {
    if (g.model.scenes.empty()) {
        for (size_t i = 0; i < parent.size(); ++i)
            if (parent[i] < 0) roots.push_back(int(i));
        return ok();
    }
    const int index = std::max(g.model.defaultScene, 0);
    REPRISE_TRY(check_index(g, "scene", index, g.model.scenes.size(), "scenes"));
    const tg::Scene& scene = g.model.scenes[size_t(index)];
    const std::string field = item("scenes", size_t(index)) + ".nodes";
    if (scene.nodes.empty()) return g.fail(field, "empty, nothing to draw");
    std::vector<bool> listed(parent.size(), false);
    for (size_t r = 0; r < scene.nodes.size(); ++r) {
        const int node = scene.nodes[r];
        REPRISE_TRY(check_index(g, item(field, r), node, parent.size(), "nodes"));
        if (parent[size_t(node)] >= 0)
            return g.fail(item(field, r), "node " + std::to_string(node) + " is a child of nodes[" +
                                              std::to_string(parent[size_t(node)]) +
                                              "], not a root");
        if (listed[size_t(node)])
            return g.fail(item(field, r), "node " + std::to_string(node) + " is listed twice");
        listed[size_t(node)] = true;
        roots.push_back(node);
    }
    name = scene.name;
    return ok();
}

bool draws_triangles(const Scene& scene) {
    std::vector<int> stack = scene.roots;
    while (!stack.empty()) {
        const Node& node = scene.nodes[size_t(stack.back())];
        stack.pop_back();
        if (node.mesh >= 0)
            for (const Primitive& p : scene.meshes[size_t(node.mesh)].primitives)
                if (!p.indices.empty()) return true;
        stack.insert(stack.end(), node.children.begin(), node.children.end());
    }
    return false;
}

// ---------------------------------------------------------------------------------------------
// Animations

Status interpolation_of(const Gltf& g, const std::string& field, const std::string& name,
                        Interpolation& out) {
    if (name == "LINEAR")
        out = Interpolation::Linear;
    else if (name == "STEP")
        out = Interpolation::Step;
    else if (name == "CUBICSPLINE")
        out = Interpolation::CubicSpline;
    else
        return g.fail(field, "\"" + name + "\" is not LINEAR, STEP or CUBICSPLINE");
    return ok();
}

// Keyframe times must not decrease; repeated times (a jump) are nudged apart by one ulp so the
// Scene's times increase strictly.
Status make_increasing(const Gltf& g, const std::string& field, std::vector<float>& times) {
    float previous = times.empty() ? 0.0f : times[0];
    for (size_t k = 1; k < times.size(); ++k) {
        const float original = times[k];
        if (original < previous)
            return g.fail(field, "time " + std::to_string(original) + " at key " +
                                     std::to_string(k) + " is before the previous key's " +
                                     std::to_string(previous));
        if (times[k] <= times[k - 1])
            times[k] = std::nextafter(times[k - 1], std::numeric_limits<float>::infinity());
        previous = original;
    }
    return ok();
}

void normalize_rotations(std::vector<float>& values, Interpolation interpolation) {
    const bool spline = interpolation == Interpolation::CubicSpline;
    const size_t stride = spline ? 12 : 4;
    for (size_t k = spline ? 4 : 0; k + 4 <= values.size(); k += stride) {
        const glm::vec4 q(values[k], values[k + 1], values[k + 2], values[k + 3]);
        const float length = glm::length(q);
        if (length > 1e-12f)
            for (size_t c = 0; c < 4; ++c) values[k + c] /= length;
    }
}

Status check_rotations(const Gltf& g, const std::string& field, const std::vector<float>& values,
                       Interpolation interpolation) {
    const bool spline = interpolation == Interpolation::CubicSpline;
    const size_t stride = spline ? 12 : 4;
    for (size_t k = spline ? 4 : 0; k + 4 <= values.size(); k += stride) {
        const float length =
            glm::length(glm::vec4(values[k], values[k + 1], values[k + 2], values[k + 3]));
        if (!(length > 1e-12f))
            return g.fail(field, "key " + std::to_string(k / stride) + " is a zero quaternion");
    }
    return ok();
}

struct ChannelTarget {
    AnimatedPath path = AnimatedPath::Translation;
    int type = TINYGLTF_TYPE_VEC3;
    unsigned kinds = F32;
    int components = 3;
};

// False in `known` for paths reprise does not animate (e.g. KHR_animation_pointer's).
Status target_of(const Gltf& g, const std::string& field, const std::string& path, const Node& node,
                 const Scene& scene, ChannelTarget& out, bool& known) {
    const unsigned normalized = F32 | I8N | U8N | I16N | U16N;
    known = true;
    if (path == "translation")
        out = {AnimatedPath::Translation, TINYGLTF_TYPE_VEC3, F32, 3};
    else if (path == "scale")
        out = {AnimatedPath::Scale, TINYGLTF_TYPE_VEC3, F32, 3};
    else if (path == "rotation")
        out = {AnimatedPath::Rotation, TINYGLTF_TYPE_VEC4, normalized, 4};
    else if (path == "weights")
        out = {AnimatedPath::Weights, TINYGLTF_TYPE_SCALAR, normalized, 0};
    else
        known = false;
    if (!known) return ok();
    if (out.path != AnimatedPath::Weights && node.has_matrix)
        return g.fail(field + ".target.path",
                      path + " of a node that has a matrix (glTF 2.0 §3.11)");
    if (out.path == AnimatedPath::Weights) {
        out.components = node.mesh >= 0 ? int(scene.meshes[size_t(node.mesh)].weights.size()) : 0;
        if (out.components == 0)
            return g.fail(field + ".target.path", "weights of a node without morph targets");
    }
    return ok();
}

Status convert_channel(const Gltf& g, const tg::Animation& animation, const std::string& prefix,
                       size_t index, const Scene& scene, AnimationChannel& out, bool& keep) {
    const tg::AnimationChannel& channel = animation.channels[index];
    const std::string field = prefix + "." + item("channels", index);
    REPRISE_TRY(
        check_index(g, field + ".sampler", channel.sampler, animation.samplers.size(), "samplers"));
    keep = channel.target_node >= 0;  // no node: the target is an extension's
    if (!keep) return ok();
    REPRISE_TRY(
        check_index(g, field + ".target.node", channel.target_node, scene.nodes.size(), "nodes"));
    ChannelTarget target;
    REPRISE_TRY(target_of(g, field, channel.target_path, scene.nodes[size_t(channel.target_node)],
                          scene, target, keep));
    if (!keep) return ok();
    const tg::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
    const std::string sampler_field = prefix + "." + item("samplers", size_t(channel.sampler));
    REPRISE_TRY(interpolation_of(g, sampler_field + ".interpolation", sampler.interpolation,
                                 out.interpolation));
    REPRISE_TRY(read_floats(g, sampler.input, {sampler_field + ".input", TINYGLTF_TYPE_SCALAR, F32},
                            out.times));
    REPRISE_TRY(make_increasing(g, sampler_field + ".input", out.times));
    const bool spline = out.interpolation == Interpolation::CubicSpline;
    if (spline && out.times.size() < 2)
        return g.fail(sampler_field + ".input", "CUBICSPLINE needs at least 2 keys");
    const std::string output = sampler_field + ".output";
    REPRISE_TRY(read_floats(g, sampler.output, {output, target.type, target.kinds}, out.values));
    const size_t expected = out.times.size() * size_t(target.components) * (spline ? 3 : 1);
    if (out.values.size() != expected)
        return g.fail(output, count_of(out.values.size(), "values") + ", expected " +
                                  std::to_string(expected) + " for " +
                                  count_of(out.times.size(), "keys"));
    if (target.path == AnimatedPath::Rotation) {
        REPRISE_TRY(check_rotations(g, output, out.values, out.interpolation));
        normalize_rotations(out.values, out.interpolation);
    }
    out.node = channel.target_node;
    out.path = target.path;
    out.components = target.components;
    return ok();
}

Status convert_animation(const Gltf& g, size_t index, const Scene& scene, Animation& out) {
    const tg::Animation& animation = g.model.animations[index];
    out.name = animation.name;
    for (size_t c = 0; c < animation.channels.size(); ++c) {
        AnimationChannel channel;
        bool keep = false;
        REPRISE_TRY(
            convert_channel(g, animation, item("animations", index), c, scene, channel, keep));
        if (keep) out.channels.push_back(std::move(channel));
    }
    return ok();
}

// ---------------------------------------------------------------------------------------------
// The whole model

template <class T, class Convert>
Status convert_all(size_t count, std::vector<T>& out, Convert convert) {
    out.resize(count);
    for (size_t i = 0; i < count; ++i) REPRISE_TRY(convert(i, out[i]));
    return ok();
}

Status convert_model(const Gltf& g, Scene& scene) {
    const tg::Model& m = g.model;
    if (m.nodes.empty()) return g.fail("nodes", "none, nothing to draw");
    REPRISE_TRY(check_buffer_views(g));
    TextureTable table;
    table.remap.assign(m.textures.size(), -1);
    REPRISE_TRY(convert_all(m.materials.size(), scene.materials, [&](size_t i, Material& out) {
        return convert_material(g, i, table, out);
    }));
    scene.textures = std::move(table.textures);
    size_t skipped = 0;
    REPRISE_TRY(convert_all(m.meshes.size(), scene.meshes, [&](size_t i, Mesh& out) {
        return convert_mesh(g, i, scene.materials, out, skipped);
    }));
    REPRISE_TRY(convert_all(m.skins.size(), scene.skins,
                            [&](size_t i, Skin& out) { return convert_skin(g, i, out); }));
    REPRISE_TRY(convert_all(m.cameras.size(), scene.cameras,
                            [&](size_t i, CameraModel& out) { return convert_camera(g, i, out); }));
    REPRISE_TRY(convert_all(m.nodes.size(), scene.nodes,
                            [&](size_t i, Node& out) { return convert_node(g, i, scene, out); }));
    std::vector<int> parent;
    REPRISE_TRY(check_hierarchy(g, scene.nodes, parent));
    REPRISE_TRY(choose_roots(g, parent, scene.roots, scene.name));
    REPRISE_TRY(convert_all(m.animations.size(), scene.animations, [&](size_t i, Animation& out) {
        return convert_animation(g, i, scene, out);
    }));
    if (!draws_triangles(scene)) {
        std::string problem = "nothing to draw: no triangles under the scene's root nodes";
        if (skipped)
            problem += " (" + count_of(skipped, "POINTS/LINES primitives") +
                       " skipped: reprise draws triangles only)";
        return Status::error(g.file + ": " + problem);
    }
    return ok();
}

// ---------------------------------------------------------------------------------------------
// Reading and parsing

Status read_file(const std::string& path, const std::string& file,
                 std::vector<unsigned char>& bytes) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
        return Status::error(file + ": not a readable file");
    const uintmax_t size = std::filesystem::file_size(path, error);
    if (error) return Status::error(file + ": " + error.message());
    if (size == 0) return Status::error(file + ": the file is empty");
    if (size > max_file_bytes)
        return Status::error(file + ": " + std::to_string(size) + " bytes is too large");
    std::ifstream in(path, std::ios::binary);
    bytes.resize(size_t(size));
    if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
        return Status::error(file + ": could not be read");
    return ok();
}

uint32_t load_u32(const unsigned char* p) {
    uint32_t v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// The GLB container (header, JSON chunk, optional BIN chunk) fits in the file; tinygltf
// 2.7 misses a BIN chunk that ends up to 8 bytes past it. `length` gets the GLB's length.
Status check_glb_layout(const std::string& file, std::span<const unsigned char> bytes,
                        uint32_t& length) {
    auto fail = [&](const std::string& problem) {
        return Status::error(file + ": GLB: " + problem);
    };
    if (bytes.size() < 20)
        return fail("truncated header (" + count_of(bytes.size(), "bytes") + ")");
    if (load_u32(&bytes[4]) != 2)
        return fail("version " + std::to_string(load_u32(&bytes[4])) + ", expected 2");
    length = load_u32(&bytes[8]);
    if (length > bytes.size())
        return fail("header length " + std::to_string(length) + " exceeds the " +
                    count_of(bytes.size(), "bytes") + " of the file (truncated?)");
    const uint64_t json_end = 20 + uint64_t(load_u32(&bytes[12]));
    if (load_u32(&bytes[16]) != 0x4E4F534Au) return fail("the first chunk is not JSON");
    if (json_end > length)
        return fail("the JSON chunk exceeds the GLB length " + std::to_string(length));
    if (json_end == length) return ok();
    if (json_end + 8 > length) return fail("truncated BIN chunk header");
    const uint64_t bin_end = json_end + 8 + load_u32(&bytes[json_end]);
    if (bin_end > length)
        return fail("the BIN chunk exceeds the GLB length " + std::to_string(length));
    return ok();
}

std::string one_line(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    for (size_t i = 0; (i = text.find('\n', i)) != std::string::npos;) text.replace(i, 1, "; ");
    return text;
}

Status check_required_extensions(const std::string& file, const tg::Model& model) {
    for (const std::string& name : model.extensionsRequired) {
        const auto* end = std::end(supported_required_extensions);
        if (std::find(std::begin(supported_required_extensions), end, name) == end)
            return Status::error(file + ": requires extension " + name +
                                 " which reprise does not support");
    }
    return ok();
}

bool ends_with_glb(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension == ".glb";
}

// tinygltf's file access for external buffers and images. tinygltf joins each URI to base_dir
// (and, failing that, to the working folder); a path is read only when it starts with base_dir
// and its canonical form lies under the canonical root. Without a root nothing is read.
struct FileAccess {
    std::string base_dir;
    std::filesystem::path root;
    std::string refused_uri;     // the first URI that resolved outside the root
    std::string refused_target;  // where it resolved to

    bool permits(const std::string& joined) {
        if (root.empty()) {
            if (refused_uri.empty()) refused_uri = joined;
            return false;
        }
        const std::string prefix = base_dir.ends_with('/') ? base_dir : base_dir + "/";
        if (joined.compare(0, prefix.size(), prefix) != 0) return false;
        std::error_code error;
        const std::filesystem::path target = std::filesystem::weakly_canonical(joined, error);
        if (!error &&
            std::mismatch(root.begin(), root.end(), target.begin(), target.end()).first == root.end())
            return true;
        if (refused_uri.empty()) {
            refused_uri = joined.substr(prefix.size());
            refused_target = error ? joined : target.string();
        }
        return false;
    }

    static bool file_exists(const std::string& path, void* self) {
        return static_cast<FileAccess*>(self)->permits(path) && tg::FileExists(path, nullptr);
    }
    static bool read_whole_file(std::vector<unsigned char>* out, std::string* error,
                                const std::string& path, void* self) {
        if (!static_cast<FileAccess*>(self)->permits(path)) {
            if (error) *error += "outside the glTF file's folder";
            return false;
        }
        return tg::ReadWholeFile(out, error, path, nullptr);
    }
    static bool write_whole_file(std::string* error, const std::string&,
                                 const std::vector<unsigned char>&, void*) {
        if (error) *error += "reprise writes no glTF files";
        return false;
    }
};

Status check_file_access(const std::string& file, const FileAccess& access) {
    if (access.refused_uri.empty()) return ok();
    if (access.root.empty())
        return Status::error(file + ": uri \"" + access.refused_uri +
                             "\": a glTF file loaded from memory reads no external files");
    return Status::error(file + ": uri \"" + access.refused_uri + "\" resolves to " +
                         access.refused_target + ", outside the glTF file's folder " +
                         access.root.string() +
                         " (for trusted files: --allow-outside-paths, "
                         "GltfOptions::allow_outside_paths)");
}

// tinygltf 2.7 hands an image's bufferView to stb_image without checking that it lies inside its
// buffer (fuzz_gltf: a GLB whose image view ran 551 bytes past its 1636-byte buffer). Image bytes
// that start inside a loaded buffer must end inside it; then tinygltf's own decoder runs.
bool load_image_within_buffers(tg::Image* image, const int index, std::string* error,
                               std::string* warning, int width, int height,
                               const unsigned char* bytes, int size, void* model) {
    const auto at = reinterpret_cast<std::uintptr_t>(bytes);
    for (const tg::Buffer& buffer : static_cast<const tg::Model*>(model)->buffers) {
        const auto begin = reinterpret_cast<std::uintptr_t>(buffer.data.data());
        const auto end = begin + buffer.data.size();
        if (buffer.data.empty() || at < begin || at > end) continue;
        if (size < 0 || uint64_t(size) > end - at) {
            if (error)
                *error += "images[" + std::to_string(index) +
                          "]: its bufferView runs past the end of its buffer\n";
            return false;
        }
    }
    return tg::LoadImageData(image, index, error, warning, width, height, bytes, size, nullptr);
}

// `access` null: tinygltf's own file access, unrestricted.
Status parse(std::span<const unsigned char> bytes, const std::string& file, bool named_glb,
             FileAccess* access, const std::string& base_dir, tg::Model& model,
             std::string& warnings) {
    if (bytes.empty()) return Status::error(file + ": the file is empty");
    if (bytes.size() > max_file_bytes)
        return Status::error(file + ": " + std::to_string(bytes.size()) + " bytes is too large");
    const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
    if (!binary && named_glb)
        return Status::error(file + ": GLB: the file does not start with \"glTF\"");
    uint32_t length = uint32_t(bytes.size());
    if (binary) REPRISE_TRY(check_glb_layout(file, bytes, length));
    tg::TinyGLTF loader;
    loader.SetImageLoader(&load_image_within_buffers, &model);
    if (access)
        loader.SetFsCallbacks({.FileExists = &FileAccess::file_exists,
                               .ExpandFilePath = &tg::ExpandFilePath,
                               .ReadWholeFile = &FileAccess::read_whole_file,
                               .WriteWholeFile = &FileAccess::write_whole_file,
                               .user_data = access});
    std::string error;
    const bool parsed =
        binary
            ? loader.LoadBinaryFromMemory(&model, &error, &warnings, bytes.data(), length, base_dir)
            : loader.LoadASCIIFromString(&model, &error, &warnings,
                                         reinterpret_cast<const char*>(bytes.data()), length,
                                         base_dir);
    warnings = one_line(warnings);
    // A refused image is only a tinygltf warning; a refused buffer is behind "File not found".
    if (access) REPRISE_TRY(check_file_access(file, *access));
    // Before tinygltf's errors, which for a Draco file are about its missing bufferViews.
    REPRISE_TRY(check_required_extensions(file, model));
    // On success tinygltf's errors are about fields it skipped (e.g. a skin without the optional
    // inverseBindMatrices); what reprise uses is validated below.
    if (parsed) return ok();
    std::string message =
        file + ": " + (error.empty() ? "tinygltf could not parse it" : one_line(error));
    if (!warnings.empty()) message += " (warnings: " + warnings + ")";
    return Status::error(message);
}

Status convert(const std::string& file, const std::string& fallback_name, const tg::Model& model,
               const std::string& warnings, Scene& scene) {
    Gltf g{file, model, warnings};
    g.quantized = std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(),
                            "KHR_mesh_quantization") != model.extensionsUsed.end();
    Scene loaded;
    REPRISE_TRY(convert_model(g, loaded));
    if (loaded.name.empty()) loaded.name = fallback_name;
    scene = std::move(loaded);
    return ok();
}

}  // namespace

Status load_gltf(const std::string& path, Scene& scene, const GltfOptions& options) {
    const std::string file = std::filesystem::path(path).filename().string();
    try {
        std::vector<unsigned char> bytes;
        REPRISE_TRY(read_file(path, file, bytes));
        std::error_code error;
        FileAccess access;
        access.base_dir = std::filesystem::absolute(path, error).parent_path().string();
        if (!error) access.root = std::filesystem::canonical(access.base_dir, error);
        if (error) return Status::error(file + ": its folder cannot be resolved: " + error.message());
        tg::Model model;
        std::string warnings;
        REPRISE_TRY(parse(bytes, file, ends_with_glb(path),
                          options.allow_outside_paths ? nullptr : &access, access.base_dir, model,
                          warnings));
        return convert(file, std::filesystem::path(path).stem().string(), model, warnings, scene);
    } catch (const std::exception& e) {
        return Status::error(file + ": " + e.what());
    }
}

Status load_gltf(std::span<const uint8_t> bytes, const std::string& name, Scene& scene) {
    try {
        FileAccess no_files;
        tg::Model model;
        std::string warnings;
        REPRISE_TRY(parse(bytes, name, ends_with_glb(name), &no_files, "", model, warnings));
        return convert(name, std::filesystem::path(name).stem().string(), model, warnings, scene);
    } catch (const std::exception& e) {
        return Status::error(name + ": " + e.what());
    }
}

}  // namespace reprise::server
