// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A userspace impairing UDP relay for tests over real sockets on 127.0.0.1, for kernels without
// netem (docs/operations.md, "Testing under impaired networks").
//
// For each target (a peer's real UDP port) the relay listens on a port of its own. A datagram
// arriving there from a client address C goes out to the target through an upstream socket kept
// for (that listener, C), NAT-style, so the target sees one distinct source per client and its
// replies come back to that upstream socket, from where the relay sends them to C from the
// listener's port: C only ever talks to the listener's address. Every datagram, both ways, is
// impaired independently with a seeded generator: lost with probability `loss`, else delivered
// after `delay_s` plus a uniform jitter in [0, jitter_s), held back `reorder_hold_s` more with
// probability `reorder`, and sent twice (each copy with its own delay) with probability
// `duplicate`. Jitter and holds reorder datagrams; the relay counts the actual inversions.
//
// Plain POSIX sockets (no ENet here). One thread; poll() waits at most 2 ms, and stop() (or the
// destructor) ends the thread within that. At most `max_queued` datagrams wait at once (more are
// dropped and counted as overflow). Only loopback addresses are used.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace pliant::test
{

struct ImpairSettings
{
    double loss = 0.05;             ///< probability a datagram is dropped
    double delay_s = 0.100;         ///< base one-way delay, s
    double jitter_s = 0.020;        ///< uniform extra delay in [0, jitter_s), s
    double duplicate = 0.01;        ///< probability a datagram is delivered twice
    double reorder = 0.02;          ///< probability a datagram is held back reorder_hold_s more
    double reorder_hold_s = 0.020;  ///< s
    std::uint64_t seed = 1;
    std::size_t max_queued = 200000;
};

/// What the relay did, cumulative over both directions.
struct ImpairCounters
{
    std::uint64_t received = 0;        ///< datagrams read from any socket
    std::uint64_t dropped = 0;         ///< lost on purpose
    std::uint64_t duplicated = 0;      ///< delivered a second time
    std::uint64_t held = 0;            ///< held back for reordering
    std::uint64_t sent = 0;            ///< datagrams sent on (copies included)
    std::uint64_t inversions = 0;      ///< sent after a later-received datagram of the same flow
    std::uint64_t overflow = 0;        ///< dropped because max_queued were waiting
    std::uint64_t send_errors = 0;     ///< sendto failed
    std::uint64_t unknown_source = 0;  ///< upstream datagrams not from the target: ignored
    std::uint64_t clients = 0;         ///< upstream sockets opened (one per listener and client)
    double delay_sum_s = 0.0;          ///< sum of the scheduled delays of the datagrams sent
    double max_delay_s = 0.0;          ///< largest scheduled delay, s
};

class ImpairRelay
{
public:
    explicit ImpairRelay(const ImpairSettings& settings);
    ~ImpairRelay();
    ImpairRelay(const ImpairRelay&) = delete;
    ImpairRelay& operator=(const ImpairRelay&) = delete;

    /// Adds a listener on 127.0.0.1 (any free port) forwarding to 127.0.0.1:`target_port`.
    /// Before start() only. \return the listener's port, or 0 (see error()) if no socket binds.
    std::uint16_t add_target(std::uint16_t target_port);
    /// Starts the relay thread. \return false if already started or no target was added.
    bool start();
    /// Stops the thread (within a few ms) and closes nothing: the sockets close in the
    /// destructor. Idempotent.
    void stop();
    [[nodiscard]] ImpairCounters counters() const;
    [[nodiscard]] const std::string& error() const { return error_; }

    struct State;

private:
    void run();

    ImpairSettings settings_;
    std::unique_ptr<State> state_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
    std::string error_;
};

}  // namespace pliant::test
