// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// The UDP transport: ENet 1.3 behind `net::Transport`. No ENet type appears here; only
/// src/net/enet_transport.cpp includes <enet/enet.h> (STYLE.md §8, checked by
/// scripts/check_includes.py).
///
/// Mapping: one ENetHost per transport (it both listens and connects, so a peer's address is the
/// one it listens on), two ENet channels (0 reliable control, 1 unreliable sequenced state),
/// Delivery::Reliable -> ENET_PACKET_FLAG_RELIABLE, Unreliable -> unsequenced-off unreliable with
/// ENET_PACKET_FLAG_UNRELIABLE_FRAGMENT (a large unreliable packet is dropped whole if a fragment
/// is lost, never silently upgraded to reliable), Unsequenced -> ENET_PACKET_FLAG_UNSEQUENCED.
/// The disconnect reason travels as ENet's disconnect data; ENet reports 0 on a timeout.
///
/// Threading: single-threaded (ENet's FAQ: an ENetHost must not be used from two threads).
/// Keep calling poll() while waiting: an unserviced host stops acknowledging, and its peers time
/// it out after `timeout_min_ms`.

#include <pliant/net/transport.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace pliant::net
{

struct EnetSettings
{
    std::size_t max_peers = 64;            ///< connections the host accepts (ENet allows 4095)
    std::uint32_t timeout_limit = 32;      ///< ENet's unacknowledged-packet limit
    std::uint32_t timeout_min_ms = 5000;   ///< a silent peer is dropped after at least this
    std::uint32_t timeout_max_ms = 30000;  ///< and at most this
    std::uint32_t connect_timeout_ms = 5000;
};

/// A Transport over ENet. ENet is initialised on first use in the process (reference counted).
/// \return nullptr never; errors appear at open().
[[nodiscard]] std::unique_ptr<Transport> make_enet_transport(const EnetSettings& settings = {});

}  // namespace pliant::net
