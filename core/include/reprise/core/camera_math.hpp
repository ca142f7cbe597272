#pragma once
// The camera math every warp shares: pixel + depth -> view-space point, point -> pixel in
// another camera, camera-only motion. Pixel positions follow docs/conventions.md (origin top-left,
// +y down, pixel (i, j) centred at (i + 0.5, j + 0.5)); depth is linear view depth (z_view =
// -depth).
#include <cmath>

#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "reprise/core/camera.hpp"

namespace reprise {

// Pixel position of a clip-space point; false when it is not in front of the camera (w <= 0, NaN).
inline bool clip_to_pixel(const glm::vec4& clip, int width, int height, glm::vec2& pixel) {
    if (!(clip.w > 0.0f)) return false;
    pixel = {(clip.x / clip.w * 0.5f + 0.5f) * float(width),
             (0.5f - 0.5f * clip.y / clip.w) * float(height)};
    return true;
}

// The view-space point seen at a pixel position at a known depth. Projections whose clip w depends
// on z_view alone (perspective and orthographic, off-centre or skewed in x/y) solve a 2x2 system
// per pixel; any other invertible projection goes through the inverse matrix.
class Unprojector {
public:
    Unprojector(const glm::mat4& projection, int width, int height, float far = 1e6f)
        : p_(projection), width_(float(width)), height_(float(height)) {
        const float det = p_[0][0] * p_[1][1] - p_[1][0] * p_[0][1];
        linear_ = p_[0][3] == 0.0f && p_[1][3] == 0.0f && det != 0.0f && std::isfinite(det);
        axis_aligned_ = linear_ && p_[1][0] == 0.0f && p_[0][1] == 0.0f;
        if (linear_) {
            i00_ = p_[1][1] / det;
            i01_ = -p_[1][0] / det;
            i10_ = -p_[0][1] / det;
            i11_ = p_[0][0] / det;
        } else {
            inverse_ = glm::inverse(p_);
        }
        perspective_ = p_[2][3] != 0.0f;
        far_ = std::isfinite(far) && far > 0.0f ? far : 1e6f;
    }

    // NDC of a pixel position.
    float ndc_x(float px) const { return 2.0f * px / width_ - 1.0f; }
    float ndc_y(float py) const { return 1.0f - 2.0f * py / height_; }
    bool perspective() const { return perspective_; }
    // point_ndc is then ((nx wc - P20 zv - P30 w) / P00, (ny wc - P21 zv - P31 w) / P11, zv, w)
    // with wc = P23 zv + P33 w: no x/y coupling, the form per-pixel loops can inline.
    bool axis_aligned() const { return axis_aligned_; }
    const glm::mat4& projection() const { return p_; }
    float far_plane() const { return far_; }

    // The point (w = 1) at view depth `depth` through NDC (nx, ny). Background (+inf) is the
    // point at infinity through the pixel (w = 0, z_view = -1) for a perspective projection and
    // the point on the far plane for an orthographic one.
    glm::vec4 point_ndc(float nx, float ny, float depth) const {
        const bool background = depth == INFINITY;
        if (background && perspective_) return direction(nx, ny);
        if (background) depth = far_;
        const float zv = -depth;
        if (linear_) {
            const float wc = p_[2][3] * zv + p_[3][3];
            const float rx = nx * wc - p_[2][0] * zv - p_[3][0];
            const float ry = ny * wc - p_[2][1] * zv - p_[3][1];
            return {solve_x(rx, ry), solve_y(rx, ry), zv, 1.0f};
        }
        // The point at z_view = -depth on the segment between the pixel's near and far points.
        const glm::vec4 a = inverse_ * glm::vec4(nx, ny, -1.0f, 1.0f);
        const glm::vec4 b = inverse_ * glm::vec4(nx, ny, 1.0f, 1.0f);
        const glm::vec3 pa = glm::vec3(a) / a.w, pb = glm::vec3(b) / b.w;
        const float t = (zv - pa.z) / (pb.z - pa.z);
        return glm::vec4(pa + t * (pb - pa), 1.0f);
    }
    glm::vec4 point(float px, float py, float depth) const {
        return point_ndc(ndc_x(px), ndc_y(py), depth);
    }

    // The direction through NDC (nx, ny) towards z_view = -1 (w = 0).
    glm::vec4 direction(float nx, float ny) const {
        if (linear_) {
            const float rx = -nx * p_[2][3] + p_[2][0];
            const float ry = -ny * p_[2][3] + p_[2][1];
            return {solve_x(rx, ry), solve_y(rx, ry), -1.0f, 0.0f};
        }
        const glm::vec4 a = inverse_ * glm::vec4(nx, ny, -1.0f, 1.0f);
        const glm::vec4 b = inverse_ * glm::vec4(nx, ny, 1.0f, 1.0f);
        const glm::vec3 d = glm::vec3(b) / b.w - glm::vec3(a) / a.w;
        return glm::vec4(d / -d.z, 0.0f);
    }

private:
    // (x, y) from P00 x + P10 y = rx, P01 x + P11 y = ry.
    float solve_x(float rx, float ry) const {
        return axis_aligned_ ? rx / p_[0][0] : i00_ * rx + i01_ * ry;
    }
    float solve_y(float rx, float ry) const {
        return axis_aligned_ ? ry / p_[1][1] : i10_ * rx + i11_ * ry;
    }

    glm::mat4 p_, inverse_{1.0f};
    float width_, height_, far_ = 1e6f;
    float i00_ = 0, i01_ = 0, i10_ = 0, i11_ = 0;
    bool linear_ = false, axis_aligned_ = false, perspective_ = true;
};

// Row r of m * (x, y, z, w), summed as glm's matrix product does: per-pixel loops that spell
// the product out get the same bits as the generic code.
inline float transform_row(const glm::mat4& m, int r, float x, float y, float z, float w) {
    return (m[0][r] * x + m[1][r] * y) + (m[2][r] * z + m[3][r] * w);
}

// From the view space of one camera to the clip space of another (its view and projection).
inline glm::mat4 view_to_clip(const glm::mat4& from_view, const glm::mat4& to_view,
                              const glm::mat4& to_projection) {
    return to_projection * (to_view * glm::inverse(from_view));
}

// Where the static surface seen at a pixel of `from` with a given depth lands in another camera:
// pixel + depth -> view point -> the other camera's pixel (and view depth). Camera-only motion
// is `land(p, depth) - p` with the previous camera as the target (camera_only_motion below).
class StaticReprojection {
public:
    StaticReprojection(const Camera& from, const glm::mat4& to_view, const glm::mat4& to_projection,
                       int width, int height)
        : unproject_(from.projection, width, height, from.far),
          to_clip_(view_to_clip(from.view, to_view, to_projection)),
          to_view_(to_view * glm::inverse(from.view)),
          width_(width),
          height_(height) {}

    const Unprojector& unprojector() const { return unproject_; }
    const glm::mat4& to_clip() const { return to_clip_; }  // view point -> target clip
    const glm::mat4& to_view() const { return to_view_; }  // view point -> target view

    // The target pixel position of view point `point` (w = 0: a direction); false behind the
    // target camera.
    bool land(const glm::vec4& point, glm::vec2& pixel) const {
        return clip_to_pixel(to_clip_ * point, width_, height_, pixel);
    }
    bool land(float px, float py, float depth, glm::vec2& pixel) const {
        return land(unproject_.point(px, py, depth), pixel);
    }
    // The view depth of a view point in the target camera.
    float target_depth(const glm::vec4& point) const { return -(to_view_ * point).z; }

private:
    Unprojector unproject_;
    glm::mat4 to_clip_, to_view_;
    int width_, height_;
};

// Backward motion of static geometry: for the camera's own prev_view / prev_projection.
inline StaticReprojection camera_only_motion(const Camera& camera, int width, int height) {
    return StaticReprojection(camera, camera.prev_view, camera.prev_projection, width, height);
}

}  // namespace reprise
