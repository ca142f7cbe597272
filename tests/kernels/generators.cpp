#include "generators.hpp"

#include <glm/gtc/matrix_transform.hpp>

namespace reprise::kernels {

float uniform(std::mt19937& rng, float a, float b) {
    return a + (b - a) * float(rng() >> 8) * (1.0f / 16777216.0f);
}

float worst_value(std::mt19937& rng) {
    constexpr float values[] = {kNaN,
                                kInf,
                                -kInf,
                                0.0f,
                                -0.0f,
                                1e30f,
                                -1e30f,
                                1e-30f,
                                -1.0f,
                                0.5f,
                                3e5f,
                                -3e5f,
                                std::numeric_limits<float>::denorm_min()};
    return values[rng() % std::size(values)];
}

float random_depth(std::mt19937& rng, float near, float far, bool worst) {
    const float z = rng() % 10 == 0 ? kInf : uniform(rng, near, far);
    return worst && rng() % 3 == 0 ? worst_value(rng) : z;
}

bool spoil_depth_or_motion(std::mt19937& rng, unsigned kind, float& z, glm::vec2& m) {
    switch (kind) {
        case 0:
            z = worst_value(rng);
            return true;
        case 1:
            m[int(rng() % 2)] = worst_value(rng);
            return true;
        case 2:
            m = {1e30f, -1e30f};
            return true;
        default:
            return false;
    }
}

glm::mat4 random_projection(std::mt19937& rng, int width, int height, bool ortho) {
    return ortho ? glm::ortho(-4.0f, 4.0f, -3.0f, 3.0f, 0.1f, 50.0f)
                 : glm::perspective(uniform(rng, 0.5f, 1.5f), float(width) / float(height), 0.1f,
                                    100.0f);
}

Camera random_camera(std::mt19937& rng, int width, int height, bool ortho, float move) {
    Camera c;
    c.projection = random_projection(rng, width, height, ortho);
    c.view =
        glm::translate(glm::mat4(1.0f), glm::vec3(uniform(rng, -1, 1), 0, uniform(rng, -1, 1)));
    c.prev_view = glm::rotate(glm::translate(c.view, move * glm::vec3(0.05f, -0.02f, 0.1f)),
                              uniform(rng, -0.05f, 0.05f), glm::vec3(0, 1, 0));
    c.prev_projection = c.projection;
    return c;
}

}  // namespace reprise::kernels
