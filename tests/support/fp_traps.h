// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

#include <cfenv>

namespace pliant::test
{

inline void enable_fp_traps()
{
#if defined(__GLIBC__) && !defined(__clang__)
    feenableexcept(FE_INVALID | FE_DIVBYZERO);
#elif defined(__GLIBC__)
    feenableexcept(FE_INVALID | FE_DIVBYZERO);
#endif
}

/// Turns the traps off for a scope, around third-party code that computes with inf/NaN on
/// purpose (for example a file importer's bounding-box code).
class FpTrapsOff
{
public:
    FpTrapsOff() : saved_(fegetexcept()) { fedisableexcept(FE_ALL_EXCEPT); }
    ~FpTrapsOff()
    {
        feclearexcept(FE_ALL_EXCEPT);
        feenableexcept(saved_);
    }
    FpTrapsOff(const FpTrapsOff&) = delete;
    FpTrapsOff& operator=(const FpTrapsOff&) = delete;

private:
    int saved_;
};

}  // namespace pliant::test
