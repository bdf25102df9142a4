// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Session::Impl, the state of a Session peer, and the module-wide constants and helpers of its
// parts (private to the session module; include/pliant/session/session.h has the design,
// docs/session.md the story). Its member functions are defined by topic:
// - session.cpp: sending, the model, the message loop and advance();
// - session_partitions.cpp: points of interest, partitions and the sets they give each peer;
// - session_coupling.cpp: forces; exact (halos, barrier) and fast (Dirichlet) coupling;
// - session_blobs.cpp (not Impl): the model and state blobs, forces from the wire;
// - session_stream.cpp: the display of own leaves and the stream of leaf states;
// - session_receive.cpp: received leaf states, acknowledgements, and the smooth view;
// - session_membership.cpp: connections, leaving, losses, pauses and master failover;
// - session_join.cpp: greetings, the Welcome and its blobs.

#include <pliant/core/assert.h>
#include <pliant/core/hash.h>
#include <pliant/net/codec.h>
#include <pliant/net/quantised.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pliant::session
{

inline constexpr double k_leave_timeout_s = 5.0;
/// The most wall time one advance() call spends stepping in exact coupling before it returns to
/// let the caller poll() (s). ENet moves at most its window (64 KiB) of reliable data per
/// service, so a master behind real time that served the network once per frame period (16.7
/// ms) sent a level-8 model of 3 MB at about 4 MB/s; ticks of a level-8 lockstep take ~1.4 ms.
inline constexpr double k_step_slice_s = 0.002;
/// The greetings go reliably, and are repeated unreliably once per stream period for at most this
/// long (s): Ready until the peer's first leaf state arrives, a dialler's Hello until anything
/// arrives from the peer. The stream to a joiner starts on its Ready, and a peer knows a dialler
/// only from its Hello; a lost reliable datagram waits for a retransmission timeout, which on a
/// young ENet connection (500 ms initial round-trip estimate, doubling) is a second or more, and
/// ENet drops what a dialler sends before the acceptor's side of the handshake completes (its
/// acknowledgement lost). Meanwhile a fast-coupled neighbour held its clock waiting for the
/// joiner's border states, and the others waited on it; a viewer saw the joiner's leaves frozen.
inline constexpr double k_greeting_repeat_s = 5.0;
/// Quantised streaming: an owner codes against a baseline only among its last 16 states sent of
/// a leaf, and a receiver holds its last 16 received, so an acknowledged baseline the owner still
/// has is one the receiver still holds (docs/protocol.md §5.5).
inline constexpr std::size_t k_baseline_window = 16;
/// Smooth display: states kept per leaf for interpolation (docs/session.md §5.3).
inline constexpr int k_view_history = 4;
/// Smooth display: the playout time lags the newest state by k_view_periods stream periods
/// beyond the smallest lead seen; that lead recovers at k_view_leak (s per s) after a late state;
/// the playout clock slews towards its target at up to k_view_slew of real time and jumps beyond
/// k_view_snap_s, but never backwards.
inline constexpr double k_view_periods = 2.0;
inline constexpr double k_view_leak = 0.05;
inline constexpr double k_view_slew = 0.5;
inline constexpr double k_view_snap_s = 0.25;
/// Failover: a successor's first epoch is this far above the newest it knows, so a Partition the
/// lost master sent to only some peers just before it went cannot share an epoch with the
/// successor's (docs/session.md §6).
inline constexpr std::uint32_t k_successor_epoch_gap = 16;
/// Likewise its first peer id is this far above the highest it knows: a joiner the lost master
/// welcomed just before it went, whose greeting has not reached the successor, holds an id just
/// above it, which the successor must not give to another joiner.
inline constexpr std::uint16_t k_successor_id_gap = 16;
/// Partitions kept aside per peer that is not (yet) our master (failover, docs/session.md §6).
inline constexpr std::size_t k_max_foreign_partitions = 8;
/// Halos held ahead of this peer's tick: an honest member is at most a tick or two ahead (the
/// lockstep's barrier), so a halo further ahead than this, or one that would make a sender's
/// held values exceed k_max_held_halo_grids × the grid's nodes, is a peer's bug or a forger's
/// flood, dropped and counted rather than kept (memory would grow without bound).
inline constexpr std::uint64_t k_max_halo_lead = 64;
inline constexpr std::size_t k_max_held_halo_grids = 4;
/// Force lists held per peer that are not in effect yet (SessionStats::force_floods).
inline constexpr std::size_t k_max_forces_ahead = 256;
/// Messages a joiner keeps for when it has the model (SessionStats::early_floods).
inline constexpr std::size_t k_max_early_messages = 4096;
/// How far a leaf state's epoch may run ahead of the newest partition held: a successor's gap
/// and a few re-partitions in flight; further is no epoch any master will issue soon.
inline constexpr std::uint32_t k_max_epoch_lead = 2 * k_successor_epoch_gap;
/// How long a leaf state of an epoch ahead of the partitions held counts without its Partition.
inline constexpr double k_provisional_s = 3.0;
/// How long an incoming connection may stay without greeting (a Hello) before it is closed: a
/// joiner or a dialling member greets at once, and an idle connection would otherwise hold one
/// of the transport's peer slots for as long as its other end keeps it alive (an audit filled
/// all 64 that way and every later joiner was turned away).
inline constexpr double k_greeting_deadline_s = 10.0;
/// After a pause (SessionSettings::pause_s), a peer that has heard no message from its master
/// (the master: from any participant) since, and whose transport has heard nothing at all on
/// that link for this long (s; a live ENet answers a ping every 0.5 s), takes itself for
/// dropped without waiting for its own timeout, which needs its retransmissions after the
/// pause to run out and takes seconds more.
inline constexpr double k_pause_silence_s = 2.0;
/// A pause stops counting against the losses that follow after this long (s): ENet's longest
/// timeout (30 s) and a margin.
inline constexpr double k_pause_suspect_s = 35.0;
/// Master: the Welcome's blob chunks go to a joiner while the transport holds less than this
/// for it (queued or unacknowledged), so a joiner that reads slowly, or never, holds at most
/// this much of the master's memory, not the whole model and state (docs/session.md §2).
inline constexpr std::size_t k_feed_window_bytes = 256 * 1024;
/// A participant's new points of interest re-partition the session at most this often (s, the
/// master's clock); a change within it waits for its end. Each change cost the master a partition
/// computed and broadcast (and every peer a hand-over), so a peer changing its points on every
/// frame, by a bug or on purpose, kept the whole session re-partitioning. A participant's first
/// points (its admission to the partition) go at once.
inline constexpr double k_points_interval_s = 0.1;

/// Coarse streaming: the largest k a grid allows with leaves of side `w >> depth`: level - k >= 1,
/// k <= net::k_max_leaf_coarsen, and 2^(k+1) divides the side, so a leaf maps to whole coarse
/// nodes and holds at least two rows of them. One row is not enough: a leaf of the bottom row
/// whose only coarse row is y = 0 right of b (W, 0) would hold only twins of the left half
/// (docs/design.md §1), i.e. no canonical coarse node at all, and could not be sent. Leaves of side
/// 8 (levels >= 3) allow k <= 2.
inline int max_coarsen_for(const core::TetraGrid& g, int depth)
{
    const int side = g.w() >> depth;
    int k = 0;
    while (k < net::k_max_leaf_coarsen && g.level() - (k + 1) >= 1 && side % (4 << k) == 0)
        ++k;
    return k;
}

/// The node of a leaf is sent with coarsening k (x and y multiples of 2^k).
constexpr bool on_coarse_level(core::GridCoord c, int k) noexcept
{
    const int mask = (1 << k) - 1;
    return (c.x & mask) == 0 && (c.y & mask) == 0;
}

inline double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The rules of coarse streaming that need the grid and the coupling (session.cpp).
core::Result<void> check_coarsen(const SessionSettings& settings, const core::TetraGrid& grid,
                                 int depth, Coupling coupling, const char* who);

struct ForceEntry
{
    std::uint64_t apply_tick = 0;
    std::vector<net::UserForce> forces;
};

struct PartitionEntry
{
    std::uint64_t apply_tick = 0;
    std::uint32_t epoch = 0;
    std::vector<net::PeerId> owners;
    std::vector<net::PeerId> members;  ///< distinct owners, increasing
};

struct RemotePeer
{
    net::PeerInfo info;
    bool info_known = false;
    std::optional<net::PeerHandle> handle;
    std::vector<std::pair<net::Message, net::SendMode>> queued;  ///< until the handle is bound
    /// Master: the Welcome's blobs still to go to this joiner (model then state, from `next`),
    /// fed as its connection drains (feed_blobs); the reliable messages for it meanwhile wait in
    /// `after_feed`, in order.
    struct BlobFeed
    {
        std::shared_ptr<const std::vector<std::byte>> model, state;
        std::size_t next = 0;
        std::uint64_t tick = 0;
    };
    std::optional<BlobFeed> feed;
    std::vector<std::pair<net::Message, net::SendMode>> after_feed;
    bool has_heartbeat = false;
    std::uint64_t heartbeat = 0;  ///< newest Heartbeat tick (exact mode)
    std::vector<ForceEntry> forces;
    bool warned_force_limit = false;  ///< a force of it above the session's limit was logged
    std::uint64_t rejected = 0;       ///< its messages dropped by the checks (PeerStatus)
    bool warned_rejected = false;     ///< the first of them was logged
    std::vector<net::Target> points;
    /// Master: when its points last re-partitioned the session (the master's clock), and
    /// whether newer ones wait for k_points_interval_s to pass.
    double points_applied_at = 0.0;
    bool points_waiting = false;
    bool ready = false;  ///< sent its points of interest (participants): may be partitioned
    /// Sent Ready: it holds the model and can show leaf states, so they are streamed to it. A
    /// joiner still downloading the model gets none (they would only compete with the download).
    bool has_model = false;
    /// Until when (our clock) our Ready to it is repeated unreliably (k_greeting_repeat_s).
    double ready_repeat_until = -1.0;
    bool streams_to_us = false;  ///< a LeafState or LeafBatch came from it: our Ready arrived
    /// We dialled it: until when (our clock) our Hello is repeated unreliably, unless `heard`.
    double hello_repeat_until = -1.0;
    bool heard = false;      ///< a message came from it on a bound connection: it knows us
    double heard_at = -1.0;  ///< when the last one was handled (our clock)
    bool leaving = false;
    bool departed = false;
    /// Exact coupling: the apply tick of the first partition it is no longer a member of, after
    /// one it was in (it left, was lost, or was the lost master): its forces end there, on every
    /// peer alike, since every peer holds the same partitions (docs/session.md §6).
    std::optional<std::uint64_t> forces_end;
};

/// A quantised leaf state an owner sent (per leaf) or a receiver holds (per leaf, with sender).
struct QuantisedLeaf
{
    std::uint16_t sender = 0;
    std::uint64_t tick = 0;
    double time = 0.0;  ///< simulation time of the state, s (the LeafState's time)
    int u_exponent = 0;
    int v_exponent = 0;
    std::vector<std::int32_t> qu, qv;
};

/// The last k_baseline_window quantised states of one leaf, oldest first (docs/session.md §5.1):
/// a ring over a fixed array whose entries keep their vectors when they leave it, so storing a
/// state (every stream period per leaf sent, every leaf state received) reuses the oldest
/// entry's storage instead of allocating (a deque allocated blocks and two vectors per state).
class BaselineRing
{
public:
    [[nodiscard]] std::size_t size() const noexcept { return count_; }
    [[nodiscard]] bool empty() const noexcept { return count_ == 0; }
    /// Entry i, 0 the oldest.
    [[nodiscard]] const QuantisedLeaf& operator[](std::size_t i) const noexcept
    {
        return entries_[(first_ + i) % k_baseline_window];
    }
    [[nodiscard]] const QuantisedLeaf& back() const noexcept { return (*this)[count_ - 1]; }
    void clear() noexcept { first_ = count_ = 0; }
    void pop_front() noexcept
    {
        first_ = (first_ + 1) % k_baseline_window;
        --count_;
    }
    void pop_back() noexcept { --count_; }
    /// Appends an entry, the oldest's if full (its vectors keep their capacity): the caller fills
    /// every field.
    QuantisedLeaf& push_back() noexcept
    {
        if (count_ == k_baseline_window)
            pop_front();
        ++count_;
        return entries_[(first_ + count_ - 1) % k_baseline_window];
    }

private:
    std::array<QuantisedLeaf, k_baseline_window> entries_;
    std::size_t first_ = 0;
    std::size_t count_ = 0;
};

/// Stores leaf state (qu, qv: the first n of each) in `e`, reusing its vectors.
inline void store_quantised(QuantisedLeaf& e, std::uint16_t sender, std::uint64_t tick, double time,
                            int u_exponent, int v_exponent, const std::vector<std::int32_t>& qu,
                            const std::vector<std::int32_t>& qv, std::size_t n)
{
    e.sender = sender;
    e.tick = tick;
    e.time = time;
    e.u_exponent = u_exponent;
    e.v_exponent = v_exponent;
    e.qu.assign(qu.begin(), qu.begin() + static_cast<std::ptrdiff_t>(n));
    e.qv.assign(qv.begin(), qv.begin() + static_cast<std::ptrdiff_t>(n));
}

struct HaloBuffer
{
    std::uint64_t tick = 0;
    net::PeerId sender;
    double time = 0.0;
    std::vector<net::NodeRange> ranges;  // the nodes, as received (checked against the grid)
    std::vector<double> u, v;            // in range order
};

/// One Halo datagram to one receiver, planned once per pair of partitions (refresh_exact_sets):
/// its node ranges, and the same nodes as runs of consecutive padded offsets in the state's
/// planes, from which each tick gathers the values.
struct HaloChunk
{
    std::vector<net::NodeRange> ranges;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> runs;  // {padded offset, length}
    std::size_t values = 0;
};

struct Session::Impl
{
    Session& s;
    net::Transport& transport;
    net::Messenger messenger;
    SessionSettings settings;
    std::uint32_t session_id = 0;
    net::PeerId master_id{0};
    std::optional<net::PeerHandle> master_handle;  // joiner: the first connection
    bool welcomed = false;
    std::uint16_t next_peer_id = 1;
    std::map<std::uint16_t, RemotePeer> peers;
    std::map<net::PeerHandle, std::uint16_t> handle_ids;  // bound connections
    // Incoming connections not bound yet, and the caller's time they connected (close_ungreeted).
    std::map<net::PeerHandle, double> ungreeted;
    bool advanced = false;  // advance() has been called: last_now is the caller's clock
    std::map<net::PeerHandle, std::uint16_t> dialing;  // joiner -> listed peers
    std::map<net::PeerHandle, net::PeerStats> last_stats;
    std::vector<net::PeerHandle> live_handles;  ///< poll()'s scratch: the live connections
    net::PeerStats closed_stats;

    // Blobs being received (joiner).
    net::Welcome welcome;
    std::uint64_t welcome_tick = 0;
    std::vector<std::byte> model_blob, state_blob;
    std::size_t model_got = 0, state_got = 0;

    // Simulation.
    std::unique_ptr<sim::Rkf45Workspace> ws;
    // forces_at's result and scratch, reused tick after tick; the list last written into ws
    // (set_forces places each force anew, a whole-grid search for a point force that reaches
    // no node: done only when the list changes).
    std::vector<std::pair<std::uint16_t, const ForceEntry*>> force_entries;
    std::vector<sim::Force> forces_now, forces_in_ws;
    bool forces_in_ws_valid = false;
    mutable std::vector<std::uint16_t> barrier_scratch;  // barrier_set's, in barrier_missing
    std::vector<std::uint16_t> heartbeat_to;             // publish's recipients
    std::vector<PartitionEntry> partitions;
    std::vector<ForceEntry> my_forces;
    std::vector<ForceEntry> pending_forces;  // apply_tick = the earliest tick asked for
    std::size_t warned_idle_members = 0;     // members count last warned of leaves too few
    double warned_full_at = -1e300;          // when a joiner was last refused for room
    bool recording = false;
    std::vector<ForceRecord> force_log;  // every force list seen, when recording
    std::vector<net::Target> my_points;
    bool points_dirty = false;
    bool points_sent = false;  // participant: our points went out once (greetings repeat them)
    // Failover (docs/session.md §6).
    net::PeerInfo my_info;  // our entry in the Welcome, announced if we become master
    bool my_info_known = false;
    // Partitions from a peer we do not follow yet (it may be the successor of a master whose loss
    // we have not noticed): applied, in order, if it becomes our master.
    std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, net::Partition>>>
        foreign_partitions;
    bool repartition_pending = false;
    std::uint32_t next_epoch = 1;
    bool lockstep = false;    // exact: a member stepping in lockstep
    bool published = false;   // exact: tick state_.tick published
    bool state_exact = true;  // exact: joiner before its first halos
    std::uint64_t exact_from = 0;
    std::deque<HaloBuffer> halos;
    std::vector<HaloBuffer> spare_halos;  // applied halos' buffers, reused by on_halo
    net::Message halo_message;            // send_halos' message, reused
    // Per leaf: the state shown (display): partition epoch, tick and owner's time of the newest
    // state (received states older than it are ignored, docs/protocol.md §2), and its sender.
    std::vector<std::uint32_t> leaf_epoch;
    std::vector<std::uint64_t> leaf_tick;
    std::vector<double> leaf_time;
    std::vector<std::uint16_t> leaf_sender;
    // Per leaf: the newest whole state of an epoch ahead of every partition held, set aside
    // (neither shown nor, in fast coupling, simulated) until that epoch's Partition says whether
    // its sender owns the leaf (settle_provisional_states); and the leaves holding one.
    struct AsideState
    {
        std::uint32_t epoch = 0;
        std::uint64_t tick = 0;
        double time = 0.0;
        std::uint16_t sender = 0;
        double until = 0.0;  ///< last_now after which its epoch is taken as never coming; 0: none
        std::vector<double> u, v;  // the leaf's nodes (LeafGraph order)
    };
    std::vector<AsideState> aside;
    std::vector<std::uint32_t> provisional_leaves;
    std::vector<std::uint8_t> provisional_listed;  // per leaf: in provisional_leaves
    std::vector<double> leaf_sent_time;            // our leaves: simulated time last streamed

    // Smooth display (docs/session.md §5.3): per leaf not ours, the displacements of the last
    // states received (as displayed, coarse leaves refined), oldest first; per sender, a
    // playout clock. What is drawn is u alone, so velocities are neither kept nor interpolated.
    struct ViewHistory
    {
        std::uint16_t sender = 0;
        int count = 0;  // states held, <= k_view_history
        int first = 0;  // the slot of the oldest state: state k (0 = oldest) is in slot
                        // (first + k) % k_view_history
        std::array<double, k_view_history> time{};  // per slot
        std::vector<double> u;  // k_view_history x nodes, slot j at [j n, (j + 1) n)

        [[nodiscard]] int slot(int k) const noexcept { return (first + k) % k_view_history; }
        [[nodiscard]] double time_of(int k) const noexcept
        {
            return time[static_cast<std::size_t>(slot(k))];
        }
    };
    struct Playout
    {
        double newest = 0.0;  // newest owner time received from this sender, s
        bool fresh = false;   // newest grew since the last update_view
        double lead = 0.0;    // leaky minimum of newest - now when newest grew, s
        double offset = 0.0;  // playout time = now + offset, slewed towards lead - margin
        double render = 0.0;  // the playout time of the last update_view (never decreases)
        double last_now = 0.0;
        bool set = false;
        // The sender's stream period as seen here: the smallest growth of `newest` among the
        // last k_period_samples (0: none yet). The receiver's own stream_rate_hz says nothing
        // of it (a viewer streams nothing; peers may stream at other rates).
        static constexpr std::size_t k_period_samples = 8;
        std::array<double, k_period_samples> growth{};
        std::size_t growths = 0;
        void grew(double by) noexcept { growth[growths++ % k_period_samples] = by; }
        [[nodiscard]] double period() const noexcept
        {
            const std::size_t n = std::min(growths, k_period_samples);
            return n == 0 ? 0.0 : *std::min_element(growth.begin(), growth.begin() + n);
        }
    };
    std::vector<ViewHistory> history;
    std::vector<std::uint32_t> updated;  // leaves whose shown state changed in this poll
    std::vector<char> updated_flag;
    std::map<std::uint16_t, Playout> playout;
    core::Field<double> view_u;
    std::vector<double> view_time;

    // Quantised streaming (docs/protocol.md §5.5).
    std::vector<BaselineRing> sent;  // per leaf: our last states sent, newest last
    std::vector<BaselineRing> held;  // per leaf: last states received, newest last
    std::map<std::uint16_t, std::vector<std::uint64_t>> acked;  // peer -> per leaf: tick + 1
    // Acks to send, per peer: the newest tick + 1 per leaf and the leaves listed. Kept across
    // ack periods (cleared, not freed), so scheduling an ack allocates nothing.
    struct PendingAcks
    {
        std::vector<std::uint64_t> tick_plus_one;  // per leaf, valid where listed
        std::vector<char> listed;                  // per leaf
        std::vector<std::uint32_t> leaves;         // listed leaves, in arrival order
    };
    std::map<std::uint16_t, PendingAcks> pending_acks;
    bool acks_pending = false;  // some PendingAcks lists a leaf
    net::Message ack_msg;       // send_acks(): the Ack being filled, reused
    double next_ack = 0.0;
    // Bandwidth cap (settings.bandwidth_cap_mbit_s): per peer, a byte budget and leaf priorities.
    std::map<std::uint16_t, double> budget;
    std::map<std::uint16_t, std::vector<double>> priority;
    // Batched streaming (settings.batch_leaves): per peer, the LeafBatch (quantised leaves) or
    // ValueBatch (coarse leaves) being filled this period. The messages stay when sent (`open`
    // false), and their leaves' vectors go to the spares, so a period allocates nothing once
    // they have grown.
    struct OutBatch
    {
        net::Message message;
        bool open = false;
    };
    std::map<std::uint16_t, OutBatch> batch;
    std::vector<net::QuantisedDelta> spare_deltas;  // of LeafBatch leaves sent
    std::vector<net::ValueLeaf> spare_values;       // of ValueBatch leaves sent
    net::BatchLeaf coded;                           // code_leaf()'s output for one receiver
    net::ValueLeaf coded_values;                    // batch_values(): the leaf being added
    net::Message quantised_msg;  // stream_quantised(): a leaf state sent alone (not batched)
    net::LeafState batch_state;  // on_leaf_batch / on_value_batch: the leaf as a LeafState
    std::vector<core::Vec3> leaf_centre;  // rest positions, m
    std::vector<double> leaf_radius;      // m
    std::vector<char> near_interest;      // per leaf, refreshed each stream
    std::vector<std::uint32_t> order;     // my leaves by priority
    // Scratch of one leaf (no allocation per node or per leaf once sized).
    std::vector<double> xu, xv, xp;
    std::vector<std::int32_t> qu, qv, ru, rv, pu;

    // Cached sets for (prev, next) partition epochs.
    std::uint32_t cache_prev = 0, cache_next = 0;
    std::vector<core::Region> integrate_runs;                  // exact: dilated own set
    std::vector<core::Region> own_runs;                        // exact: own set
    std::map<std::uint16_t, std::vector<HaloChunk>> halo_out;  // receiver -> its datagrams
    std::uint32_t fast_epoch = 0;
    std::vector<char> fast_mine;  // fast: owned_mask of fast_mine_epoch
    // Fast: the x-runs of in-range positions whose canonical node fast_mine does not own, as
    // {padded offset, length}: the Dirichlet values copied from the display before each frame.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> fast_fill_runs;
    // Every node's offset in the padded plane of a ghost-ring-1 field of the grid (the state,
    // the display, the view): the per-node loops of the display, the streams and the halos
    // index the planes with it instead of dividing the node index by the row length.
    std::vector<std::uint32_t> pad;
    // Per leaf, its nodes (LeafGraph order) as runs of consecutive padded offsets: a leaf is a
    // block of grid rows listed row-major, so a run is one of its rows (cut where the canonical
    // nodes stop). The whole-object copies of every frame (the display, the view history, the
    // view, the stream) move these spans instead of indexing node by node.
    struct NodeRun
    {
        std::uint32_t first;   // index of the run's first node in the leaf's node list
        std::uint32_t offset;  // its padded offset
        std::uint32_t count;
    };
    std::vector<NodeRun> node_runs;
    std::vector<std::uint32_t> node_run_begin;  // per leaf, and one past the last
    std::vector<net::PeerHandle> stream_to;     // stream(): the receivers of a leaf state
    net::Message stream_msg;                    // stream(): the leaf state being sent
    // Our leaves' nodes in the display are older than the state (flush_display).
    bool own_display_pending = false;
    // A frame's update_view has not been written into view_u yet (materialize_view).
    bool view_due = false;
    double stall_since = -1.0;  // fast: our clock when the current hold began (-1: none)
    // exact: the tick whose barrier this peer waits at, since when (caller's clock; -1: not
    // waiting), and whether that wait was warned about
    std::uint64_t barrier_tick = 0;
    double barrier_since = -1.0;
    bool barrier_warned = false;
    // fast: a hold ran out (max_stall_s) and the frames since have all been stale: step on
    // without a new hold until a frame is fresh again (a neighbour silent, not slow).
    bool stepping_stale = false;
    std::uint32_t fast_mine_epoch = std::numeric_limits<std::uint32_t>::max();
    std::vector<core::Region> owned_regions;  // fast: own leaves
    // Fast: the coupling edges (owned node, Dirichlet neighbour) and their interface damping
    // (fast_advance explains it). Per owned node with Dirichlet neighbours: its (x, y) and its
    // edges [begin, next begin); per edge: the stencil direction (grid_neighbours order) and the
    // leaf whose streamed state gives the neighbour's value. Rebuilt when the partition changes.
    std::uint32_t border_epoch = std::numeric_limits<std::uint32_t>::max();
    std::vector<core::GridCoord> border_nodes;
    std::vector<char> border_mask;  // per canonical node: 1 on border_nodes
    std::vector<std::uint32_t> border_begin;
    std::vector<std::uint8_t> border_dir;
    std::vector<std::uint32_t> border_leaf;
    std::vector<std::uint32_t> my_leaves;  // streamed leaves
    // Coarse streaming (docs/session.md §5.2). Per leaf: the coarsening of the values shown (0 for
    // our own leaves and for leaves received at full resolution).
    std::vector<std::uint8_t> leaf_coarsen;
    std::vector<char> leaf_mine;  // scratch: our own leaves, per leaf
    int max_coarsen = 0;          // the grid's limit (max_coarsen_for)
    // Allocated on the first coarse state: plans from level n - max_coarsen up, the restricted
    // display per coarsening j = 1..max_coarsen (level n - j, ghost 1; index j - 1) and the
    // refined level-n field.
    std::vector<subdiv::ConvolutionPlan> coarse_plans;
    std::vector<core::Field<double>> coarse_u, coarse_v;
    core::Field<double> refined_u, refined_v;
    std::uint32_t my_leaves_epoch = std::numeric_limits<std::uint32_t>::max();

    // Clock.
    bool clock_set = false;
    double clock_offset = 0.0;  // sim time = now + clock_offset
    double last_now = 0.0;
    double next_stream = 0.0;
    double next_greeting_repeat = 0.0;
    double next_frame = 0.0;
    double next_view = 0.0;  // view_u is refreshed at frame_rate_hz
    bool leaving = false;
    double leave_started = 0.0;
    // Pauses (SessionSettings::pause_s): where the last one ended (caller's clock; -1: none) and
    // how long it was; the departures noticed (lose_peer) and not yet handled, which advance()
    // weighs against a pause before following a successor or re-partitioning.
    double pause_end = -1.0;
    double pause_length = 0.0;
    // Since the last pause nothing has come from the master (the master: from any participant):
    // this peer may have been dropped (check_pause, dropped_after_pause).
    bool pause_suspect = false;
    std::vector<std::pair<std::uint16_t, net::DisconnectReason>> lost_pending;

    SessionStats counters;
    bool warned_own_force_limit = false;  ///< count_limited's flag for this peer's own forces
    double next_unbound_warning = 0.0;

    std::shared_ptr<const std::vector<std::byte>> model_blob_shared;
    std::size_t feeding = 0;  // peers with a feed

    std::vector<std::pair<net::PeerHandle, net::Message>> early;  // before the model
    double welcome_now = 0.0;  // our clock when the Welcome arrived
    bool display_dirty = false;
    bool behind = false;  ///< the last advance() returned on its wall-time budget (Session::behind)
    std::string refusal;  // why this joiner left on its own (settings refused, a blob refused)
    // A joiner whose connection to the master ended before the Welcome: why (Session::
    // join_failure), and whether the transport had connected it (handshake and key check done).
    std::optional<net::DisconnectReason> join_lost;
    bool master_connected = false;

    Impl(Session& session, net::Transport& t, const SessionSettings& set)
        : s(session), transport(t), messenger(t), settings(set)
    {
    }

    // --- helpers -------------------------------------------------------------------------------

    /// Copies a run of c values. Runs are a leaf's rows, mostly 8 nodes: blocks of 8 as
    /// fixed-size copies (a few vector moves) rather than a call to memmove per run.
    static void copy_run(const double* src, std::size_t c, double* dst) noexcept
    {
        for (; c >= 8; c -= 8, src += 8, dst += 8)
            std::memcpy(dst, src, 8 * sizeof(double));
        for (; c > 0; --c)
            *dst++ = *src++;
    }
    /// Calls f(offset, first, count) for each run of leaf l's nodes [lo, hi) (leaf order):
    /// nodes first .. first + count - 1 lie at padded offsets offset .. offset + count - 1.
    template <class F>
    void for_node_runs(std::size_t l, std::size_t lo, std::size_t hi, F&& f) const
    {
        for (std::uint32_t r = node_run_begin[l]; r < node_run_begin[l + 1]; ++r)
        {
            const NodeRun& run = node_runs[r];
            const std::size_t a = std::max<std::size_t>(run.first, lo);
            const std::size_t b = std::min<std::size_t>(std::size_t{run.first} + run.count, hi);
            if (a < b)
                f(run.offset + (a - run.first), a, b - a);
        }
    }
    template <class F>
    void for_node_runs(std::size_t l, F&& f) const
    {
        for (std::uint32_t r = node_run_begin[l]; r < node_run_begin[l + 1]; ++r)
            f(std::size_t{node_runs[r].offset}, std::size_t{node_runs[r].first},
              std::size_t{node_runs[r].count});
    }

    // --- session.cpp: sending, the model, the message loop and advance()
    net::Message make(net::Body body, std::uint64_t tick) const;
    void send_to(std::uint16_t id, const net::Message& m,
                 net::SendMode mode = net::SendMode::Default);
    void send_ready(std::uint16_t id);

    [[nodiscard]] bool streamed_to_us(net::PeerId id) const
    {
        const auto it = peers.find(id.value);
        return it != peers.end() && it->second.streams_to_us;
    }

    void repeat_greetings();
    [[nodiscard]] net::Hello make_hello() const;

    void send_all(const net::Message& m, net::SendMode mode = net::SendMode::Default)
    {
        for (auto& [id, p] : peers)
            send_to(id, m, mode);
    }

    void bind(net::PeerHandle h, std::uint16_t id);
    void install_model(sim::MembraneModel model);
    std::string describe_peer(std::uint16_t id) const;
    void reject(std::uint64_t& counter, std::uint16_t from, std::string_view what);
    void reject(std::uint64_t& counter, net::PeerHandle h, std::string_view what);
    /// reject()'s counting alone. \return whether the drop is to be logged (warn_rejected): a
    /// caller whose message needs formatting formats it only then, not for every drop of a
    /// flood.
    [[nodiscard]] bool count_reject(std::uint64_t& counter, std::uint16_t from);
    [[nodiscard]] bool count_reject(std::uint64_t& counter, net::PeerHandle h);
    void warn_rejected(std::uint16_t from, std::string_view what) const;
    void warn_rejected(net::PeerHandle h, std::string_view what) const;
    void handle(net::PeerHandle h, const net::Message& m);
    void poll();
    void apply_waiting_points();
    void advance(double now);

    // --- session_partitions.cpp: points of interest, partitions and the sets they give each peer
    void refresh_interest();
    const PartitionEntry* partition_at(std::uint64_t tick) const;
    const PartitionEntry* with_epoch(std::uint32_t epoch) const;
    const PartitionEntry* newest() const;

    static bool member(const PartitionEntry* p, net::PeerId id)
    {
        return p != nullptr && std::binary_search(p->members.begin(), p->members.end(), id);
    }

    void add_partition(std::uint64_t apply, std::uint32_t epoch, std::vector<net::PeerId> owners);
    std::optional<core::NodeIndex> seed_of(const std::vector<net::Target>& pts) const;
    std::vector<net::PeerId> compute_partition() const;
    void warn_idle_members(const std::vector<net::PeerId>& owners);
    void master_repartition(std::uint64_t apply);
    std::vector<char> owned_mask(const PartitionEntry* p, net::PeerId id) const;

    std::vector<char> dilate(std::vector<char> mask, int rings) const
    {
        return core::dilate_nodes(s.model_->grid(), std::move(mask), rings);
    }

    std::vector<core::Region> runs_of(const std::vector<char>& mask) const
    {
        return core::node_runs(s.model_->grid(), mask);
    }

    void refresh_exact_sets(const PartitionEntry* prev, const PartitionEntry* next);
    std::vector<HaloChunk> plan_halo(const std::vector<std::uint32_t>& nodes) const;
    void refresh_my_leaves(const PartitionEntry* p);
    void send_points();
    void on_partition(std::uint16_t from, const net::Message& m, const net::Partition& p);
    void apply_partition(std::uint64_t tick, const net::Partition& p);

    std::uint32_t newest_epoch() const
    {
        const PartitionEntry* p = newest();
        return p != nullptr ? p->epoch : 0;
    }

    // --- session_coupling.cpp: forces; exact (halos, barrier) and fast (Dirichlet) coupling
    void end_forces(std::uint16_t id, std::uint64_t tick);
    static const ForceEntry* active(const std::vector<ForceEntry>& table, std::uint64_t tick);
    /// The forces of every peer at `tick` (forces_now, rebuilt in place).
    const std::vector<sim::Force>& forces_at(std::uint64_t tick);
    /// Writes forces_now into ws unless it holds them already.
    void prepare_forces();
    void count_limited(std::span<const net::UserForce> list, std::uint16_t from, bool& warned);
    void flush_forces(std::uint64_t earliest);
    void trim(std::vector<ForceEntry>& table) const;
    void send_halos(std::uint64_t t);
    /// The members whose Heartbeat(t) this peer needs, by increasing id, into `out`.
    void barrier_set(std::uint64_t t, std::vector<std::uint16_t>& out) const;
    void publish(std::uint64_t t);
    std::vector<std::uint16_t> barrier_missing(std::uint64_t t) const;

    bool barrier_ok(std::uint64_t t) const { return barrier_missing(t).empty(); }

    void wait_at_barrier(std::uint64_t t, const std::vector<std::uint16_t>& missing);
    void apply_halos(std::uint64_t t);
    bool owns_every_node(const PartitionEntry* part, const HaloBuffer& h) const;
    void on_non_finite_step(std::uint64_t tick);

    /// After on_non_finite_step: our leaves' last finite state goes out once more, then we
    /// disconnect from everyone, as a master's leave() does. The others treat it as a departure
    /// (a participant's: the master re-partitions; the master's: failover) and take our leaves
    /// over from that state, instead of waiting for our halos for ever (exact coupling) or
    /// holding our leaves at their last streamed values with nobody stepping them (fast).
    void drop_out_diverged()
    {
        stream();
        close_all(net::DisconnectReason::Quit);
    }

    bool may_step(std::uint64_t t) const;
    void exact_advance();
    void adopt_orphans(std::uint64_t t);
    void become_member(std::uint64_t apply);
    void refresh_border(const PartitionEntry* p, const std::vector<char>& mine);
    void damp_border(double t0, double dt);
    void fast_advance();
    void on_halo(std::uint16_t from, const net::Message& m, const net::Halo& h);

    // --- session_stream.cpp: the display of own leaves and the stream of leaf states

    [[nodiscard]] bool quantised_stream() const noexcept
    {
        return settings.stream_encoding == net::ValueEncoding::QuantisedDelta;
    }

    std::size_t quantise_leaf(std::uint32_t l);
    void adopt_quantised();
    void copy_own_to_display(const PartitionEntry* p);
    void flush_display();
    void refine_display();

    /// The plan refining level n - j to n - j + 1.
    const subdiv::ConvolutionPlan& plan(int j) const
    {
        return coarse_plans[static_cast<std::size_t>(max_coarsen - j)];
    }

    void refine_plane(int top, const core::Field<double>& display,
                      std::vector<core::Field<double>>& coarse, core::Field<double>& refined);
    const PartitionEntry* stream_partition() const;
    bool extrapolate(const QuantisedLeaf& base, double time, std::size_t n);
    const QuantisedLeaf* acked_baseline(std::uint16_t peer, std::uint32_t l) const;
    bool code_leaf(net::QuantisedDelta& q, std::size_t n, const QuantisedLeaf* base);
    std::size_t batch_leaf(std::uint16_t pid, std::uint32_t epoch, std::uint64_t tick);
    void batch_values(std::uint16_t pid, const net::LeafState& m, std::uint64_t tick);
    void send_batch(std::uint16_t pid, OutBatch& b);
    void flush_batches();
    [[nodiscard]] bool shows_now(const BaselineRing& entries, const QuantisedLeaf& base,
                                 std::size_t n) const;
    bool stream_quantised(const PartitionEntry* p, std::uint32_t l);

    [[nodiscard]] bool capped() const noexcept
    {
        return quantised_stream() && settings.bandwidth_cap_mbit_s > 0.0;
    }

    void plan_capped_stream();
    void stream();

    // --- session_receive.cpp: received leaf states, acknowledgements and the smooth view
    bool rebuild_quantised(std::uint16_t from, std::uint64_t tick, double time, std::size_t l,
                           const net::QuantisedDelta& q, std::size_t n);
    void hold_quantised(std::uint16_t from, std::uint64_t tick, double time, std::size_t l,
                        const net::QuantisedDelta& q, std::size_t n);
    void send_acks();
    void send_ack(std::uint16_t to);
    void on_ack(std::uint16_t from, const net::Ack& ack);
    void on_leaf_state(std::uint16_t from, const net::Message& m, const net::LeafState& ls);
    void mark_shown(std::size_t l, std::uint32_t epoch, std::uint64_t tick, double time,
                    std::uint16_t from, int coarsen);
    void show(std::size_t l, std::size_t offset, std::size_t count, const double* u,
              const double* v);
    void set_aside(std::size_t l, std::uint16_t from, std::uint64_t tick, const net::LeafState& ls,
                   const double* u, const double* v);
    void on_leaf_batch(std::uint16_t from, const net::Message& m, const net::LeafBatch& b);
    void on_value_batch(std::uint16_t from, const net::Message& m, const net::ValueBatch& b);
    void settle_provisional_states();
    bool settle_leaf(std::uint32_t l, std::uint32_t last);
    void record_history();
    void update_view(double now);
    void materialize_view();

    // --- session_membership.cpp: connections, leaving, losses, pauses and master failover
    void finish_leave_soon();
    void close_all(net::DisconnectReason reason);
    void disconnect_finished_leavers();
    void on_connected(net::PeerHandle h);
    void close_ungreeted();
    void on_disconnected(net::PeerHandle h, net::DisconnectReason reason);
    void lose_peer(net::PeerHandle h, net::DisconnectReason reason);
    void settle_losses();
    bool dropped_after_pause(
        const std::vector<std::pair<std::uint16_t, net::DisconnectReason>>& lost);
    bool pause_witness(std::uint16_t id, const RemotePeer& p) const;
    void check_pause();
    void leave_after_pause();
    void note_pause(double now, double gap);
    std::optional<net::PeerId> successor(std::optional<net::PeerId> without = std::nullopt) const;
    void follow_master();
    void promote();

    // --- session_join.cpp: greetings, the Welcome and its blobs
    void on_hello(net::PeerHandle h, const net::Message& m, const net::Hello& hello);
    void greet_new_peer(std::uint16_t id);
    void feed_blobs();
    void send_welcome(std::uint16_t id);
    void on_welcome(net::PeerHandle h, const net::Message& m, const net::Welcome& w);
    void on_blob(const net::Blob& b);
};

}  // namespace pliant::session
