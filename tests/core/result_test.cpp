// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/hash.h>
#include <pliant/core/result.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pliant::core
{
namespace
{

Result<int> half(int x)
{
    if (x % 2 != 0)
        return fail(ErrorCode::InvalidArgument, "half: " + std::to_string(x) + " is odd");
    return x / 2;
}

TEST(Result, CarriesAValueOrAnError)
{
    auto ok = half(8);
    ASSERT_TRUE(ok.has_value());
    EXPECT_EQ(*ok, 4);
    auto bad = half(3);
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
    EXPECT_EQ(bad.error().message, "half: 3 is odd");
    EXPECT_EQ(to_string(ErrorCode::OpenBoundary), "open-boundary");
}

// Reading the value of an error is a contract failure whose message keeps the error: a user who
// forgot to test the result still learns why the call failed.
TEST(ResultDeathTest, ValueOfAnErrorAbortsNamingTheError)
{
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_DEATH((void)half(3).value(),
                 "assertion failed: Result::value\\(\\) on an error: invalid-argument: half: 3 is "
                 "odd \\(has_value\\(\\)\\)");
}

TEST(Hash, DependsOnEveryByteAndIsStable)
{
    std::vector<double> a(1000, 1.5);
    const std::uint64_t h = hash_span<double>(a);
    EXPECT_EQ(h, hash_span<double>(a));
    a[999] = std::nextafter(1.5, 2.0);
    EXPECT_NE(h, hash_span<double>(a));
    // a golden value guards against accidental changes of the function itself
    const char text[] = "pliant";
    EXPECT_EQ(hash_bytes(std::as_bytes(std::span(text, 6))), 15553383032119672127ULL);
}

}  // namespace
}  // namespace pliant::core
