#pragma once
// Shared by the binding files: errors as Python exceptions, images as numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <stdexcept>
#include <string>

#include "reprise/core/frame.hpp"
#include "reprise/core/nonfinite.hpp"

namespace reprise::python {

namespace py = pybind11;

// reprise.Error (a RuntimeError) carries a failed Status's message.
struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// NaN/Inf counts per channel (repaired by the library before use).
inline py::dict nonfinite_dict(const NonfiniteCounts& c) {
    py::dict d;
    d["color"] = c.color;
    d["depth"] = c.depth;
    d["motion"] = c.motion;
    d["normal"] = c.normal;
    d["ui"] = c.ui;
    d["frames"] = c.frames;
    return d;
}

inline void check(const Status& status) {
    if (!status.ok()) throw Error(status.message());
}

// Bad arguments: ValueError and TypeError with a message naming the argument.
[[noreturn]] inline void value_error(const std::string& message) { throw py::value_error(message); }
[[noreturn]] inline void type_error(const std::string& message) { throw py::type_error(message); }

// How a pixel type looks to numpy: scalar type and components per pixel (1 = a 2-D array).
template <class T>
struct PixelLayout {
    using Scalar = T;
    static constexpr int components = 1;
};
template <int N>
struct PixelLayout<glm::vec<N, float, glm::defaultp>> {
    using Scalar = float;
    static constexpr int components = N;
};

// A numpy view of an owned image (no copy): `owner` stays alive as long as the array does.
// None for an empty image.
template <class T>
py::object image_array(Image<T>& image, py::handle owner) {
    if (image.empty()) return py::none();
    using L = PixelLayout<T>;
    std::vector<py::ssize_t> shape{image.height(), image.width()};
    std::vector<py::ssize_t> strides{py::ssize_t(sizeof(T)) * image.width(), sizeof(T)};
    if (L::components > 1) {
        shape.push_back(L::components);
        strides.push_back(sizeof(typename L::Scalar));
    }
    return py::array_t<typename L::Scalar>(
        shape, strides, reinterpret_cast<typename L::Scalar*>(image.data()), owner);
}

// glm (column-major) <-> a 4x4 numpy array indexed [row, column].
py::array_t<float> matrix_array(const glm::mat4& m);
glm::mat4 matrix_from(const py::handle& value, const char* what);

// Display images (H, W, 3) floating point in [0, 1] as views for the metrics; a float32 array
// laid out as packed RGB rows is used in place, anything else is converted once into `storage`.
ImageView<const glm::vec3> display_view(const py::handle& value, const char* what,
                                        py::array_t<float>& storage);

void bind_frame(py::module_& m);
void bind_fruc(py::module_& m);
void bind_stereo(py::module_& m);
void bind_metrics(py::module_& m);
void bind_render(py::module_& m);
void bind_codec(py::module_& m);
void bind_upsample(py::module_& m);

}  // namespace reprise::python
