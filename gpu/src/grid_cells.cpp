// Growing the adaptive grid's cells on the GPU: warp/src/grid_cells.cpp's Builder as a compute
// shader, one invocation per starting cell (its splits on a small stack, in the CPU's order; the
// vertices shared between cells recomputed instead of remembered). A first pass counts each
// starting cell's cells, one invocation turns the counts into offsets in the CPU's order (rows of
// starting cells, left to right), and a second pass writes the cells there: the same cells, in
// the same order, as warp::GridWarper::cells, which grid.cpp draws.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kCells = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(std430, binding = 1) buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) writeonly buffer Cells { uint words[]; };
uniform ivec2 size;  // the source's
uniform ivec2 starting;  // starting cells in a row, rows of them
uniform int cell, min_cell;
uniform highp float depth_tolerance, motion_limit, vertex_z_ratio, vertex_motion, factor;
// 131072 * stretched_area rounded down, 64 bits (hi, lo); never: +inf (nothing stretched).
uniform uvec2 stretch_limit;
uniform bool never_stretched;
uniform bool write_cells;  // else count them

const highp float kHugeMotion = 1e30, kBackgroundFrom = 1e29, kBackgroundDepth = 1e30;
const highp float kInvalidMotion = 1e38, kMaxCoordinate = 1048576.0;

bool is_nan(highp float v) { return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u; }
highp float depth_at(int x, int y) { return texelFetch(depth_map, ivec2(x, y), 0).r; }
highp vec2 motion_at(int x, int y) { return texelFetch(motion_map, ivec2(x, y), 0).rg; }

// Depth and motion ranges of a few pixels; invalid depth enters as -1, invalid motion as
// kInvalidMotion (grid_cells.cpp's Range).
struct Range {
    highp float zmin, zmax;
    highp vec2 m0, m1;
};
highp float clean_motion(highp float m) { return finite(m) && abs(m) < kHugeMotion ? m : kInvalidMotion; }
Range range_of(highp float depth, highp vec2 m) {
    highp float z = !is_nan(depth) && depth >= 0.0 ? depth : -1.0;
    highp vec2 c = vec2(clean_motion(m.x), clean_motion(m.y));
    return Range(z, z, c, c);
}
void add(inout Range r, Range o) {
    r.zmin = min(r.zmin, o.zmin);
    r.zmax = max(r.zmax, o.zmax);
    r.m0 = min(r.m0, o.m0);
    r.m1 = max(r.m1, o.m1);
}
bool invalid(Range r) { return r.zmin < 0.0 || r.m1.x >= kHugeMotion || r.m1.y >= kHugeMotion; }
bool narrow(Range r, highp float z_ratio, highp float motion) {
    bool mixed = r.zmin < kBackgroundFrom && r.zmax >= kBackgroundFrom;
    PRECISE highp float far = r.zmin * z_ratio;
    PRECISE highp float mx = r.m1.x - r.m0.x, my = r.m1.y - r.m0.y;
    return !invalid(r) && !mixed && (r.zmin >= kBackgroundFrom || r.zmax <= far) &&
           mx <= motion && my <= motion;
}
Range block_range(int x, int y, int x1, int y1) {
    Range r = range_of(depth_at(x, y), motion_at(x, y));
    for (int j = y; j < y1; ++j)
        for (int i = x; i < x1; ++i) add(r, range_of(depth_at(i, j), motion_at(i, j)));
    return r;
}
bool valid_motion(highp vec2 m) {
    return finite(m.x) && finite(m.y) && abs(m.x) < kHugeMotion && abs(m.y) < kHugeMotion;
}

// Every pixel of [x, x1) x [y, y1) valid, of its corners' kind and within the thresholds of the
// interpolation of its corner pixels over the cell's two triangles (start + fit_row).
bool fits(int x, int y, int x1, int y1) {
    int n = x1 - x, rows = y1 - y;
    if ((n <= 2 || rows <= 2) && !narrow(block_range(x, y, x1, y1), vertex_z_ratio, vertex_motion))
        return false;
    int xr = x1 - 1, yb = y1 - 1;
    highp float z[4] = float[4](depth_at(x, y), depth_at(xr, y), depth_at(xr, yb), depth_at(x, yb));
    highp vec2 m[4] = vec2[4](motion_at(x, y), motion_at(xr, y), motion_at(xr, yb), motion_at(x, yb));
    int background = 0;
    for (int k = 0; k < 4; ++k) {
        if (is_nan(z[k]) || !(z[k] >= 0.0) || !valid_motion(m[k])) return false;
        background += z[k] >= kBackgroundFrom ? 1 : 0;
    }
    if (background != 0 && background != 4) return false;
    bool sky = background == 4;
    highp float iu = n > 1 ? 1.0 / float(n - 1) : 0.0;
    highp float iv = rows > 1 ? 1.0 / float(rows - 1) : 0.0;
    highp float w[4];
    for (int k = 0; k < 4; ++k) w[k] = sky ? 0.0 : 1.0 / z[k];
    PRECISE highp float wb0 = w[1] - w[0], wb1 = w[2] - w[3];
    PRECISE highp vec2 mb0 = m[1] - m[0], mb1 = m[2] - m[3];
    PRECISE highp float wv0 = w[2] - w[1], wv1 = w[3] - w[0];
    PRECISE highp vec2 mv0 = m[2] - m[1], mv1 = m[3] - m[0];
    for (int j = 0; j < rows; ++j) {
        PRECISE highp float v = float(j) * iv;
        PRECISE highp float wa0 = w[0] + v * wv0, wa1 = w[0] + v * wv1;
        PRECISE highp vec2 ma0 = m[0] + v * mv0, ma1 = m[0] + v * mv1;
        for (int i = 0; i < n; ++i) {
            PRECISE highp float u = float(i) * iu;
            bool upper = u >= v;
            highp float zi = depth_at(x + i, y + j);
            if (sky) {
                if (is_nan(zi) || !(zi >= kBackgroundFrom)) return false;
            } else {
                PRECISE highp float predicted = upper ? wa0 + u * wb0 : wa1 + u * wb1;
                PRECISE highp float e = abs(1.0 - predicted * zi);
                if (is_nan(e) || !(e <= depth_tolerance)) return false;
            }
            highp vec2 mi = motion_at(x + i, y + j);
            PRECISE highp vec2 p = upper ? ma0 + u * mb0 : ma1 + u * mb1;
            PRECISE highp vec2 d = abs(mi - p);
            if (!valid_motion(mi) || is_nan(d.x) || is_nan(d.y) || !(d.x <= motion_limit) ||
                !(d.y <= motion_limit))
                return false;
        }
    }
    return true;
}

// A float to 1/256 px, rounded to nearest (ties up), as warp's to_fixed in double: exact for
// |v| <= 2^20, where v * 256 is exact and, from 2^23 on, already whole.
int to_fixed(highp float v) {
    PRECISE highp float scaled = v * 256.0;
    highp float whole = floor(scaled);
    PRECISE highp float part = scaled - whole;  // exact
    return int(whole) + (part >= 0.5 ? 1 : 0);
}

struct Vertex {
    int x, y;
    highp float sx, sy, z, mx, my;
};
bool place(int cx, int cy, highp float z, highp vec2 m, out Vertex v) {
    PRECISE highp float tx = float(cx) + factor * m.x, ty = float(cy) + factor * m.y;
    if (!(finite(tx) && finite(ty) && abs(tx) <= kMaxCoordinate && abs(ty) <= kMaxCoordinate))
        return false;
    v = Vertex(to_fixed(tx), to_fixed(ty), float(cx), float(cy), z, m.x, m.y);
    return true;
}
// Grid point (cx, cy): the mean of the 2x2 pixels around it where they are continuous, else
// pixel (ix, iy)'s depth and motion (grid_cells.cpp's vertex()).
bool vertex(int cx, int cy, int ix, int iy, out Vertex v) {
    int xa = max(cx - 1, 0), xb = min(cx, size.x - 1);
    int ya = max(cy - 1, 0), yb = min(cy, size.y - 1);
    highp float d0 = depth_at(xa, ya), d1 = depth_at(xb, ya), d2 = depth_at(xa, yb),
                d3 = depth_at(xb, yb);
    highp vec2 m0 = motion_at(xa, ya), m1 = motion_at(xb, ya), m2 = motion_at(xa, yb),
               m3 = motion_at(xb, yb);
    Range r = range_of(d0, m0);
    add(r, range_of(d1, m1));
    add(r, range_of(d2, m2));
    add(r, range_of(d3, m3));
    if (narrow(r, vertex_z_ratio, vertex_motion)) {
        PRECISE highp float mean_z = ((d0 + d1) + (d2 + d3)) * 0.25;
        PRECISE highp vec2 mean_m = ((m0 + m1) + (m2 + m3)) * 0.25;
        return place(cx, cy, r.zmin < kBackgroundFrom ? mean_z : kBackgroundDepth, mean_m, v);
    }
    highp float d = depth_at(ix, iy);
    return place(cx, cy, !is_nan(d) && d < kBackgroundFrom ? d : kBackgroundDepth,
                 motion_at(ix, iy), v);
}

// 2 where an edge triangle across a depth edge grew by more than stretched_area px^2: exactly,
// in integers (twice the target area in 1/65536 px^2, less twice the source's, a whole number
// of px^2 as source positions are grid points, against 131072 stretched_area).
uint coverage(Vertex a, Vertex b, Vertex c) {
    highp float z_lo = min(a.z, min(b.z, c.z)), z_hi = max(a.z, max(b.z, c.z));
    PRECISE highp float far = z_lo * vertex_z_ratio;
    if (!(z_hi > far) || never_stretched) return 1u;
    PRECISE highp float source = abs((b.sx - a.sx) * (c.sy - a.sy) - (b.sy - a.sy) * (c.sx - a.sx));
    int h1, l1, h2, l2;
    imulExtended(b.x - a.x, c.y - a.y, h1, l1);
    imulExtended(b.y - a.y, c.x - a.x, h2, l2);
    uint borrow, carry;
    uint lo = usubBorrow(uint(l1), uint(l2), borrow);
    uint hi = uint(h1) - uint(h2) - borrow;
    if ((hi & 0x80000000u) != 0u) {  // |.|: two's complement negation
        lo = uaddCarry(~lo, 1u, carry);
        hi = ~hi + carry;
    }
    lo = usubBorrow(lo, uint(source) * 65536u, borrow);
    if (hi < borrow) return 1u;  // grew by less than nothing
    hi -= borrow;
    return hi > stretch_limit.x || (hi == stretch_limit.x && lo > stretch_limit.y) ? 2u : 1u;
}

uint emitted = 0u, first_cell = 0u, end_cell = 0u;
void put(uint at, Vertex v) {
    words[at] = uint(v.x);
    words[at + 1u] = uint(v.y);
    words[at + 2u] = floatBitsToUint(v.sx);
    words[at + 3u] = floatBitsToUint(v.sy);
    words[at + 4u] = floatBitsToUint(v.z);
    words[at + 5u] = floatBitsToUint(v.mx);
    words[at + 6u] = floatBitsToUint(v.my);
}
void emit(int x, int y, int x1, int y1, bool fitted) {
    Vertex v0, v1, v2, v3;
    if (!vertex(x, y, x, y, v0) || !vertex(x1, y, x1 - 1, y, v1) ||
        !vertex(x1, y1, x1 - 1, y1 - 1, v2) || !vertex(x, y1, x, y1 - 1, v3))
        return;
    if (write_cells && first_cell + emitted < end_cell) {  // never past its counted range
        uint at = (first_cell + emitted) * 29u;
        put(at, v0);
        put(at + 7u, v1);
        put(at + 14u, v2);
        put(at + 21u, v3);
        uint c0 = fitted ? 1u : coverage(v0, v1, v2), c1 = fitted ? 1u : coverage(v0, v2, v3);
        words[at + 28u] = (fitted ? 1u : 0u) | (c0 << 8) | (c1 << 16);
    }
    ++emitted;
}

void grow(int x0, int y0) {
    if (cell > min_cell && fits(x0, y0, min(x0 + cell, size.x), min(y0 + cell, size.y))) {
        emit(x0, y0, min(x0 + cell, size.x), min(y0 + cell, size.y), true);
        return;
    }
    // Splits depth first, top-left, top-right, bottom-left, bottom-right: the CPU's order.
    ivec3 stack[24];
    int top = 0;
    stack[0] = ivec3(x0, y0, cell);
    bool failed = true;  // the starting cell was tested above
    while (top >= 0) {
        ivec3 b = stack[top--];
        int x = b.x, y = b.y, s = b.z;
        if (x >= size.x || y >= size.y) continue;
        int x1 = min(x + s, size.x), y1 = min(y + s, size.y);
        if (s > min_cell) {
            if (!failed && fits(x, y, x1, y1)) {
                emit(x, y, x1, y1, true);
            } else {
                int h2 = s / 2;
                stack[++top] = ivec3(x + h2, y + h2, h2);
                stack[++top] = ivec3(x, y + h2, h2);
                stack[++top] = ivec3(x + h2, y, h2);
                stack[++top] = ivec3(x, y, h2);
            }
            failed = false;
            continue;
        }
        failed = false;
        Range r = block_range(x, y, x1, y1);
        if (!invalid(r)) emit(x, y, x1, y1, narrow(r, vertex_z_ratio, vertex_motion));
    }
}

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (id.x >= starting.x || id.y >= starting.y) return;
    uint index = uint(id.y * starting.x + id.x);
    if (write_cells) {
        first_cell = offsets[index];
        end_cell = offsets[index + 1u];
    }
    grow(id.x * cell, id.y * cell);
    if (!write_cells) offsets[index] = emitted;
}
)";

// Each starting cell's count into its offset, in order; the total after the last.
constexpr const char* kOffsets = R"(
layout(std430, binding = 1) buffer Offsets { uint offsets[]; };
uniform uint count;
void main() {
    if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
    uint total = 0u;
    for (uint k = 0u; k < count; ++k) {
        uint n = offsets[k];
        offsets[k] = total;
        total += n;
    }
    offsets[count] = total;
}
)";

}  // namespace

Status create_grid_cell_programs(ContextState& s) {
    GridRaster& g = s.grid;
    glDeleteProgram(g.cells_program);  // a failed try's
    glDeleteProgram(g.offsets_program);
    g.cells_program = g.offsets_program = 0;
    const std::string header = kComputeHeader;
    REPRISE_TRY(gl::link_compute((header + kCells).c_str(), "grid cells", g.cells_program));
    REPRISE_TRY(
        gl::link_compute((header + kOffsets).c_str(), "grid cell offsets", g.offsets_program));
    glGenBuffers(2, g.grown);
    glGenBuffers(1, &g.offsets);  // made last: everything before it is ready
    return gl::check_errors("gpu grid cell programs");
}

Status grow_cells(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                  const warp::GridOptions& options, float factor, int slot, std::size_t& count) {
    GridRaster& g = s.grid;
    g.overflowed = false;
    if (!g.offsets) REPRISE_TRY(create_grid_cell_programs(s));
    const warp::GridParameters p = warp::grid_parameters(options, factor);
    const int columns = (w + p.cell - 1) / p.cell, rows = (h + p.cell - 1) / p.cell;
    const std::size_t starting = std::size_t(columns) * std::size_t(rows);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g.offsets);
    const std::size_t offset_bytes = (starting + 1) * sizeof(GLuint);
    if (g.offsets_bytes < offset_bytes) {
        glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(offset_bytes), nullptr, GL_DYNAMIC_COPY);
        g.offsets_bytes = offset_bytes;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, g.offsets);
    const GLuint program = g.cells_program;
    glUseProgram(program);
    s.bind_inputs({depth, motion});
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
    glUniform2i(glGetUniformLocation(program, "starting"), columns, rows);
    glUniform1i(glGetUniformLocation(program, "cell"), p.cell);
    glUniform1i(glGetUniformLocation(program, "min_cell"), p.min_cell);
    glUniform1f(glGetUniformLocation(program, "depth_tolerance"), p.depth_tolerance);
    glUniform1f(glGetUniformLocation(program, "motion_limit"), p.motion_limit);
    glUniform1f(glGetUniformLocation(program, "vertex_z_ratio"), p.vertex_z_ratio);
    glUniform1f(glGetUniformLocation(program, "vertex_motion"), p.vertex_motion);
    const double stretch = std::floor(131072.0 * double(p.stretched_area));
    const bool never = !(stretch < 1.8e19);  // +inf, or more than 64 bits hold
    const uint64_t limit = never ? 0 : uint64_t(stretch);
    glUniform2ui(glGetUniformLocation(program, "stretch_limit"), GLuint(limit >> 32),
                 GLuint(limit & 0xffffffffu));
    glUniform1i(glGetUniformLocation(program, "never_stretched"), never);
    glUniform1f(glGetUniformLocation(program, "factor"), factor);
    glUniform1i(glGetUniformLocation(program, "write_cells"), 0);
    dispatch(columns, rows);

    glUseProgram(g.offsets_program);
    glUniform1ui(glGetUniformLocation(g.offsets_program, "count"), GLuint(starting));
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    auto unbind = [&] {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, 0);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        ContextState::unbind_inputs();
        glUseProgram(0);
    };
    GLuint total = 0;
    glBindBuffer(GL_COPY_READ_BUFFER, g.offsets);
    glBindBuffer(GL_COPY_WRITE_BUFFER, s.readback_buffer);
    glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER,
                        GLintptr(starting * sizeof(GLuint)), 0, sizeof(GLuint));
    const void* mapped = glMapBufferRange(GL_COPY_WRITE_BUFFER, 0, sizeof(GLuint), GL_MAP_READ_BIT);
    if (mapped) std::memcpy(&total, mapped, sizeof total);
    glUnmapBuffer(GL_COPY_WRITE_BUFFER);
    glBindBuffer(GL_COPY_READ_BUFFER, 0);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
    if (!mapped) {
        unbind();
        return Status::error("gpu grid cells: the cell count could not be read back");
    }
    // One storage buffer holds them (and 32-bit word offsets reach them all).
    GLint64 max_bytes = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_bytes);
    max_bytes = std::min<GLint64>(max_bytes, GLint64(1) << 31);
    const std::size_t bytes = std::size_t(total) * sizeof(warp::GridCell);
    g.overflowed = bytes > std::size_t(max_bytes);
    if (g.overflowed) {
        unbind();
        return Status::error("gpu grid cells: " + std::to_string(total) +
                             " cells exceed one storage buffer (" + std::to_string(max_bytes) +
                             " bytes)");
    }
    if (total) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, g.grown[slot]);
        if (g.grown_bytes[slot] < bytes) {
            glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_COPY);
            g.grown_bytes[slot] = bytes;
        }
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, g.grown[slot]);
        glUseProgram(program);
        glUniform1i(glGetUniformLocation(program, "write_cells"), 1);
        dispatch(columns, rows);
    }
    unbind();
    count = total;
    return gl::check_errors("gpu grid cells");
}

}  // namespace reprise::gpu
