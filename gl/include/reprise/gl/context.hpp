#pragma once
// A headless OpenGL ES 3 context through EGL: a real GPU's EGL device when one is present,
// else Mesa's surfaceless platform (llvmpipe). REPRISE_EGL=surfaceless|device forces one.
#include <memory>
#include <string>

#include "reprise/core/status.hpp"

namespace reprise::gl {

class Context {
public:
    static Status create(std::unique_ptr<Context>& context);
    // The application's EGL context current on this thread (OpenGL ES 3.1 or later), used as it
    // is: nothing is created, made current or destroyed; acquire() checks that it is current.
    static Status adopt_current(std::unique_ptr<Context>& context);
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    void make_current() const;  // an adopted context: nothing (the application makes it current)
    // The same, or an error when EGL refuses: the context is current on another thread (a
    // context serves one thread at a time). An adopted context: an error unless it is current.
    Status acquire() const;
    bool adopted() const { return adopted_; }
    const std::string& description() const { return description_; }  // "llvmpipe (LLVM ...)"

private:
    Context() = default;
    Status describe(bool compute);  // the renderer's name; an error where it lacks what we need
    void* display_ = nullptr;
    void* context_ = nullptr;
    bool adopted_ = false;
    std::string description_;
};

}  // namespace reprise::gl
