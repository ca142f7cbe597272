#include <algorithm>

#include "bench.hpp"
#include "reprise/core/exr.hpp"
#include "timing.hpp"

namespace reprise::cli {

namespace fs = std::filesystem;

bool is_sequence(const std::string& scene) { return scene.rfind(kSequencePrefix, 0) == 0; }

bool holds_exr(const fs::path& dir) {
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
        if (e.path().extension() == ".exr") return true;
    return false;
}

std::vector<std::string> sequence_folders(const std::string& spec, bool (*holds)(const fs::path&)) {
    std::vector<std::string> sequences;
    for (const std::string& dir : split_list(spec)) {
        std::error_code ec;
        std::vector<std::string> inner;
        if (!holds(dir))
            for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
                if (e.is_directory() && holds(e.path())) inner.push_back(e.path().string());
        std::sort(inner.begin(), inner.end(), natural_less);
        if (inner.empty()) inner.push_back(dir);
        for (const std::string& d : inner) sequences.push_back(kSequencePrefix + d);
    }
    return sequences;
}

Status open_bench_scene(const std::string& name, BenchScene& bench) {
    REPRISE_TRY(server::load_scene(name, bench.scene, bench.path));
    return server::Renderer::create(bench.renderer);
}

}  // namespace reprise::cli
