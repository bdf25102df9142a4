// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// SecureTransport (see secure_transport.h and docs/protocol.md §10): the only file that includes
// libsodium. Wire formats of this layer (all integers little-endian):
//
//   Hello   (36 bytes): u8 type 1 | u8 version 1 | u16 reserved 0 | u8[16] random | u8[16] MAC
//                       MAC = BLAKE2b-128 keyed with the handshake key over bytes 0..19
//   Data    (25 + n):   u8 type (2 unreliable, 3 reliable) | u64 counter | ciphertext[n] | tag[16]
//   Confirm (25 bytes): u8 type 4 | u64 counter 0 | tag[16] (an empty plaintext)
//
// The Hello and the Confirm go reliably on channel 0; until a datagram from the peer opens, the
// Hello is repeated unsequenced on channel 1 every SecureSettings::hello_repeat_s, and a repeat
// of the peer's verified Hello is answered with the (identical) Confirm, unsequenced on channel 1.
//
// The associated data of Data and Confirm is their first 9 bytes; the 12-byte ChaCha20-Poly1305
// nonce is (u64 counter, u8 stream, 3 zero bytes), stream = 2 * channel + reliable (0..3), or 4
// for Confirm. Keys are per connection and direction, so (key, nonce) never repeats: a sender
// increments the counter of a stream for every datagram and a connection's keys die with it.
//
// Costs: one AEAD per datagram each way; the replay window is a 1024-bit ring per stream.
// Nothing is logged per datagram, and nothing is allocated per datagram once the buffers have
// grown: a datagram is sealed into one send buffer, received from the inner transport with
// poll_into() into one reused event, opened in place and queued in a vector taken from a free
// list, which poll_into() swaps into the caller's event (the caller's previous vector goes back on
// the list). poll() hands its vector over, so the list then runs dry and vectors are made anew.

#include <pliant/core/assert.h>
#include <pliant/net/secure_transport.h>

#include <sodium.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

namespace pliant::net
{
namespace
{

constexpr std::uint8_t k_type_hello = 1;
constexpr std::uint8_t k_type_data = 2;
constexpr std::uint8_t k_type_data_reliable = 3;
constexpr std::uint8_t k_type_confirm = 4;
constexpr std::uint8_t k_hello_version = 1;

constexpr std::size_t k_random_size = 16;
constexpr std::size_t k_mac_size = 16;
constexpr std::size_t k_hello_signed = 4 + k_random_size;  // bytes covered by the MAC
constexpr std::size_t k_hello_size = k_hello_signed + k_mac_size;
constexpr std::size_t k_head_size = 9;  // type + counter: the associated data
constexpr std::size_t k_tag_size = crypto_aead_chacha20poly1305_ietf_ABYTES;
static_assert(k_head_size + k_tag_size == k_secure_overhead);
static_assert(crypto_aead_chacha20poly1305_ietf_NPUBBYTES == 12);
static_assert(crypto_aead_chacha20poly1305_ietf_KEYBYTES == 32);

constexpr std::size_t k_data_streams = 4;  // (channel, reliable)
constexpr std::uint8_t k_confirm_stream = 4;
constexpr std::size_t k_max_passphrase = 4096;

// crypto_kdf subkey ids under the context "pliantv1" (8 bytes, as crypto_kdf requires).
constexpr char k_kdf_context[crypto_kdf_CONTEXTBYTES + 1] = "pliantv1";
constexpr std::uint64_t k_subkey_hello = 1;
constexpr std::uint64_t k_subkey_datagram = 2;

// Refusals are logged as warnings at most this often, µs.
constexpr std::int64_t k_refusal_warning_us = 10'000'000;

// What a refusal's reason most likely means, for the log.
const char* refusal_cause(DisconnectReason reason) noexcept
{
    switch (reason)
    {
    case DisconnectReason::Refused: return "its Hello does not authenticate: another secret";
    case DisconnectReason::TooManyBadDatagrams:
        return "too many datagrams that do not authenticate: tampering, or no secret there";
    case DisconnectReason::TimedOut:
        return "no authenticated datagram within the handshake timeout: no secret there, or no "
               "path back";
    default: return "dropped";
    }
}

using Key = std::array<std::uint8_t, 32>;
using Random = std::array<std::uint8_t, k_random_size>;

void store_u64(std::uint8_t* p, std::uint64_t v) noexcept
{
    for (int k = 0; k < 8; ++k)
        p[k] = static_cast<std::uint8_t>(v >> (8 * k));
}

std::uint64_t load_u64(const std::uint8_t* p) noexcept
{
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k)
        v |= static_cast<std::uint64_t>(p[k]) << (8 * k);
    return v;
}

std::array<std::uint8_t, 12> make_nonce(std::uint64_t counter, std::uint8_t stream) noexcept
{
    std::array<std::uint8_t, 12> n{};
    store_u64(n.data(), counter);
    n[8] = stream;
    return n;
}

// Anti-replay window over one stream's counters (RFC 6479's bitmap without the block trick):
// counters start at 1; `top_` is the newest accepted; bit (c mod 1024) says whether c was seen
// for c in (top_ - 1024, top_].
class ReplayWindow
{
public:
    static constexpr std::uint64_t k_bits = 1024;
    enum class Verdict : std::uint8_t
    {
        Fresh,
        Duplicate,
        TooOld
    };

    [[nodiscard]] Verdict check(std::uint64_t c) const noexcept
    {
        if (c == 0)
            return Verdict::TooOld;
        if (c > top_)
            return Verdict::Fresh;
        if (top_ - c >= k_bits)
            return Verdict::TooOld;
        return test(c) ? Verdict::Duplicate : Verdict::Fresh;
    }

    /// Call only after the datagram with counter `c` authenticated and check(c) was Fresh.
    void mark(std::uint64_t c) noexcept
    {
        if (c > top_)
        {
            if (c - top_ >= k_bits)
                words_.fill(0);
            else
                for (std::uint64_t k = top_ + 1; k < c; ++k)  // at most 1023 bits
                    words_[(k % k_bits) / 64] &= ~(std::uint64_t{1} << (k % 64));
            top_ = c;
        }
        words_[(c % k_bits) / 64] |= std::uint64_t{1} << (c % 64);
    }

private:
    [[nodiscard]] bool test(std::uint64_t c) const noexcept
    {
        return (words_[(c % k_bits) / 64] >> (c % 64)) & 1u;
    }
    std::array<std::uint64_t, k_bits / 64> words_{};
    std::uint64_t top_ = 0;
};

struct Conn
{
    bool initiated = false;  // the user called connect(): it learns of failures too
    bool inner_connected = false;
    bool have_keys = false;  // the peer's Hello arrived and verified
    bool ready = false;      // a datagram from the peer opened: Connected was reported
    bool closing = false;
    bool confirm_seen = false;
    std::int64_t since_us = 0;
    std::int64_t hello_us = 0;      // the last Hello sent
    std::optional<Address> remote;  // for the log: gone from the inner transport once closed
    Random mine{};
    Random theirs{};
    Key tx{};
    Key rx{};
    std::array<std::uint64_t, k_data_streams> sent{};
    std::array<ReplayWindow, k_data_streams> windows{};
    SecureStats stats;
};

void wipe(Conn& c) noexcept
{
    sodium_memzero(c.tx.data(), c.tx.size());
    sodium_memzero(c.rx.data(), c.rx.size());
}

bool sodium_ready() noexcept
{
    return sodium_init() >= 0;
}

}  // namespace

// ---- keys -------------------------------------------------------------------------------------

core::Result<SecretKey> derive_key(std::string_view passphrase, std::string_view context,
                                   const KdfLimits& limits)
{
    if (!sodium_ready())
        return core::fail(core::ErrorCode::NetworkError, "derive_key: libsodium failed to start");
    if (passphrase.empty() || passphrase.size() > k_max_passphrase)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "derive_key: the passphrase must hold 1.." +
                              std::to_string(k_max_passphrase) + " bytes");
    if (limits.opslimit < crypto_pwhash_OPSLIMIT_MIN ||
        limits.memlimit < crypto_pwhash_MEMLIMIT_MIN)
        return core::fail(core::ErrorCode::InvalidArgument, "derive_key: limits below libsodium's");
    // The salt must be the same on every peer, which cannot exchange one before the key exists:
    // it is derived from a protocol label and the context (docs/protocol.md §10.1).
    std::string salt_input = "pliant/salt/v1";
    salt_input.append(context);
    std::array<std::uint8_t, crypto_pwhash_SALTBYTES> salt{};
    crypto_generichash(salt.data(), salt.size(),
                       reinterpret_cast<const unsigned char*>(salt_input.data()), salt_input.size(),
                       nullptr, 0);
    SecretKey key;
    if (crypto_pwhash(key.bytes.data(), key.bytes.size(), passphrase.data(), passphrase.size(),
                      salt.data(), limits.opslimit, limits.memlimit,
                      crypto_pwhash_ALG_ARGON2ID13) != 0)
        return core::fail(core::ErrorCode::NetworkError,
                          "derive_key: Argon2id ran out of memory (" +
                              std::to_string(limits.memlimit >> 20) + " MiB)");
    return key;
}

core::Result<SecretKey> key_from_file(const std::filesystem::path& path, std::string_view context,
                                      const KdfLimits& limits)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        return core::fail(core::ErrorCode::IoError, "cannot read key file " + path.string());
    std::string text;
    // Read at most one byte more than a passphrase may hold, so a huge file is refused cheaply.
    text.resize(k_max_passphrase + 3);
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<std::size_t>(in.gcount()));
    if (!text.empty() && text.back() == '\n')
    {
        text.pop_back();
        if (!text.empty() && text.back() == '\r')
            text.pop_back();
    }
    if (text.empty())
    {
        // Advice to write the key into the file, unless it is no file (/dev/null, a pipe).
        std::error_code ec;
        const std::string target =
            std::filesystem::is_regular_file(path, ec) ? path.string() : "session.key";
        return core::fail(core::ErrorCode::InvalidArgument,
                          "key file " + path.string() +
                              " is empty (a final newline aside): it should hold 32 random bytes "
                              "(head -c 32 /dev/urandom > " +
                              target + ")");
    }
    if (text.size() > k_max_passphrase)
    {
        sodium_memzero(text.data(), text.size());
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        return core::fail(core::ErrorCode::InvalidArgument,
                          "key file " + path.string() + " holds " +
                              (ec ? std::string("more than ") + std::to_string(k_max_passphrase)
                                  : std::to_string(size)) +
                              " bytes; a key file holds at most " +
                              std::to_string(k_max_passphrase) + " (32 random bytes are enough)");
    }
    auto key = derive_key(text, context, limits);
    sodium_memzero(text.data(), text.size());
    if (!key)
        return core::fail(key.error().code,
                          "key file " + path.string() + ": " + key.error().message);
    return key;
}

// ---- the transport ----------------------------------------------------------------------------

struct SecureTransport::Impl
{
    std::unique_ptr<Transport> inner;
    SecureSettings settings;
    bool sodium_ok = false;
    Key hello_key{};
    Key datagram_key{};
    std::map<std::uint32_t, Conn> conns;
    // Events for the caller, read from `pending_head`; cleared (storage kept) once all are read.
    // poll() fills it only when empty, so it holds one or two (a Connected and the first data).
    std::vector<TransportEvent> pending;
    std::size_t pending_head = 0;
    TransportEvent incoming;  // the inner transport's event, reused (Transport::poll_into)
    std::vector<std::vector<std::byte>> spare_buffers;  // empty, with capacity: see the top
    std::vector<std::uint8_t> buffer;
    SecureStats totals;
    std::int64_t last_refusal_warning_us = -1;  // when refuse() last warned (-1: never)

    [[nodiscard]] bool nothing_pending() const noexcept { return pending_head == pending.size(); }

    // The next pending event is read: its slot must be left without storage (moved from).
    void pop_pending() noexcept
    {
        if (++pending_head == pending.size())
        {
            pending.clear();
            pending_head = 0;
        }
    }

    // Keeps `b`'s storage for a later datagram; `b` is left empty.
    void recycle(std::vector<std::byte>& b)
    {
        if (b.capacity() == 0)
            return;
        b.clear();
        spare_buffers.push_back(std::move(b));
        b = {};
    }

    // Handshakes, then events from the inner transport until one is for the caller. \return
    // whether one is pending.
    bool fill_pending(int timeout_ms) noexcept
    {
        if (!nothing_pending())
            return true;
        service_handshakes();
        // Bounded, like Messenger::poll: a flood of bad datagrams cannot hold the caller.
        constexpr int k_max_inner_events = 256;
        int wait = timeout_ms;
        for (int k = 0; k < k_max_inner_events && nothing_pending(); ++k)
        {
            if (!inner->poll_into(incoming, wait))
                break;
            wait = 0;
            switch (incoming.kind)
            {
            case TransportEvent::Kind::Connected: on_connected(incoming.peer); break;
            case TransportEvent::Kind::Disconnected: on_disconnected(incoming); break;
            case TransportEvent::Kind::Received: on_received(incoming); break;
            }
        }
        return !nothing_pending();
    }

    [[nodiscard]] std::int64_t now_us() const
    {
        if (settings.clock)
            return settings.clock();
        return std::chrono::duration_cast<std::chrono::microseconds>(
                   std::chrono::steady_clock::now().time_since_epoch())
            .count();
    }

    void count(Conn& c, std::uint64_t SecureStats::*field) noexcept
    {
        ++(c.stats.*field);
        ++(totals.*field);
    }

    void refuse(PeerHandle h, Conn& c, DisconnectReason reason) noexcept
    {
        if (c.closing)
            return;
        c.closing = true;
        note_refusal(h, c, to_string(reason), refusal_cause(reason));
        inner->disconnect(h, reason);
    }

    // Counts a connection that never authenticated and ended (refused here, or closed by the
    // peer first). That is what a user with the wrong secret, or none, causes: worth a warning,
    // but at most one per k_refusal_warning_us, so that a flood of attempts cannot flood the log
    // (as EnetTransport's rate-limit message); the count is in totals().refused.
    void note_refusal(PeerHandle h, const Conn& c, std::string_view what,
                      std::string_view cause) noexcept
    {
        ++totals.refused;
        const std::int64_t now = now_us();
        if (last_refusal_warning_us >= 0 && now - last_refusal_warning_us < k_refusal_warning_us)
        {
            spdlog::debug("secure: connection {} refused: {}", h.value, what);
            return;
        }
        last_refusal_warning_us = now;
        spdlog::warn("secure: refused the connection {} {} ({}: {}; {} refused so far)",
                     c.initiated ? "to" : "from",
                     c.remote ? to_string(*c.remote) : std::string("an unknown address"), what,
                     cause, totals.refused);
    }

    // An authentication failure or a malformed datagram: held against the peer.
    void failure(PeerHandle h, Conn& c, std::uint64_t SecureStats::*field) noexcept
    {
        count(c, field);
        if (c.stats.auth_failures + c.stats.malformed > settings.max_failures)
            refuse(h, c, DisconnectReason::TooManyBadDatagrams);
    }

    // The Hello: reliable on channel 0 first, then unsequenced repeats on channel 1.
    void send_hello(PeerHandle h, Conn& c, bool repeat = false) noexcept
    {
        std::array<std::uint8_t, k_hello_size> hello{};
        hello[0] = k_type_hello;
        hello[1] = k_hello_version;
        std::memcpy(hello.data() + 4, c.mine.data(), k_random_size);
        crypto_generichash(hello.data() + k_hello_signed, k_mac_size, hello.data(), k_hello_signed,
                           hello_key.data(), hello_key.size());
        (void)inner->send(h, repeat ? Channel::State : Channel::Control,
                          std::as_bytes(std::span(hello)),
                          repeat ? Delivery::Unsequenced : Delivery::Reliable);
        c.hello_us = now_us();
    }

    // The Confirm (counter 0 on its own stream: the same bytes every time it is sealed).
    void send_confirm(PeerHandle h, const Conn& c, bool repeat) noexcept
    {
        const std::size_t n = seal(c, k_type_confirm, k_confirm_stream, 0, {});
        (void)inner->send(h, repeat ? Channel::State : Channel::Control,
                          std::as_bytes(std::span(buffer.data(), n)),
                          repeat ? Delivery::Unsequenced : Delivery::Reliable);
    }

    // Seals `plain` into `buffer`. \return the datagram's size.
    std::size_t seal(const Conn& c, std::uint8_t type, std::uint8_t stream, std::uint64_t counter,
                     std::span<const std::byte> plain)
    {
        const std::size_t size = k_head_size + plain.size() + k_tag_size;
        if (buffer.size() < size)
            buffer.resize(size);
        buffer[0] = type;
        store_u64(buffer.data() + 1, counter);
        const auto nonce = make_nonce(counter, stream);
        unsigned long long written = 0;
        crypto_aead_chacha20poly1305_ietf_encrypt(
            buffer.data() + k_head_size, &written,
            reinterpret_cast<const unsigned char*>(plain.data()), plain.size(), buffer.data(),
            k_head_size, nullptr, nonce.data(), c.tx.data());
        return k_head_size + static_cast<std::size_t>(written);
    }

    void on_connected(PeerHandle h)
    {
        Conn& c = conns[h.value];
        c.inner_connected = true;
        c.remote = inner->remote_address(h);
        c.since_us = now_us();
        randombytes_buf(c.mine.data(), c.mine.size());
        send_hello(h, c);
    }

    void on_disconnected(const TransportEvent& ev)
    {
        auto it = conns.find(ev.peer.value);
        if (it == conns.end())
            return;
        const Conn& c = it->second;
        // The peer hung up before authenticating: a peer without our secret gives up on the
        // datagrams it cannot read (a plaintext pliant after 16 of our Hellos, 0.8 s).
        if (c.inner_connected && !c.ready && !c.closing)
            note_refusal(ev.peer, c, "closed by the peer before authenticating",
                         "it has no secret or another one");
        const bool tell = c.ready || c.initiated;
        wipe(it->second);
        conns.erase(it);
        if (tell)
            pending.push_back(ev);
    }

    void on_hello(PeerHandle h, Conn& c, std::span<const std::uint8_t> d) noexcept
    {
        if (d.size() != k_hello_size || d[1] != k_hello_version || d[2] != 0 || d[3] != 0)
            return failure(h, c, &SecureStats::malformed);
        std::array<std::uint8_t, k_mac_size> mac{};
        crypto_generichash(mac.data(), mac.size(), d.data(), k_hello_signed, hello_key.data(),
                           hello_key.size());
        if (sodium_memcmp(mac.data(), d.data() + k_hello_signed, k_mac_size) != 0)
        {
            // Not a network accident (the MAC covers what the network could not change by
            // chance): the peer has another key.
            count(c, &SecureStats::auth_failures);
            return refuse(h, c, DisconnectReason::Refused);
        }
        if (c.have_keys)
        {
            // The peer's Hello again (a repeat, or the reliable copy after a repeat): it has not
            // opened our Confirm yet, so send that again. Any other second Hello is malformed.
            if (sodium_memcmp(c.theirs.data(), d.data() + 4, k_random_size) != 0)
                return failure(h, c, &SecureStats::malformed);
            count(c, &SecureStats::hello_repeats);
            return send_confirm(h, c, true);
        }
        std::memcpy(c.theirs.data(), d.data() + 4, k_random_size);
        // A Hello that is one of ours, reflected back on this or another live connection, would
        // make that connection's receive key equal a send key of ours: refuse it.
        for (const auto& [other, oc] : conns)
            if (oc.inner_connected &&
                sodium_memcmp(oc.mine.data(), c.theirs.data(), k_random_size) == 0)
            {
                count(c, &SecureStats::auth_failures);
                return refuse(h, c, DisconnectReason::Refused);
            }
        std::array<std::uint8_t, 2 * k_random_size> both{};
        std::memcpy(both.data(), c.mine.data(), k_random_size);
        std::memcpy(both.data() + k_random_size, c.theirs.data(), k_random_size);
        crypto_generichash(c.tx.data(), c.tx.size(), both.data(), both.size(), datagram_key.data(),
                           datagram_key.size());
        std::memcpy(both.data(), c.theirs.data(), k_random_size);
        std::memcpy(both.data() + k_random_size, c.mine.data(), k_random_size);
        crypto_generichash(c.rx.data(), c.rx.size(), both.data(), both.size(), datagram_key.data(),
                           datagram_key.size());
        c.have_keys = true;
        send_confirm(h, c, false);
    }

    void on_received(TransportEvent& ev)
    {
        auto it = conns.find(ev.peer.value);
        if (it == conns.end() || it->second.closing)
            return;
        Conn& c = it->second;
        const PeerHandle h = ev.peer;
        auto* d = reinterpret_cast<std::uint8_t*>(ev.data.data());
        const std::size_t size = ev.data.size();
        if (size == 0)
            return failure(h, c, &SecureStats::malformed);
        const std::uint8_t type = d[0];
        if (type == k_type_hello)
            return on_hello(h, c, std::span<const std::uint8_t>(d, size));
        if ((type != k_type_data && type != k_type_data_reliable && type != k_type_confirm) ||
            size < k_secure_overhead)
            return failure(h, c, &SecureStats::malformed);
        if (!c.have_keys)
        {
            // Unreliable data may overtake the peer's Hello; anything reliable may not.
            if (type == k_type_data)
                return count(c, &SecureStats::early);
            return failure(h, c, &SecureStats::malformed);
        }
        const std::uint64_t counter = load_u64(d + 1);
        const auto channel_index = static_cast<std::uint8_t>(ev.channel);
        const std::uint8_t stream =
            type == k_type_confirm
                ? k_confirm_stream
                : static_cast<std::uint8_t>(2 * channel_index + (type == k_type_data_reliable));
        if (type == k_type_confirm)
        {
            if (c.confirm_seen)
                return count(c, &SecureStats::replayed);
            if (size != k_secure_overhead || counter != 0)
                return failure(h, c, &SecureStats::malformed);
        }
        else if (stream >= k_data_streams)
        {
            return failure(h, c, &SecureStats::malformed);
        }
        else
        {
            switch (c.windows[stream].check(counter))
            {
            case ReplayWindow::Verdict::Fresh: break;
            case ReplayWindow::Verdict::Duplicate: return count(c, &SecureStats::replayed);
            case ReplayWindow::Verdict::TooOld: return count(c, &SecureStats::too_old);
            }
        }
        const auto nonce = make_nonce(counter, stream);
        unsigned long long plain_size = 0;
        // In place: libsodium allows the plaintext to overwrite the ciphertext.
        if (crypto_aead_chacha20poly1305_ietf_decrypt(d + k_head_size, &plain_size, nullptr,
                                                      d + k_head_size, size - k_head_size, d,
                                                      k_head_size, nonce.data(), c.rx.data()) != 0)
            return failure(h, c, &SecureStats::auth_failures);
        count(c, &SecureStats::opened);
        if (type == k_type_confirm)
            c.confirm_seen = true;
        else
            c.windows[stream].mark(counter);
        if (!c.ready)
        {
            c.ready = true;
            TransportEvent connected;
            connected.kind = TransportEvent::Kind::Connected;
            connected.peer = h;
            pending.push_back(std::move(connected));
        }
        if (type == k_type_confirm)
            return;
        ev.data.erase(ev.data.begin(), ev.data.begin() + static_cast<std::ptrdiff_t>(k_head_size));
        ev.data.resize(static_cast<std::size_t>(plain_size));
        pending.push_back(std::move(ev));
        // `ev` is the reused inner event: it receives the next datagram into a spare buffer.
        if (!spare_buffers.empty())
        {
            ev.data = std::move(spare_buffers.back());
            spare_buffers.pop_back();
        }
    }

    // Drops handshakes past their timeout and repeats the Hello of the others that are due.
    void service_handshakes() noexcept
    {
        const std::int64_t now = now_us();
        const auto limit = static_cast<std::int64_t>(settings.handshake_timeout_s * 1e6);
        const auto repeat = static_cast<std::int64_t>(settings.hello_repeat_s * 1e6);
        for (auto& [h, c] : conns)
        {
            if (!c.inner_connected || c.ready || c.closing)
                continue;
            if (now - c.since_us > limit)
                refuse(PeerHandle{h}, c, DisconnectReason::TimedOut);
            else if (repeat > 0 && now - c.hello_us >= repeat)
                send_hello(PeerHandle{h}, c, true);
        }
    }
};

SecureTransport::SecureTransport(std::unique_ptr<Transport> inner, const SecretKey& key,
                                 const SecureSettings& settings)
    : impl_(std::make_unique<Impl>())
{
    PLIANT_ASSERT(inner != nullptr, "SecureTransport needs an inner transport");
    impl_->inner = std::move(inner);
    impl_->settings = settings;
    impl_->sodium_ok = sodium_ready();
    if (impl_->sodium_ok)
    {
        crypto_kdf_derive_from_key(impl_->hello_key.data(), impl_->hello_key.size(), k_subkey_hello,
                                   k_kdf_context, key.bytes.data());
        crypto_kdf_derive_from_key(impl_->datagram_key.data(), impl_->datagram_key.size(),
                                   k_subkey_datagram, k_kdf_context, key.bytes.data());
    }
}

SecureTransport::~SecureTransport()
{
    for (auto& [h, c] : impl_->conns)
        wipe(c);
    sodium_memzero(impl_->hello_key.data(), impl_->hello_key.size());
    sodium_memzero(impl_->datagram_key.data(), impl_->datagram_key.size());
}

core::Result<Address> SecureTransport::open(const Address& bind) noexcept
{
    if (!impl_->sodium_ok)
        return core::fail(core::ErrorCode::NetworkError,
                          "SecureTransport::open: libsodium failed to start");
    return impl_->inner->open(bind);
}

core::Result<PeerHandle> SecureTransport::connect(const Address& remote) noexcept
{
    auto h = impl_->inner->connect(remote);
    if (h)
        impl_->conns[h->value].initiated = true;
    return h;
}

core::Result<void> SecureTransport::send(PeerHandle peer, Channel channel,
                                         std::span<const std::byte> bytes,
                                         Delivery delivery) noexcept
{
    auto it = impl_->conns.find(peer.value);
    if (it == impl_->conns.end() || !it->second.ready || it->second.closing)
        return core::fail(
            core::ErrorCode::NetworkError,
            "SecureTransport::send: no authenticated peer " + std::to_string(peer.value));
    Conn& c = it->second;
    const bool reliable = delivery == Delivery::Reliable;
    const auto stream =
        static_cast<std::uint8_t>(2 * static_cast<int>(channel) + (reliable ? 1 : 0));
    PLIANT_ASSERT(stream < k_data_streams, "channel out of range");
    const std::uint64_t counter = ++c.sent[stream];
    const std::size_t n =
        impl_->seal(c, reliable ? k_type_data_reliable : k_type_data, stream, counter, bytes);
    return impl_->inner->send(peer, channel, std::as_bytes(std::span(impl_->buffer.data(), n)),
                              delivery);
}

std::optional<TransportEvent> SecureTransport::poll(int timeout_ms) noexcept
{
    Impl& s = *impl_;
    if (!s.fill_pending(timeout_ms))
        return std::nullopt;
    TransportEvent out = std::move(s.pending[s.pending_head]);
    s.pop_pending();
    return out;
}

bool SecureTransport::poll_into(TransportEvent& out, int timeout_ms) noexcept
{
    Impl& s = *impl_;
    if (!s.fill_pending(timeout_ms))
        return false;
    TransportEvent& ev = s.pending[s.pending_head];
    swap_into(out, ev);
    s.recycle(ev.data);
    s.pop_pending();
    return true;
}

void SecureTransport::flush() noexcept
{
    impl_->inner->flush();
}

void SecureTransport::wait(double max_s) noexcept
{
    if (impl_->nothing_pending())
        impl_->inner->wait(max_s);
}

void SecureTransport::disconnect(PeerHandle peer, DisconnectReason reason) noexcept
{
    auto it = impl_->conns.find(peer.value);
    if (it != impl_->conns.end())
        it->second.closing = true;
    impl_->inner->disconnect(peer, reason);
}

std::optional<PeerStats> SecureTransport::stats(PeerHandle peer) const noexcept
{
    auto s = impl_->inner->stats(peer);
    auto it = impl_->conns.find(peer.value);
    if (s && it != impl_->conns.end())
        s->bad_datagrams += it->second.stats.auth_failures + it->second.stats.malformed;
    return s;
}

std::optional<Address> SecureTransport::remote_address(PeerHandle peer) const noexcept
{
    return impl_->inner->remote_address(peer);
}

std::size_t SecureTransport::queued_bytes(PeerHandle peer) const noexcept
{
    return impl_->inner->queued_bytes(peer);
}

void SecureTransport::report_bad_datagram(PeerHandle peer) noexcept
{
    impl_->inner->report_bad_datagram(peer);
}

void SecureTransport::live_peers(std::vector<PeerHandle>& out) const
{
    out.clear();
    for (const auto& [h, c] : impl_->conns)
        if (c.ready)
            out.push_back(PeerHandle{h});
}

std::optional<SecureStats> SecureTransport::secure_stats(PeerHandle peer) const noexcept
{
    auto it = impl_->conns.find(peer.value);
    if (it == impl_->conns.end())
        return std::nullopt;
    return it->second.stats;
}

SecureStats SecureTransport::totals() const noexcept
{
    return impl_->totals;
}

Transport& SecureTransport::inner() noexcept
{
    return *impl_->inner;
}

}  // namespace pliant::net
