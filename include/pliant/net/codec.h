// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The pure codec: `Message` <-> datagram bytes, exactly as docs/protocol.md specifies. No
/// transport types, no allocation on the encode side (nor on the decode side with decode_into() and
/// a reused message, once its vectors have grown), no exceptions, no logging; safe on hostile
/// input (the fuzz target `fuzz/fuzz_net_decode.cpp` and tests/net/codec_test.cpp check that).
///
/// Design: one validation routine per body struct (`validate`) holds the semantic rules; the
/// encoder runs it before writing and the decoder after reading, so the two cannot disagree about
/// what is valid (the fuzz round trip checks it). Structure (lengths, counts, reserved bytes) is
/// checked while reading, so a truncated or extended datagram is `BadLength` before any other
/// body error. Floats are classified by their bits, so a signalling NaN never reaches the FPU.
///
/// Thread safety: all functions are pure and may run concurrently.

#include <pliant/net/expected.h>
#include <pliant/net/message.h>

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>

namespace pliant::net
{

/// Why a datagram was rejected (docs/protocol.md §7).
enum class DecodeError : std::uint8_t
{
    TooShort = 1,         ///< fewer than k_header_size bytes
    TooLarge = 2,         ///< more than k_max_datagram_size bytes
    BadMagic = 3,         ///< protocol id is not "PLNT"
    BadVersion = 4,       ///< version is not k_protocol_version
    UnknownType = 5,      ///< message type outside 1..k_message_type_count (19)
    BadFlags = 6,         ///< header flags not zero (reserved)
    BadSession = 7,       ///< session 0 in a message other than Hello or Reject
    BadSender = 8,        ///< sender k_no_peer in a message other than Hello
    BadLength = 9,        ///< body shorter or longer than its fields and counts imply
    BadReserved = 10,     ///< a reserved field is not zero
    BadEnum = 11,         ///< an enumeration outside its values
    BadCount = 12,        ///< a count outside its range or a state payload over 1,200 bytes
    BadRange = 13,        ///< an id, index, size or offset outside its range
    NonFinite = 14,       ///< a NaN or infinite float
    BadName = 15,         ///< a name of bad length or with a non-printable byte
    Duplicate = 16,       ///< a peer listed twice
    BadCompression = 17,  ///< packed residuals that do not unpack exactly: not one bounded zstd
                          ///< frame, or Rice codes breaking a rule of §5.6
};
inline constexpr std::uint8_t k_decode_error_count = 17;

/// Why a message could not be encoded.
enum class EncodeError : std::uint8_t
{
    BufferTooSmall = 1,  ///< `out` is shorter than encoded_size()
    InvalidMessage = 2,  ///< the message breaks a rule the decoder would reject it for
};

[[nodiscard]] std::string_view to_string(DecodeError error) noexcept;
[[nodiscard]] std::string_view to_string(EncodeError error) noexcept;

/// Checks every rule of docs/protocol.md that the struct can break (ranges, counts, finite floats,
/// sizes, the f32 range with F32 encoding). \return the error decode() would report, or nothing.
[[nodiscard]] std::optional<DecodeError> validate(const Message& message) noexcept;

/// Whether `name` is a valid peer name on the wire: 1 to k_max_name_length bytes of printable
/// ASCII (0x20..0x7E; docs/protocol.md §6 Hello).
[[nodiscard]] bool is_valid_name(std::string_view name) noexcept;

/// Bytes encode() writes for `message` (valid or not; at most k_max_datagram_size when valid).
[[nodiscard]] std::size_t encoded_size(const Message& message) noexcept;

/// Bytes one leaf adds to a LeafBatch body (docs/protocol.md §6 LeafBatch).
[[nodiscard]] std::size_t batch_leaf_size(const BatchLeaf& leaf) noexcept;
/// Bytes one leaf adds to a ValueBatch body of `encoding` (docs/protocol.md §6 ValueBatch).
[[nodiscard]] std::size_t value_leaf_size(const ValueLeaf& leaf, ValueEncoding encoding) noexcept;

/// Writes `message` to the front of `out`. \return the number of bytes written;
/// EncodeError::InvalidMessage if validate() fails; EncodeError::BufferTooSmall if `out` is shorter
/// than encoded_size(). Nothing is written on error.
[[nodiscard]] Expected<std::size_t, EncodeError> encode(const Message& message,
                                                        std::span<std::byte> out) noexcept;

/// Parses one datagram. \return the message, or the first rule it breaks: the header's fields,
/// then what reading the body checks in field order (reserved bytes, enumerations, counts,
/// depths), then the body's length, then the values' rules (leaf ids, levels, ranges, finite
/// values, ids in lists); docs/protocol.md §4.
[[nodiscard]] Expected<Message, DecodeError> decode(std::span<const std::byte> datagram) noexcept;

/// decode() into a caller's message, for a receive loop that allocates nothing in the steady
/// state: `out.body` keeps its alternative when the datagram is of the same type, and its vectors
/// (those of a LeafBatch's or ValueBatch's leaves included) are refilled in place, keeping their
/// storage. On success `out` equals what decode() returns, whatever it held before; no field keeps
/// a previous message's value. \return the error decode() would report, or nothing; on error
/// `out` holds unspecified (valid) contents.
[[nodiscard]] std::optional<DecodeError> decode_into(std::span<const std::byte> datagram,
                                                     Message& out) noexcept;

}  // namespace pliant::net
