// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `Session`: one peer of a collaborative session (docs/design.md §5, docs/session.md): the master
/// (first peer, partitions), a participant (simulates its leaves, applies forces) or a viewer
/// (only watches), all driving a `net::Messenger` over any `net::Transport`.
///
/// Design
/// - Single-threaded and pumped by the caller: `poll()` handles every pending network event,
///   `advance(now)` steps the simulation up to the caller's clock and streams state. Nothing
///   blocks or sleeps, so several peers run deterministically in one thread over a
///   `SimulatedNetwork` (tests), or each in its own process over ENet (`pliant host/join`).
/// - Join: Hello -> Welcome (ids, level, epoch, time, blob sizes and hashes) -> Blob chunks of
///   the model (level, material, rest positions) and of the master's current displayed state,
///   then the current Partition; the joiner greets every listed peer (full mesh) and later peers
///   greet it. Messages to a peer whose connection is not bound yet are queued in order.
/// - `exact` coupling (lockstep, common fixed step): tick t is "published" by every member of the
///   partitions used for steps t-1 and t: forces applying from t+1 and a Partition applying from
///   t+1 (master) go first, then the halo values of tick t, then a Heartbeat(t), all on the
///   reliable channel, so a peer holding every member's Heartbeat(t) holds everything that
///   influences step t. Each peer integrates its owned nodes dilated by `halo_rings` rings
///   (through the ghost map) with the sim's restricted step; the restricted step holds the other
///   nodes fixed and the error this makes moves inwards as the stages read their neighbours, so
///   nodes deep enough inside are bit-exact (3 rings suffice, see halo_rings); the halo (u, v of
///   the dilated ring at the step start) comes from its owners every tick. One exchange per step
///   instead of one per stage (docs/session.md explains why).
/// - `fast` coupling (the paper's): no lockstep; every peer advances its owned leaves once per
///   frame with the latest streamed state of all other nodes held as Dirichlet values. A held,
///   late neighbour value makes each border edge a delayed spring, which feeds the grid's fastest
///   modes along partition borders until they diverge; so owned nodes next to held values get the
///   damping that keeps such a spring passive (sum of |edge weight| x |value age|; docs/session.md
///   §4.2).
/// - Streaming: owners send their leaves' (u, v) to every peer at `stream_rate_hz`, unsequenced;
///   every peer (viewers included) displays the whole object from its own leaves and the newest
///   state received per leaf (by partition epoch, then tick), and draws `view_u`: the same
///   displacements with the others' leaves interpolated in time at a per-sender playout clock
///   (docs/session.md §5.3).
/// - Loss and latency (§4.3): fast coupling bounds halo staleness (`max_halo_age_s`: a frame whose
///   Dirichlet values are older waits), quiescent compressed leaves are refreshed so rest is not
///   mistaken for silence, and a joiner's clock starts half a round trip after the welcome's.
/// - Compressed streaming (`stream_encoding = QuantisedDelta`, docs/protocol.md §5.5): u and v are
///   quantised to power-of-two steps; each receiver acknowledges the leaf states it holds (Ack,
///   at `ack_rate_hz`), and the owner codes each leaf against the newest state that receiver
///   acknowledged (a key state when there is none), with left-neighbour prediction where it pays,
///   Rice-packed, several leaves per LeafBatch datagram. A leaf unchanged since the receiver's
///   baseline costs nothing. Every peer, the owner included, displays the same dequantised bits. In
///   `fast` mode, where the streamed values are the neighbours' Dirichlet values, the owner also
///   adopts them where they are used: u on its border nodes is quantised after every frame
///   (interior nodes and v keep full precision, so no rounding noise is fed into the whole region).
///   In `exact` mode the stream is display-only and the integrated state is untouched (halos stay
///   f64), so lockstep and replay stay bit-exact.
/// - Coarse streaming (`stream_coarsen = k`): an owner sends each leaf's nodes at level n - k
///   only; a receiver restricts what it shows to level n - k, refines it back k levels with
///   butterfly subdivision (`subdiv::refine`) and shows the refined values on the leaves it got
///   coarse. Display only (exact mode); refused with fast coupling and with QuantisedDelta.
/// - Leaving: a participant sends Leave; the master re-partitions; in exact mode the leaver keeps
///   publishing until the tick where it owns nothing, and the others disconnect it once they are
///   past that tick (so no halo of its is lost).
/// - Loss (crash, timeout): the master re-partitions without the lost participant; its leaves
///   continue from the last state received for them (fast mode: the Dirichlet copy of the
///   displayed state; exact mode: the displayed state is loaded at the hand-over tick). A lost
///   master is replaced by the lowest remaining participant id, which every peer computes from the
///   peer list it holds (Welcome, PeerJoined, greetings, departures): the successor becomes master
///   (new epochs above any seen, joins, PeerLeft), the others accept its Partitions (kept aside if
///   they arrive before the loss is noticed) over the connections they have. A master that shuts
///   down (reason Shutdown) ends the session; one that calls leave() hands over the same way.

#include <pliant/core/field.h>
#include <pliant/core/result.h>
#include <pliant/core/tetra_grid.h>
#include <pliant/core/vec3.h>
#include <pliant/net/messenger.h>
#include <pliant/net/transport.h>
#include <pliant/session/partition.h>
#include <pliant/sim/membrane.h>
#include <pliant/sim/rkf45.h>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace pliant::session
{

/// How the peers' simulations are coupled (docs/session.md §4).
enum class Coupling : std::uint8_t
{
    Exact = 1,  ///< lockstep, common fixed step, equal to a single process to 1e-12
    Fast = 2,   ///< halos once per frame held as Dirichlet values (the paper's)
};

struct SessionSettings
{
    Coupling coupling = Coupling::Exact;  ///< master's choice; joiners take the master's
    /// What the partition's slabs must leave around the points of interest (docs/session.md
    /// §3): unset takes the coupling's rule, AsGrown in fast coupling (no border nearer a grab
    /// than its grown share puts it: fast coupling errs most next to borders) and Inside in
    /// exact coupling (the point's leaf and its neighbours in its own slab: the state does not
    /// depend on the borders). Inside in fast coupling trades accuracy near a new grab for the
    /// bands' lower step cost (measured in docs/session.md §3). The master's choice, carried in
    /// the model blob: joiners, and a master's successor, take it.
    std::optional<PointClearance> point_clearance;
    /// Master only: the largest user force [N] any peer's grab applies; a longer one acts scaled
    /// down to it, its direction kept (sim::limit_force), so that no peer, buggy or hostile, can
    /// throw the shared object arbitrarily far or overflow it. Unset: sim::default_max_force of
    /// the model (the force holding a patch of a tenth of the object's radius a diameter from
    /// rest); 0: no limit. Carried in the model blob (sim::MembraneSettings::max_force), so
    /// every peer and a replay apply the same forces; the material's own max_force is replaced.
    std::optional<double> max_force;
    double stream_rate_hz = 60.0;  ///< LeafState rate per owned leaf, > 0
    /// LeafState values: F64, F32, or QuantisedDelta (compressed, see the file comment).
    net::ValueEncoding stream_encoding = net::ValueEncoding::F64;
    /// QuantisedDelta steps: u to 2^u_step_exponent m, v to 2^v_step_exponent m/s, each in
    /// -40..0 (docs/protocol.md §5.5 explains the defaults: 2^-14 m = 61 um, 2^-10 m/s = 0.98
    /// mm/s).
    int u_step_exponent = -14;
    int v_step_exponent = -10;
    /// QuantisedDelta: how residuals are packed (docs/protocol.md §5.5, §5.6): Rice bit strings
    /// (the default since protocol version 4) or zigzag varints in a zstd frame.
    net::Packing stream_packing = net::Packing::Rice;
    /// QuantisedDelta: a peer's leaves for one receiver go out as LeafBatch datagrams (several
    /// leaves, one header, up to 1,200 bytes) instead of one LeafState per leaf; coarse leaves
    /// (stream_coarsen > 0) likewise as ValueBatch datagrams.
    bool batch_leaves = true;
    /// QuantisedDelta: how often a receiver acknowledges the leaf states it got, Hz, > 0. At the
    /// stream rate (the default) baselines are a frame or two old, which halves the residuals'
    /// bits against 20 Hz for ~3 bytes per leaf acknowledged (docs/session.md §5.1).
    double ack_rate_hz = 60.0;
    /// QuantisedDelta: LeafState and Ack bytes per second sent to each peer at most, as Mbit/s
    /// (0: no cap; datagram bytes without UDP/ENet headers). Leaves wait their turn by priority:
    /// each stream period a leaf not sent gains 1, or 1 + interest_boost if it lies near a point of
    /// interest or a force being applied, and the highest go first while the peer's budget lasts (a
    /// token bucket of two periods). In fast coupling the cap delays the neighbours' Dirichlet
    /// values and changes the motion (docs/session.md §5.1): meant for exact mode and viewers.
    double bandwidth_cap_mbit_s = 0.0;
    double interest_boost = 8.0;  ///< >= 0
    /// Coarse streaming (docs/session.md §5.2): 0 sends every node of a leaf (the default);
    /// k in 1..2 sends only the leaf's nodes at the level k below the grid's (x and y multiples
    /// of 2^k, about 4^-k of the bytes), which receivers refine back with butterfly subdivision
    /// for display. Needs level - k >= 1 and 2^(k+1) dividing the leaf side (8 cells at levels
    /// >= 3, fewer below: so k <= 2 at every level).
    /// Display only: exact-mode halos stay f64 at full resolution. Refused with fast coupling
    /// (the streamed values are the neighbours' Dirichlet values there) and with QuantisedDelta
    /// (its baselines are whole leaves). A per-sender choice; every peer refines what it gets.
    int stream_coarsen = 0;
    /// Exact mode: dilation of the integrated set, >= 3: the sim's fused RKF45 moves a boundary
    /// error one ring per two stages, so 3 rings are exact (tests/session/halo_rings_test.cpp
    /// fails if that stops holding). More rings cost compute and halo traffic for nothing with
    /// this integrator (6 would cover one whose every stage reads the previous one).
    int halo_rings = 3;
    /// Fast mode: restricted advances per second; every mode: view_u updates per second; > 0.
    double frame_rate_hz = 60.0;
    /// Fast mode: the bound on halo staleness, s (0: none). A frame steps only if every streamed
    /// state that holds a Dirichlet value next to an owned node is at most this old at the
    /// frame's end (neighbours that have not streamed to this peer yet, still connecting, are
    /// not waited for); otherwise the peer holds its clock (up to max_stall_s) and catches
    /// up, frame by frame, once fresher states arrive (docs/session.md §4.3;
    /// SessionStats::stalled_s).
    double max_halo_age_s = 0.5;
    /// Fast mode: the longest a peer holds its clock for fresher states, s (wall time, as the
    /// caller's clock). Past it, a neighbour is taken as silent (crashed or cut off, until the
    /// transport reports it lost, 5-30 s with ENet) and the peer steps on with its last values
    /// (SessionStats::stale_frames) instead of freezing.
    double max_stall_s = 1.0;
    /// A leaf whose state has not changed since the receiver acknowledged it (QuantisedDelta's
    /// quiescent leaves) is still re-sent, as an all-zero delta of a few bytes, when this long
    /// (s, simulated) has passed since it was last sent, so that receivers can tell a leaf at
    /// rest from a lost one and the halo age stays bounded (0: never, quiescent leaves cost
    /// nothing).
    double quiescent_refresh_s = 0.25;
    /// Smooth display (view_u): the leaves this peer does not compute are shown
    /// interpolated between the states received, at a playout time per sender delayed just
    /// enough to have a state on each side (docs/session.md §5.3). false: view = display.
    bool interpolate_view = true;
    /// Exact mode, master only: a member that keeps the lockstep waiting this long at one tick
    /// (its Heartbeat never comes, yet its connection stays up: a hung or hostile peer) is
    /// removed from the session as if lost, and its leaves continue from their last streamed
    /// state (docs/session.md §6), s; 0: never. Any peer warns after k_barrier_warn_s, naming
    /// the peers it waits for (SessionStats::barrier_wait_s, barrier_peer).
    double max_barrier_wait_s = 10.0;
    /// A gap of at least this between two advance() calls (s, the caller's clock) is a pause:
    /// the process was stopped (SIGSTOP, Ctrl-Z, a suspended machine, a debugger) or starved.
    /// The others drop a peer that stays silent for their transport's timeout (ENet: 5-30 s).
    /// Until a message comes from its master (the master: from a participant) after a pause,
    /// a peer that loses it (a participant) by a timeout, or whose link to it stays silent for
    /// 2 s, takes that for its own removal and leaves, saying so in refusal(), rather than
    /// take over and run a second session beside theirs (docs/session.md §6); 0: never.
    /// Below ENet's shortest timeout (5 s) by default, and above any step or frame.
    double pause_s = 4.0;
    std::string name = "peer";      ///< 1..32 printable ASCII
    std::uint16_t listen_port = 0;  ///< announced in Hello; 0: the port the master sees
    std::uint32_t session_id = 0;   ///< master only; 0 draws a random non-zero id
    std::uint64_t max_ticks = 0;    ///< stop stepping at this tick (0: never), for tests
    int threads = 1;                ///< OpenMP threads of a step
};

struct Recording;

/// Why a joiner never got into the session (Session::join_failure).
struct JoinFailure
{
    net::DisconnectReason reason = net::DisconnectReason::None;
    /// The transport had connected to the master (ENet's handshake, and with SecureTransport
    /// the key check, completed) before the connection ended.
    bool connected = false;
};

enum class SessionRole : std::uint8_t
{
    Master,
    Participant,
    Viewer,
};

/// Cumulative counters (the CLI turns them into per-second rows).
struct SessionStats
{
    std::uint64_t bytes_sent = 0;
    std::uint64_t bytes_received = 0;
    std::uint64_t packets_sent = 0;
    std::uint64_t packets_received = 0;
    std::uint64_t bad_datagrams = 0;  ///< dropped by the Messenger
    std::uint64_t steps = 0;          ///< accepted steps of this peer
    double step_seconds = 0.0;        ///< wall time spent in steps, s
    std::size_t owned_nodes = 0;
    /// Peers this one has a greeted connection to (a dialler's Hello received, or ours sent on
    /// a connection we dialled), not departed: the full mesh is every other peer.
    std::size_t peers_connected = 0;
    double halo_age_s = 0.0;  ///< oldest streamed leaf shown, relative to the own time, s
    // Leaf-state streaming (sender side counts per receiver).
    std::uint64_t leaf_states_sent = 0;  ///< LeafState datagrams sent
    std::uint64_t key_states_sent = 0;   ///< of those, quantised without a baseline
    std::uint64_t quiescent_skips = 0;   ///< (leaf, receiver) left out: unchanged since its ack
    std::uint64_t capped_skips = 0;      ///< (leaf, receiver) postponed by the bandwidth cap
    // Receiver side: quantised LeafStates dropped (never displayed, never acknowledged).
    std::uint64_t baseline_misses = 0;  ///< the baseline named is not held (lost, late join)
    std::uint64_t state_rejects = 0;    ///< wrong node count, or values leaving the int32 range
    /// Exact mode: Halo datagrams dropped because their sender did not own every node they carry
    /// at their tick (an honest peer sends only its own nodes; docs/session.md §4.1), or they
    /// were not the accepted step's u and v in f64 (stage 6; any other would be taken for it).
    std::uint64_t halo_rejects = 0;
    /// Leaf states that arrived before this joiner had the model: dropped, since the next
    /// stream period resends every leaf it has not acknowledged.
    std::uint64_t early_states_dropped = 0;
    /// Other messages that arrived before this joiner had the model beyond the 4,096 it keeps
    /// for then (an honest peer sends a few: partitions, force lists, points): dropped.
    std::uint64_t early_floods = 0;
    /// Exact mode: leaves taken over from a lost peer, started from their last streamed state.
    std::uint64_t adopted_leaves = 0;
    std::uint64_t promotions = 0;  ///< times this peer became master after the master was lost
    // Loss and latency (docs/session.md §4.3, §5.3).
    /// Fast mode: age of the oldest Dirichlet value next to an owned node at the last frame
    /// stepped, and the largest such age of any frame stepped, s (<= max_halo_age_s when set);
    /// only values of neighbours that have streamed to this peer count (docs/session.md §4.3).
    double border_age_s = 0.0;
    double max_border_age_s = 0.0;
    double stalled_s = 0.0;          ///< fast mode: time the clock was held by max_halo_age_s, s
    std::uint64_t stale_frames = 0;  ///< fast mode: frames stepped past the bound (max_stall_s)
    /// Smooth display: how far the playout time lags the newest state received, s (the largest
    /// over senders; 0 when nothing is interpolated).
    double view_delay_s = 0.0;
    std::uint64_t stale_states = 0;  ///< LeafStates older than the one shown (reordered, late)
    /// LeafStates of a partition epoch this peer does not hold: superseded long ago, or more
    /// than 32 epochs ahead of the newest partition held (dropped); or ahead, taken
    /// provisionally, and undone when their epoch never came within 3 s.
    std::uint64_t unknown_epoch_states = 0;
    /// LeafStates from a peer that does not own the leaf under the partition they name: dropped
    /// (or, taken provisionally before that partition arrived, undone then).
    std::uint64_t foreign_states = 0;
    /// User forces acting in this peer's last step (every peer's grabs; a departed peer's end:
    /// in fast coupling as each peer notices, in exact coupling at the first tick of the
    /// partition without it, on every peer alike; docs/session.md §6).
    std::size_t active_forces = 0;
    /// Forces received (in Force lists of other peers, or set here) longer than the session's
    /// max_force: they act scaled down to it (SessionSettings::max_force).
    std::uint64_t limited_forces = 0;
    /// Force lists from a viewer (which only watches): dropped, never applied or recorded.
    std::uint64_t viewer_forces = 0;
    /// Force lists from a peer that already has 256 not yet in effect here (an honest peer sends
    /// about one per frame, applying a few ticks ahead): dropped, never applied or recorded
    /// (each was kept until its tick came, and memory grew without bound).
    std::uint64_t force_floods = 0;
    /// Master: times a participant's new points of interest waited before re-partitioning,
    /// because its previous ones had done so less than 0.1 s before (docs/session.md §3).
    std::uint64_t points_waits = 0;
    /// Claims about who is in the session that did not hold: a PeerJoined from a peer other than
    /// the master (dropped: only the master admits peers), a Reject from anyone but the master
    /// of a joiner not yet welcomed (dropped: one would end the session), or a greeting Hello on
    /// a new connection for a peer id already connected or departed (refused: ids are never
    /// reused, and each peer dials each other once). docs/session.md §2.
    std::uint64_t peer_claim_rejects = 0;
    /// Incoming connections closed for sending no Hello within 10 s of connecting (an idle
    /// connection holds one of the transport's peer slots; docs/session.md §2).
    std::uint64_t ungreeted_closed = 0;
    /// Blob chunks (the Welcome's model and state) from a connection other than the master's:
    /// dropped (docs/protocol.md, Blob).
    std::uint64_t foreign_blobs = 0;
    /// The sum of the counters above that only a faulty or hostile peer makes grow
    /// (state_rejects, halo_rejects, foreign_states, peer_claim_rejects, foreign_blobs,
    /// viewer_forces, force_floods, early_floods): the --stats column `rejected`. Each peer's share
    /// is in PeerStatus, and its first such message is logged.
    [[nodiscard]] std::uint64_t rejected_messages() const noexcept
    {
        return state_rejects + halo_rejects + foreign_states + peer_claim_rejects + foreign_blobs +
               viewer_forces + force_floods + early_floods;
    }
    /// Exact mode: how long this peer has waited at its current tick for the other members'
    /// Heartbeats, s (0: not waiting), and the lowest id among those it waits for (k_no_peer:
    /// none). A peer waits a round trip or so per tick; seconds mean a member stopped stepping.
    double barrier_wait_s = 0.0;
    net::PeerId barrier_peer = net::k_no_peer;
    /// Master, exact mode: members removed for holding the lockstep longer than
    /// SessionSettings::max_barrier_wait_s.
    std::uint64_t stalled_removed = 0;
    /// Pauses of this peer (SessionSettings::pause_s: no advance() for that long) and the
    /// longest, s.
    std::uint64_t pauses = 0;
    double longest_pause_s = 0.0;
};

/// Exact mode: a peer waiting this long at one tick for a member's Heartbeat logs a warning
/// naming it, s.
inline constexpr double k_barrier_warn_s = 2.0;

/// What a peer knows of another one (Session::peer_status), for a peer list.
struct PeerStatus
{
    net::PeerId id{0};
    net::Role role = net::Role::Participant;  ///< as it announced itself (a master: participant)
    std::string name;                         ///< as it announced itself; empty until known
    bool master = false;                      ///< the peer this one follows as master
    bool connected = false;      ///< a greeted connection (SessionStats::peers_connected)
    bool has_model = false;      ///< it sent Ready: it holds the model, leaf states go to it
    bool streams_to_us = false;  ///< its leaf states have arrived here
    /// Its messages dropped here for failing a check no honest peer fails (a state or halo of
    /// nodes it does not own, forces from a viewer, ...; SessionStats::rejected_messages).
    std::uint64_t rejected = 0;
};

class Session
{
public:
    /// Starts a session as master on an opened transport, at rest or, with `start`, from a
    /// saved state (its u and v, any ghost width, of `grid`'s level; time and tick start at 0,
    /// and a recording is then refused, since a replay starts at rest). \return InvalidArgument
    /// for bad settings or material, or a `start` of another level or with a non-finite value;
    /// the model's errors (DegenerateFace, ...).
    /// In exact coupling every peer steps in lockstep with the fixed step `material.fixed_dt`
    /// (`material.fixed_step` is set and re-assembly turned off, whatever they were); fast
    /// coupling steps as the material says. Nothing here checks a fixed step against the grid's
    /// stability bound: choose it at most `sim::stable_fixed_step` of the model (`pliant host`
    /// takes min(1 ms, 0.9 x that) by default and warns above it, docs/session.md §7); a step
    /// above it grows without limit.
    static core::Result<std::unique_ptr<Session>> host(net::Transport& transport,
                                                       const core::TetraGrid& grid,
                                                       const core::Vec3Field<double>& rest,
                                                       const sim::MembraneSettings& material,
                                                       const SessionSettings& settings,
                                                       const sim::MembraneState* start = nullptr);
    /// Starts joining the master at `master` (the transport must be open). \return NetworkError
    /// if connect() fails; InvalidArgument for bad settings.
    static core::Result<std::unique_ptr<Session>> join(net::Transport& transport,
                                                       const net::Address& master, net::Role role,
                                                       const SessionSettings& settings);
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    /// Handles every pending network event (never waits).
    void poll();
    /// Steps and streams up to the caller's clock `now_s` (monotonic, s; any origin), read after
    /// the poll() before it (a stop of the process during poll() must show as a gap: pause_s).
    /// A peer behind real time steps for a bounded slice of wall time per call (2 ms in exact
    /// coupling, a frame period in fast coupling) and goes on at the next call, so that poll()
    /// keeps serving the network.
    void advance(double now_s);
    /// Whether the last advance() stopped on its slice with steps still due: the caller should
    /// poll() and advance() again at once rather than sleep.
    [[nodiscard]] bool behind() const noexcept;
    /// A caller's idle time between two rounds of poll() and advance(), at most `max_s` seconds:
    /// it ends as soon as a datagram arrives (net::Transport::wait), so a lockstep peer waiting
    /// for its neighbours' halos and heartbeats steps as soon as they are in, where a sleep
    /// made it wait out the nap every tick (docs/session.md §4.1).
    void wait(double max_s) noexcept;

    /// This peer's points of interest (participants): sent to the master, which re-partitions.
    void set_points_of_interest(std::vector<net::Target> points);
    /// This peer's user forces (replacing its previous list) from tick `from_tick` on, or from
    /// the earliest tick every peer can still honour if that is later (exact mode: the tick after
    /// the next one this peer publishes; fast mode: at once). Several calls queue in order.
    /// Checked here, at the boundary: more than net::k_max_points forces, or one that
    /// sim::validate_forces refuses (through to_sim_force: a non-finite vector or point, a
    /// negative radius, a face beyond the grid once the model is known), or any force from a
    /// viewer (it only watches, and the others drop a viewer's Force lists) is refused and
    /// nothing is queued. (Before a joiner's welcome the grid is not known: a face beyond it is
    /// then left out where the list applies, by every peer alike, `append_valid_forces`.)
    /// \return InvalidArgument naming the force and the rule.
    core::Result<void> set_forces(std::vector<net::UserForce> forces, std::uint64_t from_tick = 0);
    /// Leaves the session; `left()` becomes true when done. Participants and viewers leave as
    /// described in the file comment; the master streams its leaves once more and disconnects
    /// (reason Quit), and the others promote a successor that takes its leaves over.
    void leave();
    /// Starts recording every force list of every peer (recording.h) for deterministic replay.
    /// \return InvalidArgument unless this is the master of an exact-mode session that has not
    /// stepped yet and started at rest (a recording replays from rest).
    core::Result<void> start_recording();
    /// The inputs recorded so far, with `final_tick` = this peer's tick (final_hash unset).
    /// `Recording` is defined in <pliant/session/recording.h>: include it to use the result.
    [[nodiscard]] Recording recording() const;
    /// Ends the session (master): disconnects every peer. `left()` becomes true. Nothing if this
    /// peer has left already.
    void shutdown();

    [[nodiscard]] SessionRole role() const noexcept { return role_; }
    [[nodiscard]] net::PeerId id() const noexcept { return id_; }
    /// The peer this one follows as master (itself when master; changes on failover).
    [[nodiscard]] net::PeerId master() const noexcept;
    [[nodiscard]] Coupling coupling() const noexcept { return coupling_; }
    /// The point clearance this peer partitions with if it is (or becomes) the master: the
    /// master's SessionSettings::point_clearance (a joiner's own is not used), resolved by the
    /// coupling when unset. A joiner knows it once welcomed.
    [[nodiscard]] PointClearance point_clearance() const noexcept
    {
        return clearance_.value_or(coupling_ == Coupling::Exact ? PointClearance::Inside
                                                                : PointClearance::AsGrown);
    }
    /// The model arrived (or was given) and the peer displays the object.
    [[nodiscard]] bool ready() const noexcept { return model_ != nullptr; }
    /// Left the session (after leave()), or the session ended (the master shut it down, or it was
    /// lost and no participant remains to take over).
    [[nodiscard]] bool left() const noexcept { return left_; }
    /// The tick of the integrated state (exact mode: the lockstep tick).
    [[nodiscard]] std::uint64_t tick() const noexcept { return state_.tick; }
    /// The session's SessionSettings::max_barrier_wait_s, which this peer applies as master: the
    /// master's own; a joiner takes the master's from the Welcome (its own is not used).
    [[nodiscard]] double max_barrier_wait() const noexcept;
    /// Stepping ended on purpose: tick() reached this peer's SessionSettings::max_ticks.
    [[nodiscard]] bool at_max_ticks() const noexcept;
    /// This peer's SessionSettings::max_ticks (0: it never stops stepping on its own).
    [[nodiscard]] std::uint64_t max_ticks() const noexcept;
    [[nodiscard]] double time() const noexcept { return state_.time; }
    /// The newest session time and tick this peer shows: its own (time(), tick()) when it
    /// simulates, else (a viewer) those of the newest leaf state received.
    [[nodiscard]] double shown_time() const;
    [[nodiscard]] std::uint64_t shown_tick() const;
    /// The newest partition known (epoch 0: none).
    [[nodiscard]] std::uint32_t epoch() const noexcept;
    /// The session id every datagram of this session carries (0: a joiner not yet welcomed).
    [[nodiscard]] std::uint32_t session_id() const noexcept;
    /// Owner of every leaf under the newest partition (empty: none).
    [[nodiscard]] std::vector<net::PeerId> owners() const;
    /// Owner of every leaf under the partition state() was stepped with: in exact coupling,
    /// the leaves this peer owns there hold the session's state at tick() bit for bit (empty:
    /// none yet, or a joiner before its first halos). Fast coupling: the newest partition.
    [[nodiscard]] std::vector<net::PeerId> state_owners() const;
    [[nodiscard]] const LeafGraph* leaf_graph() const noexcept { return graph_.get(); }
    [[nodiscard]] const sim::MembraneModel* model() const noexcept { return model_.get(); }
    /// The integrated state (valid on the nodes this peer owns).
    [[nodiscard]] const sim::MembraneState& state() const noexcept { return state_; }
    /// What this peer shows: the whole object, its own leaves and the newest received ones
    /// (ghost ring 1, twins synced). Our own leaves are copied from the state when the display
    /// is read, not at every step (an exact-coupling peer steps 1,000 times a second).
    [[nodiscard]] const core::Field<double>& display_u() const noexcept;
    [[nodiscard]] const core::Field<double>& display_v() const noexcept;
    /// What to draw: display_u with the leaves this peer does not compute interpolated in
    /// time between the states received (SessionSettings::interpolate_view; equal to the display
    /// when off). Updated at most frame_rate_hz times per second: advance() sets the playout
    /// times, and the nodes are computed when the view is first read after it (a peer that
    /// draws nothing does not compute them). The display holds
    /// the newest values, which fast coupling uses as Dirichlet values; the view lags them by
    /// view_delay_s and moves smoothly.
    /// Displacements only: what is drawn is p = P + u N, so the view keeps and interpolates no
    /// velocities (display_v holds the newest received ones).
    [[nodiscard]] const core::Field<double>& view_u() const noexcept;
    /// Per leaf (LeafGraph order): the owner's simulation time of the state shown in the view,
    /// s (own leaves: this peer's time; leaves never received: 0).
    [[nodiscard]] std::span<const double> view_time() const noexcept;
    /// Ids of the other peers this one knows (connected or not yet).
    [[nodiscard]] std::vector<net::PeerId> peers() const;
    /// The same peers (not departed), by id, with their roles, names and the state of the link.
    [[nodiscard]] std::vector<PeerStatus> peer_status() const;
    [[nodiscard]] SessionStats stats() const;
    /// Why this peer left on its own when the session refused its settings, or it refused the
    /// master's model or state blob, or why it had to leave: the master removed it (exact
    /// coupling: it held the lockstep past max_barrier_wait_s), or it was paused so long that the
    /// others went on without it (SessionSettings::pause_s) (empty otherwise): a joiner
    /// learns the level and coupling
    /// only from the model (e.g. stream_coarsen in a fast session, docs/session.md §5.2), and
    /// decodes the blobs only once they are in (docs/protocol.md, Blob).
    [[nodiscard]] std::string refusal() const;
    /// The tick from which this peer's own step gave non-finite values (the state diverged: a
    /// fixed step above the stable one, or forces without a limit), after which it holds its
    /// last finite state and steps no more; nullopt while it steps normally. It then streams
    /// that state once more and leaves (`left()`): the others take its leaves over from it (a
    /// diverged master's successor takes over, docs/session.md §6). `pliant host` and `join`
    /// then end with an error.
    [[nodiscard]] std::optional<std::uint64_t> diverged() const noexcept { return diverged_tick_; }
    /// A joiner whose connection to the master ended before it was welcomed: the reason the
    /// transport gave (net::DisconnectReason::Refused: the master, or its SecureTransport,
    /// turned it away; TimedOut: no answer; ...). nullopt otherwise (still joining, welcomed, or
    /// not a joiner). `pliant join` turns it into its error message.
    [[nodiscard]] std::optional<JoinFailure> join_failure() const;

    struct Impl;

private:
    Session();
    std::unique_ptr<Impl> impl_;
    SessionRole role_ = SessionRole::Participant;
    net::PeerId id_ = net::k_no_peer;
    Coupling coupling_ = Coupling::Exact;
    std::optional<PointClearance> clearance_;     ///< the master's SessionSettings::point_clearance
    std::optional<std::uint64_t> diverged_tick_;  ///< diverged()
    bool left_ = false;
    std::unique_ptr<sim::MembraneModel> model_;
    std::unique_ptr<LeafGraph> graph_;
    sim::MembraneState state_;
    core::Field<double> display_u_;
    core::Field<double> display_v_;
    bool resumed_ = false;  ///< hosted from a saved state, not from rest
};

/// Encodes a model (level, material, rest positions) and the master's session-wide choices
/// (coupling, point clearance, unset: the coupling's rule; the barrier limit,
/// SessionSettings::max_barrier_wait_s) as the Welcome's model blob, version 4.
[[nodiscard]] std::vector<std::byte> encode_model(
    const sim::MembraneModel& model, Coupling coupling,
    std::optional<PointClearance> clearance = std::nullopt,
    double max_barrier_wait_s = SessionSettings{}.max_barrier_wait_s);

/// A decoded model blob.
struct DecodedModel
{
    sim::MembraneModel model;
    Coupling coupling = Coupling::Exact;
    std::optional<PointClearance> clearance;   ///< unset: the coupling's rule (and version 1)
    std::optional<double> max_barrier_wait_s;  ///< unset before version 4
};
/// Decodes a model blob: version 4; 3, without the barrier limit; 2, without the force limit
/// either; 1, without the clearance byte either (docs/protocol.md §6). Every field is checked:
/// the header's values, the length, finite values, a re-assembly period of at most 2^30 steps,
/// a barrier limit >= 0, and twin nodes whose rest positions equal their canonical node's, so
/// that a version-4 blob it accepts encodes back to the same bytes
/// (fuzz/fuzz_session_blobs.cpp).
/// \return InvalidArgument for a malformed blob; the model's errors (settings out of range, a
/// degenerate face).
core::Result<DecodedModel> decode_model(std::span<const std::byte> blob);

/// A session's state as the Welcome's state blob carries it: every node of u and v (twins and
/// all), the tick and the simulation time.
struct DecodedState
{
    std::uint64_t tick = 0;
    double time = 0.0;
    core::Field<double> u;
    core::Field<double> v;
};
/// Encodes the state blob of a Welcome (DecodedState's fields).
[[nodiscard]] std::vector<std::byte> encode_state(const core::TetraGrid& grid,
                                                  const core::Field<double>& u,
                                                  const core::Field<double>& v, std::uint64_t tick,
                                                  double time);
/// Decodes a state blob for `grid`. \return InvalidArgument for a wrong length or a non-finite
/// value (a time, a displacement or a velocity); what it accepts encodes back to the same
/// bytes.
core::Result<DecodedState> decode_state(const core::TetraGrid& grid,
                                        std::span<const std::byte> blob);

/// The sim force of a wire force (face or point + radius).
[[nodiscard]] sim::Force to_sim_force(const net::UserForce& force);
/// Appends to `out` the sim forces of `forces` that `model` accepts (sim::validate_forces: a face
/// on the grid, finite vector and point, radius >= 0) and leaves out the others. Every peer and
/// the replay apply it to the same lists, so they leave out the same forces, and one bad force
/// (a face beyond this grid in someone's script) does not cancel everyone's grabs.
/// \return how many were left out.
std::size_t append_valid_forces(const sim::MembraneModel& model,
                                std::span<const net::UserForce> forces,
                                std::vector<sim::Force>& out);

}  // namespace pliant::session
