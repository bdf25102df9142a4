// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for net::decode (docs/style.md §10, after netcode's fuzz/fuzz_read_packet.c). Two
// modes, chosen by the first input byte:
// - even: raw bytes. The rest of the input is one datagram. decode() must not crash, and anything
//   it accepts must re-encode to exactly the same bytes (the wire format is canonical).
// - odd: build -> encode -> corrupt one byte -> decode. Bytes 1..4 pick a sample message (every
//   type), a byte offset and an XOR mask; the sample must round-trip unmodified, and the corrupted
//   datagram is either rejected or re-encodes to itself.
// In both modes decode_into() into one message reused across inputs (holding the previous
// input's message, or what a failed decode left) must give what decode() gives: the same error,
// or an equal message (no field left from before; in odd mode the sample is decoded into it
// first, so the corrupted datagram often meets a message of its own type).
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/net/codec.h>

#include "net/sample_messages.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant::net;

void require(bool ok, const char* what)
{
    if (!ok)
    {
        std::fprintf(stderr, "fuzz_net_decode: %s\n", what);
        std::abort();
    }
}

Message& reused()
{
    static Message message;
    return message;
}

void check_canonical(std::span<const std::byte> datagram)
{
    auto decoded = decode(datagram);
    const auto error = decode_into(datagram, reused());
    require(decoded.has_value() == !error.has_value(), "decode_into and decode disagree");
    if (!decoded)
    {
        require(*error == decoded.error(), "decode_into reports another error");
        return;
    }
    require(reused() == *decoded, "decode_into into a reused message differs from decode");
    static std::vector<std::byte> buffer(k_max_datagram_size);
    auto size = encode(*decoded, buffer);
    require(size.has_value(), "a decoded message does not encode");
    require(*size == datagram.size(), "re-encoded size differs");
    require(std::memcmp(buffer.data(), datagram.data(), *size) == 0, "re-encoded bytes differ");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0)
        return 0;
    const auto* bytes = reinterpret_cast<const std::byte*>(data);
    if (data[0] % 2 == 0)
    {
        check_canonical(std::span(bytes + 1, size - 1));
        return 0;
    }
    if (size < 5)
        return 0;
    static const std::vector<Message> messages = samples::all();
    const Message& m = messages[data[1] % messages.size()];
    std::vector<std::byte> encoded(encoded_size(m));
    require(encode(m, encoded).has_value(), "a sample does not encode");
    auto back = decode(encoded);
    require(back.has_value() && *back == m, "a sample does not round-trip");
    require(!decode_into(encoded, reused()).has_value() && reused() == m,
            "a sample does not round-trip through decode_into");
    const std::size_t at = (std::size_t{data[2]} | (std::size_t{data[3]} << 8)) % encoded.size();
    const auto mask = static_cast<std::byte>(data[4] == 0 ? 1 : data[4]);
    encoded[at] ^= mask;
    check_canonical(encoded);
    return 0;
}
