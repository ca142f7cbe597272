// reprise_gbuffer <-> Frame (gbuffer.hpp).
#include "gbuffer.hpp"

#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>

#include <Imath/half.h>

#include "plumbing.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::capi {
namespace {

enum class Kind { Float32, Float16, Uint32, Srgb8 };

struct Format {
    int components = 0;  // 0: not a format
    Kind kind = Kind::Float32;
    const char* name = "unknown";
    int component_bytes() const { return kind == Kind::Srgb8 ? 1 : kind == Kind::Float16 ? 2 : 4; }
    int pixel_bytes() const { return components * component_bytes(); }
};

Format describe(reprise_format format) {
    switch (format) {
        case REPRISE_FORMAT_R32_FLOAT:
            return {1, Kind::Float32, "R32_FLOAT"};
        case REPRISE_FORMAT_RG32_FLOAT:
            return {2, Kind::Float32, "RG32_FLOAT"};
        case REPRISE_FORMAT_RGB32_FLOAT:
            return {3, Kind::Float32, "RGB32_FLOAT"};
        case REPRISE_FORMAT_RGBA32_FLOAT:
            return {4, Kind::Float32, "RGBA32_FLOAT"};
        case REPRISE_FORMAT_R16_FLOAT:
            return {1, Kind::Float16, "R16_FLOAT"};
        case REPRISE_FORMAT_RG16_FLOAT:
            return {2, Kind::Float16, "RG16_FLOAT"};
        case REPRISE_FORMAT_RGB16_FLOAT:
            return {3, Kind::Float16, "RGB16_FLOAT"};
        case REPRISE_FORMAT_RGBA16_FLOAT:
            return {4, Kind::Float16, "RGBA16_FLOAT"};
        case REPRISE_FORMAT_R32_UINT:
            return {1, Kind::Uint32, "R32_UINT"};
        case REPRISE_FORMAT_RGBA8_SRGB:
            return {4, Kind::Srgb8, "RGBA8_SRGB"};
        default:
            return {};
    }
}

// What one G-buffer channel takes: `min_components`..`components` float or half components
// (colour: RGB or RGBA, A = 1 when absent), or one uint32 (id).
struct Spec {
    const char* field;  // "color"
    int min_components, components;
    bool integer;
    const char* accepted;  // for messages
    bool srgb8 = false;    // 8-bit sRGB display values (the codec's colour) instead
};
constexpr Spec kColorSpec{"color", 3, 4, false,
                          "RGB32_FLOAT, RGBA32_FLOAT, RGB16_FLOAT, RGBA16_FLOAT"};
constexpr Spec kDisplaySpec{"color", 4, 4, false, "RGBA8_SRGB", true};
constexpr Spec kDepthSpec{"depth", 1, 1, false, "R32_FLOAT, R16_FLOAT"};
constexpr Spec kMotionSpec{"motion", 2, 2, false, "RG32_FLOAT, RG16_FLOAT"};
constexpr Spec kNormalSpec{"normal", 3, 3, false, "RGB32_FLOAT, RGB16_FLOAT"};
constexpr Spec kIdSpec{"id", 1, 1, true, "R32_UINT"};
constexpr Spec kUiSpec{"ui", 4, 4, false, "RGBA32_FLOAT, RGBA16_FLOAT"};

// Longest row stride taken: far more than any accepted row (16384 RGBA floats is 256 KiB).
constexpr int64_t kMaxStride = int64_t(1) << 30;

std::string size_text(int width, int height) {
    return std::to_string(width) + "x" + std::to_string(height);
}

// Checks one present channel: format, size (`width` x `height`, or 1..16384 for the colour that
// sets it when width is 0) and stride.
reprise_status check_image(const char* function, const std::string& name, const Spec& spec,
                           const reprise_image& image, int width, int height) {
    const std::string field = name + "->" + spec.field;
    const Format format = describe(image.format);
    const bool fits =
        format.components >= spec.min_components && format.components <= spec.components &&
        (format.kind == Kind::Uint32) == spec.integer && (format.kind == Kind::Srgb8) == spec.srgb8;
    if (!fits)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    field + ".format " + std::to_string(image.format) + " (" + format.name +
                        ") is not one of " + spec.accepted);
    if (width == 0) {
        if (image.width < 1 || image.height < 1 || image.width > kMaxImageSide ||
            image.height > kMaxImageSide)
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        field + " size " + size_text(image.width, image.height) +
                            " is outside 1.." + std::to_string(kMaxImageSide));
    } else if (image.width != width || image.height != height) {
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    field + " is " + size_text(image.width, image.height) + ", the frame " +
                        size_text(width, height));
    }
    const int64_t row = int64_t(image.width) * format.pixel_bytes();
    if (image.stride < row || image.stride > kMaxStride)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    field + ".stride " + std::to_string(image.stride) + " bytes is not in " +
                        std::to_string(row) + ".." + std::to_string(kMaxStride) + " (a row of " +
                        std::to_string(image.width) + " " + format.name + " pixels and more)");
    return REPRISE_OK;
}

float load(const unsigned char* p, Kind kind) {
    if (kind == Kind::Float16) {
        uint16_t bits;
        std::memcpy(&bits, p, 2);
        Imath::half h;
        h.setBits(bits);
        return float(h);
    }
    float value;
    std::memcpy(&value, p, 4);
    return value;
}

void store(unsigned char* p, Kind kind, float value) {
    if (kind == Kind::Float16) {
        const uint16_t bits = Imath::half(value).bits();
        std::memcpy(p, &bits, 2);
    } else {
        std::memcpy(p, &value, 4);
    }
}

template <class T>
constexpr int components_of() {
    if constexpr (std::is_arithmetic_v<T>)
        return 1;
    else
        return T::length();
}

// Pixel (x) of a checked image row into T: missing components (colour's A) are 1.
template <class T>
T load_pixel(const unsigned char* p, const Format& f) {
    if constexpr (std::is_same_v<T, uint32_t>) {
        uint32_t value;
        std::memcpy(&value, p, 4);
        return value;
    } else if constexpr (std::is_same_v<T, float>) {
        return load(p, f.kind);
    } else {
        T value(1.0f);
        for (int c = 0; c < f.components; ++c) value[c] = load(p + c * f.component_bytes(), f.kind);
        return value;
    }
}

template <class T>
void store_pixel(unsigned char* p, const Format& f, const T& value) {
    if constexpr (std::is_same_v<T, uint32_t>) {
        std::memcpy(p, &value, 4);
    } else if constexpr (std::is_same_v<T, float>) {
        store(p, f.kind, value);
    } else {
        for (int c = 0; c < f.components && c < components_of<T>(); ++c)
            store(p + c * f.component_bytes(), f.kind, value[c]);
    }
}

template <class T>
void read_pixels(const reprise_image& image, Image<T>& out) {
    const Format f = describe(image.format);
    out.resize(image.width, image.height);
    const auto* base = static_cast<const unsigned char*>(image.data);
    parallel_for(0, image.height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const unsigned char* row = base + int64_t(y) * image.stride;
            if constexpr (std::is_same_v<T, glm::u8vec4>)  // RGBA8_SRGB: the bytes as they are
                std::memcpy(&out(0, y), row, std::size_t(image.width) * sizeof(T));
            else
                for (int x = 0; x < image.width; ++x)
                    out(x, y) = load_pixel<T>(row + int64_t(x) * f.pixel_bytes(), f);
        }
    });
}

template <class T>
void write_pixels(const Image<T>& in, const reprise_image& image) {
    const Format f = describe(image.format);
    auto* base = static_cast<unsigned char*>(image.data);
    parallel_for(0, image.height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            unsigned char* row = base + int64_t(y) * image.stride;
            if constexpr (std::is_same_v<T, glm::u8vec4>)
                std::memcpy(row, &in(0, y), std::size_t(image.width) * sizeof(T));
            else
                for (int x = 0; x < image.width; ++x)
                    store_pixel(row + int64_t(x) * f.pixel_bytes(), f, in(x, y));
        }
    });
}

// One optional input channel: read when present and wanted, else cleared.
template <class T>
reprise_status read_channel(const char* function, const std::string& name, const Spec& spec,
                            const reprise_image& image, bool wanted, int width, int height,
                            Image<T>& out) {
    if (!wanted || !image.data) {
        out.clear();
        return REPRISE_OK;
    }
    REPRISE_CAPI_TRY(check_image(function, name, spec, image, width, height));
    read_pixels(image, out);
    return REPRISE_OK;
}

glm::mat4 to_matrix(const float* a) {
    glm::mat4 m;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[c][r] = a[c * 4 + r];
    return m;
}

void from_matrix(const glm::mat4& m, float* a) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) a[c * 4 + r] = m[c][r];
}

reprise_status read_camera(const char* function, const std::string& name,
                           const reprise_camera& given, Camera& camera) {
    const std::string field = name + "->camera";
    camera = Camera{};
    if (!std::isfinite(given.time))
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, field + ".time is not finite");
    camera.time = given.time;
    REPRISE_CAPI_TRY(check_flag(function, (field + ".valid").c_str(), given.valid));
    if (!given.valid) return REPRISE_OK;
    const std::pair<const char*, const float*> matrices[] = {
        {"view", given.view},
        {"projection", given.projection},
        {"prev_view", given.prev_view},
        {"prev_projection", given.prev_projection}};
    for (const auto& [matrix, values] : matrices)
        for (int i = 0; i < 16; ++i)
            if (!std::isfinite(values[i]))
                return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                            field + "." + matrix + "[" + std::to_string(i) + "] is not finite");
    if (!(given.near_plane > 0.0f) || !std::isfinite(given.near_plane) ||
        !(given.far_plane > given.near_plane))
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    field + ": near_plane " + std::to_string(given.near_plane) + " and far_plane " +
                        std::to_string(given.far_plane) + " must satisfy 0 < near < far");
    if (!std::isfinite(given.jitter[0]) || !std::isfinite(given.jitter[1]))
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, field + ".jitter is not finite");
    camera.view = to_matrix(given.view);
    camera.projection = to_matrix(given.projection);
    camera.prev_view = to_matrix(given.prev_view);
    camera.prev_projection = to_matrix(given.prev_projection);
    camera.near = given.near_plane;
    camera.far = given.far_plane;
    camera.jitter = {given.jitter[0], given.jitter[1]};
    return REPRISE_OK;
}

void write_camera(const Camera& camera, reprise_camera& out) {
    out = reprise_camera{};
    out.time = camera.time;
    from_matrix(camera.view, out.view);
    from_matrix(camera.projection, out.projection);
    from_matrix(camera.prev_view, out.prev_view);
    from_matrix(camera.prev_projection, out.prev_projection);
    out.jitter[0] = camera.jitter.x;
    out.jitter[1] = camera.jitter.y;
    out.near_plane = camera.near;
    out.far_plane = camera.far;
    out.valid = has_projection(camera) ? 1 : 0;
}

struct OutputChannel {
    const Spec& spec;
    unsigned bit;
    reprise_image reprise_gbuffer::*image;
};
constexpr OutputChannel kChannels[] = {
    {kColorSpec, kColor, &reprise_gbuffer::color},
    {kDepthSpec, kDepth, &reprise_gbuffer::depth},
    {kMotionSpec, kMotion, &reprise_gbuffer::motion},
    {kNormalSpec, kNormal, &reprise_gbuffer::normal},
    {kIdSpec, kId, &reprise_gbuffer::id},
    {kUiSpec, kUi, &reprise_gbuffer::ui},
};

bool frame_has(const Frame& frame, unsigned bit) {
    switch (bit) {
        case kColor:
            return !frame.color.empty();
        case kDepth:
            return !frame.depth.empty();
        case kMotion:
            return !frame.motion.empty();
        case kNormal:
            return !frame.normal.empty();
        case kId:
            return !frame.id.empty();
        default:
            return !frame.ui.empty();
    }
}

reprise_status check_gbuffer_struct(const char* function, const char* name,
                                    const reprise_gbuffer* gbuffer) {
    REPRISE_CAPI_TRY(check_pointer(function, gbuffer, name));
    return check_struct_size(function, (std::string(name) + "->struct_size").c_str(),
                             gbuffer->struct_size, kSizes<reprise_gbuffer>);
}

}  // namespace

reprise_status read_gbuffer(const char* function, const char* name, const reprise_gbuffer* given,
                            unsigned read, Frame& frame, Image<glm::u8vec4>* display) {
    REPRISE_CAPI_TRY(check_gbuffer_struct(function, name, given));
    const std::string prefix = std::string(name) + "->";
    if (given->reset < REPRISE_RESET_UNKNOWN || given->reset > REPRISE_RESET_NO)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    prefix + "reset " + std::to_string(given->reset) +
                        " is not REPRISE_RESET_UNKNOWN (0), _YES (1) or _NO (2)");
    if (!given->color.data)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    prefix + "color.data is NULL: colour is required");
    const std::string n = name;
    const bool srgb8 = display && given->color.format == REPRISE_FORMAT_RGBA8_SRGB;
    REPRISE_CAPI_TRY(
        check_image(function, n, srgb8 ? kDisplaySpec : kColorSpec, given->color, 0, 0));
    const int w = given->color.width, h = given->color.height;
    if (srgb8) {
        read_pixels(given->color, *display);
        frame.color.clear();
    } else {
        if (display) display->clear();
        read_pixels(given->color, frame.color);
    }
    REPRISE_CAPI_TRY(
        read_channel(function, n, kDepthSpec, given->depth, read & kDepth, w, h, frame.depth));
    REPRISE_CAPI_TRY(
        read_channel(function, n, kMotionSpec, given->motion, read & kMotion, w, h, frame.motion));
    REPRISE_CAPI_TRY(
        read_channel(function, n, kNormalSpec, given->normal, read & kNormal, w, h, frame.normal));
    REPRISE_CAPI_TRY(read_channel(function, n, kIdSpec, given->id, read & kId, w, h, frame.id));
    REPRISE_CAPI_TRY(read_channel(function, n, kUiSpec, given->ui, read & kUi, w, h, frame.ui));
    REPRISE_CAPI_TRY(read_camera(function, n, given->camera, frame.camera));
    frame.camera.cut = given->reset == REPRISE_RESET_YES  ? Cut::Yes
                       : given->reset == REPRISE_RESET_NO ? Cut::No
                                                          : Cut::Unknown;
    if (!std::isfinite(given->fps) || given->fps < 0.0)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    prefix + "fps " + std::to_string(given->fps) + " is not 0 or positive");
    frame.fps = given->fps;
    return REPRISE_OK;
}

reprise_status check_output(const char* function, const reprise_gbuffer* out, int width, int height,
                            unsigned written, bool srgb8) {
    REPRISE_CAPI_TRY(check_gbuffer_struct(function, "out", out));
    for (const OutputChannel& channel : kChannels) {
        const reprise_image& image = out->*channel.image;
        if (!image.data) {
            if (channel.bit == kColor)
                return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                            "out->color.data is NULL: colour is required");
            continue;
        }
        if (!(written & channel.bit))
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        std::string("out->") + channel.spec.field + ": this call writes no " +
                            channel.spec.field + " (leave its data NULL)");
        const Spec& spec = channel.bit == kColor && srgb8 ? kDisplaySpec : channel.spec;
        REPRISE_CAPI_TRY(check_image(function, "out", spec, image, width, height));
    }
    return REPRISE_OK;
}

reprise_status write_gbuffer(const char* function, const Frame& frame, reprise_gbuffer* out,
                             const Image<glm::u8vec4>* display) {
    for (const OutputChannel& channel : kChannels)
        if ((out->*channel.image).data && !frame_has(frame, channel.bit) &&
            !(channel.bit == kColor && display && !display->empty()))
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        std::string("out->") + channel.spec.field + ": this frame has no " +
                            channel.spec.field + " (its input had none; leave data NULL)");
    if (display && !display->empty())
        write_pixels(*display, out->color);
    else
        write_pixels(frame.color, out->color);
    if (out->depth.data) write_pixels(frame.depth, out->depth);
    if (out->motion.data) write_pixels(frame.motion, out->motion);
    if (out->normal.data) write_pixels(frame.normal, out->normal);
    if (out->id.data) write_pixels(frame.id, out->id);
    if (out->ui.data) write_pixels(frame.ui, out->ui);
    write_camera(frame.camera, out->camera);
    out->fps = frame.fps;
    out->reset = frame.camera.cut == Cut::Yes  ? REPRISE_RESET_YES
                 : frame.camera.cut == Cut::No ? REPRISE_RESET_NO
                                               : REPRISE_RESET_UNKNOWN;
    return REPRISE_OK;
}

reprise_status held_size(const char* function, const HeldFrame& next, int32_t* width,
                         int32_t* height) {
    REPRISE_CAPI_TRY(check_pointer(function, width, "width"));
    REPRISE_CAPI_TRY(check_pointer(function, height, "height"));
    *width = *height = 0;
    if (!next.held) return REPRISE_NEED_MORE;
    *width = next.width();
    *height = next.height();
    return REPRISE_OK;
}

reprise_status receive_held(const char* function, HeldFrame& next, unsigned written,
                            reprise_gbuffer* out) {
    if (!next.held) {
        REPRISE_CAPI_TRY(check_gbuffer_struct(function, "out", out));
        return REPRISE_NEED_MORE;
    }
    REPRISE_CAPI_TRY(
        check_output(function, out, next.width(), next.height(), written, !next.display.empty()));
    REPRISE_CAPI_TRY(write_gbuffer(function, next.frame, out, &next.display));
    next.held = false;
    return REPRISE_OK;
}

}  // namespace reprise::capi

extern "C" reprise_status reprise_gbuffer_init(reprise_gbuffer* gbuffer, size_t struct_size) {
    using namespace reprise::capi;
    return guarded("reprise_gbuffer_init", [&] {
        const char* function = "reprise_gbuffer_init";
        REPRISE_CAPI_TRY(check_pointer(function, gbuffer, "gbuffer"));
        REPRISE_CAPI_TRY(
            check_struct_size(function, "struct_size", struct_size, kSizes<reprise_gbuffer>));
        *gbuffer = reprise_gbuffer{};
        gbuffer->struct_size = uint32_t(sizeof(reprise_gbuffer));
        return reprise_status(REPRISE_OK);
    });
}
