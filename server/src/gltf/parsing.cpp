// glTF loader, reading and parsing: the file, the GLB container, tinygltf with file access
// restricted to the file's folder, the whole-model conversion, and load_gltf. tinygltf leaves
// ranges, types, finiteness and the node graph unchecked; the Scene is only written once the
// whole file has passed.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <span>

#include "internal.hpp"
#include "reprise/server/gltf.hpp"

namespace reprise::server::gltf_loader {

namespace {

// tinygltf takes lengths as 32-bit unsigned integers.
constexpr uint64_t max_file_bytes = std::numeric_limits<uint32_t>::max();

constexpr std::string_view supported_required_extensions[] = {"KHR_mesh_quantization"};

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
        if (!error && std::mismatch(root.begin(), root.end(), target.begin(), target.end()).first ==
                          root.end())
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

}  // namespace reprise::server::gltf_loader

namespace reprise::server {

Status load_gltf(const std::string& path, Scene& scene, const GltfOptions& options) {
    const std::string file = std::filesystem::path(path).filename().string();
    try {
        std::vector<unsigned char> bytes;
        REPRISE_TRY(gltf_loader::read_file(path, file, bytes));
        std::error_code error;
        gltf_loader::FileAccess access;
        access.base_dir = std::filesystem::absolute(path, error).parent_path().string();
        if (!error) access.root = std::filesystem::canonical(access.base_dir, error);
        if (error)
            return Status::error(file + ": its folder cannot be resolved: " + error.message());
        tinygltf::Model model;
        std::string warnings;
        REPRISE_TRY(gltf_loader::parse(bytes, file, gltf_loader::ends_with_glb(path),
                                       options.allow_outside_paths ? nullptr : &access,
                                       access.base_dir, model, warnings));
        return gltf_loader::convert(file, std::filesystem::path(path).stem().string(), model,
                                    warnings, scene);
    } catch (const std::exception& e) {
        return Status::error(file + ": " + e.what());
    }
}

Status load_gltf(std::span<const uint8_t> bytes, const std::string& name, Scene& scene) {
    try {
        gltf_loader::FileAccess no_files;
        tinygltf::Model model;
        std::string warnings;
        REPRISE_TRY(gltf_loader::parse(bytes, name, gltf_loader::ends_with_glb(name), &no_files, "",
                                       model, warnings));
        return gltf_loader::convert(name, std::filesystem::path(name).stem().string(), model,
                                    warnings, scene);
    } catch (const std::exception& e) {
        return Status::error(name + ": " + e.what());
    }
}

}  // namespace reprise::server
