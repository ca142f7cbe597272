// libFuzzer target: cameras.json (the cameras of a sequence whose frames carry none), parsed from
// memory against two frame names.
#include <cstdint>
#include <string_view>

#include "reprise/core/exr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::vector<std::string> files = {"dir/0001.exr", "dir/0002.exr"};
    std::vector<reprise::Camera> cameras;
    (void)reprise::parse_cameras_json(std::string_view(reinterpret_cast<const char*>(data), size),
                                      "fuzz/cameras.json", files, cameras);
    return 0;
}
