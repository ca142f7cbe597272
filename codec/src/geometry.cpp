// Motion and depth that the cameras explain: both sides compute them from decoded depth with the
// same float arithmetic, so they agree bit for bit.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <glm/mat4x4.hpp>

#include "internal.hpp"
#include "kernels.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Pixel (x, y) with depth z as a homogeneous point in the camera space of `projection`
// (w = 0: the direction of a background pixel under perspective). False for NaN/negative depth.
struct Unprojector {
    glm::mat4 p;
    bool perspective;
    float far_plane;
    float width, height;

    bool point(int x, int y, float z, glm::vec4& out) const {
        if (!(z >= 0.0f)) return false;
        const float x_ndc = 2.0f * (float(x) + 0.5f) / width - 1.0f;
        const float y_ndc = 1.0f - 2.0f * (float(y) + 0.5f) / height;
        const bool background = z == kInf;
        if (background && perspective) {
            const float wc = -p[2][3];
            out = {(x_ndc * wc + p[2][0]) / p[0][0], (y_ndc * wc + p[2][1]) / p[1][1], -1.0f, 0.0f};
            return true;
        }
        if (background) z = far_plane;
        const float zv = -z;
        const float wc = p[2][3] * zv + p[3][3];
        out = {(x_ndc * wc - p[2][0] * zv - p[3][0]) / p[0][0],
               (y_ndc * wc - p[2][1] * zv - p[3][1]) / p[1][1], zv, 1.0f};
        return true;
    }
};

Unprojector unprojector(const Camera& c, int w, int h) {
    return {c.projection, c.projection[2][3] != 0.0f, std::isfinite(c.far) ? c.far : 1e6f, float(w),
            float(h)};
}

glm::mat4 between(const glm::mat4& from_view, const glm::mat4& to_view) {
    return glm::mat4(glm::dmat4(to_view) * glm::inverse(glm::dmat4(from_view)));
}

}  // namespace

void camera_motion_row_reference(const CameraMotionRow& r, int x_begin, int x_end) {
    const Unprojector un{r.projection, r.perspective, r.far_plane, float(r.width), float(r.height)};
    const int w = r.width, h = r.height, y = r.y;
    const float cy = float(y) + 0.5f;
    for (int x = x_begin; x < x_end; ++x) {
        const float d = r.depth[x];
        glm::vec4 clip;
        if (un.perspective && d >= 0.0f && d < kInf) {
            const float fx = float(x);
            clip = (r.a0 + fx * r.a1) + d * (r.b0 + fx * r.b1);
        } else {
            glm::vec4 point;
            if (!un.point(x, y, d, point)) {
                r.out[x] = {kNan, kNan};
                continue;
            }
            clip = r.to_clip * point;
        }
        if (!(clip.w > 0.0f)) {
            r.out[x] = {kNan, kNan};
            continue;
        }
        const float px = (clip.x / clip.w + 1.0f) * 0.5f * float(w);
        const float py = (1.0f - clip.y / clip.w) * 0.5f * float(h);
        r.out[x] = {px - (float(x) + 0.5f), py - cy};
    }
}

void camera_motion(const Camera& from, ImageView<const float> depth, const glm::mat4& to_view,
                   const glm::mat4& to_projection, ImageView<glm::vec2> out) {
    const int w = depth.width, h = depth.height;
    REPRISE_ASSERT(out.width == w && out.height == h);
    if (from.view == to_view && from.projection == to_projection) {
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) std::fill(out.row(y), out.row(y) + w, glm::vec2(0.0f));
        });
        return;
    }
    const Unprojector un = unprojector(from, w, h);
    const glm::mat4 to_clip =
        glm::mat4(glm::dmat4(to_projection) * glm::dmat4(between(from.view, to_view)));
    // Under perspective a finite depth's point is a + z b with a and b affine along a row, so its
    // clip position is c0 + z c1 with c0 = A0 + x A1 and c1 = B0 + x B1 (per row, in double).
    const glm::dmat4 p(from.projection), m(to_clip);
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const double y_ndc = 1.0 - 2.0 * (double(y) + 0.5) / double(h);
            // a = ((x_ndc p33 - p30) / p00, (y_ndc p33 - p31) / p11, 0, 1)
            // b = ((p20 - x_ndc p23) / p00, (p21 - y_ndc p23) / p11, -1, 0), x_ndc = 2 (x + 0.5) /
            // w - 1
            const double ay = (y_ndc * p[3][3] - p[3][1]) / p[1][1],
                         by = (p[2][1] - y_ndc * p[2][3]) / p[1][1];
            const double sx = 2.0 / double(w), x0 = sx * 0.5 - 1.0;  // x_ndc = x0 + sx x
            const glm::dvec4 a_at0 =
                m * glm::dvec4((x0 * p[3][3] - p[3][0]) / p[0][0], ay, 0.0, 1.0);
            const glm::dvec4 a_step = m * glm::dvec4(sx * p[3][3] / p[0][0], 0.0, 0.0, 0.0);
            const glm::dvec4 b_at0 =
                m * glm::dvec4((p[2][0] - x0 * p[2][3]) / p[0][0], by, -1.0, 0.0);
            const glm::dvec4 b_step = m * glm::dvec4(-sx * p[2][3] / p[0][0], 0.0, 0.0, 0.0);
            camera_motion_row({.a0 = glm::vec4(a_at0),
                               .a1 = glm::vec4(a_step),
                               .b0 = glm::vec4(b_at0),
                               .b1 = glm::vec4(b_step),
                               .projection = un.p,
                               .to_clip = to_clip,
                               .perspective = un.perspective,
                               .far_plane = un.far_plane,
                               .y = y,
                               .width = w,
                               .height = h,
                               .depth = depth.row(y),
                               .out = out.row(y)});
        }
    });
}

bool unproject_pixel(const Camera& camera, int width, int height, int x, int y, float z,
                     glm::vec4& out) {
    return unprojector(camera, width, height).point(x, y, z, out);
}

glm::mat4 rigid_to_clip(const Camera& camera, const glm::dmat4& moved) {
    return glm::mat4(glm::dmat4(camera.prev_projection) *
                     glm::dmat4(between(camera.view, camera.prev_view)) * moved);
}

void rigid_motion(const Camera& from, ImageView<const float> depth, const glm::mat4& to_clip,
                  int x0, int y0, ImageView<glm::vec2> out, const glm::mat4& to_camera,
                  ImageView<float> out_depth) {
    const Unprojector un = unprojector(from, depth.width, depth.height);
    parallel_for(0, out.height, [&](int r0, int r1) {
        for (int r = r0; r < r1; ++r)
            for (int c = 0; c < out.width; ++c) {
                const int x = x0 + c, y = y0 + r;
                glm::vec4 point;
                glm::vec2 m{kNan, kNan};
                float z = kNan;
                if (un.point(x, y, depth(x, y), point)) {
                    const glm::vec4 clip = to_clip * point;
                    if (clip.w > 0.0f) {
                        m = {(clip.x / clip.w + 1.0f) * 0.5f * un.width - (float(x) + 0.5f),
                             (1.0f - clip.y / clip.w) * 0.5f * un.height - (float(y) + 0.5f)};
                        if (!out_depth.empty()) z = -(to_camera * point).z;
                    }
                }
                out(c, r) = m;
                if (!out_depth.empty()) out_depth(c, r) = z;
            }
    });
}

namespace {

// Where each reference pixel lands in the target (reproject_depth).
struct Landings {
    Image<int32_t> slot;
    Image<float> z, px, py, held;
    Image<float> inverse;  // 1 / z of each landing (plane fit only)
    Image<int> object;     // index into the objects, -1: none
    // Per reference row, the smallest and largest slot its landings reach (first > last: none).
    std::vector<int32_t> first_slot, last_slot;
    // The plane's span in pixels (plane_row): 2 below a height of 900, 3 at 1080 (version 19; the
    // best of 2 to 6 on 20 frames of ten scenes at 360 and 720, of 2 to 18 at 1080).
    int span = 1;
    bool no_objects = false;  // every pixel of `object` is -1
    void resize(int w, int h) {
        span = std::max(2, int(std::lround(double(h) / 360.0)));
        for (Image<float>* i : {&z, &px, &py, &held, &inverse}) ensure_size(*i, w, h);
        ensure_size(slot, w, h);
        first_slot.resize(std::size_t(h));
        last_slot.resize(std::size_t(h));
        if (object.width() != w || object.height() != h) no_objects = false;
        ensure_size(object, w, h);
    }
};

// A run of up to kWidestGap pixels across where nothing landed, between two landings, takes the
// farther one's depth: where the camera or an object moved, what comes into view lies behind.
constexpr int kWidestGap = 8;

// The first pixel of row[x, end) without a landing (NaN), or end: sixteen at a time first, a
// test the compiler vectorises.
inline int next_without_landing(const float* row, int x, int end) {
    for (; x + 16 <= end; x += 16) {
        bool any = false;
        for (int k = 0; k < 16; ++k) any |= std::isnan(row[x + k]);
        if (any) break;
    }
    while (x < end && !std::isnan(row[x])) ++x;
    return x;
}

// The first pixel of row[x, end) with a landing, or end (a run of background, say, can be long).
inline int next_with_landing(const float* row, int x, int end) {
    for (; x + 16 <= end; x += 16) {
        bool all = true;
        for (int k = 0; k < 16; ++k) all &= std::isnan(row[x + k]);
        if (!all) break;
    }
    while (x < end && std::isnan(row[x])) ++x;
    return x;
}

// Whether a pixel of up[x, end) or down[x, end) has a landing in front of the background.
inline bool any_surface(const float* up, const float* down, int x, int end) {
    for (; x + 16 <= end; x += 16) {
        bool any = false;
        for (int k = 0; k < 16; ++k) any |= (up[x + k] < kInf) | (down[x + k] < kInf);
        if (any) return true;
    }
    for (; x < end; ++x)
        if (up[x] < kInf || down[x] < kInf) return true;
    return false;
}

// A pixel no landing reached between two on one surface, across, down or diagonally (a crack
// where the reference was stretched, or where two cracks cross), takes their mean inverse depth:
// exact on a plane, as both are values at pixel centres. Then the gaps left in each row are
// filled (kWidestGap).
void fill_cracks_and_gaps(ImageView<float> depth, Image<float>& scratch, float step) {
    const int w = depth.width, h = depth.height;
    auto mean = [step](float a, float b) {
        if (!(a < kInf && b < kInf)) return kNan;  // nothing landed there, or background
        const float va = 1.0f / a, vb = 1.0f / b;
        return std::abs(va - vb) <= std::max(kSameSurface * std::max(va, vb), 2.0f * step)
                   ? 2.0f / (va + vb)
                   : kNan;
    };
    // The first pair of landings across pixel c that lie on one surface: their mean.
    auto across = [&](const float* up, const float* row, const float* down, int c) {
        for (const auto& [a, b] : {std::pair{row[c - 1], row[c + 1]},
                                   {up[c], down[c]},
                                   {up[c - 1], down[c + 1]},
                                   {down[c - 1], up[c + 1]}})
            if (const float v = mean(a, b); !std::isnan(v)) return v;
        return kNan;
    };
    // The cracks' values go to scratch first: a filled pixel is not the neighbour of another.
    parallel_for(1, h - 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float *up = depth.row(y - 1), *row = depth.row(y), *down = depth.row(y + 1);
            float* crack = &scratch(0, y);
            for (int x = next_without_landing(row, 1, w - 1); x + 1 < w;
                 x = next_without_landing(row, x + 1, w - 1)) {
                // The run of pixels without a landing, within the interior.
                const int end = next_with_landing(row, x + 1, w - 1);
                // A run of two or more (background, say) with no landing above or below it has
                // no pair of landings across any of its pixels.
                if (end - x < 2 || any_surface(up, down, x - 1, end + 1))
                    for (int c = x; c < end; ++c) crack[c] = across(up, row, down, c);
                else
                    std::fill(crack + x, crack + end, kNan);
                x = end - 1;
            }
        }
    });
    // Then each run of pixels without a landing takes its cracks' values, and what is left of it
    // in runs of at most kWidestGap the farther of the landings beside them: pixels with a landing
    // are not written, scratch is read only under a run.
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            float* row = depth.row(y);
            const bool cracks = y >= 1 && y + 1 < h;
            const float* crack = cracks ? &scratch(0, y) : nullptr;
            for (int x = next_without_landing(row, 1, w); x < w;
                 x = next_without_landing(row, x + 1, w)) {
                const int end = next_with_landing(row, x + 1, w);  // the run without a landing
                if (cracks)
                    for (int c = x; c < std::min(end, w - 1); ++c) row[c] = crack[c];
                for (int a = x; a < end; ++a) {  // what the cracks left
                    if (!std::isnan(row[a])) continue;
                    int b = a + 1;
                    while (b < end && std::isnan(row[b])) ++b;
                    if (b < w && b - a <= kWidestGap && row[a - 1] < kInf && row[b] < kInf)
                        std::fill(row + a, row + b, std::max(row[a - 1], row[b]));
                    a = b;
                }
                x = end;
            }
        }
    });
}

}  // namespace

void reproject_depth(const Camera& from, ImageView<const float> depth, const Camera& to,
                     ImageView<float> out, ImageView<const uint32_t> owner,
                     std::span<const ObjectMotion> objects, float plane_step) {
    const bool plane_fit = plane_step > 0.0f;
    const int w = depth.width, h = depth.height;
    REPRISE_ASSERT(out.width == w && out.height == h);
    if (owner.empty()) objects = {};
    // The object a pixel moves with, or -1.
    auto object_of = [&](int x, int y) {
        const uint32_t id = owner(x, y);
        if (id != 0)
            for (std::size_t k = 0; k < objects.size(); ++k)
                if (objects[k].id == id) return int(k);
        return -1;
    };
    if (from.view == to.view && from.projection == to.projection && objects.empty()) {
        for (int y = 0; y < h; ++y) std::copy(depth.row(y), depth.row(y) + w, out.row(y));
        return;
    }
    const glm::mat4 to_camera = between(from.view, to.view);
    const glm::mat4 to_clip = glm::mat4(glm::dmat4(to.projection) * glm::dmat4(to_camera));
    REPRISE_ASSERT(out.stride == w);
    // Pixels that moved with an object land where its inverse motion takes them.
    std::vector<glm::mat4> object_clip, object_camera;
    for (const ObjectMotion& o : objects) {
        const glm::dmat4 moved = glm::inverse(o.matrix()) * glm::dmat4(to_camera);
        object_camera.push_back(glm::mat4(moved));
        object_clip.push_back(glm::mat4(glm::dmat4(to.projection) * moved));
    }
    // First where every pixel lands (objects' pixels with their object's motion), then each
    // landing's value at the centre of the pixel it lands in.
    thread_local Landings scratch;  // the workers below use this thread's, by reference
    Landings& landings = scratch;
    landings.resize(w, h);
    if (!objects.empty()) landings.no_objects = false;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            ForwardRow row{.projection = from.projection,
                           .to_clip = to_clip,
                           .to_camera = to_camera,
                           .x0 = 0,
                           .y = y,
                           .count = w,
                           .width = w,
                           .height = h,
                           .depth = depth.row(y),
                           .slot = &landings.slot(0, y),
                           .z = &landings.z(0, y),
                           .px = &landings.px(0, y),
                           .py = &landings.py(0, y),
                           .inverse = plane_fit ? &landings.inverse(0, y) : nullptr};
            int* object = &landings.object(0, y);
            bool moved = false;
            if (!objects.empty()) {
                uint32_t last_id = 0;
                int last_object = -1;  // of id 0
                for (int x = 0; x < w; ++x) {
                    if (const uint32_t id = owner(x, y); id != last_id)
                        last_id = id, last_object = object_of(x, y);
                    moved |= (object[x] = last_object) >= 0;
                }
            } else if (!landings.no_objects)
                std::fill(object, object + w, -1);
            if (!moved) {
                forward_row(row);
            } else {
                float* held = &landings.held(0, y);
                for (int x = 0; x < w; ++x) held[x] = object[x] >= 0 ? kNan : depth(x, y);
                row.depth = held;
                forward_row(row);
                for (int x = 0, end = 0; x < w; x = end) {  // each run of one object's pixels
                    for (end = x + 1; end < w && object[end] == object[x];) ++end;
                    if (object[x] < 0) continue;
                    ForwardRow run = row;
                    run.to_clip = object_clip[std::size_t(object[x])];
                    run.to_camera = object_camera[std::size_t(object[x])];
                    run.x0 = x, run.count = end - x;
                    run.depth = depth.row(y) + x;
                    run.slot += x, run.z += x, run.px += x, run.py += x;
                    if (run.inverse) run.inverse += x;
                    forward_row(run);
                }
            }
            // -1 (nowhere) is the largest slot as unsigned.
            uint32_t first = std::numeric_limits<uint32_t>::max();
            int32_t last = -1;
            for (int x = 0; x < w; ++x) {
                first = std::min(first, uint32_t(row.slot[x]));
                last = std::max(last, row.slot[x]);
            }
            landings.first_slot[std::size_t(y)] = int32_t(std::min<uint32_t>(first, INT32_MAX));
            landings.last_slot[std::size_t(y)] = last;
        }
    });
    landings.no_objects = objects.empty();
    // Each landing's value: its depth, or its plane's at the centre of the pixel it lands in.
    if (plane_fit)
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                plane_row({.slot = landings.slot.data(),
                           .object = landings.object.data(),
                           .inverse = landings.inverse.data(),
                           .z = landings.z.data(),
                           .px = landings.px.data(),
                           .py = landings.py.data(),
                           .width = w,
                           .height = h,
                           .span = landings.span,
                           .y = y,
                           .step = plane_step,
                           .out = &landings.held(0, y)});
        });
    const Image<float>& value = plane_fit ? landings.held : landings.z;
    // Each pixel keeps the nearest landing (NaN: none), whatever order they land in. Landings
    // never come out NaN, and the nearest of several is the same in any order: each worker takes
    // a band of the picture's rows and the landings in it, from the reference rows that reach it
    // (without atomics; a row's landings mostly stay within a few rows).
    const int bands = std::max(1, 2 * thread_count());
    parallel_for(
        0, h,
        [&](int t0, int t1) {
            const int32_t lo = t0 * w, hi = t1 * w;
            std::fill(out.data + lo, out.data + hi, kNan);
            for (int y = 0; y < h; ++y) {
                if (landings.last_slot[std::size_t(y)] < lo ||
                    landings.first_slot[std::size_t(y)] >= hi)
                    continue;
                const int32_t* slots = &landings.slot(0, y);
                const float* values = &value(0, y);
                for (int x = 0; x < w; ++x)
                    if (const int32_t slot = slots[x];
                        slot >= lo && slot < hi && !(values[x] >= out.data[slot]))
                        out.data[slot] = values[x];
            }
        },
        (h + bands - 1) / bands);
    if (plane_fit) fill_cracks_and_gaps(out, landings.held, plane_step);
}

void forward_row_reference(const ForwardRow& r, int i_begin, int i_end) {
    const Unprojector un{r.projection, r.projection[2][3] != 0.0f, 1e6f, float(r.width),
                         float(r.height)};
    const int w = r.width, h = r.height;
    for (int i = i_begin; i < i_end; ++i) {
        const int x = r.x0 + i;
        r.slot[i] = -1;
        const float z = r.depth[i];
        glm::vec4 point;
        if (!(z < kInf) || !un.point(x, r.y, z, point)) continue;
        const glm::vec4 clip = r.to_clip * point;
        if (!(clip.w > 0.0f)) continue;
        const float px = (clip.x / clip.w + 1.0f) * 0.5f * float(w);
        const float py = (1.0f - clip.y / clip.w) * 0.5f * float(h);
        if (!(px >= 0.0f && py >= 0.0f && px < float(w) && py < float(h))) continue;
        const float tz = -(r.to_camera * point).z;
        if (!(tz > 0.0f)) continue;
        r.slot[i] = int32_t(py) * w + int32_t(px);
        r.z[i] = tz;
        r.px[i] = px;
        r.py[i] = py;
        if (r.inverse) r.inverse[i] = 1.0f / tz;
    }
}

// A decoded surface is a staircase of kept values: a wider span averages its steps out. Decoded
// depth carries errors of up to the bound, and a prediction from one landing would carry its
// error on, frame after frame, until the errors of a surface spread past the bound (each such
// pixel a residual): hence the mean through the adjacent landings.
void plane_row_reference(const PlaneRow& r, int x_begin, int x_end) {
    const int w = r.width, y = r.y;
    auto at = [&](const auto* image, int x, int yy) { return image[std::size_t(yy) * w + x]; };
    auto beside = [&](int x, int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= w || ny >= r.height || at(r.slot, nx, ny) < 0 ||
            at(r.object, nx, ny) != at(r.object, x, y))
            return false;
        const float v = at(r.inverse, x, y);
        const float d = float(std::abs(nx - x) + std::abs(ny - y));
        return std::abs(at(r.inverse, nx, ny) - v) <= std::max(kSameSurface * v, r.step * d);
    };
    auto at_centre = [&](int x) {
        const float v = at(r.inverse, x, y), px = at(r.px, x, y), py = at(r.py, x, y);
        const float cx = float(int32_t(px)) + 0.5f, cy = float(int32_t(py)) + 0.5f;
        for (int k = r.span; k >= 1; k /= 2) {
            const int dx = beside(x, x + k, y) ? k : beside(x, x - k, y) ? -k : 0;
            const int dy = beside(x, x, y + k) ? k : beside(x, x, y - k) ? -k : 0;
            if (dx == 0 || dy == 0) continue;
            const float ax = at(r.px, x + dx, y) - px, ay = at(r.py, x + dx, y) - py;
            const float bx = at(r.px, x, y + dy) - px, by = at(r.py, x, y + dy) - py;
            const float av = at(r.inverse, x + dx, y) - v, bv = at(r.inverse, x, y + dy) - v;
            const float det = ax * by - ay * bx;
            if (!(std::abs(det) >= 0.25f * float(k * k))) continue;
            const float gx = (av * by - bv * ay) / det, gy = (ax * bv - bx * av) / det;
            const float change = gx * (cx - px) + gy * (cy - py);
            if (!(std::abs(change) <= std::max(std::abs(av), std::abs(bv))) || !(v + change > 0.0f))
                continue;
            float sum = v + change;
            int count = 1;
            for (const auto& [nx, ny] : {std::pair{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}}) {
                if (!beside(x, nx, ny)) continue;
                const float value = at(r.inverse, nx, ny) + gx * (cx - at(r.px, nx, ny)) +
                                    gy * (cy - at(r.py, nx, ny));
                if (value > 0.0f) sum += value, ++count;
            }
            return float(count) / sum;
        }
        return at(r.z, x, y);
    };
    for (int x = x_begin; x < x_end; ++x)
        if (at(r.slot, x, y) >= 0) r.out[x] = at_centre(x);
}

namespace {

// 2 / (k ln 2) for odd k: log2(m) = sum over odd k of (2 / (k ln 2)) s^k, s = (m - 1) / (m + 1).
constexpr std::array<double, 11> log2_series() {
    std::array<double, 11> c{};
    for (int i = 0; i < 11; ++i) c[i] = 2.0 / (double(2 * i + 1) * 0.69314718055994531);
    return c;
}
// (ln 2)^k / k!: 2^f = sum of these times f^k.
constexpr std::array<double, 15> exp2_series() {
    std::array<double, 15> c{};
    double term = 1.0;
    for (int k = 0; k < 15; ++k) {
        c[k] = term;
        term = term * 0.69314718055994531 / double(k + 1);
    }
    return c;
}
constexpr auto kLog2Series = log2_series();
constexpr auto kExp2Series = exp2_series();

}  // namespace

ImageView<const glm::vec2> motion_to_reference(const SequenceParams& sp, const Camera& camera,
                                               const Image<float>& depth,
                                               const Image<glm::vec2>& motion,
                                               const Picture* reference, uint32_t frame,
                                               Workspace& work) {
    if (!reference || reference->frame + 1 == frame) return motion.view();
    ensure_size(work.to_reference, sp.width, sp.height);
    if (depth.empty())
        std::fill(work.to_reference.data(),
                  work.to_reference.data() + work.to_reference.pixel_count(), glm::vec2(0.0f));
    else
        camera_motion(camera, depth.view(), reference->camera.view, reference->camera.projection,
                      work.to_reference.view());
    return work.to_reference.view();
}

double exact_log2(double x) {
    int e = 0;
    double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
    if (m < 0.70710678118654752) {
        m *= 2.0;
        --e;
    }
    const double s = (m - 1.0) / (m + 1.0), s2 = s * s;
    double sum = 0.0;
    for (int i = int(kLog2Series.size()) - 1; i >= 0; --i) sum = sum * s2 + kLog2Series[i];
    return double(e) + s * sum;
}

double exact_exp2(double x) {
    if (x > 1100.0) x = 1100.0;
    if (x < -1100.0) x = -1100.0;
    const double n = std::floor(x);
    const double f = x - n;
    double sum = 0.0;
    for (int k = int(kExp2Series.size()) - 1; k >= 0; --k) sum = sum * f + kExp2Series[k];
    return std::ldexp(sum, int(n));
}

}  // namespace reprise::codec

namespace reprise::codec {

// Shift of a pixel at normalised position p (focal lengths fx, fy in pixels) when its inverse
// depth w becomes w' and the camera moves by t (t_z towards the scene):
// (fx (t_z p_x - t_x), fy (t_z p_y - t_y)) (w - w') / ((1 - t_z w) (1 - t_z w')). The numerator's
// largest norm over |t| <= B is f B sqrt(1 + |p|^2) (f = max(fx, fy)); the step is the 1/z error
// for which that is the bound, rounded down to a power of 2^(1/8) so that small zooms keep the
// parameters. Without a perspective projection a 90 degree horizontal field of view is assumed.
float view_depth_step(const glm::mat4& projection, int width, int height, float error_px,
                      float displacement) {
    const glm::mat4& p = projection;
    const bool perspective = p[2][3] != 0.0f && p[0][0] != 0.0f && p[1][1] != 0.0f;
    const double sx = perspective ? std::abs(double(p[0][0])) : 1.0;
    const double sy = perspective ? std::abs(double(p[1][1])) : double(width) / double(height);
    const double ox = perspective ? std::abs(double(p[2][0])) : 0.0;
    const double oy = perspective ? std::abs(double(p[2][1])) : 0.0;
    const double focal = std::max(sx * width, sy * height) / 2.0;  // pixels
    const double u = (1.0 + ox) / sx, v = (1.0 + oy) / sy;         // the farthest image corner
    const double bound =
        double(error_px) / (focal * double(displacement) * std::sqrt(1.0 + u * u + v * v));
    const double step = std::exp2(std::floor(8.0 * std::log2(bound)) / 8.0);
    float f = float(std::clamp(step, 1e-12, 1e6));
    if (double(f) > step) f = std::nextafter(f, 0.0f);  // never coarser than the bound asks
    return f;
}

}  // namespace reprise::codec
