#pragma once
// Command-line options of one `reprise` subcommand: declared once, parsed with one clear error
// per bad argument, listed by --help.
#include <string>
#include <vector>

#include "reprise/core/status.hpp"

namespace reprise::cli {

class Args {
public:
    Args(std::string command, std::string summary);

    // Options write into the given variables only when present on the command line.
    void option(const std::string& name, std::string* value, const std::string& help);
    void option(const std::string& name, int* value, const std::string& help);
    void option(const std::string& name, double* value, const std::string& help);
    void flag(const std::string& name, bool* value, const std::string& help);
    // Positional arguments, in order.
    void positional(const std::string& name, std::string* value, const std::string& help,
                    bool required = true);

    // Returns an error naming the argument; sets help_requested() on -h/--help.
    Status parse(int argc, char** argv);
    bool help_requested() const { return help_; }
    bool given(const std::string& name) const;
    // The options given, sorted, as "--name value" (flags bare), leaving out `leave_out`: what a
    // run was asked to do, compared when it is resumed.
    std::string given_line(const std::vector<std::string>& leave_out) const;
    std::string usage() const;

private:
    enum class Kind { String, Int, Double, Flag };
    struct Spec {
        std::string name;
        Kind kind;
        void* target;
        std::string help;
        bool required = false;
        bool seen = false;
        std::string text;  // as given
    };
    void add(Spec spec);

    std::string command_, summary_;
    std::vector<Spec> options_, positionals_;
    bool help_ = false;
};

// Parses "WxH" (e.g. 1920x1080) with both sides in 1..16384.
Status parse_size(const std::string& text, int& width, int& height);

// Runs a parsed subcommand body: prints --help or the error ("reprise CMD: ...") and maps
// failures to exit code 1 (bad data) or 2 (bad arguments).
int report(const Args& args, const Status& parsed, const Status& result);

}  // namespace reprise::cli
