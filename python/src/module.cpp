// The `reprise` Python module: numpy in, numpy out; a failed Status raises reprise.Error.
#include "common.hpp"

PYBIND11_MODULE(reprise, m) {
    namespace rp = reprise::python;
    m.doc() =
        "reprise: frames nobody rendered (frame-rate upconversion, the other eye, a codec) from "
        "rendered colour, depth and motion. Conventions: docs/conventions.md.";
    pybind11::register_exception<rp::Error>(m, "Error", PyExc_RuntimeError);
    rp::bind_frame(m);
    rp::bind_fruc(m);
    rp::bind_stereo(m);
    rp::bind_metrics(m);
    rp::bind_render(m);
    rp::bind_codec(m);
    m.attr("__version__") = "0.1.0";
}
