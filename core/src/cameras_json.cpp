// cameras.json: the cameras of a sequence whose frames carry none (Blender's render passes).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "reprise/core/exr.hpp"

namespace reprise {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::uintmax_t kMaxBytes = 64u << 20;

Status matrix(const json& entry, const char* key, const std::string& where, bool required,
              glm::mat4& out, bool& found) {
    found = entry.contains(key);
    if (!found) return required ? Status::error(where + ": no \"" + key + "\"") : Status();
    const json& values = entry[key];
    if (!values.is_array() || values.size() != 16)
        return Status::error(where + ": \"" + key + "\" must hold 16 numbers (column-major)");
    for (int i = 0; i < 16; ++i) {
        if (!values[i].is_number() || !std::isfinite(values[i].get<double>()))
            return Status::error(where + ": \"" + key + "\"[" + std::to_string(i) +
                                 "] is not a finite number");
        out[i / 4][i % 4] = values[i].get<float>();
    }
    return {};
}

Status number(const json& entry, const char* key, const std::string& where, double& out) {
    if (!entry.contains(key)) return {};
    if (!entry[key].is_number() || !std::isfinite(entry[key].get<double>()))
        return Status::error(where + ": \"" + key + "\" is not a finite number");
    out = entry[key].get<double>();
    return {};
}

}  // namespace

Status read_cameras_json(const std::string& path, const std::vector<std::string>& files,
                         std::vector<Camera>& cameras) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) return Status::error(path + ": cannot read: " + ec.message());
    if (size > kMaxBytes) return Status::error(path + ": larger than 64 MiB");
    std::ifstream in(path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) return Status::error(path + ": cannot read");
    return parse_cameras_json(text.str(), path, files, cameras);
}

Status parse_cameras_json(std::string_view text, const std::string& path,
                          const std::vector<std::string>& files, std::vector<Camera>& cameras) {
    cameras.assign(files.size(), Camera{});
    const json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded()) return Status::error(path + ": not valid JSON");
    if (!doc.is_object() || !doc.contains("frames") || !doc["frames"].is_array())
        return Status::error(path + ": expected an object with a \"frames\" array");
    std::map<std::string, std::size_t> by_name;
    for (std::size_t i = 0; i < files.size(); ++i)
        by_name[fs::path(files[i]).filename().string()] = i;
    const json& frames = doc["frames"];
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const json& entry = frames[k];
        const std::string where = path + ": frames[" + std::to_string(k) + "]";
        if (!entry.is_object() || !entry.contains("file") || !entry["file"].is_string())
            return Status::error(where + ": expected an object with a \"file\" name");
        const auto file = by_name.find(entry["file"].get<std::string>());
        Camera camera;
        bool found = false;
        REPRISE_TRY(matrix(entry, "view", where, true, camera.view, found));
        REPRISE_TRY(matrix(entry, "projection", where, true, camera.projection, found));
        REPRISE_TRY(matrix(entry, "prev_view", where, true, camera.prev_view, found));
        REPRISE_TRY(matrix(entry, "prev_projection", where, true, camera.prev_projection, found));
        double near = camera.near, far = camera.far, time = 0.0;
        REPRISE_TRY(number(entry, "near", where, near));
        REPRISE_TRY(number(entry, "far", where, far));
        REPRISE_TRY(number(entry, "time", where, time));
        if (!(near > 0.0 && far > near)) return Status::error(where + ": needs 0 < near < far");
        if (!has_projection(camera) || glm::determinant(camera.projection) == 0.0f ||
            glm::determinant(camera.prev_projection) == 0.0f)
            return Status::error(where + ": a projection is the identity or singular");
        if (glm::determinant(camera.view) == 0.0f || glm::determinant(camera.prev_view) == 0.0f)
            return Status::error(where + ": a view matrix is singular");
        camera.near = float(near), camera.far = float(far), camera.time = time;
        if (entry.contains("cut")) {
            if (!entry["cut"].is_boolean())
                return Status::error(where + ": \"cut\" must be true or false");
            camera.cut = entry["cut"].get<bool>() ? Cut::Yes : Cut::No;
        }
        if (file != by_name.end()) cameras[file->second] = camera;  // others: not in this folder
    }
    return {};
}

Status read_frame(const Sequence& sequence, std::size_t index, Frame& frame) {
    REPRISE_ASSERT(index < sequence.files.size());
    REPRISE_TRY(read_frame(sequence.files[index], frame));
    if (!has_projection(frame.camera) && index < sequence.cameras.size())
        frame.camera = sequence.cameras[index];
    return {};
}

}  // namespace reprise
