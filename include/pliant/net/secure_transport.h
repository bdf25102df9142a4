// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `SecureTransport`: authentication and privacy of every datagram (issue 7 item 4,
/// docs/protocol.md §10). A decorator implementing `net::Transport` over any inner Transport
/// (ENet or simulated), so the Messenger and the Session are unchanged. Only
/// src/net/secure_transport.cpp includes libsodium.
///
/// Design:
/// - Key: a passphrase is stretched by Argon2id (`derive_key`) with a salt every peer computes
///   alike (BLAKE2b of a protocol label and a context string); two subkeys follow by crypto_kdf:
///   one to authenticate handshakes, one from which per-connection datagram keys are derived.
/// - Handshake, per connection, as soon as the inner transport connects: each side sends a Hello
///   with 16 fresh random bytes, MACed with the handshake key; each direction's datagram key is
///   BLAKE2b(datagram key; sender's random || receiver's random), so every connection has fresh
///   keys and a datagram recorded on one connection never opens on another. Each side then seals a
///   Confirm; the outer `Connected` event is reported only once a datagram from the peer opened
///   under its key (key confirmation). A Hello with a bad MAC (wrong passphrase) refuses the
///   connection at once; no authenticated datagram within `handshake_timeout_s` drops it.
///   Until a datagram from the peer opens, the Hello is also repeated unreliably every
///   `hello_repeat_s` on channel 1, and a repeat of the peer's verified Hello is answered with the
///   Confirm again, unreliably: a lost handshake datagram costs a repeat period instead of the
///   inner transport's retransmission timeout (ENet's is a second or more on a young connection).
/// - Data: ChaCha20-Poly1305 (IETF) with the nonce (64-bit counter, stream, zeros), where the
///   stream is (channel, reliable or not); the counter travels in the clear and is authenticated
///   as associated data with the type byte. 25 bytes per datagram (1 type, 8 counter, 16 tag).
/// - Replay: a 1024-bit sliding window per (connection, stream) accepts reordering within 1024
///   datagrams and drops duplicates and older ones (counted, not held against the peer: the
///   network duplicates too). Failed authentication or malformed datagrams are dropped, counted
///   and past `max_failures` disconnect the peer with TooManyBadDatagrams.
///
/// Threading: single-threaded, like every Transport.

#include <pliant/core/result.h>
#include <pliant/net/transport.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string_view>

namespace pliant::net
{

/// Argon2id cost. Every peer of a session must use the same values (they change the key).
struct KdfLimits
{
    std::uint64_t opslimit = 2;                    ///< passes (libsodium's OPSLIMIT_INTERACTIVE)
    std::size_t memlimit = std::size_t{64} << 20;  ///< bytes (MEMLIMIT_INTERACTIVE: 64 MiB)

    /// What `pliant host` / `pliant join` use: INTERACTIVE, 0.4-0.9 s on the 2-core CI machine
    /// (MODERATE took 3-4.6 s: too slow to start a join; docs/protocol.md §10.1).
    [[nodiscard]] static KdfLimits protocol() noexcept { return {}; }
    /// libsodium's minimum (1 pass, 8 KiB): for tests only, worthless against guessing.
    [[nodiscard]] static KdfLimits cheapest_for_tests() noexcept { return {1, 8192}; }
};

/// The salt context of the CLI: a fixed protocol label (docs/protocol.md §10.1 says why).
inline constexpr std::string_view k_default_key_context = "pliant session v1";

/// A 256-bit secret. Not printable; compare with `==` only in tests.
struct SecretKey
{
    std::array<std::uint8_t, 32> bytes{};
    friend bool operator==(const SecretKey&, const SecretKey&) = default;
};

/// Stretches `passphrase` (any bytes, 1..4096) with Argon2id; salt = BLAKE2b-128("pliant/salt/v1"
/// || context). \return InvalidArgument for an empty or over-long passphrase; NetworkError if
/// libsodium cannot initialise or runs out of memory (memlimit).
[[nodiscard]] core::Result<SecretKey> derive_key(std::string_view passphrase,
                                                 std::string_view context = k_default_key_context,
                                                 const KdfLimits& limits = KdfLimits::protocol());

/// Reads a key file: its bytes, minus one trailing "\n" or "\r\n", are the passphrase (so a file of
/// 32 random bytes and a text passphrase both work, and `--passphrase X` equals a file holding X).
/// \return IoError if unreadable; derive_key's errors otherwise.
[[nodiscard]] core::Result<SecretKey> key_from_file(
    const std::filesystem::path& path, std::string_view context = k_default_key_context,
    const KdfLimits& limits = KdfLimits::protocol());

struct SecureSettings
{
    /// Authentication failures or malformed datagrams on one connection before it is dropped.
    std::uint32_t max_failures = 8;
    /// A connection with no authenticated datagram from the peer this long after the inner
    /// transport connected is dropped, s.
    double handshake_timeout_s = 5.0;
    /// The Hello's unreliable repeats until the peer is authenticated, s (<= 0: none).
    double hello_repeat_s = 0.05;
    /// The clock for that timeout, µs; empty: std::chrono::steady_clock. Tests over a
    /// SimulatedNetwork pass its virtual clock.
    std::function<std::int64_t()> clock;
};

/// What SecureTransport dropped on one connection (or in total).
struct SecureStats
{
    std::uint64_t opened = 0;         ///< datagrams authenticated and delivered
    std::uint64_t auth_failures = 0;  ///< did not authenticate (wrong key, tampered, bad Hello MAC)
    std::uint64_t malformed = 0;      ///< too short, unknown type, or out of handshake order
    std::uint64_t replayed = 0;       ///< counter already seen within the window
    std::uint64_t too_old = 0;        ///< counter older than the window
    std::uint64_t early = 0;          ///< data before the peer's Hello (unreliable only; dropped)
    std::uint64_t hello_repeats = 0;  ///< repeats of the peer's verified Hello, answered with the
                                      ///< Confirm again (a lost handshake datagram, not a failure)
    /// Totals only: connections that never authenticated and ended: dropped here (a Hello of
    /// another key, too many failures, the handshake timeout) or closed by the peer first (a
    /// peer without our secret gives up on datagrams it cannot read). Each is logged as a
    /// warning, at most one line per 10 s.
    std::uint64_t refused = 0;
};

/// Bytes SecureTransport adds to each datagram: type (1) + counter (8) + Poly1305 tag (16).
inline constexpr std::size_t k_secure_overhead = 25;

class SecureTransport final : public Transport
{
public:
    /// Wraps `inner` (opened or not). `key` is the master key from derive_key/key_from_file.
    SecureTransport(std::unique_ptr<Transport> inner, const SecretKey& key,
                    const SecureSettings& settings = {});
    ~SecureTransport() override;

    core::Result<Address> open(const Address& bind) noexcept override;
    core::Result<PeerHandle> connect(const Address& remote) noexcept override;
    /// Seals and sends. \return NetworkError for a peer that is not authenticated yet (no
    /// Connected event) and the inner transport's errors.
    core::Result<void> send(PeerHandle peer, Channel channel, std::span<const std::byte> bytes,
                            Delivery delivery) noexcept override;
    std::optional<TransportEvent> poll(int timeout_ms = 0) noexcept override;
    /// As poll(), allocating nothing once its buffers have grown: the decrypted datagram's vector
    /// is swapped into `out.data`, and `out`'s previous vector is kept for a later datagram.
    bool poll_into(TransportEvent& out, int timeout_ms = 0) noexcept override;
    void flush() noexcept override;
    /// Returns at once while decrypted events are pending, else waits on the inner transport.
    void wait(double max_s) noexcept override;
    void disconnect(PeerHandle peer, DisconnectReason reason) noexcept override;
    /// The inner transport's counters (bytes include the 25-byte overhead), with
    /// `bad_datagrams` increased by this layer's authentication failures and malformed drops.
    [[nodiscard]] std::optional<PeerStats> stats(PeerHandle peer) const noexcept override;
    [[nodiscard]] std::optional<Address> remote_address(PeerHandle peer) const noexcept override;
    [[nodiscard]] std::size_t queued_bytes(PeerHandle peer) const noexcept override;
    void report_bad_datagram(PeerHandle peer) noexcept override;
    /// Authenticated connections only.
    void live_peers(std::vector<PeerHandle>& out) const override;

    /// This layer's drop counters of a live connection (authenticated or not).
    [[nodiscard]] std::optional<SecureStats> secure_stats(PeerHandle peer) const noexcept;
    /// Counters summed over every connection since creation, gone ones included.
    [[nodiscard]] SecureStats totals() const noexcept;
    [[nodiscard]] Transport& inner() noexcept;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace pliant::net
