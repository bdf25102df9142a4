// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Address formatting and parsing for the command line ("HOST:PORT"); IPv4 dotted quads and
// "localhost" only, with no name lookup (ENet 1.3 has no IPv6, and a resolver would block).

#include <pliant/net/transport.h>

#include <charconv>

namespace pliant::net
{
namespace
{

bool parse_number(std::string_view s, unsigned max, unsigned& out) noexcept
{
    if (s.empty() || s.size() > 5)
        return false;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc{} && end == s.data() + s.size() && out <= max;
}

}  // namespace

std::string to_string(const Address& a)
{
    return std::to_string(a.ipv4[0]) + "." + std::to_string(a.ipv4[1]) + "." +
           std::to_string(a.ipv4[2]) + "." + std::to_string(a.ipv4[3]) + ":" +
           std::to_string(a.port);
}

core::Result<Address> parse_address(std::string_view text)
{
    const auto bad = [&text](const char* why)
    {
        return core::fail(core::ErrorCode::InvalidArgument,
                          "parse_address: '" + std::string(text) + "' " + why +
                              " (expected a.b.c.d:port or localhost:port)");
    };
    const auto colon = text.rfind(':');
    if (colon == std::string_view::npos)
        return bad("has no port");
    unsigned port = 0;
    if (!parse_number(text.substr(colon + 1), 65535, port))
        return bad("has a bad port");
    Address a;
    a.port = static_cast<std::uint16_t>(port);
    std::string_view host = text.substr(0, colon);
    if (host == "localhost")
    {
        a.ipv4 = {127, 0, 0, 1};
        return a;
    }
    for (int i = 0; i < 4; ++i)
    {
        const auto dot = host.find('.');
        if ((i < 3) == (dot == std::string_view::npos))
            return bad("has a bad IPv4 address");
        unsigned part = 0;
        if (!parse_number(host.substr(0, dot), 255, part))
            return bad("has a bad IPv4 address");
        a.ipv4[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(part);
        host = i < 3 ? host.substr(dot + 1) : std::string_view{};
    }
    return a;
}

}  // namespace pliant::net
