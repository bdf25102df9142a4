// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Stable short names of the net module's enumerations, for logs and statistics files.

#include <pliant/net/codec.h>
#include <pliant/net/types.h>

namespace pliant::net
{

std::string_view to_string(DisconnectReason reason) noexcept
{
    switch (reason)
    {
    case DisconnectReason::None: return "none";
    case DisconnectReason::Quit: return "quit";
    case DisconnectReason::Shutdown: return "shutdown";
    case DisconnectReason::TimedOut: return "timed-out";
    case DisconnectReason::TooManyBadDatagrams: return "too-many-bad-datagrams";
    case DisconnectReason::ProtocolMismatch: return "protocol-mismatch";
    case DisconnectReason::WrongSession: return "wrong-session";
    case DisconnectReason::Refused: return "refused";
    case DisconnectReason::SessionFull: return "session-full";
    case DisconnectReason::Kicked: return "kicked";
    }
    return "unknown";
}

std::string_view to_string(MessageType type) noexcept
{
    switch (type)
    {
    case MessageType::Hello: return "hello";
    case MessageType::Welcome: return "welcome";
    case MessageType::Reject: return "reject";
    case MessageType::PeerJoined: return "peer-joined";
    case MessageType::PeerLeft: return "peer-left";
    case MessageType::Blob: return "blob";
    case MessageType::PointsOfInterest: return "points-of-interest";
    case MessageType::Partition: return "partition";
    case MessageType::Force: return "force";
    case MessageType::Leave: return "leave";
    case MessageType::LeafState: return "leaf-state";
    case MessageType::Halo: return "halo";
    case MessageType::Heartbeat: return "heartbeat";
    case MessageType::Ping: return "ping";
    case MessageType::Pong: return "pong";
    case MessageType::Ack: return "ack";
    case MessageType::LeafBatch: return "leaf-batch";
    case MessageType::ValueBatch: return "value-batch";
    case MessageType::Ready: return "ready";
    }
    return "unknown";
}

std::string_view to_string(DecodeError error) noexcept
{
    switch (error)
    {
    case DecodeError::TooShort: return "too-short";
    case DecodeError::TooLarge: return "too-large";
    case DecodeError::BadMagic: return "bad-magic";
    case DecodeError::BadVersion: return "bad-version";
    case DecodeError::UnknownType: return "unknown-type";
    case DecodeError::BadFlags: return "bad-flags";
    case DecodeError::BadSession: return "bad-session";
    case DecodeError::BadSender: return "bad-sender";
    case DecodeError::BadLength: return "bad-length";
    case DecodeError::BadReserved: return "bad-reserved";
    case DecodeError::BadEnum: return "bad-enum";
    case DecodeError::BadCount: return "bad-count";
    case DecodeError::BadRange: return "bad-range";
    case DecodeError::NonFinite: return "non-finite";
    case DecodeError::BadName: return "bad-name";
    case DecodeError::Duplicate: return "duplicate";
    case DecodeError::BadCompression: return "bad-compression";
    }
    return "unknown";
}

std::string_view to_string(EncodeError error) noexcept
{
    switch (error)
    {
    case EncodeError::BufferTooSmall: return "buffer-too-small";
    case EncodeError::InvalidMessage: return "invalid-message";
    }
    return "unknown";
}

}  // namespace pliant::net
