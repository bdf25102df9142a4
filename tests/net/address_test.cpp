// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// "HOST:PORT" on the command line: dotted quads and localhost parse without a look-up, port 0
// (a port nobody listens on) and malformed text are refused naming the text, and host names go
// through the system's resolver (an unresolvable one is refused naming the host).
#include <pliant/net/transport.h>

#include <gtest/gtest.h>

namespace pliant::net
{
namespace
{

TEST(Address, ParsesDottedQuadsAndLocalhostAndRefusesPortZero)
{
    const auto a = parse_address("192.168.1.20:7777");
    ASSERT_TRUE(a) << a.error().message;
    EXPECT_EQ(a->ipv4, (std::array<std::uint8_t, 4>{192, 168, 1, 20}));
    EXPECT_EQ(a->port, 7777);
    EXPECT_EQ(to_string(*a), "192.168.1.20:7777");
    const auto l = parse_address("localhost:1");
    ASSERT_TRUE(l);
    EXPECT_EQ(l->ipv4, (std::array<std::uint8_t, 4>{127, 0, 0, 1}));
    for (const char* bad : {"127.0.0.1:0", "127.0.0.1", "127.0.0:7777", "127.0.0.256:7777",
                            "127.0.0.1:65536", "127.0.0.1:x", ":7777"})
    {
        const auto r = parse_address(bad);
        ASSERT_FALSE(r) << bad;
        EXPECT_EQ(r.error().code, core::ErrorCode::InvalidArgument);
        EXPECT_NE(r.error().message.find(bad), std::string::npos) << r.error().message;
    }
    EXPECT_NE(parse_address("127.0.0.1:0").error().message.find("port 0"), std::string::npos);
}

TEST(Address, ResolvesWhatParsesAndRefusesAnUnknownHostNamingIt)
{
    const auto q = resolve_address("10.1.2.3:9000");
    ASSERT_TRUE(q);
    EXPECT_EQ(q->ipv4, (std::array<std::uint8_t, 4>{10, 1, 2, 3}));
    // A malformed dotted quad or port is parse_address's error, not a look-up.
    EXPECT_NE(resolve_address("10.1.2:9000").error().message.find("bad IPv4 address"),
              std::string::npos);
    EXPECT_NE(resolve_address("example.invalid:0").error().message.find("port 0"),
              std::string::npos);
    // IPv6 is said to be IPv6, not looked up as a name ("cannot find ... host ':'").
    for (const char* v6 : {"[::1]:7777", "::1:7777", "::1"})
    {
        const auto r = resolve_address(v6);
        ASSERT_FALSE(r) << v6;
        EXPECT_NE(r.error().message.find("IPv4 only"), std::string::npos) << r.error().message;
    }
    // RFC 6761: names under .invalid never resolve.
    const auto unknown = resolve_address("no-such-host.invalid:7777");
    ASSERT_FALSE(unknown);
    // Not the address's fault: a name lookup that fails is a network error (`pliant join` exits
    // 1 for it and 2 for a malformed address).
    EXPECT_EQ(unknown.error().code, core::ErrorCode::NetworkError);
    EXPECT_NE(unknown.error().message.find("'no-such-host.invalid'"), std::string::npos)
        << unknown.error().message;
}

}  // namespace
}  // namespace pliant::net
