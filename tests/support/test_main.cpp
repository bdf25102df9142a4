// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The test main: floating-point traps on invalid operations and division by zero
// (docs/style.md §10), so a NaN born in a kernel stops the test where it is made; and each test's
// scratch folders removed when it passes (kept for a look when it fails).
#include <gtest/gtest.h>

#include "support/fp_traps.h"
#include "support/test_paths.h"

namespace
{

class ScratchCleaner final : public ::testing::EmptyTestEventListener
{
    void OnTestEnd(const ::testing::TestInfo& info) override
    {
        const ::testing::TestResult* result = info.result();
        pliant::test::end_scratch_dirs(result == nullptr || !result->Failed());
    }
};

}  // namespace

int main(int argc, char** argv)
{
    ::testing::InitGoogleTest(&argc, argv);
    pliant::test::enable_fp_traps();
    // The listener list owns the listener.
    ::testing::UnitTest::GetInstance()->listeners().Append(new ScratchCleaner);
    return RUN_ALL_TESTS();
}
