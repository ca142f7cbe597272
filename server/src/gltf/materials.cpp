// glTF loader, textures and materials: images expanded to RGBA, samplers, PBR metallic-roughness
// as reprise's materials.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "internal.hpp"

namespace reprise::server::gltf_loader {

namespace {

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

}  // namespace

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

}  // namespace reprise::server::gltf_loader
