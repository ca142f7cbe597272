// PSNR, SSIM and FLIP on display values, and linear -> display conversion.
#include <cmath>

#include "common.hpp"
#include "reprise/core/metrics.hpp"

namespace reprise::python {
namespace {

py::array_t<float> as_float_array(const py::handle& value, const char* what) {
    const py::array raw = py::module_::import("numpy").attr("asarray")(value);
    if (raw.dtype().kind() != 'f')
        type_error(std::string(what) + ": expected a floating-point array, got dtype " +
                   py::str(raw.dtype()).cast<std::string>());
    return py::array_t<float>::ensure(raw);  // float32 as it is, other floats converted
}

void require_finite(const ImageView<const glm::vec3>& v, const char* what) {
    for (int y = 0; y < v.height; ++y)
        for (int x = 0; x < v.width; ++x) {
            const glm::vec3& p = v(x, y);
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                value_error(std::string(what) + ": NaN or Inf at pixel (" + std::to_string(x) +
                            ", " + std::to_string(y) + ")");
        }
}

// Display inputs of one size and an optional mask: views, no copies where the layout allows.
struct Inputs {
    py::array_t<float> reference_storage, test_storage;
    py::array_t<uint8_t> mask_storage;
    ImageView<const glm::vec3> reference, test;
    ImageView<const uint8_t> mask;

    Inputs(const py::handle& ref, const py::handle& tst, const py::handle& msk) {
        reference = display_view(ref, "reference", reference_storage);
        test = display_view(tst, "test", test_storage);
        if (reference.width != test.width || reference.height != test.height)
            value_error("reference is " + std::to_string(reference.width) + "x" +
                        std::to_string(reference.height) + " but test is " +
                        std::to_string(test.width) + "x" + std::to_string(test.height));
        if (msk.is_none()) return;
        const py::array raw = py::module_::import("numpy").attr("asarray")(msk);
        const char kind = raw.dtype().kind();
        if (kind != 'b' && kind != 'u' && kind != 'i')
            type_error("mask: expected a bool or integer array");
        if (raw.ndim() != 2 || raw.shape(0) != reference.height || raw.shape(1) != reference.width)
            value_error("mask: expected shape (height, width) of the images");
        if (kind == 'b' || raw.dtype().itemsize() == 1)
            mask_storage = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(
                raw.attr("view")("uint8"));
        else
            mask_storage = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(
                raw.attr("__ne__")(0));
        mask = {mask_storage.data(), reference.width, reference.height, reference.width};
    }
};

}  // namespace

ImageView<const glm::vec3> display_view(const py::handle& value, const char* what,
                                        py::array_t<float>& storage) {
    py::array_t<float> a = as_float_array(value, what);
    if (a.ndim() != 3 || a.shape(2) != 3)
        value_error(std::string(what) + ": expected shape (height, width, 3) of display RGB");
    if (a.shape(0) < 1 || a.shape(1) < 1 || a.shape(0) > kMaxImageSide ||
        a.shape(1) > kMaxImageSide)
        value_error(std::string(what) + ": size outside 1.." + std::to_string(kMaxImageSide));
    // Used in place when pixels are packed RGB and rows a whole number of pixels apart.
    const bool packed = a.strides(2) == 4 && a.strides(1) == 12 && a.strides(0) > 0 &&
                        a.strides(0) % 12 == 0 &&
                        reinterpret_cast<std::uintptr_t>(a.data()) % alignof(glm::vec3) == 0;
    if (!packed) a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
    storage = a;
    const ImageView<const glm::vec3> view{reinterpret_cast<const glm::vec3*>(a.data()),
                                          int(a.shape(1)), int(a.shape(0)),
                                          packed ? a.strides(0) / 12 : a.shape(1)};
    require_finite(view, what);
    return view;
}

void bind_metrics(py::module_& m) {
    m.def(
        "to_display",
        [](const py::handle& linear) {
            const py::array_t<float> a = as_float_array(linear, "linear");
            if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4))
                value_error("linear: expected shape (height, width, 3 or 4)");
            const auto in = a.unchecked<3>();
            py::array_t<float> out({a.shape(0), a.shape(1), py::ssize_t(3)});
            auto o = out.mutable_unchecked<3>();
            for (py::ssize_t y = 0; y < a.shape(0); ++y)
                for (py::ssize_t x = 0; x < a.shape(1); ++x)
                    for (int c = 0; c < 3; ++c) o(y, x, c) = linear_to_srgb(in(y, x, c));
            return out;
        },
        py::arg("linear"),
        "Display RGB (H, W, 3) in [0, 1]: linear light clamped, then sRGB-encoded (alpha "
        "dropped). The metrics compare such images.");

    auto one = [&](const char* name, auto metric, const char* doc) {
        m.def(
            name,
            [metric](const py::handle& reference, const py::handle& test, const py::handle& mask) {
                Inputs in(reference, test, mask);
                py::gil_scoped_release release;
                return metric(in.reference, in.test, in.mask);
            },
            py::arg("reference"), py::arg("test"), py::arg("mask") = py::none(), doc);
    };
    one(
        "psnr", [](auto r, auto t, auto k) { return psnr(r, t, k); },
        "PSNR in dB over RGB of two display images (H, W, 3); +inf when identical.");
    one(
        "ssim", [](auto r, auto t, auto k) { return ssim(r, t, k); },
        "Mean SSIM over RGB of two display images (H, W, 3).");
    m.def(
        "flip",
        [](const py::handle& reference, const py::handle& test, const py::handle& mask,
           double pixels_per_degree, bool error_map) -> py::object {
            Inputs in(reference, test, mask);
            check(check_flip(in.reference.width, in.reference.height, pixels_per_degree));
            py::array_t<float> map;
            ImageView<float> map_view;
            if (error_map) {
                map = py::array_t<float>(
                    {py::ssize_t(in.reference.height), py::ssize_t(in.reference.width)});
                map_view = {map.mutable_data(), in.reference.width, in.reference.height,
                            in.reference.width};
            }
            double mean;
            {
                py::gil_scoped_release release;
                mean = flip(in.reference, in.test, in.mask, map_view, float(pixels_per_degree));
            }
            if (error_map) return py::make_tuple(mean, map);
            return py::float_(mean);
        },
        py::arg("reference"), py::arg("test"), py::arg("mask") = py::none(),
        py::arg("pixels_per_degree") = 67.0, py::arg("error_map") = false,
        "Mean LDR-FLIP of two display images; with error_map=True, (mean, per-pixel map).");
    m.def(
        "image_error",
        [](const py::handle& reference, const py::handle& test, const py::handle& mask) {
            Inputs in(reference, test, mask);
            ImageError e;
            {
                py::gil_scoped_release release;
                e = image_error(in.reference, in.test, in.mask);
            }
            py::dict d;
            d["psnr"] = e.psnr;
            d["ssim"] = e.ssim;
            d["flip"] = e.flip;
            return d;
        },
        py::arg("reference"), py::arg("test"), py::arg("mask") = py::none(),
        "{'psnr', 'ssim', 'flip'} of two display images (H, W, 3).");
}

}  // namespace reprise::python
