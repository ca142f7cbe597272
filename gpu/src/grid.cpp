// The adaptive grid warp on the GPU: warp::GridWarper's cells (grown by grid_cells.cpp, or on
// the CPU) drawn by GL's rasteriser. Each triangle is drawn as its
// pixel bounding box; the fragment shader keeps the pixel centres inside the CPU's integer edge
// functions (1/256-px vertices, edges pushed out by 1/16 px, products in 64 bits through
// imulExtended), evaluates the CPU's attribute planes at the centre with its clamps, and the
// depth test keeps the nearest, ties to the first cell drawn (GL draws in order), as the CPU.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "state.hpp"

namespace reprise::gpu {

namespace {

static_assert(sizeof(warp::GridCell) == 116, "the shader reads a cell as 29 words");
constexpr int kCellWords = 29;

constexpr const char* kGraphicsHeader = R"(
precision highp float;
precision highp int;
bool finite(highp float v) { return (floatBitsToUint(v) & 0x7f800000u) != 0x7f800000u; }
// x * y - z * w + 16 * e >= 0 (e >= 0), exactly: 64-bit products and sums.
bool edge_inside(int x, int y, int z, int w, int e) {
    int h1, l1, h2, l2, h3, l3;
    imulExtended(x, y, h1, l1);
    imulExtended(z, w, h2, l2);
    imulExtended(16, e, h3, l3);
    uint borrow, carry;
    uint lo = usubBorrow(uint(l1), uint(l2), borrow);
    uint hi = uint(h1) - uint(h2) - borrow;
    lo = uaddCarry(lo, uint(l3), carry);
    hi += uint(h3) + carry;
    return (hi & 0x80000000u) == 0u;
}
)";

// One cell's triangle per 6 vertices (two per cell): its bounding box of pixel centres, and its
// edges and attribute planes (grid_raster.cpp's Triangle) for the fragment shader, the same in
// each of its vertices.
constexpr const char* kVertex = R"(
layout(std430, binding = 1) readonly buffer Cells { uint words[]; };
uniform ivec2 target_size, source_size;
flat out ivec4 ab;   // vertices a and b, 1/256 px (b and c swapped for fold-overs)
flat out ivec2 c;
flat out vec4 z_plane;  // at a, gradient x, y, lo
flat out vec4 z_more;   // hi, depth lo, hi (perspective), stretch scale
flat out vec4 sx_plane; // at a, gradient x, y, stretch span
flat out vec4 sy_plane; // at a, gradient x, y
flat out vec4 source_clamp;  // sx lo, hi, sy lo, hi
flat out vec4 mx_plane, my_plane;  // at a, gradient x, y, lo
flat out vec2 motion_hi;
flat out int flags;  // 1: perspective, 2: stretched

const int kSubpixel = 256, kOverlap = 16;
int first_centre(int v) { return (v - kSubpixel / 2 + kSubpixel - 1) >> 8; }
int last_centre(int v) { return (v - kSubpixel / 2) >> 8; }

struct Vertex { ivec2 p; highp float sx, sy, z, mx, my; };
Vertex vertex_at(uint base, int k) {
    uint o = base + uint(7 * k);
    return Vertex(ivec2(int(words[o]), int(words[o + 1u])), uintBitsToFloat(words[o + 2u]),
                  uintBitsToFloat(words[o + 3u]), uintBitsToFloat(words[o + 4u]),
                  uintBitsToFloat(words[o + 5u]), uintBitsToFloat(words[o + 6u]));
}

// Value at a, gradients and the least of the three; e = (b - a, c - a) in pixels.
vec4 plane(highp float va, highp float vb, highp float vc, highp vec4 e, highp float inverse_det) {
    PRECISE highp float d1 = vb - va, d2 = vc - va;
    PRECISE highp float gx = (d1 * e.w - d2 * e.y) * inverse_det;
    PRECISE highp float gy = (d2 * e.x - d1 * e.z) * inverse_det;
    return vec4(va, gx, gy, min(va, min(vb, vc)));
}
// 1/z is affine in screen space on a plane; depth 0 stands in as 1e-30.
highp float reciprocal(highp float z) { return 1.0 / max(z, 1e-30); }

void main() {
    int id = gl_VertexID;
    uint base = uint(id / 12) * 29u;
    int tri = (id / 6) % 2, corner = id % 6;
    Vertex a = vertex_at(base, 0), b = vertex_at(base, tri == 0 ? 1 : 2),
           cv = vertex_at(base, tri == 0 ? 2 : 3);
    uint cell_flags = words[base + 28u];
    bool perspective = (cell_flags & 0xffu) != 0u;
    bool stretched = ((cell_flags >> (8u + 8u * uint(tri))) & 0xffu) == 2u;
    gl_Position = vec4(2.0, 2.0, 0.0, 1.0);  // nothing drawn unless set below
    // The area's sign and zero exactly; fold-overs turned over.
    int bx = b.p.x - a.p.x, by = b.p.y - a.p.y, cx = cv.p.x - a.p.x, cy = cv.p.y - a.p.y;
    int h1, l1, h2, l2;
    imulExtended(bx, cy, h1, l1);
    imulExtended(by, cx, h2, l2);
    uint borrow;
    uint lo = usubBorrow(uint(l1), uint(l2), borrow);
    int hi = int(uint(h1) - uint(h2) - borrow);
    if (hi == 0 && lo == 0u) return;
    highp float area = float(hi) * 4294967296.0 + float(lo);
    if (hi < 0) {
        Vertex t = b;
        b = cv;
        cv = t;
        area = -area;
    }
    int x_lo = max(0, first_centre(min(a.p.x, min(b.p.x, cv.p.x)) - kOverlap));
    int x_hi = min(target_size.x - 1, last_centre(max(a.p.x, max(b.p.x, cv.p.x)) + kOverlap));
    int y_lo = max(0, first_centre(min(a.p.y, min(b.p.y, cv.p.y)) - kOverlap));
    int y_hi = min(target_size.y - 1, last_centre(max(a.p.y, max(b.p.y, cv.p.y)) + kOverlap));
    if (x_lo > x_hi || y_lo > y_hi) return;
    bool right = corner == 1 || corner == 2 || corner == 4;
    bool bottom = corner == 2 || corner == 4 || corner == 5;
    vec2 q = vec2(float(right ? x_hi + 1 : x_lo), float(bottom ? y_hi + 1 : y_lo));
    gl_Position = vec4(2.0 * q / vec2(target_size) - 1.0, 0.0, 1.0);

    ab = ivec4(a.p, b.p);
    c = cv.p;
    const highp float scale = 1.0 / 256.0;
    highp vec4 e = vec4(float(b.p.x - a.p.x), float(b.p.y - a.p.y), float(cv.p.x - a.p.x),
                        float(cv.p.y - a.p.y)) * scale;
    highp float inverse_det = 1.0 / (area * (scale * scale));
    highp float stretch_span = 0.0, stretch_scale = 0.0;
    highp float z_lo = min(a.z, min(b.z, cv.z)), z_hi = max(a.z, max(b.z, cv.z));
    if (stretched) {
        stretch_span = max(length(e.xy), max(length(e.zw), length(e.zw - e.xy)));
        stretch_scale = stretch_span / (z_hi - z_lo);
    }
    highp float z_hi_plane;
    if (perspective) {
        z_plane = plane(reciprocal(a.z), reciprocal(b.z), reciprocal(cv.z), e, inverse_det);
        z_hi_plane = max(reciprocal(a.z), max(reciprocal(b.z), reciprocal(cv.z)));
    } else {
        z_plane = plane(a.z, b.z, cv.z, e, inverse_det);
        z_hi_plane = z_hi;
        z_lo = z_hi = 0.0;
    }
    z_more = vec4(z_hi_plane, z_lo, z_hi, stretch_scale);
    sx_plane = vec4(plane(a.sx, b.sx, cv.sx, e, inverse_det).xyz, stretch_span);
    sy_plane = plane(a.sy, b.sy, cv.sy, e, inverse_det);
    // A position within half a pixel of the border reads the border pixel either way.
    source_clamp = vec4(max(min(a.sx, min(b.sx, cv.sx)), 0.5),
                        min(max(a.sx, max(b.sx, cv.sx)), float(source_size.x) - 0.5),
                        max(min(a.sy, min(b.sy, cv.sy)), 0.5),
                        min(max(a.sy, max(b.sy, cv.sy)), float(source_size.y) - 0.5));
    mx_plane = plane(a.mx, b.mx, cv.mx, e, inverse_det);
    my_plane = plane(a.my, b.my, cv.my, e, inverse_det);
    motion_hi = vec2(max(a.mx, max(b.mx, cv.mx)), max(a.my, max(b.my, cv.my)));
    flags = (perspective ? 1 : 0) | (stretched ? 2 : 0);
}
)";

constexpr const char* kFragment = R"(
layout(binding = 0) uniform highp sampler2D source_color;
uniform ivec2 source_size;
uniform bool bicubic_fetch;
flat in ivec4 ab;
flat in ivec2 c;
flat in vec4 z_plane, z_more, sx_plane, sy_plane, source_clamp, mx_plane, my_plane;
flat in vec2 motion_hi;
flat in int flags;
layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_depth;
layout(location = 2) out uvec4 out_covered;
layout(location = 3) out vec4 out_motion;

// The way SSE's max-then-min clamps (NaN gives the lower bound), as the CPU.
highp float clamp_like_sse(highp float v, highp float lo, highp float hi) {
    v = v > lo ? v : lo;
    return v < hi ? v : hi;
}
bool inside(ivec2 p, ivec2 q, ivec2 at) {
    int dx = q.x - p.x, dy = q.y - p.y;
    return edge_inside(dx, at.y - p.y, dy, at.x - p.x, max(abs(dx), abs(dy)));
}
)";
constexpr const char* kFragmentMain = R"(
void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 at = pixel * 256 + 128;
    ivec2 a = ab.xy, b = ab.zw;
    if (!inside(a, b, at) || !inside(b, c, at) || !inside(c, a, at)) discard;
    PRECISE highp vec2 o = vec2(float(pixel.x) + 0.5, float(pixel.y) + 0.5) - vec2(a) * (1.0 / 256.0);
    PRECISE highp float z = z_plane.x + z_plane.y * o.x + z_plane.z * o.y;
    highp float zc = clamp_like_sse(z, z_plane.w, z_more.x);
    if ((flags & 1) != 0) zc = clamp_like_sse(1.0 / zc, z_more.y, z_more.z);
    // Scaled by a power of two: exact, in order, and within the depth buffer's [0, 1] (the
    // background stand-in 1e30 is 0.79); the test keeps the nearer, ties to the first drawn.
    gl_FragDepth = ldexp(abs(zc), -100);
    uint covered = 1u;
    if ((flags & 2) != 0) {
        PRECISE highp float from_near = (zc - z_plane.w) * z_more.w;
        if (from_near >= 1.0 && from_near <= sx_plane.w - 1.0) covered = 2u;
    }
    PRECISE highp float sx = sx_plane.x + sx_plane.y * o.x + sx_plane.z * o.y;
    PRECISE highp float sy = sy_plane.x + sy_plane.y * o.x + sy_plane.z * o.y;
    PRECISE highp float fx = clamp_like_sse(sx, source_clamp.x, source_clamp.y) - 0.5;
    PRECISE highp float fy = clamp_like_sse(sy, source_clamp.z, source_clamp.w) - 0.5;
    if (bicubic_fetch) {
        out_color = bicubic(vec2(fx + 0.5, fy + 0.5));
    } else {
        int x0 = int(fx), y0 = int(fy);
        PRECISE highp float wx = fx - float(x0), wy = fy - float(y0);
        int x1 = x0 < source_size.x - 1 ? x0 + 1 : x0, y1 = y0 < source_size.y - 1 ? y0 + 1 : y0;
        highp vec4 r00 = texelFetch(source_color, ivec2(x0, y0), 0);
        highp vec4 r10 = texelFetch(source_color, ivec2(x1, y0), 0);
        highp vec4 r01 = texelFetch(source_color, ivec2(x0, y1), 0);
        highp vec4 r11 = texelFetch(source_color, ivec2(x1, y1), 0);
        PRECISE highp vec4 top = r00 + (r10 - r00) * wx;
        PRECISE highp vec4 bottom = r01 + (r11 - r01) * wx;
        PRECISE highp vec4 color = top + (bottom - top) * wy;
        out_color = color;
    }
    out_depth = vec4(zc);
    out_covered = uvec4(covered);
    PRECISE highp float mx = mx_plane.x + mx_plane.y * o.x + mx_plane.z * o.y;
    PRECISE highp float my = my_plane.x + my_plane.y * o.x + my_plane.z * o.y;
    out_motion = vec4(clamp_like_sse(mx, mx_plane.w, motion_hi.x),
                      clamp_like_sse(my, my_plane.w, motion_hi.y), 0.0, 0.0);
}
)";

// After the draw (band.cpp's finish_band with stretched kept): background depth to +inf;
// counts covered pixels, those whose colour has a NaN or infinite channel, and stretched ones.
constexpr const char* kFinish = R"(
layout(binding = 0) uniform highp sampler2D color;
layout(binding = 0, r32f) uniform highp image2D depth;
layout(binding = 1, r32ui) readonly uniform highp uimage2D covered;
uniform ivec2 size;
uniform highp float background_from;
void finish(ivec2 p) {
    uint mark = imageLoad(covered, p).r;
    if (mark == 0u) return;
    atomicAdd(group_counts[0], 1u);
    if (mark == 2u) atomicAdd(group_counts[2], 1u);
    highp vec4 c = texelFetch(color, p, 0);
    if (!(finite(c.x) && finite(c.y) && finite(c.z) && finite(c.w))) atomicAdd(group_counts[1], 1u);
    if (imageLoad(depth, p).r >= background_from)
        imageStore(depth, p, vec4(uintBitsToFloat(0x7f800000u)));
}
void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) finish(p);
    count_end();
}
)";

// Sets the rasteriser state the draw needs and puts the application's back when it goes.
class RasterState {
public:
    explicit RasterState(GLuint vertex_array) {
        for (int k = 0; k < kCaps; ++k) enabled_[k] = glIsEnabled(kCap[k]);
        glGetBooleanv(GL_COLOR_WRITEMASK, color_mask_);
        glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &vertex_array_);
        glGetIntegerv(GL_VIEWPORT, viewport_);
        glGetIntegerv(GL_DEPTH_FUNC, &depth_func_);
        glGetBooleanv(GL_DEPTH_WRITEMASK, &depth_mask_);
        glGetFloatv(GL_DEPTH_RANGE, depth_range_);
        for (int k = 0; k < kCaps; ++k) glDisable(kCap[k]);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glDepthRangef(0.0f, 1.0f);
        glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        glBindVertexArray(vertex_array);  // an empty one: the application's may hold arrays
    }
    ~RasterState() {
        for (int k = 0; k < kCaps; ++k) (enabled_[k] ? glEnable : glDisable)(kCap[k]);
        glViewport(viewport_[0], viewport_[1], viewport_[2], viewport_[3]);
        glDepthFunc(GLenum(depth_func_));
        glDepthMask(depth_mask_);
        glDepthRangef(depth_range_[0], depth_range_[1]);
        glColorMask(color_mask_[0], color_mask_[1], color_mask_[2], color_mask_[3]);
        glBindVertexArray(GLuint(vertex_array_));
    }
    RasterState(const RasterState&) = delete;
    RasterState& operator=(const RasterState&) = delete;

private:
    static constexpr int kCaps = 8;
    static constexpr GLenum kCap[kCaps] = {GL_DEPTH_TEST,      GL_BLEND,
                                           GL_SCISSOR_TEST,    GL_CULL_FACE,
                                           GL_STENCIL_TEST,    GL_RASTERIZER_DISCARD,
                                           GL_SAMPLE_COVERAGE, GL_SAMPLE_ALPHA_TO_COVERAGE};
    GLboolean enabled_[kCaps];
    GLint viewport_[4], depth_func_ = GL_LESS, vertex_array_ = 0;
    GLboolean color_mask_[4];
    GLboolean depth_mask_ = GL_TRUE;
    GLfloat depth_range_[2];
};

Status create_grid_programs(ContextState& s) {
    GridRaster& g = s.grid;
    if (g.counts) return {};     // made last: everything before it is ready
    glDeleteProgram(g.program);  // a failed try's
    glDeleteProgram(g.finish_program);
    g.program = g.finish_program = 0;
    GLint blocks = 0;
    glGetIntegerv(GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS, &blocks);
    if (blocks < 1)
        return Status::error(
            "gpu grid warp: " + s.gl->description() +
            " offers no storage buffer in vertex shaders (the cells are read there)");
    const std::string header = std::string(kShaderPrelude) + kGraphicsHeader;
    REPRISE_TRY(gl::link_program((header + kVertex).c_str(),
                                 (header + kFragment + kBicubicFetch + kFragmentMain).c_str(),
                                 "grid warp", g.program));
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + kGroupCounts + kFinish).c_str(),
                                 "grid finish", g.finish_program));
    glGenFramebuffers(1, &g.framebuffer);
    glGenRenderbuffers(1, &g.depth_buffer);
    glGenBuffers(1, &g.cells);
    glGenVertexArrays(1, &g.vertex_array);
    g.counts = s.make_counters(4 * sizeof(GLuint));
    return gl::check_errors("gpu grid warp programs");
}

}  // namespace

void destroy_grid(GridRaster& g) {
    glDeleteProgram(g.program);
    glDeleteProgram(g.finish_program);
    glDeleteFramebuffers(1, &g.framebuffer);
    glDeleteRenderbuffers(1, &g.depth_buffer);
    glDeleteBuffers(1, &g.cells);
    glDeleteBuffers(1, &g.counts);
    glDeleteProgram(g.cells_program);
    glDeleteProgram(g.offsets_program);
    glDeleteProgram(g.eye_valid_program);
    glDeleteBuffers(1, &g.offsets);
    glDeleteBuffers(2, g.grown);
    glDeleteVertexArrays(1, &g.vertex_array);
}

Status grid_passes(ContextState& s, GLuint source_color, int sw, int sh, const GridCells& cells,
                   bool bicubic, const GridOutput& out, warp::GridStats& stats,
                   std::size_t& stretched) {
    REPRISE_TRY(create_grid_programs(s));
    GridRaster& g = s.grid;
    const int tw = out.width, th = out.height;
    if (g.depth_width != tw || g.depth_height != th) {
        glBindRenderbuffer(GL_RENDERBUFFER, g.depth_buffer);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, tw, th);
        glBindRenderbuffer(GL_RENDERBUFFER, 0);
        g.depth_width = tw;
        g.depth_height = th;
    }
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, g.framebuffer);
    const GLuint attached[4] = {out.color, out.depth, out.covered, out.motion};
    GLenum buffers[4];
    for (int k = 0; k < 4; ++k) {
        glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + k), GL_TEXTURE_2D,
                               attached[k], 0);
        buffers[k] = attached[k] ? GLenum(GL_COLOR_ATTACHMENT0 + k) : GL_NONE;
    }
    glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              g.depth_buffer);
    glDrawBuffers(4, buffers);
    const GLenum complete = glCheckFramebufferStatus(GL_DRAW_FRAMEBUFFER);
    if (complete != GL_FRAMEBUFFER_COMPLETE) {
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        return Status::error("gpu grid warp: " + s.gl->description() +
                             " cannot draw into 32-bit float textures (framebuffer status " +
                             std::to_string(complete) + "; EXT_color_buffer_float)");
    }
    {
        RasterState raster(g.vertex_array);
        glViewport(0, 0, tw, th);
        const GLfloat zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        const GLfloat far[4] = {INFINITY, 0.0f, 0.0f, 0.0f};
        const GLuint none[4] = {0, 0, 0, 0};
        glClearBufferfv(GL_COLOR, 0, zero);
        glClearBufferfv(GL_COLOR, 1, far);
        glClearBufferuiv(GL_COLOR, 2, none);
        if (out.motion) glClearBufferfv(GL_COLOR, 3, zero);
        const GLfloat one = 1.0f;
        glClearBufferfv(GL_DEPTH, 0, &one);
        glUseProgram(g.program);
        s.bind_inputs({source_color});
        glUniform2i(glGetUniformLocation(g.program, "target_size"), tw, th);
        glUniform2i(glGetUniformLocation(g.program, "source_size"), sw, sh);
        glUniform1i(glGetUniformLocation(g.program, "bicubic_fetch"), bicubic);
        const GLuint buffer = cells.cpu ? g.cells : g.grown[cells.slot];
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffer);
        if (cells.cpu) {
            // In batches that fit a storage buffer; GL draws them in order.
            const std::vector<warp::GridCell>& cpu = *cells.cpu;
            GLint64 max_bytes = 0;
            glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_bytes);
            const std::size_t batch = std::max<std::size_t>(
                1, std::min<std::size_t>(std::size_t(1) << 18,
                                         std::size_t(max_bytes) / sizeof(warp::GridCell)));
            const std::size_t bytes = std::min(cpu.size(), batch) * sizeof(warp::GridCell);
            if (g.cells_bytes < bytes) {
                glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_STREAM_DRAW);
                g.cells_bytes = bytes;
            }
            for (std::size_t first = 0; first < cpu.size(); first += batch) {
                const std::size_t n = std::min(batch, cpu.size() - first);
                glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(n * sizeof(warp::GridCell)),
                                &cpu[first]);
                glDrawArrays(GL_TRIANGLES, 0, GLsizei(12 * n));
            }
        } else if (cells.grown) {
            glDrawArrays(GL_TRIANGLES, 0, GLsizei(12 * cells.grown));
        }
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    }
    for (int k = 0; k < 4; ++k)
        glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + k), GL_TEXTURE_2D,
                               0, 0);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);

    glUseProgram(g.finish_program);
    s.bind_inputs({out.color});
    glBindImageTexture(0, out.depth, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32F);
    glBindImageTexture(1, out.covered, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
    glUniform2i(glGetUniformLocation(g.finish_program, "size"), tw, th);
    glUniform1f(glGetUniformLocation(g.finish_program, "background_from"),
                warp::kGridBackgroundFrom);
    ContextState::reset_counters(g.counts, 4);
    dispatch(tw, th);
    GLuint counts[3] = {0, 0, 0};
    s.read_counters(g.counts, counts, sizeof counts);
    stats.cells = cells.cpu ? cells.cpu->size() : cells.grown;
    stats.covered = counts[0];
    stats.nonfinite = counts[1];
    stretched = counts[2];
    ContextState::unbind_inputs();
    glUseProgram(0);
    return gl::check_errors("gpu grid warp");
}

Status Context::grid_cells(const GBufferView& source, float factor,
                           const warp::GridOptions& options, std::vector<warp::GridCell>& cells) {
    timings_ = {};
    cells.clear();
    const int w = source.width(), h = source.height();
    REPRISE_ASSERT(source.depth.width == w && source.motion.width == w);
    if (!std::isfinite(factor)) return Status::error("gpu grid cells: the factor is not finite");
    if (w <= 0 || h <= 0) return {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    s.previous_depth.ensure(GL_R32F, w, h);
    s.motion.ensure(GL_RG32F, w, h);
    s.upload(s.previous_depth, source.depth.data, source.depth.stride);
    s.upload(s.motion, source.motion.data, source.motion.stride);
    timings_.upload_ms = finish_ms(t);
    std::size_t grown = 0;
    REPRISE_TRY(
        grow_cells(s, s.previous_depth.name, s.motion.name, w, h, options, factor, 0, grown));
    timings_.compute_ms = finish_ms(t);
    cells.resize(grown);
    if (grown) {
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glBindBuffer(GL_COPY_READ_BUFFER, s.grid.grown[0]);
        const void* mapped = glMapBufferRange(
            GL_COPY_READ_BUFFER, 0, GLsizeiptr(grown * sizeof(warp::GridCell)), GL_MAP_READ_BIT);
        if (mapped) std::memcpy(cells.data(), mapped, grown * sizeof(warp::GridCell));
        glUnmapBuffer(GL_COPY_READ_BUFFER);
        glBindBuffer(GL_COPY_READ_BUFFER, 0);
        if (!mapped) return Status::error("gpu grid cells: the cells could not be read back");
    }
    timings_.download_ms = finish_ms(t);
    return gl::check_errors("gpu grid cells");
}

Status Context::grid_warp(const GBufferView& source, float factor, const warp::WarpTarget& target,
                          const warp::GridOptions& options, warp::GridStats& stats) {
    timings_ = {};
    stats = {};
    const int sw = source.width(), sh = source.height();
    const int tw = target.color.width, th = target.color.height;
    REPRISE_ASSERT(source.depth.width == sw && source.depth.height == sh);
    REPRISE_ASSERT(source.motion.width == sw && source.motion.height == sh);
    REPRISE_ASSERT(target.depth.width == tw && target.depth.height == th);
    REPRISE_ASSERT(target.covered.width == tw && target.covered.height == th);
    REPRISE_ASSERT(target.motion.empty() ||
                   (target.motion.width == tw && target.motion.height == th));
    if (!std::isfinite(factor)) return Status::error("gpu grid warp: the factor is not finite");
    if (tw <= 0 || th <= 0) return {};
    if (sw <= 0 || sh <= 0) {  // nothing lands, as the CPU's warp leaves it
        for (int y = 0; y < th; ++y) {
            std::fill_n(target.color.row(y), tw, glm::vec4(0.0f));
            std::fill_n(target.depth.row(y), tw, INFINITY);
            std::fill_n(target.covered.row(y), tw, uint8_t(0));
            if (!target.motion.empty()) std::fill_n(target.motion.row(y), tw, glm::vec2(0.0f));
        }
        return {};
    }
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    s.upload_frame(source, s.payload, s.previous_depth, s.motion);
    timings_.upload_ms = finish_ms(t);
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.out.ensure(GL_RGBA32F, tw, th);
    s.depth.ensure(GL_R32F, tw, th);
    s.hit.ensure(GL_R32UI, tw, th);
    const bool motion = !target.motion.empty();
    if (motion) s.splat_motion.ensure(GL_RGBA32F, tw, th);
    std::size_t grown = 0, stretched = 0;
    GridCells cells{nullptr, 0, 0};
    const Status on_gpu =
        grow_cells(s, s.previous_depth.name, s.motion.name, sw, sh, options, factor, 0, grown);
    cells.grown = grown;
    if (!on_gpu.ok()) {
        if (!s.grid.overflowed) return on_gpu;
        auto cpu = std::chrono::steady_clock::now();  // more cells than a buffer: the CPU's
        s.grid.warper.cells(source, factor, options, s.grid.cells_cpu);
        timings_.cpu_ms = ms_since(cpu);
        cells.cpu = &s.grid.cells_cpu;
    }
    REPRISE_TRY(grid_passes(
        s, s.payload.name, sw, sh, cells, options.bicubic,
        {s.out.name, s.depth.name, s.hit.name, motion ? s.splat_motion.name : 0u, tw, th}, stats,
        stretched));
    timings_.compute_ms = finish_ms(t);
    s.download(s.out, target.color.data, target.color.stride);
    s.download_channels(s.depth, target.depth.data, 1, target.depth.stride);
    s.download(s.hit, nullptr, 0);
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x)
            target.covered(x, y) = uint8_t(s.hit_readback[std::size_t(y) * tw + x].x);
    if (motion)
        s.download_channels(s.splat_motion, &target.motion.data->x, 2, target.motion.stride);
    REPRISE_TRY(gl::check_errors("gpu grid warp download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
