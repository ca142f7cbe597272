#pragma once
// Levenberg-Marquardt for the codec's small rigid fits (camera_fit.cpp, object_motion.cpp): a
// model gives the residuals of its samples under parameters q; central differences give the
// Jacobian. Encoder only: nothing here has to be reproducible by the decoder.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/mat3x3.hpp>

namespace reprise::codec::fit {

using Params = std::array<double, 7>;
inline constexpr int kIterations = 30;
inline constexpr double kBehindPx = 1e4;  // the error of a point that lands behind the camera

// Rodrigues: the rotation by |w| radians about w.
inline glm::dmat3 rotation(double wx, double wy, double wz) {
    const double theta = std::sqrt(wx * wx + wy * wy + wz * wz);
    const glm::dmat3 k(0.0, wz, -wy, -wz, 0.0, wx, wy, -wx, 0.0);  // [w]x, column-major
    if (theta < 1e-12) return glm::dmat3(1.0) + k;
    const double a = std::sin(theta) / theta, b = (1.0 - std::cos(theta)) / (theta * theta);
    return glm::dmat3(1.0) + a * k + b * (k * k);
}

inline double weighted_cost(const std::vector<double>& r, const std::vector<uint8_t>& inlier) {
    double c = 0.0;
    for (std::size_t i = 0; i < inlier.size(); ++i)
        if (inlier[i]) c += r[2 * i] * r[2 * i] + r[2 * i + 1] * r[2 * i + 1];
    return c;
}

// Solves a x = b (n x n, symmetric positive definite) by Cholesky; false when not definite.
inline bool solve(std::array<std::array<double, 7>, 7> a, std::array<double, 7> b, int n,
                  std::array<double, 7>& x) {
    for (int j = 0; j < n; ++j) {
        double d = a[j][j];
        for (int k = 0; k < j; ++k) d -= a[j][k] * a[j][k];
        if (!(d > 0.0)) return false;
        a[j][j] = std::sqrt(d);
        for (int i = j + 1; i < n; ++i) {
            double v = a[i][j];
            for (int k = 0; k < j; ++k) v -= a[i][k] * a[j][k];
            a[i][j] = v / a[j][j];
        }
    }
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < i; ++k) b[i] -= a[i][k] * b[k];
        b[i] /= a[i][i];
    }
    for (int i = n - 1; i >= 0; --i) {
        for (int k = i + 1; k < n; ++k) b[i] -= a[k][i] * b[k];
        b[i] /= a[i][i];
    }
    x = b;
    return true;
}

// Levenberg-Marquardt over the first n parameters on the inliers; central differences.
template <class Model, class Sample>
void refine(const Model& model, const std::vector<Sample>& s, const std::vector<uint8_t>& inlier,
            int n, Params& q) {
    std::vector<double> r, rp, rm;
    model.residuals(q, s, r);
    double cost = weighted_cost(r, inlier);
    double lambda = 1e-3;
    std::vector<std::array<double, 7>> jac(r.size());
    for (int it = 0; it < kIterations; ++it) {
        constexpr double h = 1e-6;
        for (int k = 0; k < n; ++k) {
            Params a = q, b = q;
            a[k] += h;
            b[k] -= h;
            model.residuals(a, s, rp);
            model.residuals(b, s, rm);
            for (std::size_t i = 0; i < r.size(); ++i) jac[i][k] = (rp[i] - rm[i]) / (2.0 * h);
        }
        std::array<std::array<double, 7>, 7> a{};
        std::array<double, 7> g{};
        for (std::size_t i = 0; i < r.size(); ++i) {
            if (!inlier[i / 2] || r[i] == kBehindPx) continue;
            for (int j = 0; j < n; ++j) {
                g[j] -= jac[i][j] * r[i];
                for (int k = 0; k <= j; ++k) a[j][k] += jac[i][j] * jac[i][k];
            }
        }
        double largest = 0.0;
        for (int j = 0; j < n; ++j) largest = std::max(largest, a[j][j]);
        if (!(largest > 0.0) || !std::isfinite(largest)) return;
        bool improved = false;
        while (lambda < 1e12) {
            auto damped = a;
            for (int j = 0; j < n; ++j) {
                for (int k = j + 1; k < n; ++k) damped[j][k] = damped[k][j];
                damped[j][j] += lambda * (a[j][j] + 1e-9 * largest);
            }
            std::array<double, 7> step{};
            Params next = q;
            if (solve(damped, g, n, step)) {
                for (int j = 0; j < n; ++j) next[j] += step[j];
                model.residuals(next, s, rp);
                const double c = weighted_cost(rp, inlier);
                if (c < cost) {
                    const bool converged = cost - c <= 1e-12 * cost;
                    q = next;
                    r.swap(rp);
                    cost = c;
                    lambda = std::max(lambda / 3.0, 1e-9);
                    improved = !converged;
                    break;
                }
            }
            lambda *= 4.0;
        }
        if (!improved) return;
    }
}

inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

}  // namespace reprise::codec::fit
