// Test support: one headless renderer per test binary, created on first use.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "reprise/server/renderer.hpp"

namespace reprise::test {

// The renderer every test of this binary shares; a failure to create it fails the test asking.
inline server::Renderer& shared_renderer() {
    static std::unique_ptr<server::Renderer> renderer = [] {
        std::unique_ptr<server::Renderer> made;
        Status status = server::Renderer::create(made);
        if (!status.ok()) ADD_FAILURE() << status.message();
        return made;
    }();
    return *renderer;
}

}  // namespace reprise::test
