// reprise batch — a sequence's fruc or stereo over a Dask cluster: runs `python3 -m
// reprise.batch` (python/reprise/batch.py) with the Python package beside this executable.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"

namespace fs = std::filesystem;

namespace reprise::cli {

namespace {

// The folder that holds reprise/__init__.py for this executable: the build tree's python/
// (build/tools/reprise -> build/python), else the installed one (PREFIX/bin/reprise ->
// PREFIX/REPRISE_PYTHON_INSTALL_DIR); empty when neither is there (the interpreter's own path).
std::string package_folder(const fs::path& executable) {
    const fs::path tools = executable.parent_path();
    const fs::path installed(REPRISE_PYTHON_INSTALL_DIR);
    for (const fs::path& candidate :
         {tools.parent_path() / "python",
          installed.is_absolute() ? installed : tools.parent_path() / installed}) {
        std::error_code ec;
        if (fs::exists(candidate / "reprise" / "__init__.py", ec))
            return candidate.lexically_normal().string();
    }
    return {};
}

}  // namespace

int command_batch(int argc, char** argv) {
    std::error_code ec;
    const fs::path executable = fs::read_symlink("/proc/self/exe", ec);
    if (ec) {
        std::fprintf(stderr, "reprise batch: cannot find this executable: %s\n",
                     ec.message().c_str());
        return 1;
    }
    const std::string package = package_folder(executable);
    if (!package.empty()) {
        std::string joined = package;
        if (const char* path = std::getenv("PYTHONPATH"); path && *path)
            joined.append(":").append(path);
        ::setenv("PYTHONPATH", joined.c_str(), 1);
    }
    // The workers run this very executable (reprise.batch's --reprise).
    const std::string self = executable.string();
    // The interpreter the package was built for (Debian's python3-distributed belongs to
    // /usr/bin/python3, which another python3 first on PATH may lack), else python3 on PATH.
    std::error_code found;
    const std::string python = fs::exists(REPRISE_PYTHON, found) ? REPRISE_PYTHON : "python3";
    std::vector<std::string> words = {python, "-m", "reprise.batch"};
    for (int i = 0; i < argc; ++i) words.push_back(argv[i]);
    words.insert(words.end(), {"--reprise", self});
    std::vector<char*> line;
    for (std::string& w : words) line.push_back(w.data());
    line.push_back(nullptr);
    ::execvp(python.c_str(), line.data());
    std::fprintf(stderr,
                 "reprise batch: cannot run %s (%s); it needs Python 3 with Dask distributed "
                 "(Debian: python3-distributed)\n",
                 python.c_str(), std::strerror(errno));
    return 1;
}

}  // namespace reprise::cli
