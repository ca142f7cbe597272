// Lists reprise's built-in scenes: a program that links reprise::server (tinygltf, EGL and GLES
// behind it) from an installed package. It creates no GL context.
#include <cstdio>

#include "reprise/server/builtin_scenes.hpp"

int main() {
    for (const reprise::server::SceneInfo& scene : reprise::server::builtin_scenes())
        std::printf("%-10s %s\n", scene.name, scene.stresses);
    return 0;
}
