// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Floating-point traps held off while Assimp runs (its readers and exporters compute with NaN and
// infinities on purpose; a program that enables FE_INVALID traps must not die inside them).

#include <cfenv>

namespace pliant::mesh::detail
{

/// Holds floating-point traps off for a scope (feholdexcept saves the environment and masks all
/// exceptions; fesetenv restores it without raising the flags set meanwhile).
class FpHold
{
public:
    FpHold() { feholdexcept(&saved_); }
    ~FpHold()
    {
        feclearexcept(FE_ALL_EXCEPT);
        fesetenv(&saved_);
    }
    FpHold(const FpHold&) = delete;
    FpHold& operator=(const FpHold&) = delete;

private:
    std::fenv_t saved_{};
};

}  // namespace pliant::mesh::detail
