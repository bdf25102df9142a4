// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Address formatting and parsing for the command line ("HOST:PORT"): parse_address takes IPv4
// dotted quads and "localhost" only, with no name lookup (ENet 1.3 has no IPv6); resolve_address
// adds host names through the system's resolver, which blocks, so only before a session starts.

#include <pliant/net/transport.h>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <charconv>
#include <cstring>

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
                          "address '" + std::string(text) + "' " + why +
                              " (expected HOST:PORT: a.b.c.d, localhost or a host name, and a "
                              "port from 1 to 65535)");
    };
    const auto colon = text.rfind(':');
    if (colon == std::string_view::npos)
        return bad("has no port");
    unsigned port = 0;
    if (!parse_number(text.substr(colon + 1), 65535, port))
        return bad("has a bad port");
    if (port == 0)
        return bad("has port 0 (a peer listens on a port from 1 to 65535)");
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

core::Result<Address> resolve_address(std::string_view text)
{
    auto parsed = parse_address(text);
    if (parsed)
        return parsed;
    // Look a host part up only when it is a name (not a malformed dotted quad) and the port is
    // good; otherwise parse_address's message says what is wrong.
    const auto colon = text.rfind(':');
    unsigned port = 0;
    if (colon == std::string_view::npos || colon == 0 ||
        !parse_number(text.substr(colon + 1), 65535, port) || port == 0)
        return parsed;
    const std::string host(text.substr(0, colon));
    if (host.find_first_not_of("0123456789.") == std::string::npos)
        return parsed;
    // "[::1]:7777", "::1": the resolver said "Name or service not known" of '[::1]' or ':'.
    if (host.find_first_of("[]:") != std::string::npos)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "address '" + std::string(text) +
                              "' is IPv6: pliant speaks IPv4 only (ENet 1.3); give a.b.c.d, "
                              "localhost or a host name with an IPv4 address, and a port");
    addrinfo hints{};
    hints.ai_family = AF_INET;  // ENet 1.3 speaks IPv4 only
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* found = nullptr;
    const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found);
    if (rc != 0 || found == nullptr)
        return core::fail(core::ErrorCode::NetworkError,
                          "cannot find an IPv4 address for host '" + host + "' (" +
                              ::gai_strerror(rc) +
                              "); give HOST:PORT with a host name, a.b.c.d or localhost");
    Address a;
    a.port = static_cast<std::uint16_t>(port);
    sockaddr_in in{};
    std::memcpy(&in, found->ai_addr, sizeof in);
    ::freeaddrinfo(found);
    const std::uint32_t ip = ntohl(in.sin_addr.s_addr);
    a.ipv4 = {static_cast<std::uint8_t>(ip >> 24), static_cast<std::uint8_t>(ip >> 16),
              static_cast<std::uint8_t>(ip >> 8), static_cast<std::uint8_t>(ip)};
    return a;
}

}  // namespace pliant::net
