#include "bench.hpp"

namespace reprise::cli {

Status open_bench_scene(const std::string& name, BenchScene& bench) {
    REPRISE_TRY(server::load_scene(name, bench.scene, bench.path));
    return server::Renderer::create(bench.renderer);
}

}  // namespace reprise::cli
