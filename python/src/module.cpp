// The native part of the `reprise` Python package (reprise._native, re-exported by
// reprise/__init__.py): numpy in, numpy out; a failed Status raises reprise.Error.
#include <cstdint>
#include <string>

#include "common.hpp"
#include "reprise/core/memory_limit.hpp"

PYBIND11_MODULE(_native, m) {
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
    rp::bind_upsample(m);
    reprise::set_memory_limit_hint("reprise.set_max_memory() to change");
    m.def(
        "set_max_memory",
        [](const pybind11::object& size) {
            std::uint64_t bytes = 0;
            if (pybind11::isinstance<pybind11::str>(size)) {
                const reprise::Status parsed =
                    reprise::parse_bytes(size.cast<std::string>(), bytes);
                if (!parsed.ok()) rp::value_error(parsed.message());
            } else {
                const long long value = size.cast<long long>();
                if (value <= 0) rp::value_error("set_max_memory: bytes must be > 0");
                bytes = std::uint64_t(value);
            }
            reprise::set_memory_limit(bytes);
        },
        pybind11::arg("size"),
        "What one call may allocate, in bytes or as '8G', '512M' (default 4 GiB). Calls estimate "
        "their needs first and raise reprise.Error with the figure instead of allocating more.");
    m.def(
        "max_memory", [] { return reprise::memory_limit(); },
        "The memory limit in bytes (reprise.set_max_memory).");
    m.attr("__version__") = REPRISE_VERSION;  // CMake's project version
}
