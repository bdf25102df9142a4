// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The test main: floating-point traps on invalid operations and division by zero (STYLE.md §10),
// so a NaN born in a kernel stops the test where it is made.
#include <gtest/gtest.h>

#include "support/fp_traps.h"

int main(int argc, char** argv)
{
    ::testing::InitGoogleTest(&argc, argv);
    pliant::test::enable_fp_traps();
    return RUN_ALL_TESTS();
}
