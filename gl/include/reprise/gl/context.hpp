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
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    void make_current() const;
    // The same, or an error when EGL refuses: the context is current on another thread (a
    // context serves one thread at a time).
    Status acquire() const;
    const std::string& description() const { return description_; }  // "llvmpipe (LLVM ...)"

private:
    Context() = default;
    void* display_ = nullptr;
    void* context_ = nullptr;
    std::string description_;
};

}  // namespace reprise::gl
