// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `SimulatedNetwork`: an in-process network of endpoints (each a `Transport`) with seeded
/// latency, jitter, loss, duplication and reordering per directed link, and a virtual clock that
/// the caller advances (nothing sleeps), so tests are fast, bounded and repeatable. Follows
/// netcode's `netcode_network_simulator_t` (docs/style.md §8).
///
/// Model:
/// - Endpoint k opened on port p has address 10.0.0.k:p (port 0 picks 40000 + k).
/// - Every transmission on link (a -> b) draws its fate from that link's own random stream, seeded
///   from (seed, a, b): lost with probability `loss`; otherwise it arrives after
///   latency + U(0, jitter), plus `reorder_delay` with probability `reorder`; with probability
///   `duplicate` a second copy arrives independently. So the outcome depends only on the seed and
///   on the order of sends per link, even when endpoints run on different threads.
/// - Reliable packets are retransmitted every `retransmit_s` until one copy survives (at most
///   `max_attempts`; then both ends see Disconnected(TimedOut)); the receiver buffers and
///   delivers them in order exactly once per channel. Unreliable packets are sequenced per channel
///   (a packet older than one delivered is dropped, as ENet does); Unsequenced ones are delivered
///   as they come, duplicates included.
/// - connect(), its acceptance and disconnect() travel as reliable packets too.
/// - No bandwidth limit is modelled (issue 7 may add one).
/// - Buffers: a datagram's bytes travel in one vector from send() to the receiver's event, and
///   the network recycles vectors (lost and dropped packets', and the previous vector of an event
///   given to poll_into(), kept by size class: powers of two from 64 bytes to 64 KiB), so send()
///   and poll_into() allocate nothing per datagram once the network has carried as many
///   datagrams of each class at once as it carries now. poll() hands its vector over for good.
///
/// Threading: the network's state is guarded by one mutex, so each endpoint may live on its own
/// thread (peers as threads of one process); each endpoint itself is single-threaded, as every
/// Transport. Endpoints must be destroyed before their network.

#include <pliant/net/transport.h>

#include <cstdint>
#include <memory>
#include <optional>

namespace pliant::net
{

/// Conditions of one directed link. Probabilities are in [0, 1) (loss) and [0, 1].
struct LinkSettings
{
    double latency_s = 0.005;        ///< one-way base delay, s
    double jitter_s = 0.0;           ///< extra delay uniform in [0, jitter_s], s
    double loss = 0.0;               ///< probability that one transmission is lost
    double duplicate = 0.0;          ///< probability that a packet arrives twice
    double reorder = 0.0;            ///< probability that a packet is held back by reorder_delay_s
    double reorder_delay_s = 0.020;  ///< s
};

struct SimulatedNetworkSettings
{
    std::uint64_t seed = 1;
    LinkSettings link;               ///< default for every link
    double retransmit_s = 0.0;       ///< 0: 2 * (latency + jitter) + 1 ms, per link
    int max_attempts = 64;           ///< reliable transmissions before a link times out
    double connect_timeout_s = 5.0;  ///< connect() to an address nobody listens on
};

/// Counts over the whole network since creation.
struct SimulatedTotals
{
    std::uint64_t transmissions = 0;  ///< sends plus retransmissions
    std::uint64_t lost = 0;
    std::uint64_t duplicated = 0;
    std::uint64_t reordered = 0;
    std::uint64_t retransmitted = 0;
    std::uint64_t delivered = 0;      ///< Received events handed to endpoints
    std::uint64_t dropped_stale = 0;  ///< unreliable packets older than one delivered
};

class SimulatedNetwork
{
public:
    /// \pre settings hold probabilities in range and non-negative times (asserted: test code).
    explicit SimulatedNetwork(const SimulatedNetworkSettings& settings = {});
    ~SimulatedNetwork();
    SimulatedNetwork(const SimulatedNetwork&) = delete;
    SimulatedNetwork& operator=(const SimulatedNetwork&) = delete;

    /// A new endpoint; open() it before use. It must not outlive the network.
    [[nodiscard]] std::unique_ptr<Transport> create_endpoint();

    /// Conditions for packets from `from` to `to` (both opened addresses).
    void set_link(const Address& from, const Address& to, const LinkSettings& link);

    /// The endpoint at `a` stops as a stopped process does (SIGSTOP), keeping its socket: it
    /// answers nothing, so after connect_timeout_s every connection to it times out at the far
    /// end, and at its own end too (resumed, its transport hears nothing back: the far ends
    /// have dropped it). What reaches it meanwhile waits in its queue, as in a socket buffer.
    /// The caller stops polling it for that time; a pause shorter than the timeout is only
    /// that (no call needed).
    void suspend(const Address& a);

    /// Advances the virtual clock by `seconds` (>= 0).
    void advance(double seconds);
    /// Moves every packet due by now into its endpoint's queue. Each transport's poll() does
    /// this first; a harness that times its peers' polls calls it before them, so that the
    /// first to poll is not charged for everyone's deliveries.
    void deliver_due();
    /// Advances the clock to the next pending arrival. \return false if nothing is in flight.
    bool advance_to_next_arrival();
    [[nodiscard]] std::int64_t now_us() const;
    [[nodiscard]] SimulatedTotals totals() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace pliant::net
