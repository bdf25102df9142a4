// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The net tests' one way to encode a message into a buffer of its own (a GoogleTest failure when
// the encoder refuses it or writes other than encoded_size bytes).

#include <pliant/net/codec.h>

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

namespace pliant::test
{

inline std::vector<std::byte> encode_vec(const net::Message& m)
{
    std::vector<std::byte> out(encoded_size(m));
    auto r = encode(m, out);
    EXPECT_TRUE(r.has_value()) << to_string(m.type());
    if (r)
    {
        EXPECT_EQ(*r, out.size());
    }
    return out;
}

}  // namespace pliant::test
