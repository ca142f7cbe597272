// Test support: running the `reprise` executable and its subcommands, scratch folders, files.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace reprise::test {

// What a run of the `reprise` executable gave back.
struct Outcome {
    int status = -1;  // exit status; 128 + signal when killed, 124 when it timed out
    std::string output;
};

// Runs `reprise ARGUMENTS` (REPRISE_BINARY) with stderr folded into stdout, killed after
// `timeout_seconds`.
inline Outcome run_reprise(const std::string& arguments, int timeout_seconds) {
    std::string command =
        "timeout " + std::to_string(timeout_seconds) + " " REPRISE_BINARY " " + arguments + " 2>&1";
    Outcome r;
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return r;
    std::array<char, 4096> buffer;
    std::size_t n;
    while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
        r.output.append(buffer.data(), n);
    int raw = pclose(pipe);
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
    return r;
}

// The standard output of a shell command; empty when it cannot be started.
inline std::string run_output(const std::string& command) {
    std::string out;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return out;
    char buf[256];
    while (std::fgets(buf, sizeof buf, pipe)) out += buf;
    ::pclose(pipe);
    return out;
}

// Calls a subcommand in process (cli::command_*) with `args` as its argv.
inline int run_command(int (*command)(int, char**), std::vector<std::string> args) {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    return command(int(argv.size()), argv.data());
}

// The whole of a text file; empty when it cannot be read.
inline std::string read_text(const std::filesystem::path& path) {
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

// `dir`, emptied: removed with all it holds, then created again.
inline std::filesystem::path fresh_directory(const std::filesystem::path& dir) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// Quoted for the shell.
inline std::string q(const std::filesystem::path& p) {
    std::string quoted(1, '\'');
    quoted += p.string();
    quoted += '\'';
    return quoted;
}

// Every regular file below `dir` (hidden ones too), by relative path, with its bytes.
inline std::map<std::string, std::string> contents(const std::filesystem::path& dir) {
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
        if (entry.is_regular_file())
            files[std::filesystem::relative(entry.path(), dir).string()] = read_text(entry.path());
    return files;
}

// The names of the files that differ between two listings, or are in one only.
inline std::string differences(const std::map<std::string, std::string>& a,
                               const std::map<std::string, std::string>& b) {
    std::string names;
    for (const auto& [name, bytes] : a)
        if (!b.count(name) || b.at(name) != bytes) names += " " + name;
    for (const auto& [name, bytes] : b)
        if (!a.count(name)) names += " " + name;
    return names;
}

// Frames only: frame_NNNNN.exr below `dir`.
inline std::map<std::string, std::string> frames(const std::filesystem::path& dir) {
    std::map<std::string, std::string> all = contents(dir), exr;
    for (auto& [name, bytes] : all)
        if (name.ends_with(".exr")) exr[name] = bytes;
    return exr;
}

}  // namespace reprise::test
