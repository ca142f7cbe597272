#pragma once
// Inputs and comparisons shared by every kernel case.
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include "kernel_case.hpp"
#include "reprise/core/camera.hpp"

namespace reprise::kernels {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

float uniform(std::mt19937& rng, float a, float b);

// The worst values a float input can hold, picked at random.
float worst_value(std::mt19937& rng);

// A depth: background (+inf) one time in ten, else in [near, far]; in the worst case a third of
// them a worst value.
float random_depth(std::mt19937& rng, float near, float far, bool worst);

// The worst cases of every depth + motion input: kind 0 a bad depth, 1 a bad motion component,
// 2 motion (1e30, -1e30). False for other kinds (the caller's own).
bool spoil_depth_or_motion(std::mt19937& rng, unsigned kind, float& z, glm::vec2& m);

// A perspective projection of random field of view, or an orthographic one.
glm::mat4 random_projection(std::mt19937& rng, int width, int height, bool ortho);

// Two cameras a little apart (a translation and a turn), perspective or orthographic.
Camera random_camera(std::mt19937& rng, int width, int height, bool ortho, float move);

// Bitwise equality of two arrays of floats (float, glm vectors), NaN payloads included unless
// `any_nan` (then a NaN matches any NaN); names the first difference and both values.
template <class T>
std::string compare_floats(const char* what, const std::vector<T>& a, const std::vector<T>& b,
                           bool any_nan = false) {
    static_assert(sizeof(T) % sizeof(float) == 0);
    const std::size_t floats = a.size() * sizeof(T) / sizeof(float);
    for (std::size_t i = 0; i < floats; ++i) {
        float va, vb;
        std::memcpy(&va, reinterpret_cast<const char*>(a.data()) + 4 * i, 4);
        std::memcpy(&vb, reinterpret_cast<const char*>(b.data()) + 4 * i, 4);
        if (std::memcmp(&va, &vb, 4) == 0 || (any_nan && va != va && vb != vb)) continue;
        return std::string(what) + ": float " + std::to_string(i) + " is " + std::to_string(va) +
               ", reference " + std::to_string(vb);
    }
    return {};
}

// Equality of two arrays of integers or structs, element by element; names the first difference.
template <class T>
std::string compare_elements(const char* what, const std::vector<T>& a, const std::vector<T>& b) {
    for (std::size_t i = 0; i < a.size(); ++i)
        if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0)
            return std::string(what) + ": element " + std::to_string(i) + " differs";
    return {};
}

template <class T, auto... Args>
std::unique_ptr<KernelCase> make() {
    return std::make_unique<T>(Args...);
}

}  // namespace reprise::kernels
