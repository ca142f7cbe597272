// read_frame / read_frame_header: reprise frames and Blender multilayer renders.
// Channel layouts, header attributes and the Blender mapping are in docs/exr_format.md.
#include <OpenImageIO/half.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <limits>
#include <memory>
#include <string_view>
#include <vector>

#include "reprise/core/exr.hpp"
#include "reprise/core/memory_limit.hpp"

namespace reprise {
namespace {

namespace fs = std::filesystem;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

enum Slot {
    R,
    G,
    B,
    A,
    Z,
    MotionX,
    MotionY,
    NormalX,
    NormalY,
    NormalZ,
    Id,
    UiR,
    UiG,
    UiB,
    UiA,
    kSlots
};
using Channels = std::array<int, kSlots>;  // file channel index per slot, -1 when absent

constexpr std::array<const char*, kSlots> kRepriseNames = {
    "R",   "G",   "B",  "A",    "Z",    "motion.x", "motion.y", "N.X",
    "N.Y", "N.Z", "id", "ui.R", "ui.G", "ui.B",     "ui.A"};

struct Layout {
    Channels channel;
    bool blender = false;
};

bool complete(const Channels& c, std::initializer_list<Slot> slots) {
    return std::all_of(slots.begin(), slots.end(), [&](Slot s) { return c[s] >= 0; });
}

std::string type_name(TypeDesc type) {
    if (type == TypeDesc::HALF) return "half";
    if (type == TypeDesc::FLOAT) return "float";
    if (type == TypeDesc::UINT) return "uint";
    return type.c_str();
}

// The size OpenEXR reads for a value of a fixed-size type; -1 for the others.
int natural_size(const std::string& type) {
    static const std::pair<const char*, int> sizes[] = {
        {"box2i", 16},      {"box2f", 16},        {"chromaticities", 32},
        {"compression", 1}, {"double", 8},        {"envmap", 1},
        {"float", 4},       {"int", 4},           {"keycode", 28},
        {"lineOrder", 1},   {"m22f", 16},         {"m22d", 32},
        {"m33f", 36},       {"m33d", 72},         {"m44f", 64},
        {"m44d", 128},      {"rational", 8},      {"tiledesc", 9},
        {"timecode", 8},    {"v2i", 8},           {"v2f", 8},
        {"v2d", 16},        {"v3i", 12},          {"v3f", 12},
        {"v3d", 24},        {"deepImageState", 1}};
    for (const auto& [name, size] : sizes)
        if (type == name) return size;
    return -1;
}

// A preview is width, height and 4 bytes a pixel; a string vector is length-prefixed strings.
bool sizes_inside_fit(const std::string& type, const std::vector<char>& value) {
    auto u32 = [&](std::size_t at) {
        uint32_t v;
        std::memcpy(&v, value.data() + at, 4);
        return v;
    };
    if (type == "preview")
        return value.size() >= 8 && uint64_t(u32(0)) * u32(4) * 4 + 8 == value.size();
    for (std::size_t at = 0; at < value.size();) {
        if (value.size() - at < 4) return false;
        const uint64_t length = u32(at);
        at += 4;
        if (length > value.size() - at) return false;
        at += std::size_t(length);
    }
    return true;
}

// OpenEXR allocates each header attribute at its declared size before reading it, and buffers
// for the data window's width before the size check in open_exr, so a few hundred bytes can ask
// for gigabytes. Every attribute must fit in the file and every header must hold a dataWindow
// within kMaxImageSide (OpenEXR 2 layout: magic, version and flags, then headers of
// `name\0 type\0 int32 size, value` ended by an empty name, names of at most 31 bytes or 255 with
// the long-names flag; a multi-part file ends its list of headers with an empty header). A file
// without the magic is left to OpenImageIO's own error.
Status check_exr_header(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    std::error_code ec;
    const uint64_t file_size = fs::file_size(path, ec);
    unsigned char start[8];
    if (!file || ec || !file.read(reinterpret_cast<char*>(start), 8)) return {};
    if (std::memcmp(start, "\x76\x2f\x31\x01", 4) != 0) return {};
    const bool multipart = (start[5] & 0x10) != 0;
    // OpenEXR reads at most this many bytes of a name and goes on from there: longer names would
    // put this walk and OpenEXR's out of step.
    const std::size_t max_name = (start[5] & 0x04) != 0 ? 255 : 31;
    auto fail = [&](const std::string& problem) {
        return Status::error(path + ": not a readable OpenEXR file (header: " + problem + ")");
    };
    // A name or type: at most max_name bytes and a terminating 0; an empty name ends a header.
    auto read_name = [&](std::string& name) {
        name.clear();
        for (char c; file.get(c);) {
            if (c == 0) return true;
            if (name.size() == max_name) return false;
            name += c;
        }
        return false;
    };
    std::string name, type;
    bool empty_header = true, data_window = false;
    int64_t image[2] = {0, 0};
    uint32_t tile[2] = {0, 0};  // 0 for scanline parts
    int64_t channels = 0, chunk_lines = 1;
    for (;;) {
        if (!read_name(name)) return fail("truncated or overlong attribute name");
        if (name.empty()) {
            // A single-part file has one header, a multi-part list ends with an empty one.
            if (empty_header && multipart) return {};
            if (!data_window) return fail("no dataWindow");
            // OpenEXR decodes whole tiles: a 1x1 image in one 8192x8192 tile costs gigabytes.
            // Real tiles are at most 64 pixels or as large as the image.
            for (int axis = 0; axis < 2; ++axis)
                if (tile[axis] > std::max<int64_t>(image[axis], 64))
                    return fail("tile " + std::to_string(tile[0]) + "x" + std::to_string(tile[1]) +
                                " is larger than the " + std::to_string(image[0]) + "x" +
                                std::to_string(image[1]) + " image");
            // The compressor's buffers hold a chunk of rows of every channel (4 bytes a sample
            // at most): an 8K frame of 11 channels in DWAB's 256 rows needs 90 MiB.
            const int64_t chunk_bytes = image[0] * std::max<int64_t>(channels, 1) * 4 * chunk_lines;
            if (chunk_bytes > (int64_t(512) << 20))
                return fail(std::to_string(channels) + " channels of " + std::to_string(image[0]) +
                            " pixels in chunks of " + std::to_string(chunk_lines) +
                            " rows need more than 512 MiB of compression buffers");
            if (!multipart) return {};
            empty_header = true;
            data_window = false;
            tile[0] = tile[1] = 0;
            channels = 0;
            chunk_lines = 1;
            continue;
        }
        empty_header = false;
        if (!read_name(type)) return fail("attribute " + name + ": truncated type name");
        unsigned char size_bytes[4];
        if (!file.read(reinterpret_cast<char*>(size_bytes), 4))
            return fail("attribute " + name + ": truncated size");
        int32_t size;
        std::memcpy(&size, size_bytes, 4);
        const uint64_t at = uint64_t(file.tellg());
        if (size < 0 || at + uint64_t(size) > file_size)
            return fail("attribute " + name + " declares " + std::to_string(size) +
                        " bytes, more than the " + std::to_string(file_size - at) + " left");
        // OpenEXR reads a value of a known type at that type's size, whatever the declared one,
        // and then goes on out of step with the declared sizes.
        if (const int natural = natural_size(type); natural >= 0 && size != natural)
            return fail("attribute " + name + " of type " + type + " declares " +
                        std::to_string(size) + " bytes, not " + std::to_string(natural));
        if (name == "channels" && type == "chlist") {
            // Entries are a name ended by 0 and 16 bytes; the list ends with an empty name.
            std::vector<char> value(std::size_t(size), 0);
            file.read(value.data(), size);
            // OpenEXR sizes its row buffers from each channel's type and sampling.
            std::size_t i = 0;
            for (; i < value.size() && value[i] != 0; ++channels) {
                while (i < value.size() && value[i] != 0) ++i;
                int32_t entry[4];  // pixel type, linear + reserved, x and y sampling
                if (value.size() - i < 17) return fail("channels: truncated channel list");
                std::memcpy(entry, value.data() + i + 1, 16);
                if (entry[0] < 0 || entry[0] > 2 || entry[2] != 1 || entry[3] != 1)
                    return fail("channels: type " + std::to_string(entry[0]) + ", sampling " +
                                std::to_string(entry[2]) + "x" + std::to_string(entry[3]) +
                                " (types 0..2 and full-resolution channels only)");
                i += 17;
            }
            // OpenEXR reads entries up to the empty name, whatever the declared size.
            if (i + 1 != value.size())
                return fail("channels: the list ends at byte " + std::to_string(i + 1) +
                            " of the " + std::to_string(size) + " it declares");
            continue;
        }
        if (name == "compression" && type == "compression" && size == 1) {
            char method = 0;
            file.read(&method, 1);
            // Rows per chunk: none, RLE, ZIPS 1; ZIP, PXR24 16; PIZ, B44, B44A, DWAA 32; DWAB 256.
            static const int kLines[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
            chunk_lines = method >= 0 && method < 10 ? kLines[int(method)] : 256;
            continue;
        }
        if (type == "preview" || type == "stringvector") {
            // Sizes inside the value that OpenEXR allocates before reading: they must add up.
            std::vector<char> value(std::size_t(size), 0);
            file.read(value.data(), size);
            if (!sizes_inside_fit(type, value))
                return fail("attribute " + name + " of type " + type +
                            ": its sizes do not add up to the " + std::to_string(size) +
                            " bytes it declares");
            continue;
        }
        if (name == "dataWindow" && type == "box2i" && size == 16) {
            int32_t box[4];
            file.read(reinterpret_cast<char*>(box), 16);
            const int64_t width = int64_t(box[2]) - box[0] + 1,
                          height = int64_t(box[3]) - box[1] + 1;
            if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
                return fail("dataWindow " + std::to_string(width) + "x" + std::to_string(height) +
                            " is outside 1.." + std::to_string(kMaxImageSide));
            data_window = true;
            image[0] = width;
            image[1] = height;
        } else if (name == "tiles" && type == "tiledesc" && size == 9) {
            file.read(reinterpret_cast<char*>(tile), 8);
            file.seekg(1, std::ios::cur);
        } else {
            file.seekg(size, std::ios::cur);
        }
    }
}

Status open_exr(const std::string& path, std::unique_ptr<OIIO::ImageInput>& in) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) return Status::error(path + ": no such file");
    if (fs::is_directory(status)) return Status::error(path + ": is a folder, not an EXR file");
    REPRISE_TRY(check_exr_header(path));
    // Only the OpenEXR reader: a file that is not EXR must fail, whatever else it may be.
    in = OIIO::ImageInput::create("openexr");
    if (!in) return Status::error(path + ": " + OIIO::geterror());
    ImageSpec spec;
    if (!in->open(path, spec)) {
        std::string why = in->geterror();
        in.reset();
        return Status::error(path + ": not a readable OpenEXR file" +
                             (why.empty() ? std::string() : " (" + why + ")"));
    }
    if (spec.deep) return Status::error(path + ": deep EXR images are not supported");
    if (spec.depth > 1) return Status::error(path + ": volume EXR images are not supported");
    REPRISE_TRY(check_image_size(spec.width, spec.height, path));
    for (int c = 0; c < spec.nchannels; ++c) {
        const TypeDesc type = spec.channelformat(c);
        if (type != TypeDesc::HALF && type != TypeDesc::FLOAT && type != TypeDesc::UINT)
            return Status::error(path + ": channel " + spec.channelnames[c] + " has type " +
                                 type_name(type));
    }
    return {};
}

// Blender multilayer names are LAYER.PASS.CHANNEL or LAYER.PASS.VIEW.CHANNEL (OpenEXR's
// multi-view naming); layer names may contain dots themselves.
struct BlenderChannel {
    std::string group;  // LAYER|VIEW
    Slot slot;
};

bool parse_blender(std::string_view name, BlenderChannel& out) {
    std::vector<std::string_view> tokens;
    for (std::size_t start = 0;;) {
        const std::size_t dot = name.find('.', start);
        tokens.push_back(name.substr(start, dot - start));
        if (dot == std::string_view::npos) break;
        start = dot + 1;
    }
    if (tokens.size() < 2) return false;
    const std::string_view letter = tokens.back();
    struct Pass {
        std::string_view pass, letter;
        Slot slot;
    };
    static constexpr Pass kPasses[] = {
        {"Combined", "R", R},     {"Combined", "G", G},     {"Combined", "B", B},
        {"Combined", "A", A},     {"Depth", "Z", Z},        {"Vector", "X", MotionX},
        {"Vector", "Y", MotionY}, {"Normal", "X", NormalX}, {"Normal", "Y", NormalY},
        {"Normal", "Z", NormalZ}, {"IndexOB", "X", Id},     {"UI", "R", UiR},
        {"UI", "G", UiG},         {"UI", "B", UiB},         {"UI", "A", UiA},
    };
    for (std::size_t k = tokens.size() - 1; k-- > 0;) {
        for (const Pass& p : kPasses) {
            if (tokens[k] != p.pass || letter != p.letter) continue;
            // group = everything but the pass and the channel letter
            std::string group;
            for (std::size_t t = 0; t + 1 < tokens.size(); ++t) {
                if (t == k)
                    group += '|';
                else
                    group.append(tokens[t]).append(".");
            }
            out = {group, p.slot};
            return true;
        }
    }
    return false;
}

// Picks the layer (and view) with a complete Combined pass and the most other passes.
bool find_blender_layout(const ImageSpec& spec, Layout& layout) {
    std::vector<std::pair<std::string, Channels>> groups;  // in file order
    for (int c = 0; c < spec.nchannels; ++c) {
        BlenderChannel bc;
        if (!parse_blender(spec.channelnames[c], bc)) continue;
        auto it = std::find_if(groups.begin(), groups.end(),
                               [&](const auto& g) { return g.first == bc.group; });
        if (it == groups.end()) {
            Channels none;
            none.fill(-1);
            it = groups.insert(groups.end(), {bc.group, none});
        }
        if (it->second[bc.slot] < 0) it->second[bc.slot] = c;
    }
    int best_score = -1;
    for (auto& [group, c] : groups) {
        if (!complete(c, {R, G, B})) continue;
        // Incomplete optional passes are left out.
        if (!complete(c, {MotionX, MotionY})) c[MotionX] = c[MotionY] = -1;
        if (!complete(c, {NormalX, NormalY, NormalZ})) c[NormalX] = c[NormalY] = c[NormalZ] = -1;
        if (!complete(c, {UiR, UiG, UiB, UiA})) c[UiR] = c[UiG] = c[UiB] = c[UiA] = -1;
        const int score = (c[Z] >= 0) + (c[MotionX] >= 0) + (c[NormalX] >= 0) + (c[Id] >= 0);
        if (score > best_score) {
            best_score = score;
            layout = {.channel = c, .blender = true};
        }
    }
    return best_score >= 0;
}

Status find_layout(const ImageSpec& spec, const std::string& path, Layout& layout) {
    Channels c;
    for (int s = 0; s < kSlots; ++s) c[s] = spec.channelindex(kRepriseNames[s]);
    if (c[R] < 0 && c[G] < 0 && c[B] < 0 && find_blender_layout(spec, layout)) return {};
    for (Slot s : {R, G, B})
        if (c[s] < 0)
            return Status::error(path + ": no colour channel " + kRepriseNames[s] +
                                 " (nor a Blender Combined pass)");
    auto group = [&](std::initializer_list<Slot> slots) {
        const bool any = std::any_of(slots.begin(), slots.end(), [&](Slot s) { return c[s] >= 0; });
        for (Slot s : slots)
            if (any && c[s] < 0)
                return Status::error(path + ": channel " + kRepriseNames[s] + " is missing");
        return ok();
    };
    REPRISE_TRY(group({MotionX, MotionY}));
    REPRISE_TRY(group({NormalX, NormalY, NormalZ}));
    REPRISE_TRY(group({UiR, UiG, UiB, UiA}));
    layout = {.channel = c, .blender = false};
    return {};
}

bool get_matrix(const ImageSpec& spec, const char* name, glm::mat4& m) {
    // Imath's row-vector M44f holds the same 16 floats, in the same order, as glm's mat4.
    return spec.getattribute(name, OIIO::TypeMatrix44, glm::value_ptr(m));
}

void read_camera(const ImageSpec& spec, Camera& camera, bool& has_camera) {
    camera = Camera{};
    glm::mat4 world_to_camera, world_to_ndc;
    const bool view = get_matrix(spec, "worldToCamera", world_to_camera);
    // Negating z again is exact: the view comes back bit for bit.
    if (view) camera.view = exr_world_to_camera(world_to_camera);
    bool projection = get_matrix(spec, "reprise:projection", camera.projection);
    if (!projection && view && get_matrix(spec, "worldToNDC", world_to_ndc)) {
        // A file from elsewhere: undo exr_world_to_ndc's clip-to-NDC step.
        const glm::mat4 ndc_to_clip(glm::vec4(2, 0, 0, 0), glm::vec4(0, -2, 0, 0),
                                    glm::vec4(0, 0, 1, 0), glm::vec4(-1, 1, 0, 1));
        camera.projection = ndc_to_clip * world_to_ndc * glm::inverse(camera.view);
        projection = true;
    }
    has_camera = view || projection;
    if (!get_matrix(spec, "reprise:prevView", camera.prev_view)) camera.prev_view = camera.view;
    if (!get_matrix(spec, "reprise:prevProjection", camera.prev_projection))
        camera.prev_projection = camera.projection;
    spec.getattribute("reprise:near", OIIO::TypeFloat, &camera.near);
    spec.getattribute("reprise:far", OIIO::TypeFloat, &camera.far);
    spec.getattribute("reprise:jitter", OIIO::TypeVector2, glm::value_ptr(camera.jitter));
    spec.getattribute("reprise:time", TypeDesc::DOUBLE, &camera.time);
    int cut = 0;
    if (spec.getattribute("reprise:cut", TypeDesc::INT, &cut))
        camera.cut = cut ? Cut::Yes : Cut::No;
}

double read_fps(const ImageSpec& spec) {
    double fps = 0.0;
    if (spec.getattribute("reprise:fps", TypeDesc::DOUBLE, &fps)) return fps;
    int rational[2] = {0, 0};  // OpenEXR's standard framesPerSecond
    if (spec.getattribute("FramesPerSecond", OIIO::TypeRational, rational) && rational[1] != 0)
        return double(rational[0]) / double(rational[1]);
    return 0.0;
}

float to_float(TypeDesc type, const unsigned char* p) {
    if (type == TypeDesc::FLOAT) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    if (type == TypeDesc::HALF) {
        uint16_t bits;
        std::memcpy(&bits, p, 2);
        Imath::half h;
        h.setBits(bits);
        return float(h);
    }
    uint32_t v;
    std::memcpy(&v, p, 4);
    return float(v);
}

uint32_t to_uint(TypeDesc type, const unsigned char* p) {
    if (type == TypeDesc::UINT) {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    // A float id (Blender's IndexOB): rounded; NaN and negatives are background.
    const float f = to_float(type, p);
    if (!(f > 0.0f)) return 0;
    return f >= 4294967295.0f ? std::numeric_limits<uint32_t>::max() : uint32_t(std::lround(f));
}

// One slot's destination: a 4-byte component of one of the Frame's buffers.
struct Target {
    int channel;
    unsigned char* first;
    std::size_t stride;
    bool is_uint;
};

template <class T>
void add_target(std::vector<Target>& targets, int channel, Image<T>& image, int component) {
    if (channel < 0) return;
    targets.push_back({channel, reinterpret_cast<unsigned char*>(image.data()) + 4 * component,
                       sizeof(T), std::is_same_v<T, uint32_t>});
}

template <class T>
void fit(Image<T>& image, bool present, int width, int height) {
    if (present)
        image.assign(width, height, T{});  // channels the file lacks read as 0
    else
        image.clear();
}

}  // namespace

Status read_frame_header(const std::string& path, FrameHeader& header) {
    std::unique_ptr<OIIO::ImageInput> in;
    REPRISE_TRY(open_exr(path, in));
    const ImageSpec& spec = in->spec();
    Layout layout;
    REPRISE_TRY(find_layout(spec, path, layout));
    header = FrameHeader{.width = spec.width, .height = spec.height, .blender = layout.blender};
    for (int c = 0; c < spec.nchannels; ++c) {
        header.channels.push_back(spec.channelnames[c]);
        header.channel_types.push_back(type_name(spec.channelformat(c)));
    }
    read_camera(spec, header.camera, header.has_camera);
    header.fps = read_fps(spec);
    return {};
}

Status read_frame(const std::string& path, Frame& frame) {
    std::unique_ptr<OIIO::ImageInput> in;
    REPRISE_TRY(open_exr(path, in));
    const ImageSpec& spec = in->spec();
    Layout layout;
    REPRISE_TRY(find_layout(spec, path, layout));
    const Channels& c = layout.channel;

    const int width = spec.width;
    const int height = spec.height;
    // The frame's buffers, checked before any pixel is read (the header alone can claim 16384^2).
    const std::uint64_t bytes_per_pixel =
        sizeof(glm::vec4) + (c[Z] >= 0) * sizeof(float) + (c[MotionX] >= 0) * sizeof(glm::vec2) +
        (c[NormalX] >= 0) * sizeof(glm::vec3) + (c[Id] >= 0) * sizeof(uint32_t) +
        (c[UiR] >= 0) * sizeof(glm::vec4);
    REPRISE_TRY(check_memory(
        std::uint64_t(width) * std::uint64_t(height) * bytes_per_pixel,
        path + ": " + std::to_string(width) + "x" + std::to_string(height) + " frame"));
    frame.color.assign(width, height, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    fit(frame.depth, c[Z] >= 0, width, height);
    fit(frame.motion, c[MotionX] >= 0, width, height);
    fit(frame.normal, c[NormalX] >= 0, width, height);
    fit(frame.id, c[Id] >= 0, width, height);
    fit(frame.ui, c[UiR] >= 0, width, height);

    std::vector<Target> targets;
    for (int s = R; s <= A; ++s) add_target(targets, c[s], frame.color, s - R);
    add_target(targets, c[Z], frame.depth, 0);
    add_target(targets, c[MotionX], frame.motion, 0);
    add_target(targets, c[MotionY], frame.motion, 1);
    add_target(targets, c[NormalX], frame.normal, 0);
    add_target(targets, c[NormalY], frame.normal, 1);
    add_target(targets, c[NormalZ], frame.normal, 2);
    add_target(targets, c[Id], frame.id, 0);
    for (int s = UiR; s <= UiA; ++s) add_target(targets, c[s], frame.ui, s - UiR);

    // Read the channel range that holds every target, in the file's own types.
    int chbegin = spec.nchannels, chend = 0;
    for (const Target& t : targets) {
        chbegin = std::min(chbegin, t.channel);
        chend = std::max(chend, t.channel + 1);
    }
    std::vector<std::size_t> offset(chend - chbegin);
    std::size_t pixel_bytes = 0;
    for (int ch = chbegin; ch < chend; ++ch) {
        offset[ch - chbegin] = pixel_bytes;
        pixel_bytes += spec.channelformat(ch).size();
    }

    // Strips of whole rows of tiles for a tiled file.
    const int tile = spec.tile_width > 0 ? std::max(spec.tile_height, 1) : 1;
    const int strip_rows = std::min(height, tile * std::max(1, 64 / tile));
    std::vector<unsigned char> strip(std::size_t(strip_rows) * width * pixel_bytes);
    for (int y0 = 0; y0 < height; y0 += strip_rows) {
        const int y1 = std::min(height, y0 + strip_rows);
        const bool read =
            spec.tile_width > 0
                ? in->read_tiles(0, 0, spec.x, spec.x + width, spec.y + y0, spec.y + y1, spec.z,
                                 spec.z + 1, chbegin, chend, TypeDesc::UNKNOWN, strip.data())
                : in->read_scanlines(0, 0, spec.y + y0, spec.y + y1, spec.z, chbegin, chend,
                                     TypeDesc::UNKNOWN, strip.data());
        if (!read)
            return Status::error(path + ": cannot read pixels, the file is truncated or corrupt (" +
                                 in->geterror() + ")");
        const std::size_t first = std::size_t(y0) * width;
        const std::size_t count = std::size_t(y1 - y0) * width;
        for (const Target& t : targets) {
            const TypeDesc type = spec.channelformat(t.channel);
            const unsigned char* from = strip.data() + offset[t.channel - chbegin];
            unsigned char* to = t.first + first * t.stride;
            for (std::size_t i = 0; i < count; ++i, from += pixel_bytes, to += t.stride) {
                if (t.is_uint) {
                    const uint32_t v = to_uint(type, from);
                    std::memcpy(to, &v, 4);
                } else if (type == TypeDesc::FLOAT) {
                    std::memcpy(to, from, 4);  // bit exact, NaN payloads included
                } else {
                    const float v = to_float(type, from);
                    std::memcpy(to, &v, 4);
                }
            }
        }
    }

    if (layout.blender) {
        // Cycles marks background depth with 1e10; Blender's vector pass has +y up.
        float* depth = frame.depth.data();
        for (std::size_t i = 0; i < frame.depth.pixel_count(); ++i)
            if (depth[i] >= 1e10f) depth[i] = std::numeric_limits<float>::infinity();
        for (std::size_t i = 0; i < frame.motion.pixel_count(); ++i)
            frame.motion.data()[i].y = -frame.motion.data()[i].y;
    }

    bool has_camera = false;
    read_camera(spec, frame.camera, has_camera);
    frame.fps = read_fps(spec);
    return {};
}

}  // namespace reprise
