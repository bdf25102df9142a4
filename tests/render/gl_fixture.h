// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A fixture holding an offscreen GL context (EGL surfaceless or OSMesa, Mesa llvmpipe on the CI
// machines). Floating-point traps are off inside: llvmpipe's generated code divides by zero and
// makes NaNs on purpose (clipping, 1/w). Without any context the test is skipped with the reason,
// unless PLIANT_REQUIRE_GL=1, where it fails.

#include <pliant/render/image.h>
#include <pliant/render/offscreen_context.h>

#include <gtest/gtest.h>

#include "support/fp_traps.h"

#include <cstdlib>
#include <memory>
#include <optional>

namespace pliant::test
{

/// Whether PLIANT_REQUIRE_GL=1: a context (or a backend) that cannot be made is then a failure,
/// not a skip (scripts/check.sh sets it under CI, which installs Mesa).
inline bool gl_required()
{
    const char* require = std::getenv("PLIANT_REQUIRE_GL");
    return require != nullptr && require[0] == '1';
}

class GlTest : public ::testing::Test
{
protected:
    void SetUp() override
    {
        traps_ = std::make_unique<FpTrapsOff>();
        auto made = render::OffscreenContext::create();
        if (!made)
        {
            if (gl_required())
                FAIL() << made.error().message;
            GTEST_SKIP() << made.error().message;
        }
        context_.emplace(std::move(*made));
    }
    void TearDown() override
    {
        context_.reset();
        traps_.reset();
    }

    std::optional<render::OffscreenContext> context_;

private:
    std::unique_ptr<FpTrapsOff> traps_;
};

inline bool is_rgb(const render::Image& image, int x, int y, int r, int g, int b)
{
    const std::uint8_t* p = image.pixel(x, y);
    return p[0] == r && p[1] == g && p[2] == b;
}

/// Rec. 709 luma of a pixel, 0..255.
inline double luma(const render::Image& image, int x, int y)
{
    const std::uint8_t* p = image.pixel(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

}  // namespace pliant::test
