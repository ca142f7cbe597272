// write_frame: one multichannel OpenEXR per Frame. Layout and header in docs/exr_format.md.
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <glm/gtc/type_ptr.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "reprise/core/exr.hpp"

namespace reprise {
namespace {

namespace fs = std::filesystem;

static_assert(sizeof(glm::vec4) == 16 && sizeof(glm::vec3) == 12 && sizeof(glm::vec2) == 8);

// How a value is changed on its way into the file (Blender's conventions).
enum class Convert {
    None,
    Negate,           // Blender's vector pass has +y up
    InfToBackground,  // Cycles marks background depth with 1e10
    UintToFloat,      // Blender's IndexOB pass is float
};

// One file channel: a 4-byte component of one of the Frame's buffers.
struct Source {
    const char* name;
    OIIO::TypeDesc type;
    const unsigned char* first;  // the component in pixel 0
    std::size_t stride;          // bytes from one pixel to the next
    Convert convert = Convert::None;
};

template <class T>
Source source(const char* name, const Image<T>& image, int component,
              Convert convert = Convert::None) {
    const bool is_uint = std::is_same_v<T, uint32_t> && convert != Convert::UintToFloat;
    return {name, is_uint ? OIIO::TypeUInt : OIIO::TypeFloat,
            reinterpret_cast<const unsigned char*>(image.data()) + 4 * component, sizeof(T),
            convert};
}

void copy_value(const unsigned char* from, unsigned char* to, Convert convert) {
    if (convert == Convert::None) {
        std::memcpy(to, from, 4);
        return;
    }
    float v;
    if (convert == Convert::UintToFloat) {
        uint32_t u;
        std::memcpy(&u, from, 4);
        v = float(u);
    } else {
        std::memcpy(&v, from, 4);
        if (convert == Convert::Negate) v = -v;
        if (convert == Convert::InfToBackground && v >= 1e10f) v = 1e10f;
    }
    std::memcpy(to, &v, 4);
}

// The UI layer's channels in the reprise and the Blender layout.
constexpr const char* kUiNames[2][4] = {
    {"ui.R", "ui.G", "ui.B", "ui.A"},
    {"ViewLayer.UI.R", "ViewLayer.UI.G", "ViewLayer.UI.B", "ViewLayer.UI.A"}};

std::vector<Source> reprise_sources(const Frame& frame) {
    std::vector<Source> sources = {source("R", frame.color, 0), source("G", frame.color, 1),
                                   source("B", frame.color, 2), source("A", frame.color, 3)};
    if (!frame.depth.empty()) sources.push_back(source("Z", frame.depth, 0));
    if (!frame.motion.empty()) {
        sources.push_back(source("motion.x", frame.motion, 0));
        sources.push_back(source("motion.y", frame.motion, 1));
    }
    if (!frame.normal.empty()) {
        sources.push_back(source("N.X", frame.normal, 0));
        sources.push_back(source("N.Y", frame.normal, 1));
        sources.push_back(source("N.Z", frame.normal, 2));
    }
    if (!frame.id.empty()) sources.push_back(source("id", frame.id, 0));
    if (!frame.ui.empty())
        for (int k = 0; k < 4; ++k) sources.push_back(source(kUiNames[0][k], frame.ui, k));
    return sources;
}

// Blender's Vector pass holds (previous - current) in X,Y and (current - next) in Z,W; a frame
// knows only the first, so Z,W repeat it (constant velocity).
std::vector<Source> blender_sources(const Frame& frame) {
    std::vector<Source> sources = {source("ViewLayer.Combined.R", frame.color, 0),
                                   source("ViewLayer.Combined.G", frame.color, 1),
                                   source("ViewLayer.Combined.B", frame.color, 2),
                                   source("ViewLayer.Combined.A", frame.color, 3)};
    if (!frame.depth.empty())
        sources.push_back(source("ViewLayer.Depth.Z", frame.depth, 0, Convert::InfToBackground));
    if (!frame.motion.empty()) {
        sources.push_back(source("ViewLayer.Vector.X", frame.motion, 0));
        sources.push_back(source("ViewLayer.Vector.Y", frame.motion, 1, Convert::Negate));
        sources.push_back(source("ViewLayer.Vector.Z", frame.motion, 0));
        sources.push_back(source("ViewLayer.Vector.W", frame.motion, 1, Convert::Negate));
    }
    if (!frame.normal.empty()) {
        sources.push_back(source("ViewLayer.Normal.X", frame.normal, 0));
        sources.push_back(source("ViewLayer.Normal.Y", frame.normal, 1));
        sources.push_back(source("ViewLayer.Normal.Z", frame.normal, 2));
    }
    if (!frame.id.empty())
        sources.push_back(source("ViewLayer.IndexOB.X", frame.id, 0, Convert::UintToFloat));
    if (!frame.ui.empty())
        for (int k = 0; k < 4; ++k) sources.push_back(source(kUiNames[1][k], frame.ui, k));
    return sources;
}

// glm stores a column-vector matrix column by column; Imath's M44f is the row-vector transpose
// stored row by row: the same 16 floats in the same order.
void set_matrix(OIIO::ImageSpec& spec, const char* name, const glm::mat4& m) {
    spec.attribute(name, OIIO::TypeMatrix44, glm::value_ptr(m));
}

std::string temporary_path(const fs::path& target) {
    static std::atomic<unsigned> counter{0};
    char suffix[48];
    std::snprintf(suffix, sizeof suffix, ".%ld-%u.tmp", long(::getpid()), counter++);
    std::string name(1, '.');
    name += target.filename().string();
    name += suffix;
    return (target.parent_path() / name).string();
}

}  // namespace

glm::mat4 exr_world_to_camera(const glm::mat4& view) {
    glm::mat4 m = view;
    for (int column = 0; column < 4; ++column) m[column][2] = -m[column][2];
    return m;
}

glm::mat4 exr_world_to_ndc(const glm::mat4& projection, const glm::mat4& view) {
    // Clip (x, y, w) -> (0.5 x + 0.5 w, -0.5 y + 0.5 w, w): NDC [-1, 1] with +y up becomes
    // [0, 1] with +y down once divided by w.
    const glm::mat4 clip_to_ndc(glm::vec4(0.5f, 0, 0, 0), glm::vec4(0, -0.5f, 0, 0),
                                glm::vec4(0, 0, 1, 0), glm::vec4(0.5f, 0.5f, 0, 1));
    return clip_to_ndc * projection * view;
}

Status write_frame(const std::string& path, const Frame& frame, const WriteOptions& options) {
    const int width = frame.width();
    const int height = frame.height();
    if (frame.color.empty()) return Status::error(path + ": cannot write a frame without colour");
    REPRISE_TRY(check_image_size(width, height, path));
    auto same_size = [&](const auto& image, const char* what) {
        if (image.empty() || (image.width() == width && image.height() == height)) return ok();
        return Status::error(path + ": " + what + " is " + std::to_string(image.width()) + "x" +
                             std::to_string(image.height()) + " but colour is " +
                             std::to_string(width) + "x" + std::to_string(height));
    };
    REPRISE_TRY(same_size(frame.depth, "depth"));
    REPRISE_TRY(same_size(frame.motion, "motion"));
    REPRISE_TRY(same_size(frame.normal, "normal"));
    REPRISE_TRY(same_size(frame.id, "id"));
    REPRISE_TRY(same_size(frame.ui, "ui"));

    const bool blender = options.layout == ExrLayout::Blender;
    const std::vector<Source> sources = blender ? blender_sources(frame) : reprise_sources(frame);

    OIIO::ImageSpec spec(width, height, int(sources.size()), OIIO::TypeFloat);
    spec.channelnames.clear();
    for (const Source& s : sources) {
        spec.channelnames.push_back(s.name);
        spec.channelformats.push_back(s.type);
    }
    spec.alpha_channel = 3;
    spec.z_channel = frame.depth.empty() ? -1 : 4;
    if (blender) spec.attribute("BlenderMultiChannel", "Blender V2.55.1 and newer");
    spec.attribute("compression", "zip");
    // No time of writing (OpenImageIO fills in the clock otherwise): a frame is its bytes.
    spec.attribute("DateTime", "");

    const Camera& camera = frame.camera;
    set_matrix(spec, "worldToCamera", exr_world_to_camera(camera.view));
    set_matrix(spec, "worldToNDC", exr_world_to_ndc(camera.projection, camera.view));
    set_matrix(spec, "reprise:projection", camera.projection);
    set_matrix(spec, "reprise:prevView", camera.prev_view);
    set_matrix(spec, "reprise:prevProjection", camera.prev_projection);
    spec.attribute("reprise:near", camera.near);
    spec.attribute("reprise:far", camera.far);
    spec.attribute("reprise:jitter", OIIO::TypeVector2, glm::value_ptr(camera.jitter));
    spec.attribute("reprise:time", OIIO::TypeDesc::DOUBLE, &camera.time);
    spec.attribute("reprise:fps", OIIO::TypeDesc::DOUBLE, &frame.fps);
    if (camera.cut != Cut::Unknown) spec.attribute("reprise:cut", int(camera.cut == Cut::Yes));

    const std::string temp = temporary_path(path);
    auto out = OIIO::ImageOutput::create("openexr");
    if (!out) return Status::error(path + ": " + OIIO::geterror());
    if (!out->open(temp, spec)) return Status::error(path + ": " + out->geterror());
    auto fail = [&](std::string message) {
        out->close();
        out->geterror();
        std::error_code ignored;
        fs::remove(temp, ignored);
        return Status::error(path + ": " + message);
    };

    // Native pixels: every channel is 4 bytes, packed in `sources` order.
    const std::size_t pixel_bytes = 4 * sources.size();
    const int strip_rows = std::min(height, 64);
    std::vector<unsigned char> strip(std::size_t(strip_rows) * width * pixel_bytes);
    for (int y0 = 0; y0 < height; y0 += strip_rows) {
        const int y1 = std::min(height, y0 + strip_rows);
        const std::size_t first = std::size_t(y0) * width;
        const std::size_t count = std::size_t(y1 - y0) * width;
        for (std::size_t c = 0; c < sources.size(); ++c) {
            const Source& s = sources[c];
            const unsigned char* from = s.first + first * s.stride;
            unsigned char* to = strip.data() + 4 * c;
            for (std::size_t i = 0; i < count; ++i)
                copy_value(from + i * s.stride, to + i * pixel_bytes, s.convert);
        }
        if (!out->write_scanlines(y0, y1, 0, OIIO::TypeUnknown, strip.data()))
            return fail(out->geterror());
    }
    if (!out->close()) return fail(out->geterror());

    std::error_code ec;
    fs::rename(temp, path, ec);
    if (ec) {
        fs::remove(temp, ec);
        return Status::error(path + ": cannot write: " + ec.message());
    }
    return {};
}

}  // namespace reprise
