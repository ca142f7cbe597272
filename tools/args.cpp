#include "args.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "reprise/core/image.hpp"

namespace reprise::cli {

Args::Args(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void Args::add(Spec spec) {
    for (const Spec& s : options_)
        REPRISE_ASSERT(s.name != spec.name);  // one declaration per option
    options_.push_back(std::move(spec));
}
void Args::option(const std::string& name, std::string* value, const std::string& help) {
    add({name, Kind::String, value, help});
}
void Args::option(const std::string& name, int* value, const std::string& help) {
    add({name, Kind::Int, value, help});
}
void Args::option(const std::string& name, double* value, const std::string& help) {
    add({name, Kind::Double, value, help});
}
void Args::flag(const std::string& name, bool* value, const std::string& help) {
    add({name, Kind::Flag, value, help});
}
void Args::positional(const std::string& name, std::string* value, const std::string& help,
                      bool required) {
    positionals_.push_back({name, Kind::String, value, help, required});
}

bool Args::given(const std::string& name) const {
    for (const Spec& s : options_)
        if (s.name == name) return s.seen;
    for (const Spec& s : positionals_)
        if (s.name == name) return s.seen;
    return false;
}

std::string Args::given_line(const std::vector<std::string>& leave_out) const {
    std::vector<std::string> options;
    for (const Spec& s : options_)
        if (s.seen && std::find(leave_out.begin(), leave_out.end(), s.name) == leave_out.end())
            options.push_back(s.kind == Kind::Flag ? s.name : s.name + " " + s.text);
    std::sort(options.begin(), options.end());
    std::string line = command_;
    for (const Spec& s : positionals_)
        if (s.seen) line += " " + s.text;
    for (const std::string& option : options) line += " " + option;
    return line;
}

static Status assign(const std::string& command, const std::string& name, int kind, void* target,
                     const std::string& text) {
    auto bad = [&](const char* what) {
        return Status::error(command + ": " + name + ": '" + text + "' is not " + what);
    };
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (kind == 0) {
        *static_cast<std::string*>(target) = text;
    } else if (kind == 1) {
        int v = 0;
        auto [end, ec] = std::from_chars(first, last, v);
        if (ec != std::errc() || end != last) return bad("an integer");
        *static_cast<int*>(target) = v;
    } else {
        double v = 0;
        auto [end, ec] = std::from_chars(first, last, v);
        if (ec != std::errc() || end != last || !std::isfinite(v)) return bad("a finite number");
        *static_cast<double*>(target) = v;
    }
    return {};
}

Status Args::parse(int argc, char** argv) {
    std::size_t next_positional = 0;
    for (int i = 0; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "-h" || arg == "--help") {
            help_ = true;
            return {};
        }
        if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
            std::string value;
            bool inline_value = false;
            if (auto eq = arg.find('='); eq != std::string::npos) {
                value = arg.substr(eq + 1);
                arg = arg.substr(0, eq);
                inline_value = true;
            }
            Spec* spec = nullptr;
            for (Spec& s : options_)
                if (s.name == arg) spec = &s;
            if (!spec) return Status::error(command_ + ": unknown option " + arg);
            spec->seen = true;
            if (spec->kind == Kind::Flag) {
                if (inline_value) return Status::error(command_ + ": " + arg + " takes no value");
                *static_cast<bool*>(spec->target) = true;
                continue;
            }
            if (!inline_value) {
                if (i + 1 >= argc) return Status::error(command_ + ": " + arg + " needs a value");
                value = argv[++i];
            }
            spec->text = value;
            REPRISE_TRY(assign(command_, arg, int(spec->kind), spec->target, value));
            continue;
        }
        if (next_positional >= positionals_.size())
            return Status::error(command_ + ": unexpected argument '" + arg + "'");
        Spec& spec = positionals_[next_positional++];
        spec.seen = true;
        spec.text = arg;
        *static_cast<std::string*>(spec.target) = arg;
    }
    for (const Spec& s : positionals_)
        if (s.required && !s.seen) return Status::error(command_ + ": missing " + s.name);
    return {};
}

std::string Args::usage() const {
    std::string text = "usage: reprise " + command_;
    for (const Spec& s : positionals_) text += s.required ? " " + s.name : " [" + s.name + "]";
    if (!options_.empty()) text += " [options]";
    text += "\n\n" + summary_ + "\n";
    if (!positionals_.empty() || !options_.empty()) text += "\n";
    auto line = [&](const Spec& s, const char* meta) {
        std::string left = "  " + s.name + meta;
        if (left.size() < 26)
            left.resize(26, ' ');
        else
            left += "  ";
        text += left + s.help + "\n";
    };
    for (const Spec& s : positionals_) line(s, "");
    for (const Spec& s : options_) {
        const char* meta = s.kind == Kind::Flag ? "" : s.kind == Kind::String ? " VALUE" : " N";
        line(s, meta);
    }
    text += "  --max-memory SIZE       memory limit, e.g. 8G or 512M (default 4G; any command)\n";
    return text;
}

Status parse_size(const std::string& text, int& width, int& height) {
    auto x = text.find('x');
    if (x == std::string::npos) return Status::error("size '" + text + "' is not WxH");
    auto number = [](const std::string& part, int& out) {
        auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
        return ec == std::errc() && end == part.data() + part.size();
    };
    if (!number(text.substr(0, x), width) || !number(text.substr(x + 1), height))
        return Status::error("size '" + text + "' is not WxH");
    return check_image_size(width, height, "size '" + text + "'");
}

int report(const Args& args, const Status& parsed, const Status& result) {
    if (!parsed.ok()) {
        std::fprintf(stderr, "reprise %s\n(see --help)\n", parsed.message().c_str());
        return 2;
    }
    if (args.help_requested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (!result.ok()) {
        std::fprintf(stderr, "reprise: %s\n", result.message().c_str());
        return 1;
    }
    return 0;
}

}  // namespace reprise::cli
