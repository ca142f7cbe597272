// libFuzzer target: the glTF loader on a .gltf or .glb held in memory (tinygltf's parser,
// stb_image for data: URI images, then reprise's validation and conversion). A memory load
// reads no files, and nothing here creates a GL context.
#include <cstdint>

#include "reprise/server/gltf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    reprise::server::Scene scene;
    (void)reprise::server::load_gltf(std::span(data, size), "fuzz.gltf", scene);
    return 0;
}
