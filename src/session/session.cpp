// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The Session peer (include/pliant/session/session.h has the design; docs/session.md the story).
#include <pliant/core/assert.h>
#include <pliant/core/hash.h>
#include <pliant/net/codec.h>
#include <pliant/net/quantised.h>
#include <pliant/session/recording.h>
#include <pliant/session/session.h>
#include <pliant/subdiv/convolution_plan.h>
#include <pliant/subdiv/refine.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

namespace
{

constexpr std::uint32_t k_model_magic = 0x4D534C50;  // "PLSM"
/// Version 2 adds the point clearance byte after the coupling; version 3 the force limit after
/// the step settings; version 4 the session's barrier limit after it. Older blobs (recordings
/// made before them) still decode: version 1 with the coupling's rule, versions 1 and 2 with
/// no force limit (as they were made), versions 1 to 3 with no barrier limit (a joiner keeps
/// its own).
constexpr std::uint8_t k_model_version = 4;
constexpr double k_leave_timeout_s = 5.0;
/// The most wall time one advance() call spends stepping in exact coupling before it returns to
/// let the caller poll() (s). ENet moves at most its window (64 KiB) of reliable data per
/// service, so a master behind real time that served the network once per frame period (16.7
/// ms) sent a level-8 model of 3 MB at about 4 MB/s; ticks of a level-8 lockstep take ~1.4 ms.
constexpr double k_step_slice_s = 0.002;
/// The greetings go reliably, and are repeated unreliably once per stream period for at most this
/// long (s): Ready until the peer's first leaf state arrives, a dialler's Hello until anything
/// arrives from the peer. The stream to a joiner starts on its Ready, and a peer knows a dialler
/// only from its Hello; a lost reliable datagram waits for a retransmission timeout, which on a
/// young ENet connection (500 ms initial round-trip estimate, doubling) is a second or more, and
/// ENet drops what a dialler sends before the acceptor's side of the handshake completes (its
/// acknowledgement lost). Meanwhile a fast-coupled neighbour held its clock waiting for the
/// joiner's border states, and the others waited on it; a viewer saw the joiner's leaves frozen.
constexpr double k_greeting_repeat_s = 5.0;
/// Quantised streaming: an owner codes against a baseline only among its last 16 states sent of
/// a leaf, and a receiver holds its last 16 received, so an acknowledged baseline the owner still
/// has is one the receiver still holds (docs/protocol.md §5.5).
constexpr std::size_t k_baseline_window = 16;
/// Smooth display: states kept per leaf for interpolation (docs/session.md §5.3).
constexpr int k_view_history = 4;
/// Smooth display: the playout time lags the newest state by k_view_periods stream periods
/// beyond the smallest lead seen; that lead recovers at k_view_leak (s per s) after a late state;
/// the playout clock slews towards its target at up to k_view_slew of real time and jumps beyond
/// k_view_snap_s, but never backwards.
constexpr double k_view_periods = 2.0;
constexpr double k_view_leak = 0.05;
constexpr double k_view_slew = 0.5;
constexpr double k_view_snap_s = 0.25;
/// Failover: a successor's first epoch is this far above the newest it knows, so a Partition the
/// lost master sent to only some peers just before it went cannot share an epoch with the
/// successor's (docs/session.md §6).
constexpr std::uint32_t k_successor_epoch_gap = 16;
/// Likewise its first peer id is this far above the highest it knows: a joiner the lost master
/// welcomed just before it went, whose greeting has not reached the successor, holds an id just
/// above it, which the successor must not give to another joiner.
constexpr std::uint16_t k_successor_id_gap = 16;
/// Partitions kept aside per peer that is not (yet) our master (failover, docs/session.md §6).
constexpr std::size_t k_max_foreign_partitions = 8;
/// How far a leaf state's epoch may run ahead of the newest partition held: a successor's gap
/// and a few re-partitions in flight; further is no epoch any master will issue soon.
constexpr std::uint32_t k_max_epoch_lead = 2 * k_successor_epoch_gap;
/// How long a leaf state of an epoch ahead of the partitions held counts without its Partition.
constexpr double k_provisional_s = 3.0;
/// How long an incoming connection may stay without greeting (a Hello) before it is closed: a
/// joiner or a dialling member greets at once, and an idle connection would otherwise hold one
/// of the transport's peer slots for as long as its other end keeps it alive (an audit filled
/// all 64 that way and every later joiner was turned away).
constexpr double k_greeting_deadline_s = 10.0;
/// After a pause (SessionSettings::pause_s), a peer that has heard no message from its master
/// (the master: from any participant) since, and whose transport has heard nothing at all on
/// that link for this long (s; a live ENet answers a ping every 0.5 s), takes itself for
/// dropped without waiting for its own timeout, which needs its retransmissions after the
/// pause to run out and takes seconds more.
constexpr double k_pause_silence_s = 2.0;
/// A pause stops counting against the losses that follow after this long (s): ENet's longest
/// timeout (30 s) and a margin.
constexpr double k_pause_suspect_s = 35.0;
/// Master: the Welcome's blob chunks go to a joiner while the transport holds less than this
/// for it (queued or unacknowledged), so a joiner that reads slowly, or never, holds at most
/// this much of the master's memory, not the whole model and state (docs/session.md §2).
constexpr std::size_t k_feed_window_bytes = 256 * 1024;
/// A participant's new points of interest re-partition the session at most this often (s, the
/// master's clock); a change within it waits for its end. Each change cost the master a partition
/// computed and broadcast (and every peer a hand-over), so a peer changing its points on every
/// frame, by a bug or on purpose, kept the whole session re-partitioning. A participant's first
/// points (its admission to the partition) go at once.
constexpr double k_points_interval_s = 0.1;

// --- little-endian byte writer/reader for the blobs -------------------------------------------

struct Writer
{
    std::vector<std::byte> out;
    void u8(std::uint8_t v) { out.push_back(static_cast<std::byte>(v)); }
    void u32(std::uint32_t v)
    {
        for (int k = 0; k < 4; ++k)
            u8(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void u64(std::uint64_t v)
    {
        for (int k = 0; k < 8; ++k)
            u8(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
};

struct Reader
{
    std::span<const std::byte> in;
    std::size_t pos = 0;
    bool ok = true;
    std::uint8_t u8()
    {
        if (pos >= in.size())
        {
            ok = false;
            return 0;
        }
        return static_cast<std::uint8_t>(in[pos++]);
    }
    std::uint32_t u32()
    {
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k)
            v |= static_cast<std::uint32_t>(u8()) << (8 * k);
        return v;
    }
    std::uint64_t u64()
    {
        std::uint64_t v = 0;
        for (int k = 0; k < 8; ++k)
            v |= static_cast<std::uint64_t>(u8()) << (8 * k);
        return v;
    }
    double f64()
    {
        const double v = std::bit_cast<double>(u64());
        if (!std::isfinite(v))
            ok = false;
        return v;
    }
};

/// Coarse streaming: the largest k a grid allows with leaves of side `w >> depth`: level - k >= 1,
/// k <= net::k_max_leaf_coarsen, and 2^(k+1) divides the side, so a leaf maps to whole coarse
/// nodes and holds at least two rows of them. One row is not enough: a leaf of the bottom row
/// whose only coarse row is y = 0 right of b (W, 0) would hold only twins of the left half
/// (docs/design.md §1), i.e. no canonical coarse node at all, and could not be sent. Leaves of side
/// 8 (levels >= 3) allow k <= 2.
int max_coarsen_for(const core::TetraGrid& g, int depth)
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

double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The clearance byte of a version-2 model blob: 0 the coupling's rule, 1 AsGrown, 2 Inside.
std::uint8_t clearance_byte(std::optional<PointClearance> c)
{
    if (!c)
        return 0;
    return *c == PointClearance::AsGrown ? 1 : 2;
}

}  // namespace

std::vector<std::byte> encode_model(const sim::MembraneModel& model, Coupling coupling,
                                    std::optional<PointClearance> clearance,
                                    double max_barrier_wait_s)
{
    const core::TetraGrid& g = model.grid();
    const sim::MembraneSettings& s = model.settings();
    Writer w;
    w.u32(k_model_magic);
    w.u8(k_model_version);
    w.u8(static_cast<std::uint8_t>(g.level()));
    w.u8(static_cast<std::uint8_t>(coupling));
    w.u8(clearance_byte(clearance));
    w.u8(s.fixed_step ? 1 : 0);
    w.u32(static_cast<std::uint32_t>(std::max(0, s.reassemble_every)));
    for (const double v :
         {s.T, s.rho, s.beta, s.k_f, s.rtol, s.atol, s.dt_min, s.dt_max, s.dt_initial, s.safety,
          s.max_growth, s.min_shrink, s.fixed_dt, s.max_force, max_barrier_wait_s})
        w.f64(v);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            for (int c = 0; c < 3; ++c)
                w.f64(model.rest_positions()[static_cast<std::size_t>(c)].at(x, y));
    return std::move(w.out);
}

core::Result<DecodedModel> decode_model(std::span<const std::byte> blob)
{
    const auto refuse = [](const std::string& why)
    { return core::fail(core::ErrorCode::InvalidArgument, "model blob: " + why); };
    Reader r{blob};
    const std::uint32_t magic = r.u32();
    const std::uint8_t version = r.u8();
    if (!r.ok)
        return refuse(std::to_string(blob.size()) + " bytes, shorter than its header");
    if (magic != k_model_magic)
        return refuse("it does not begin with PLSM");
    if (version < 1 || version > k_model_version)
        return refuse("version " + std::to_string(version) + ", this build reads 1 to " +
                      std::to_string(k_model_version));
    const int level = r.u8();
    const std::uint8_t coupling = r.u8();
    const std::uint8_t clearance = version >= 2 ? r.u8() : 0;
    const std::uint8_t fixed = r.u8();
    if (!r.ok)
        return refuse(std::to_string(blob.size()) + " bytes, shorter than its header");
    if (level < core::k_min_level || level > core::k_max_level)
        return refuse("grid level " + std::to_string(level) + ", pliant's grids are of levels " +
                      std::to_string(core::k_min_level) + " to " +
                      std::to_string(core::k_max_level));
    if (coupling < 1 || coupling > 2)
        return refuse("coupling " + std::to_string(coupling) + ", 1 (exact) or 2 (fast)");
    if (clearance > 2)
        return refuse("point clearance " + std::to_string(clearance) +
                      ", 0 (the coupling's rule), 1 (grown) or 2 (inside)");
    if (fixed > 1)
        return refuse("fixed-step flag " + std::to_string(fixed) + ", 0 or 1");
    const core::TetraGrid g = core::TetraGrid::create(level).value();
    const std::size_t settings_count = version >= 4 ? 15 : version >= 3 ? 14 : 13;
    const std::size_t expect = (version >= 2 ? 13 : 12) + settings_count * 8 + g.node_count() * 24;
    if (blob.size() != expect)
        return refuse(std::to_string(blob.size()) + " bytes; a version-" + std::to_string(version) +
                      " model of level " + std::to_string(level) + " takes " +
                      std::to_string(expect));
    sim::MembraneSettings s;
    s.fixed_step = fixed == 1;
    const std::uint32_t reassemble = r.u32();
    if (reassemble > (1u << 30))
        return refuse("re-assembly every " + std::to_string(reassemble) + " steps, at most 2^30");
    s.reassemble_every = static_cast<int>(reassemble);
    const std::pair<const char*, double*> settings[] = {{"tension T", &s.T},
                                                        {"density rho", &s.rho},
                                                        {"damping beta", &s.beta},
                                                        {"foundation k_f", &s.k_f},
                                                        {"rtol", &s.rtol},
                                                        {"atol", &s.atol},
                                                        {"dt_min", &s.dt_min},
                                                        {"dt_max", &s.dt_max},
                                                        {"dt_initial", &s.dt_initial},
                                                        {"safety", &s.safety},
                                                        {"max_growth", &s.max_growth},
                                                        {"min_shrink", &s.min_shrink},
                                                        {"fixed_dt", &s.fixed_dt}};
    for (const auto& [name, value] : settings)
    {
        *value = r.f64();
        if (!r.ok)
            return refuse(std::string("setting ") + name + " is not finite");
    }
    if (version >= 3)
    {
        s.max_force = r.f64();
        if (!r.ok)
            return refuse("setting max_force is not finite");
    }
    std::optional<double> barrier;
    if (version >= 4)
    {
        barrier = r.f64();
        if (!r.ok)
            return refuse("setting max_barrier_wait_s is not finite");
        if (*barrier < 0.0)
            return refuse("max_barrier_wait_s " + std::to_string(*barrier) +
                          ", which must be >= 0 s (0: never)");
    }
    core::Vec3Field<double> rest{core::Field<double>(g), core::Field<double>(g),
                                 core::Field<double>(g)};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            for (int c = 0; c < 3; ++c)
            {
                rest[static_cast<std::size_t>(c)].at(x, y) = r.f64();
                if (!r.ok)
                    return refuse("the rest position of node (" + std::to_string(x) + "," +
                                  std::to_string(y) + ") is not finite");
            }
    for (const core::TwinPair& t : g.twins())
        for (const core::Field<double>& plane : rest)
            if (plane[t.twin] != plane[t.canonical] ||
                std::signbit(plane[t.twin]) != std::signbit(plane[t.canonical]))
            {
                const core::GridCoord a = g.coord(t.twin);
                return core::fail(core::ErrorCode::InvalidArgument,
                                  "model blob: twin node (" + std::to_string(a.x) + "," +
                                      std::to_string(a.y) +
                                      ") has another rest position than its canonical node");
            }
    auto model = sim::MembraneModel::create(g, rest, s);
    if (!model)
        return core::fail(model.error().code, "model blob: " + model.error().message);
    std::optional<PointClearance> clear;
    if (clearance != 0)
        clear = clearance == 1 ? PointClearance::AsGrown : PointClearance::Inside;
    return DecodedModel{std::move(model).value(), static_cast<Coupling>(coupling), clear, barrier};
}

std::vector<std::byte> encode_state(const core::TetraGrid& grid, const core::Field<double>& u,
                                    const core::Field<double>& v, std::uint64_t tick, double time)
{
    Writer w;
    w.u64(tick);
    w.f64(time);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            w.f64(u.at(x, y));
            w.f64(v.at(x, y));
        }
    return std::move(w.out);
}

core::Result<DecodedState> decode_state(const core::TetraGrid& grid,
                                        std::span<const std::byte> blob)
{
    if (blob.size() != 16 + grid.node_count() * 16)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "state blob: " + std::to_string(blob.size()) + " bytes, level " +
                              std::to_string(grid.level()) + " needs " +
                              std::to_string(16 + grid.node_count() * 16));
    Reader r{blob};
    DecodedState out{r.u64(), r.f64(), core::Field<double>(grid), core::Field<double>(grid)};
    for (int y = 0; y < grid.ny() && r.ok; ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            out.u.at(x, y) = r.f64();
            out.v.at(x, y) = r.f64();
        }
    if (!r.ok)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "state blob: a non-finite value near byte " + std::to_string(r.pos));
    return out;
}

sim::Force to_sim_force(const net::UserForce& f)
{
    sim::Force out;
    if (f.target.kind == net::TargetKind::Face)
        out.face = static_cast<std::int64_t>(f.target.face);
    else
    {
        out.face = -1;
        out.point = {f.target.position[0], f.target.position[1], f.target.position[2]};
        out.radius = f.target.radius;
    }
    out.vector = {f.force[0], f.force[1], f.force[2]};
    return out;
}

std::size_t append_valid_forces(const sim::MembraneModel& model,
                                std::span<const net::UserForce> forces,
                                std::vector<sim::Force>& out)
{
    std::size_t dropped = 0;
    for (const net::UserForce& f : forces)
    {
        const sim::Force force = to_sim_force(f);
        if (sim::validate_forces(model, std::span(&force, 1)))
            out.push_back(force);
        else
            ++dropped;
    }
    return dropped;
}

namespace
{

/// The settings' own ranges: host and join refuse others with InvalidArgument, naming the
/// setting, its value and the rule.
core::Result<void> check_settings(const SessionSettings& s, const char* who)
{
    const auto bad = [who](const std::string& what)
    { return core::fail(core::ErrorCode::InvalidArgument, std::string(who) + ": " + what); };
    const auto num = [](double x)
    {
        char text[32];
        std::snprintf(text, sizeof text, "%g", x);
        return std::string(text);
    };
    if (!net::is_valid_name(s.name))
        return bad("the peer name '" + s.name + "' must be 1 to " +
                   std::to_string(net::k_max_name_length) +
                   " characters of printable ASCII (space to '~'), it has " +
                   std::to_string(s.name.size()) + " bytes");
    if (!(s.stream_rate_hz > 0.0) || !(s.frame_rate_hz > 0.0) || !(s.ack_rate_hz > 0.0))
        return bad("stream, frame and ack rates must be > 0 Hz (stream " + num(s.stream_rate_hz) +
                   ", frame " + num(s.frame_rate_hz) + ", ack " + num(s.ack_rate_hz) + ")");
    for (const int e : {s.u_step_exponent, s.v_step_exponent})
        if (e < net::k_min_step_exponent || e > net::k_max_step_exponent)
            return bad("quantisation step exponents must lie in " +
                       std::to_string(net::k_min_step_exponent) + ".." +
                       std::to_string(net::k_max_step_exponent) + " (u " +
                       std::to_string(s.u_step_exponent) + ", v " +
                       std::to_string(s.v_step_exponent) + ")");
    if (!(s.bandwidth_cap_mbit_s >= 0.0))
        return bad("the bandwidth cap must be >= 0 Mbit/s (0: none), not " +
                   num(s.bandwidth_cap_mbit_s));
    if (!(s.interest_boost >= 0.0))
        return bad("the interest boost must be >= 0, not " + num(s.interest_boost));
    for (const double t :
         {s.max_halo_age_s, s.max_stall_s, s.quiescent_refresh_s, s.max_barrier_wait_s, s.pause_s})
        if (!(t >= 0.0) || !std::isfinite(t))
            return bad(
                "halo age, stall, quiescent refresh, barrier wait and pause limits must be finite "
                "and >= 0 s (max_halo_age_s " +
                num(s.max_halo_age_s) + ", max_stall_s " + num(s.max_stall_s) +
                ", quiescent_refresh_s " + num(s.quiescent_refresh_s) + ", max_barrier_wait_s " +
                num(s.max_barrier_wait_s) + ", pause_s " + num(s.pause_s) + ")");
    if (s.halo_rings < 3)
        return bad("exact coupling needs at least 3 halo rings, not " +
                   std::to_string(s.halo_rings));
    if (s.max_force && (!(*s.max_force >= 0.0) || !std::isfinite(*s.max_force)))
        return bad("the force limit must be finite and >= 0 N (0: no limit), not " +
                   num(*s.max_force));
    return {};
}

/// The grid-independent rules of coarse streaming (docs/session.md §5.2).
core::Result<void> check_coarsen(const SessionSettings& settings, const char* who)
{
    const int k = settings.stream_coarsen;
    if (k < 0 || k > net::k_max_leaf_coarsen)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string(who) + ": stream_coarsen is " + std::to_string(k) +
                              ", expected 0 (off) to " +
                              std::to_string(int{net::k_max_leaf_coarsen}) + " levels");
    if (k != 0 && settings.stream_encoding == net::ValueEncoding::QuantisedDelta)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string(who) +
                              ": coarse streaming (stream_coarsen) cannot be combined with the "
                              "quantised-delta encoding (its baselines are whole leaves); use "
                              "one or the other");
    return {};
}

/// The rules that need the grid and the coupling (the host checks them at once, a joiner when
/// the model arrives).
core::Result<void> check_coarsen(const SessionSettings& settings, const core::TetraGrid& grid,
                                 int depth, Coupling coupling, const char* who)
{
    const int k = settings.stream_coarsen;
    if (k == 0)
        return {};
    if (coupling == Coupling::Fast)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string(who) +
                              ": coarse streaming (stream_coarsen) is refused in fast coupling, "
                              "where the streamed values are the neighbours' Dirichlet values; "
                              "use exact coupling or stream_coarsen 0");
    const int most = max_coarsen_for(grid, depth);
    if (k > most)
        return core::fail(core::ErrorCode::InvalidArgument,
                          std::string(who) + ": stream_coarsen " + std::to_string(k) +
                              " is too coarse for level " + std::to_string(grid.level()) +
                              " (at most " + std::to_string(most) +
                              ": the coarse level must be >= 1 and a leaf side of " +
                              std::to_string(grid.w() >> depth) +
                              " cells a multiple of 2^(k+1), so that every leaf keeps canonical "
                              "coarse nodes)");
    return {};
}

}  // namespace

// --- Impl ------------------------------------------------------------------------------------

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
    net::PeerStats closed_stats;

    // Blobs being received (joiner).
    net::Welcome welcome;
    std::uint64_t welcome_tick = 0;
    std::vector<std::byte> model_blob, state_blob;
    std::size_t model_got = 0, state_got = 0;

    // Simulation.
    std::unique_ptr<sim::Rkf45Workspace> ws;
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
    std::vector<std::deque<QuantisedLeaf>> sent;  // per leaf: our last states sent, newest last
    std::vector<std::deque<QuantisedLeaf>> held;  // per leaf: last states received, newest last
    std::map<std::uint16_t, std::vector<std::uint64_t>> acked;  // peer -> per leaf: tick + 1
    std::map<std::uint16_t, std::map<std::uint32_t, std::uint64_t>> pending_acks;  // to send
    double next_ack = 0.0;
    // Bandwidth cap (settings.bandwidth_cap_mbit_s): per peer, a byte budget and leaf priorities.
    std::map<std::uint16_t, double> budget;
    std::map<std::uint16_t, std::vector<double>> priority;
    // Batched streaming (settings.batch_leaves): per peer, the LeafBatch (quantised leaves) or
    // ValueBatch (coarse leaves) being filled this period.
    std::map<std::uint16_t, net::Message> batch;
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

    Impl(Session& session, net::Transport& t, const SessionSettings& set)
        : s(session), transport(t), messenger(t), settings(set)
    {
    }

    // --- sending -------------------------------------------------------------------------------

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

    net::Message make(net::Body body, std::uint64_t tick) const
    {
        net::Message m;
        m.header.session = session_id;
        m.header.sender = s.id_;
        m.header.tick = tick;
        m.body = std::move(body);
        return m;
    }

    void send_to(std::uint16_t id, const net::Message& m,
                 net::SendMode mode = net::SendMode::Default)
    {
        auto it = peers.find(id);
        if (it == peers.end() || it->second.departed)
            return;
        RemotePeer& p = it->second;
        if (!p.handle || p.feed)
        {
            if (net::sent_reliably(m.type(), mode))
                (p.handle ? p.after_feed : p.queued).emplace_back(m, mode);
            return;
        }
        auto r = messenger.send(*p.handle, m, mode);
        if (!r)
            spdlog::debug("session: send to {} failed: {}", id, r.error().message);
    }

    /// Tells peer `id` that we hold the model: reliably, and unreliably every stream period until
    /// it streams to us (k_greeting_repeat_s, repeat_greetings).
    void send_ready(std::uint16_t id)
    {
        send_to(id, make(net::Ready{}, s.state_.tick));
        auto it = peers.find(id);
        if (it != peers.end() && !it->second.streams_to_us)
            it->second.ready_repeat_until = last_now + k_greeting_repeat_s;
    }

    [[nodiscard]] bool streamed_to_us(net::PeerId id) const
    {
        const auto it = peers.find(id.value);
        return it != peers.end() && it->second.streams_to_us;
    }

    /// The unreliable repeats of our greetings (k_greeting_repeat_s): Ready, and Hello to the
    /// peers we dialled.
    void repeat_greetings()
    {
        for (auto& [id, p] : peers)
        {
            if (!p.handle || p.departed)
                continue;
            if (p.hello_repeat_until > last_now && !p.heard)
                send_to(id, make(make_hello(), s.state_.tick), net::SendMode::Unsequenced);
            if (p.ready_repeat_until > last_now && !p.streams_to_us)
                send_to(id, make(net::Ready{}, s.state_.tick), net::SendMode::Unsequenced);
        }
    }

    [[nodiscard]] net::Hello make_hello() const
    {
        net::Hello hello;
        hello.role = s.role_ == SessionRole::Viewer ? net::Role::Viewer : net::Role::Participant;
        hello.listen_port = settings.listen_port;
        hello.name = settings.name;
        return hello;
    }

    void send_all(const net::Message& m, net::SendMode mode = net::SendMode::Default)
    {
        for (auto& [id, p] : peers)
            send_to(id, m, mode);
    }

    void bind(net::PeerHandle h, std::uint16_t id)
    {
        messenger.bind(h, net::PeerId{id});
        handle_ids[h] = id;
        RemotePeer& p = peers[id];
        p.handle = h;
        auto queued = std::move(p.queued);
        p.queued.clear();
        for (auto& [m, mode] : queued)
            (void)messenger.send(h, m, mode);
    }

    // --- model and partitions ------------------------------------------------------------------

    void install_model(sim::MembraneModel model)
    {
        s.model_ = std::make_unique<sim::MembraneModel>(std::move(model));
        const core::TetraGrid& g = s.model_->grid();
        s.graph_ = std::make_unique<LeafGraph>(g, leaf_depth_for(g, net::ValueEncoding::F64));
        ws = std::make_unique<sim::Rkf45Workspace>(*s.model_, settings.threads);
        s.state_ = sim::MembraneState::at_rest(g);
        s.display_u_ = core::Field<double>(g, 1);
        s.display_v_ = core::Field<double>(g, 1);
        pad.resize(g.node_count());
        for (std::size_t n = 0; n < pad.size(); ++n)
        {
            const core::GridCoord c = g.coord(core::NodeIndex{static_cast<std::uint32_t>(n)});
            pad[n] = static_cast<std::uint32_t>(s.display_u_.padded_offset(c.x, c.y));
        }
        node_runs.clear();
        node_run_begin.assign(1, 0);
        for (std::size_t l = 0; l < s.graph_->size(); ++l)
        {
            const auto nodes = s.graph_->nodes(l);
            for (std::size_t k = 0; k < nodes.size(); ++k)
            {
                const std::uint32_t o = pad[nodes[k].value];
                if (k > 0 && node_runs.back().offset + node_runs.back().count == o)
                    ++node_runs.back().count;
                else
                    node_runs.push_back({static_cast<std::uint32_t>(k), o, 1});
            }
            node_run_begin.push_back(static_cast<std::uint32_t>(node_runs.size()));
        }
        leaf_epoch.assign(s.graph_->size(), 0);
        leaf_tick.assign(s.graph_->size(), 0);
        leaf_time.assign(s.graph_->size(), 0.0);
        leaf_sender.assign(s.graph_->size(), 0);
        aside.assign(s.graph_->size(), {});
        provisional_leaves.clear();
        provisional_listed.assign(s.graph_->size(), 0);
        leaf_sent_time.assign(s.graph_->size(), -std::numeric_limits<double>::infinity());
        history.assign(s.graph_->size(), {});
        updated_flag.assign(s.graph_->size(), 0);
        view_u = core::Field<double>(g, 1);
        view_time.assign(s.graph_->size(), 0.0);
        leaf_coarsen.assign(s.graph_->size(), 0);
        leaf_mine.assign(s.graph_->size(), 0);
        max_coarsen = max_coarsen_for(g, s.graph_->depth());
        sent.assign(s.graph_->size(), {});
        held.assign(s.graph_->size(), {});
        std::size_t most = 0;
        for (std::size_t l = 0; l < s.graph_->size(); ++l)
            most = std::max(most, s.graph_->node_count(l));
        for (auto* v : {&xu, &xv, &xp})
            v->assign(most, 0.0);
        for (auto* v : {&qu, &qv, &ru, &rv, &pu})
            v->assign(most, 0);
        leaf_centre.assign(s.graph_->size(), core::Vec3{});
        leaf_radius.assign(s.graph_->size(), 0.0);
        near_interest.assign(s.graph_->size(), 0);
        const auto& P = s.model_->rest_positions();
        for (std::size_t l = 0; l < s.graph_->size(); ++l)
        {
            core::Vec3 c{};
            const auto nodes = s.graph_->nodes(l);
            for (const core::NodeIndex n : nodes)
            {
                const core::GridCoord gc = g.coord(n);
                c = c + core::Vec3{P[0].at(gc.x, gc.y), P[1].at(gc.x, gc.y), P[2].at(gc.x, gc.y)};
            }
            c = c * (1.0 / static_cast<double>(std::max<std::size_t>(nodes.size(), 1)));
            double r = 0.0;
            for (const core::NodeIndex n : nodes)
            {
                const core::GridCoord gc = g.coord(n);
                const core::Vec3 p{P[0].at(gc.x, gc.y), P[1].at(gc.x, gc.y), P[2].at(gc.x, gc.y)};
                r = std::max(r, norm(p - c));
            }
            leaf_centre[l] = c;
            leaf_radius[l] = r;
        }
    }

    /// Marks the leaves within a leaf diameter of a point of interest or of an applied force.
    void refresh_interest()
    {
        std::vector<std::pair<core::Vec3, double>> spots;  // position, radius
        const core::TetraGrid& g = s.model_->grid();
        const auto& P = s.model_->rest_positions();
        auto add = [&](const net::Target& t)
        {
            if (t.kind == net::TargetKind::Position)
            {
                spots.emplace_back(core::Vec3{t.position[0], t.position[1], t.position[2]},
                                   t.radius);
                return;
            }
            if (const auto n = seed_of({t}))
            {
                const core::GridCoord c = g.coord(*n);
                spots.emplace_back(
                    core::Vec3{P[0].at(c.x, c.y), P[1].at(c.x, c.y), P[2].at(c.x, c.y)}, t.radius);
            }
        };
        for (const net::Target& t : my_points)
            add(t);
        if (const ForceEntry* e = active(my_forces, s.state_.tick))
            for (const net::UserForce& f : e->forces)
                add(f.target);
        for (const auto& [id, p] : peers)
        {
            for (const net::Target& t : p.points)
                add(t);
            if (const ForceEntry* e = active(p.forces, s.state_.tick))
                for (const net::UserForce& f : e->forces)
                    add(f.target);
        }
        for (std::size_t l = 0; l < near_interest.size(); ++l)
        {
            near_interest[l] = 0;
            for (const auto& [pos, radius] : spots)
                if (norm(pos - leaf_centre[l]) <= radius + 2.0 * leaf_radius[l])
                    near_interest[l] = 1;
        }
    }

    [[nodiscard]] bool quantised_stream() const noexcept
    {
        return settings.stream_encoding == net::ValueEncoding::QuantisedDelta;
    }

    const PartitionEntry* partition_at(std::uint64_t tick) const
    {
        const PartitionEntry* best = nullptr;
        for (const PartitionEntry& p : partitions)
            if (p.apply_tick <= tick && (best == nullptr || p.epoch > best->epoch))
                best = &p;
        return best;
    }
    const PartitionEntry* with_epoch(std::uint32_t epoch) const
    {
        for (const PartitionEntry& p : partitions)
            if (p.epoch == epoch)
                return &p;
        return nullptr;
    }
    const PartitionEntry* newest() const
    {
        const PartitionEntry* best = nullptr;
        for (const PartitionEntry& p : partitions)
            if (best == nullptr || p.epoch > best->epoch)
                best = &p;
        return best;
    }
    static bool member(const PartitionEntry* p, net::PeerId id)
    {
        return p != nullptr && std::binary_search(p->members.begin(), p->members.end(), id);
    }

    void add_partition(std::uint64_t apply, std::uint32_t epoch, std::vector<net::PeerId> owners)
    {
        for (const PartitionEntry& p : partitions)
            if (p.epoch == epoch)
                return;
        PartitionEntry e{apply, epoch, std::move(owners), {}};
        e.members = e.owners;
        std::sort(e.members.begin(), e.members.end());
        e.members.erase(std::unique(e.members.begin(), e.members.end()), e.members.end());
        // Only where every participant present gets a share (fewer members than leaves): with
        // more participants than leaves one may lose its share and still be here.
        if (s.coupling_ == Coupling::Exact && apply > 0 && e.members.size() < e.owners.size())
            if (const PartitionEntry* before = partition_at(apply - 1))
                for (const net::PeerId id : before->members)
                    if (id != s.id_ && !member(&e, id))
                        end_forces(id.value, apply);
        partitions.push_back(std::move(e));
        // Keep the table short: drop entries superseded before the oldest tick still needed.
        const std::uint64_t keep = s.state_.tick > 2 ? s.state_.tick - 2 : 0;
        const PartitionEntry* base = partition_at(keep);
        if (base != nullptr)
        {
            const std::uint32_t base_epoch = base->epoch;
            std::erase_if(partitions,
                          [&](const PartitionEntry& p) { return p.epoch < base_epoch; });
        }
    }

    /// Exact coupling: peer `id` is not a member of the partition that applies from `tick`,
    /// though it was of the one before: its forces end at `tick` (a recording master logs an
    /// empty list for it there, so that the replay ends them too).
    void end_forces(std::uint16_t id, std::uint64_t tick)
    {
        auto it = peers.find(id);
        if (it == peers.end() || (it->second.forces_end && *it->second.forces_end <= tick))
            return;
        it->second.forces_end = tick;
        if (recording)
            force_log.push_back(ForceRecord{id, tick, {}});
    }

    std::optional<core::NodeIndex> seed_of(const std::vector<net::Target>& pts) const
    {
        if (pts.empty())
            return std::nullopt;
        const core::TetraGrid& g = s.model_->grid();
        const net::Target& t = pts.front();
        if (t.kind == net::TargetKind::Face)
        {
            if (t.face >= g.face_count())
                return std::nullopt;
            const std::uint32_t cell = t.face / 2;
            const int x = static_cast<int>(cell % static_cast<std::uint32_t>(2 * g.w()));
            const int y = static_cast<int>(cell / static_cast<std::uint32_t>(2 * g.w()));
            return g.canonical(g.index(x, y));
        }
        double best = std::numeric_limits<double>::infinity();
        core::NodeIndex out{};
        const auto& P = s.model_->rest_positions();
        for (const core::NodeIndex n : g.node_of_unique())
        {
            const core::GridCoord c = g.coord(n);
            const double dx = P[0].at(c.x, c.y) - t.position[0];
            const double dy = P[1].at(c.x, c.y) - t.position[1];
            const double dz = P[2].at(c.x, c.y) - t.position[2];
            const double d = dx * dx + dy * dy + dz * dz;
            if (d < best)
            {
                best = d;
                out = n;
            }
        }
        return out;
    }

    /// Master: the partition over the ready participants (itself included).
    std::vector<net::PeerId> compute_partition() const
    {
        std::vector<Seat> seats{Seat{s.id_, seed_of(my_points)}};
        for (const auto& [id, p] : peers)
            if (p.ready && !p.leaving && !p.departed && p.info.role == net::Role::Participant)
                seats.push_back(Seat{net::PeerId{id}, seed_of(p.points)});
        // Exact coupling's state does not depend on the borders; fast coupling's errs next to
        // them, so there the points keep the distance the grown shares give them, unless the
        // session says otherwise (SessionSettings::point_clearance).
        // Exact coupling also computes the rings next to each share (§4.1): borders cost there.
        const bool exact = s.coupling_ == Coupling::Exact;
        return partition_leaves(s.model_->grid(), *s.graph_, seats, s.point_clearance(),
                                exact ? k_exact_ring_cost : 0.0);
    }

    /// Members the partition `owners` leaves without a leaf simulate nothing: a grid with fewer
    /// leaves than members (level 1 has 2: with 3 participants two of the four members owned
    /// nothing, without a word). Said once per member count, not per epoch, and whether or not
    /// the partition changed (a member seated with no leaf mostly leaves it as it was).
    void warn_idle_members(const std::vector<net::PeerId>& owners)
    {
        std::size_t seated = 1;  // the master
        for (const auto& [id, p] : peers)
            if (p.ready && !p.leaving && !p.departed && p.info.role == net::Role::Participant)
                ++seated;
        std::vector<net::PeerId> holders(owners.begin(), owners.end());
        std::sort(holders.begin(), holders.end());
        const auto holding =
            static_cast<std::size_t>(std::unique(holders.begin(), holders.end()) - holders.begin());
        if (holding < seated && seated != warned_idle_members)
        {
            warned_idle_members = seated;
            spdlog::warn(
                "session: the grid's {} leaves (level {}) are shared by {} of the {} "
                "members; the others simulate nothing (a finer level gives every member "
                "a share)",
                owners.size(), s.model_->grid().level(), holding, seated);
        }
    }

    void master_repartition(std::uint64_t apply)
    {
        repartition_pending = false;
        auto owners = compute_partition();
        warn_idle_members(owners);
        const PartitionEntry* cur = newest();
        if (cur != nullptr && cur->owners == owners)
            return;
        const std::uint32_t epoch = next_epoch++;
        add_partition(apply, epoch, owners);
        net::Partition msg;
        msg.epoch = epoch;
        msg.leaf_depth = static_cast<std::uint8_t>(s.graph_->depth());
        msg.owners = std::move(owners);
        send_all(make(msg, apply));
        spdlog::debug("session: master partition epoch {} from tick {}", epoch, apply);
    }

    // --- node sets -----------------------------------------------------------------------------

    std::vector<char> owned_mask(const PartitionEntry* p, net::PeerId id) const
    {
        const core::TetraGrid& g = s.model_->grid();
        std::vector<char> mask(g.node_count(), 0);
        if (p == nullptr)
            return mask;
        for (std::size_t l = 0; l < p->owners.size(); ++l)
            if (p->owners[l] == id)
                for (const core::NodeIndex n : s.graph_->nodes(l))
                    mask[n.value] = 1;
        return mask;
    }

    std::vector<char> dilate(std::vector<char> mask, int rings) const
    {
        return core::dilate_nodes(s.model_->grid(), std::move(mask), rings);
    }

    std::vector<core::Region> runs_of(const std::vector<char>& mask) const
    {
        return core::node_runs(s.model_->grid(), mask);
    }

    /// Exact mode sets for publishing tick t / stepping from t.
    void refresh_exact_sets(const PartitionEntry* prev, const PartitionEntry* next)
    {
        const std::uint32_t pe = prev != nullptr ? prev->epoch : 0;
        const std::uint32_t ne = next != nullptr ? next->epoch : 0;
        if (pe == cache_prev && ne == cache_next && !integrate_runs.empty())
            return;
        cache_prev = pe;
        cache_next = ne;
        const std::vector<char> own = owned_mask(next, s.id_);
        integrate_runs = runs_of(dilate(own, settings.halo_rings));
        own_runs = runs_of(own);
        halo_out.clear();
        const std::vector<char> mine = owned_mask(prev, s.id_);
        if (next == nullptr)
            return;
        for (const net::PeerId r : next->members)
        {
            if (r == s.id_)
                continue;
            const std::vector<char> need = dilate(owned_mask(next, r), settings.halo_rings);
            const std::vector<char> has = owned_mask(prev, r);
            std::vector<std::uint32_t> nodes;
            for (std::uint32_t i = 0; i < need.size(); ++i)
                if (need[i] != 0 && mine[i] != 0 && has[i] == 0)
                    nodes.push_back(i);
            if (!nodes.empty())
                halo_out[r.value] = plan_halo(nodes);
        }
    }

    /// The Halo datagrams that carry `nodes` (increasing): ranges of consecutive nodes (at most
    /// 65,535 each), as many nodes per datagram as its payload and range limits allow.
    std::vector<HaloChunk> plan_halo(const std::vector<std::uint32_t>& nodes) const
    {
        std::vector<HaloChunk> chunks(1);
        for (const std::uint32_t n : nodes)
        {
            HaloChunk* c = &chunks.back();
            const bool extend = !c->ranges.empty() &&
                                c->ranges.back().first + c->ranges.back().count == n &&
                                c->ranges.back().count < 0xFFFF;
            const std::size_t r = c->ranges.size() + (extend ? 0 : 1);
            const std::size_t bytes = 16 + 8 * r + 16 * (c->values + 1);
            if (bytes > net::k_max_state_payload || r > net::k_max_halo_ranges)
            {
                chunks.emplace_back();
                c = &chunks.back();
                c->ranges.push_back(net::NodeRange{n, 1});
            }
            else if (extend)
                ++c->ranges.back().count;
            else
                c->ranges.push_back(net::NodeRange{n, 1});
            if (!c->runs.empty() && c->runs.back().first + c->runs.back().second == pad[n])
                ++c->runs.back().second;
            else
                c->runs.emplace_back(pad[n], 1);
            ++c->values;
        }
        return chunks;
    }

    void refresh_my_leaves(const PartitionEntry* p)
    {
        const std::uint32_t e = p != nullptr ? p->epoch : 0;
        if (e == my_leaves_epoch)
            return;
        flush_display();  // a pending copy is of the leaves we owned until now
        my_leaves_epoch = e;
        const std::vector<std::uint32_t> before = std::move(my_leaves);
        my_leaves.clear();
        owned_regions.clear();
        if (p == nullptr)
            return;
        for (std::uint32_t l = 0; l < p->owners.size(); ++l)
            if (p->owners[l] == s.id_)
            {
                my_leaves.push_back(l);
                owned_regions.push_back(s.graph_->regions()[l]);
                // A leaf (re)acquired starts from key states: no receiver holds a baseline of
                // ours from this ownership.
                if (!std::binary_search(before.begin(), before.end(), l))
                    sent[l].clear();
            }
    }

    // --- forces --------------------------------------------------------------------------------

    /// The entry with the greatest apply tick <= tick (ties: the later one).
    static const ForceEntry* active(const std::vector<ForceEntry>& table, std::uint64_t tick)
    {
        const ForceEntry* best = nullptr;
        for (const ForceEntry& e : table)
            if (e.apply_tick <= tick && (best == nullptr || e.apply_tick >= best->apply_tick))
                best = &e;
        return best;
    }

    std::vector<sim::Force> forces_at(std::uint64_t tick) const
    {
        // Order: by sender id (the master, id 0, first), then each sender's list order.
        std::vector<std::pair<std::uint16_t, const ForceEntry*>> entries;
        entries.emplace_back(s.id_.value, active(my_forces, tick));
        for (const auto& [id, p] : peers)
            // A departed peer's grab ends with it in fast coupling; in exact coupling at the
            // first partition without it, the same tick on every peer and in the replay
            // (docs/session.md §6).
            if ((!p.departed || s.coupling_ == Coupling::Exact) &&
                !(p.forces_end && tick >= *p.forces_end))
                entries.emplace_back(id, active(p.forces, tick));
        std::sort(entries.begin(), entries.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<sim::Force> out;
        for (const auto& [id, e] : entries)
            if (e != nullptr)
                (void)append_valid_forces(*s.model_, e->forces, out);
        return out;
    }

    /// Counts the forces of `list` above the session's limit (they act scaled down to it) and
    /// logs the first of each peer's (`warned`), with the magnitude asked for and the limit.
    void count_limited(std::span<const net::UserForce> list, std::uint16_t from, bool& warned)
    {
        if (s.model_ == nullptr)
            return;
        const double limit = s.model_->settings().max_force;
        for (const net::UserForce& f : list)
        {
            const double magnitude = std::hypot(f.force[0], f.force[1], f.force[2]);
            if (!(limit > 0.0) || !(magnitude > limit))
                continue;
            ++counters.limited_forces;
            if (!warned)
                spdlog::warn(
                    "session: peer {} applies a force of {:.3g} N, above the session's "
                    "limit of {:.3g} N: it acts scaled down to the limit",
                    from, magnitude, limit);
            warned = true;
        }
    }

    /// Sends the queued force lists; none applies before `earliest` (exact mode: the tick after
    /// the one being published, so every peer has it before it steps that tick).
    void flush_forces(std::uint64_t earliest)
    {
        for (ForceEntry& e : pending_forces)
        {
            e.apply_tick = std::max(e.apply_tick, earliest);
            net::Force msg;
            msg.forces = e.forces;
            count_limited(e.forces, s.id_.value, warned_own_force_limit);
            send_all(make(msg, e.apply_tick));
            if (recording)
                force_log.push_back(ForceRecord{s.id_.value, e.apply_tick, e.forces});
            my_forces.push_back(std::move(e));
        }
        pending_forces.clear();
        trim(my_forces);
    }

    /// Keeps a force table short: entries superseded before the current tick go.
    void trim(std::vector<ForceEntry>& table) const
    {
        const ForceEntry* cur = active(table, s.state_.tick > 2 ? s.state_.tick - 2 : 0);
        if (cur == nullptr)
            return;
        const std::uint64_t base = cur->apply_tick;
        const ForceEntry* keep = cur;
        std::vector<ForceEntry> out;
        for (const ForceEntry& e : table)
            if (&e == keep || e.apply_tick > base)
                out.push_back(e);
        table = std::move(out);
    }

    // --- exact mode ----------------------------------------------------------------------------

    void send_halos(std::uint64_t t)
    {
        const PartitionEntry* next = partition_at(t);
        const std::uint32_t epoch = next != nullptr ? next->epoch : 0;
        // One message, filled in place: its vectors keep their capacity from tick to tick.
        if (!std::holds_alternative<net::Halo>(halo_message.body))
            halo_message.body = net::Halo{};
        halo_message.header.session = session_id;
        halo_message.header.sender = s.id_;
        halo_message.header.tick = t;
        net::Halo& h = std::get<net::Halo>(halo_message.body);
        h.epoch = epoch;
        h.stage = net::k_max_halo_stage;
        h.encoding = net::ValueEncoding::F64;
        h.time = s.state_.time;
        h.has_u = true;
        h.has_v = true;
        const double* su = s.state_.u.padded().data();
        const double* sv = s.state_.v.padded().data();
        for (const auto& [rid, chunks] : halo_out)
            for (const HaloChunk& c : chunks)
            {
                h.ranges.assign(c.ranges.begin(), c.ranges.end());
                h.u.resize(c.values);
                h.v.resize(c.values);
                std::size_t k = 0;
                for (const auto& [o, len] : c.runs)
                {
                    copy_run(su + o, len, h.u.data() + k);
                    copy_run(sv + o, len, h.v.data() + k);
                    k += len;
                }
                send_to(rid, halo_message, net::SendMode::Reliable);
            }
    }

    /// Peers whose Heartbeat(t) this peer needs before stepping from t.
    std::vector<std::uint16_t> barrier_set(std::uint64_t t) const
    {
        std::set<std::uint16_t> ids;
        for (const PartitionEntry* p : {t > 0 ? partition_at(t - 1) : nullptr, partition_at(t)})
            if (p != nullptr)
                for (const net::PeerId m : p->members)
                    ids.insert(m.value);
        ids.erase(s.id_.value);
        std::vector<std::uint16_t> out;
        for (const std::uint16_t id : ids)
        {
            auto it = peers.find(id);
            if (it != peers.end() && !it->second.departed)
                out.push_back(id);
        }
        return out;
    }

    void publish(std::uint64_t t)
    {
        if (s.role_ == SessionRole::Master && repartition_pending)
            master_repartition(t + 1);
        flush_forces(t + 1);
        const PartitionEntry* prev =
            t > exact_from ? partition_at(t - 1) : (state_exact ? partition_at(t) : nullptr);
        refresh_exact_sets(prev, partition_at(t));
        send_halos(t);
        net::Heartbeat hb;
        hb.epoch = partition_at(t) != nullptr ? partition_at(t)->epoch : 0;
        // To the members we know of, and to every ready participant: after a lost master, a peer
        // may count as a member one of us does not know of yet (a Partition only some received),
        // and must not wait for us forever (docs/session.md §6).
        const std::vector<std::uint16_t> members = barrier_set(t);
        std::set<std::uint16_t> to(members.begin(), members.end());
        for (const auto& [id, p] : peers)
            if (!p.departed && p.ready && p.info.role == net::Role::Participant)
                to.insert(id);
        for (const std::uint16_t id : to)
            send_to(id, make(hb, t), net::SendMode::Reliable);
        published = true;
    }

    /// The members whose Heartbeat(t) has not arrived, by increasing id (none: the barrier of
    /// tick t is passed).
    std::vector<std::uint16_t> barrier_missing(std::uint64_t t) const
    {
        std::vector<std::uint16_t> out;
        for (const std::uint16_t id : barrier_set(t))
        {
            const RemotePeer& p = peers.at(id);
            if (!p.has_heartbeat || p.heartbeat < t)
                out.push_back(id);
        }
        return out;
    }

    bool barrier_ok(std::uint64_t t) const { return barrier_missing(t).empty(); }

    std::string describe_peer(std::uint16_t id) const
    {
        auto it = peers.find(id);
        std::string out = "peer " + std::to_string(id);
        if (it != peers.end() && !it->second.info.name.empty())
            out += " (" + it->second.info.name + ")";
        return out;
    }

    /// A message from peer `from` failed a check no honest peer fails (`counter`, one of
    /// SessionStats' reject counters): dropped, counted, and the first one of each peer logged
    /// with what was wrong, so the user can tell who.
    void reject(std::uint64_t& counter, std::uint16_t from, std::string_view what)
    {
        ++counter;
        auto it = peers.find(from);
        if (it == peers.end())
            return;
        ++it->second.rejected;
        if (it->second.warned_rejected)
            return;
        it->second.warned_rejected = true;
        spdlog::warn(
            "session: {} sent {}: dropped (an honest peer never does; further drops "
            "are counted in the --stats column 'rejected')",
            describe_peer(from), what);
    }

    /// reject() for a connection not bound to a peer yet: logged with its address, at most once
    /// a second.
    void reject(std::uint64_t& counter, net::PeerHandle h, std::string_view what)
    {
        ++counter;
        if (last_now < next_unbound_warning)
            return;
        next_unbound_warning = last_now + 1.0;
        const auto address = transport.remote_address(h);
        spdlog::warn(
            "session: the connection from {} sent {}: dropped (an honest peer never "
            "does; counted in the --stats column 'rejected')",
            address ? net::to_string(*address) : std::string("?"), what);
    }
    double next_unbound_warning = 0.0;

    /// Exact mode, ready to step from `t` but for the members in `missing`: counts the wait,
    /// warns once past k_barrier_warn_s, and on the master removes the members that have held
    /// the lockstep past max_barrier_wait_s, as lost (docs/session.md §6): a hung or hostile
    /// participant whose connection stays up would otherwise stop everyone for good.
    void wait_at_barrier(std::uint64_t t, const std::vector<std::uint16_t>& missing)
    {
        if (barrier_since < 0.0 || barrier_tick != t)
        {
            barrier_tick = t;
            barrier_since = last_now;
            barrier_warned = false;
            return;
        }
        const double waited = last_now - barrier_since;
        std::string names;
        for (const std::uint16_t id : missing)
            names += (names.empty() ? "" : ", ") + describe_peer(id);
        if (waited >= k_barrier_warn_s && !barrier_warned)
        {
            barrier_warned = true;
            spdlog::warn(
                "session: waited {:.1f} s at tick {} for {} to publish it (exact coupling steps "
                "every member together){}",
                waited, t, names,
                s.role_ == SessionRole::Master && settings.max_barrier_wait_s > 0.0
                    ? fmt::format("; removed from the session after {:g} s",
                                  settings.max_barrier_wait_s)
                    : std::string());
        }
        if (s.role_ != SessionRole::Master || settings.max_barrier_wait_s <= 0.0 ||
            waited <= settings.max_barrier_wait_s)
            return;
        // Whom to remove: a member that waits itself (for a stopped neighbour's halos, within
        // the same tick) publishes nothing either, but its transport goes on answering; the
        // silent ones (nothing on the connection for half the wait, at least 1 s: a stopped
        // or hung process) are the cause, and only they go. Where none is silent (a member that
        // answers but never steps, or a transport that cannot tell), every missing member goes.
        std::vector<std::uint16_t> culprits;
        const double silent_after = std::max(1.0, 0.5 * settings.max_barrier_wait_s);
        for (const std::uint16_t id : missing)
        {
            const RemotePeer& p = peers.at(id);
            if (!p.handle)
                continue;
            const std::optional<net::PeerStats> st = transport.stats(*p.handle);
            if (st)
                spdlog::debug("session: {} has sent nothing for {:.2f} s", describe_peer(id),
                              st->silent_s);
            if (st && st->silent_s > silent_after)
                culprits.push_back(id);
        }
        if (culprits.empty())
            culprits = missing;
        else if (culprits.size() < missing.size())
        {
            names.clear();
            for (const std::uint16_t id : culprits)
                names += (names.empty() ? "" : ", ") + describe_peer(id);
        }
        spdlog::warn(
            "session: removing {} from the session: not one step published for {:.1f} s "
            "(tick {}); its leaves go on from their last streamed state",
            names, waited, t);
        for (const std::uint16_t id : culprits)
        {
            RemotePeer& p = peers.at(id);
            ++counters.stalled_removed;
            if (p.handle)
            {
                const net::PeerHandle h = *p.handle;
                transport.disconnect(h, net::DisconnectReason::Kicked);
                lose_peer(h, net::DisconnectReason::Kicked);  // at once, not at its ack
            }
            else
                p.departed = true;
        }
        settle_losses();  // the PeerLeft and the re-partition at once, not at the next advance
        barrier_since = -1.0;
    }

    void apply_halos(std::uint64_t t)
    {
        while (!halos.empty() && halos.front().tick < t)
        {
            spare_halos.push_back(std::move(halos.front()));  // kept for their capacity
            halos.pop_front();
        }
        double* su = s.state_.u.padded().data();
        double* sv = s.state_.v.padded().data();
        // The values of tick t were computed by the step from t - 1, under that tick's partition
        // (at a re-partition, the old owners' halos of t are also the new owners' hand-over).
        const PartitionEntry* part = partition_at(t == 0 ? 0 : t - 1);
        for (const HaloBuffer& h : halos)
        {
            if (h.tick != t)
                continue;
            if (!owns_every_node(part, h))
            {
                reject(counters.halo_rejects, h.sender.value,
                       "halo values for nodes it did not own at tick " + std::to_string(t));
                continue;
            }
            std::size_t k = 0;
            for (const net::NodeRange& r : h.ranges)
                for (std::uint32_t j = 0; j < r.count; ++j, ++k)
                {
                    su[pad[r.first + j]] = h.u[k];
                    sv[pad[r.first + j]] = h.v[k];
                }
            if (!state_exact)
                s.state_.time = h.time;
        }
        state_exact = true;
        // No whole-plane sync of the state: the halo nodes lie in the set the step integrates,
        // and a swapping step (keep_outside = false) copies every twin and ghost it reads first
        // (sim::detail::sync_live).
    }

    /// Whether the sender of `h` owns every node it carries under `part` (the partition of its
    /// tick): an honest peer sends only its own nodes, so anything else (a peer's bug, a forged
    /// halo) is dropped rather than written over nodes this peer or another one owns.
    bool owns_every_node(const PartitionEntry* part, const HaloBuffer& h) const
    {
        if (part == nullptr)
            return false;
        for (const net::NodeRange& r : h.ranges)
            for (std::uint32_t j = 0; j < r.count; ++j)
                if (part->owners[s.graph_->leaf_of(core::NodeIndex{r.first + j})] != h.sender)
                    return false;
        return true;
    }

    /// A step from `tick` gave non-finite values on this peer's nodes (sim::step kept the state
    /// of `tick`): the state diverged. Retrying would fail the same way (in exact coupling it
    /// republished the tick and logged a warning per try, hundreds per call), so the peer holds
    /// its last finite state and steps no further; said once, as an error. advance() then
    /// streams that state and leaves (drop_out_diverged).
    void on_non_finite_step(std::uint64_t tick)
    {
        s.diverged_tick_ = tick;
        spdlog::error(
            "session: the step from tick {} (t = {:.6g} s) gives non-finite values on this "
            "peer's nodes: the state diverged (a fixed step above the grid's stable step, "
            "docs/physics.md §5, or forces without a limit, docs/session.md §7); this peer holds "
            "its last finite state, streams it and leaves the session",
            tick, s.state_.time);
    }

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

    bool may_step(std::uint64_t t) const
    {
        if (settings.max_ticks != 0 && t >= settings.max_ticks)
            return false;
        if (!clock_set)
            return false;
        const double dt = s.model_->settings().fixed_dt;
        const double sim_now = last_now + clock_offset;
        return (static_cast<double>(t) + 1.0) * dt <= sim_now + 1e-9 * dt;
    }

    void exact_advance()
    {
        // A peer whose steps cannot keep real time (a lone master stepping the whole object at
        // a fine level, a loaded machine) would otherwise step here until it caught up, which it
        // never does, and stop answering the network: joiners were never welcomed. So a call
        // steps for at most k_step_slice_s of wall time and returns; the caller's poll() runs
        // between calls and the next call goes on. Steps do not depend on how they are spread
        // over calls (the lockstep fixes the forces and partitions per tick).
        const auto call_start = std::chrono::steady_clock::now();
        const double call_budget = std::min(1.0 / settings.frame_rate_hz, k_step_slice_s);
        // Bounded: each pass either steps once or returns.
        for (int guard = 0; guard < 100000 && !s.diverged_tick_; ++guard)
        {
            const std::uint64_t t = s.state_.tick;
            if (!member(partition_at(t), s.id_) &&
                !member(t > 0 ? partition_at(t - 1) : nullptr, s.id_))
            {
                if (leaving)
                    finish_leave_soon();
                return;
            }
            if (!published)
                publish(t);
            else
            {
                // Tick t is out already: a peer may have stepped to t+1 on it and published
                // t+1 without this news, but none can step t+1 before our Heartbeat(t+1), so
                // what we send now applies from t+2.
                if (s.role_ == SessionRole::Master && repartition_pending)
                    master_repartition(t + 2);
                flush_forces(t + 2);
            }
            if (!member(partition_at(t), s.id_))
            {
                // Published the hand-over tick; nothing more to integrate.
                if (leaving)
                    finish_leave_soon();
                return;
            }
            if (!may_step(t))
                return;
            if (const auto missing = barrier_missing(t); !missing.empty())
            {
                wait_at_barrier(t, missing);
                return;
            }
            barrier_since = -1.0;
            if (guard > 0 && seconds_since(call_start) >= call_budget)
            {
                behind = true;
                return;  // tick t is published; the next call steps it
            }
            adopt_orphans(t);
            apply_halos(t);
            const PartitionEntry* prev = t > exact_from ? partition_at(t - 1) : partition_at(t);
            refresh_exact_sets(prev, partition_at(t));
            const auto forces = forces_at(t);
            counters.active_forces = forces.size();
            sim::StepOptions opt;
            opt.owned = integrate_runs;
            opt.needed = own_runs;     // each stage pair only where the own nodes read it
            opt.keep_outside = false;  // the halos and the display rewrite the nodes beyond
            const auto t0 = std::chrono::steady_clock::now();
            const sim::StepReport r = sim::step(*s.model_, s.state_, *ws, forces, opt);
            counters.step_seconds += seconds_since(t0);
            if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
            {
                on_non_finite_step(t);
                return;  // held: the state stays that of tick t, published once
            }
            ++counters.steps;
            published = false;
            copy_own_to_display(partition_at(t));
            disconnect_finished_leavers();
        }
    }

    /// Exact mode, before stepping from t: leaves this peer owns from t that a lost peer owned
    /// before and did not hand over (no Heartbeat(t), so no halos of t from it) start from their
    /// last streamed state, the newest this peer received (docs/session.md §6).
    void adopt_orphans(std::uint64_t t)
    {
        if (t <= exact_from)
            return;
        const PartitionEntry* prev = partition_at(t - 1);
        const PartitionEntry* next = partition_at(t);
        if (prev == nullptr || next == nullptr || prev == next)
            return;
        const core::TetraGrid& g = s.model_->grid();
        bool any = false;
        for (std::size_t l = 0; l < next->owners.size() && l < prev->owners.size(); ++l)
        {
            const net::PeerId was = prev->owners[l];
            if (next->owners[l] != s.id_ || was == s.id_)
                continue;
            auto it = peers.find(was.value);
            if (it != peers.end() &&
                (!it->second.departed || (it->second.has_heartbeat && it->second.heartbeat >= t)))
                continue;
            flush_display();
            for (const core::NodeIndex n : s.graph_->nodes(l))
            {
                const core::GridCoord c = g.coord(n);
                s.state_.u.at(c.x, c.y) = s.display_u_.at(c.x, c.y);
                s.state_.v.at(c.x, c.y) = s.display_v_.at(c.x, c.y);
            }
            ++counters.adopted_leaves;
            any = true;
        }
        if (any)
        {
            s.model_->sync(s.state_.u);
            s.model_->sync(s.state_.v);
            spdlog::info("session: tick {}: took over leaves of a lost peer from their last state",
                         t);
        }
    }

    void become_member(std::uint64_t apply)
    {
        // A joiner (or re-admitted peer) enters the lockstep at `apply`; its state comes from
        // the halos of that tick.
        lockstep = true;
        published = false;
        state_exact = false;
        exact_from = apply;
        s.state_.tick = apply;
    }

    // --- fast mode -----------------------------------------------------------------------------

    /// The coupling edges of the owned set `mine` (see border_nodes).
    void refresh_border(const PartitionEntry* p, const std::vector<char>& mine)
    {
        const std::uint32_t e = p != nullptr ? p->epoch : 0;
        if (e == border_epoch)
            return;
        border_epoch = e;
        border_mask.assign(mine.size(), 0);
        border_nodes.clear();
        border_begin.clear();
        border_dir.clear();
        border_leaf.clear();
        const core::TetraGrid& g = s.model_->grid();
        for (const std::uint32_t l : my_leaves)
            for (const core::NodeIndex n : s.graph_->nodes(l))
            {
                const core::GridCoord c = g.coord(n);
                const auto nb = core::grid_neighbours(g, c.x, c.y);
                const std::size_t first = border_dir.size();
                for (std::size_t k = 0; k < nb.size(); ++k)
                    if (mine[nb[k].value] == 0)
                    {
                        border_dir.push_back(static_cast<std::uint8_t>(k));
                        border_leaf.push_back(s.graph_->leaf_of(nb[k]));
                    }
                if (border_dir.size() != first)
                {
                    border_mask[n.value] = 1;
                    border_nodes.push_back(c);
                    border_begin.push_back(static_cast<std::uint32_t>(first));
                }
            }
        border_begin.push_back(static_cast<std::uint32_t>(border_dir.size()));
    }

    /// The interface damping of one accepted step of `dt` from `t0` (fast_advance explains it):
    /// v *= exp(-dt sum_e |w_e| |age_e| / m) on every owned node next to a Dirichlet node, where
    /// age_e = t0 + dt/2 - (time of the streamed state that gave the neighbour's value).
    void damp_border(double t0, double dt)
    {
        const sim::MembraneModel& m = *s.model_;
        const core::Field<double>& wx = m.weight_x();
        const core::Field<double>& wy = m.weight_y();
        const core::Field<double>& wd = m.weight_d();
        const double mid = t0 + 0.5 * dt;
        for (std::size_t i = 0; i < border_nodes.size(); ++i)
        {
            const int x = border_nodes[i].x;
            const int y = border_nodes[i].y;
            double b = 0.0;  // sum of |w_e| age_e [N s/m], >= 0
            for (std::uint32_t e = border_begin[i]; e < border_begin[i + 1]; ++e)
            {
                double w = 0.0;
                switch (border_dir[e])  // grid_neighbours order: +x, -x, +y, -y, +d, -d
                {
                case 0: w = wx.at(x, y); break;
                case 1: w = wx.at(x - 1, y); break;
                case 2: w = wy.at(x, y); break;
                case 3: w = wy.at(x, y - 1); break;
                case 4: w = wd.at(x, y); break;
                default: w = wd.at(x - 1, y - 1); break;
                }
                // |w|: a negative cotangent weight (an obtuse pair of angles) is a spring of
                // negative stiffness, and its delay needs the same damper. |age|: the peers'
                // clocks are not aligned, so a value can be ahead of ours; a lead is a phase
                // shift too, and feeds the modes with omega |age| in (pi, 2 pi).
                b += std::fabs(w) * std::fabs(mid - leaf_time[border_leaf[e]]);
            }
            s.state_.v.at(x, y) *= std::exp(-dt * b / m.mass().at(x, y));
        }
        m.sync(s.state_.v);
    }

    // Fast coupling holds every node not owned at its newest streamed value (u at the owner's
    // time t_s) while the owned nodes step on: each coupling edge (weight w) is a spring whose
    // far end is sampled, held over the frame and late by the network, i.e. a spring acting
    // with a delay. A delayed spring feeds energy into the modes that move in antiphase across
    // it (Colgate & Schenkel 1997, passivity of sampled-data systems: a held spring K needs a
    // damping of at least K T/2, a delay tau adds K tau); grid-scale modes along a partition
    // border, which cannot carry the energy away, grew ~e^(4/s) until |u| ~ 1e11 m in the 2-peer
    // drag scene (docs/session.md §4.2). So each coupling edge gets the damper it needs to stay
    // passive: after every accepted step the owned end's velocity decays by
    // exp(-dt |w| |age| / m), age = how old the held value is at the middle of the step (a delay
    // of phase omega age injects at most w sin(omega age) / omega <= |w| |age| of negative
    // damping). Interior nodes and exact coupling are untouched; the price is that a smooth
    // motion is slowed at the border nodes.
    void fast_advance()
    {
        const PartitionEntry* p = newest();
        refresh_my_leaves(p);
        if (my_leaves.empty() || !clock_set)
            return;
        const core::TetraGrid& g = s.model_->grid();
        const double frame = 1.0 / settings.frame_rate_hz;
        const auto call_start = std::chrono::steady_clock::now();
        for (int guard = 0; guard < 64 && next_frame <= last_now; ++guard)
        {
            // A peer behind real time catches up over several calls, so that the caller's
            // poll() keeps serving the network (see exact_advance).
            if (guard > 0 && seconds_since(call_start) >= frame)
            {
                behind = true;
                return;
            }
            if (settings.max_ticks != 0 && s.state_.tick >= settings.max_ticks)
                return;
            // Dirichlet values: the newest displayed state of every node not owned.
            if (fast_mine_epoch != (p != nullptr ? p->epoch : 0))
            {
                std::vector<char> now_mine = owned_mask(p, s.id_);
                flush_display();
                // Leaves we gain continue from the newest state streamed for them (what we
                // displayed), not from whatever our integrated state held there.
                for (int y = 0; y < g.ny(); ++y)
                    for (int x = 0; x < g.nx(); ++x)
                    {
                        const std::size_t c = g.canonical(g.index(x, y)).value;
                        if (now_mine[c] != 0 && (fast_mine.empty() || fast_mine[c] == 0))
                        {
                            s.state_.u.at(x, y) = s.display_u_.at(x, y);
                            s.state_.v.at(x, y) = s.display_v_.at(x, y);
                        }
                    }
                fast_mine = std::move(now_mine);
                fast_mine_epoch = p != nullptr ? p->epoch : 0;
                fast_fill_runs.clear();
                for (int y = 0; y < g.ny(); ++y)
                    for (int x = 0; x < g.nx();)
                    {
                        const auto foreign = [&](int xx)
                        { return fast_mine[g.canonical(g.index(xx, y)).value] == 0; };
                        if (!foreign(x))
                        {
                            ++x;
                            continue;
                        }
                        const int x0 = x;
                        while (x < g.nx() && foreign(x))
                            ++x;
                        fast_fill_runs.emplace_back(
                            static_cast<std::uint32_t>(s.display_u_.padded_offset(x0, y)),
                            static_cast<std::uint32_t>(x - x0));
                    }
            }
            const std::vector<char>& mine = fast_mine;
            refresh_border(p, mine);
            // Bounded staleness: hold the clock while a neighbour's state is too old. Only for
            // neighbours that have streamed to us: one that has not is still connecting (ENet's
            // handshake, our Hello and Ready reach it; a lost datagram there costs a
            // retransmission timeout, a second or more on a young connection), so no state of it
            // can come sooner, and holding for it held every peer that waits on us as well. Its
            // leaves keep the values we hold (the Welcome's state, or their previous owner's).
            const double frame_end = next_frame + clock_offset;
            double oldest = 0.0;
            for (const std::uint32_t l : border_leaf)
                if (streamed_to_us(p->owners[l]))
                    oldest = std::max(oldest, frame_end - leaf_time[l]);
            if (settings.max_halo_age_s > 0.0 && oldest > settings.max_halo_age_s)
            {
                if (!stepping_stale)
                {
                    if (stall_since < 0.0)
                        stall_since = last_now;
                    if (last_now - stall_since < settings.max_stall_s)
                        break;  // hold the clock: fresher states are on their way
                    stepping_stale = true;
                }
                // A silent neighbour (gone, until the transport says so): step on with its last
                // values rather than freeze; the interface damping grows with their age. Every
                // frame until one is fresh again: a new hold per stale frame stepped one frame
                // per max_stall_s for the whole outage (5-30 s with ENet).
                ++counters.stale_frames;
            }
            else
                stepping_stale = false;
            if (stall_since >= 0.0)
            {
                counters.stalled_s += last_now - stall_since;
                stall_since = -1.0;
            }
            counters.border_age_s = oldest;
            counters.max_border_age_s = std::max(counters.max_border_age_s, oldest);
            for (const auto& [offset, length] : fast_fill_runs)
            {
                std::copy_n(s.display_u_.padded().data() + offset, length,
                            s.state_.u.padded().data() + offset);
                std::copy_n(s.display_v_.padded().data() + offset, length,
                            s.state_.v.padded().data() + offset);
            }
            const double target = next_frame + clock_offset;
            sim::StepOptions opt;
            opt.owned = owned_regions;
            opt.keep_outside = false;  // every node not owned is rewritten before each frame
            const auto t0 = std::chrono::steady_clock::now();
            // sim::advance_to's loop, with the interface damping after every accepted step.
            const auto forces = forces_at(s.state_.tick);
            counters.active_forces = forces.size();
            sim::set_forces(*s.model_, *ws, forces);
            const sim::MembraneSettings& ms = s.model_->settings();
            const double slack = 1e-12 * std::max(1.0, std::fabs(target));
            for (int k = 0; k < 100000 && !s.diverged_tick_; ++k)
            {
                const double remaining = target - s.state_.time;
                if (ms.fixed_step ? remaining + slack < ms.fixed_dt : remaining <= slack)
                    break;
                opt.dt_limit = remaining;
                const double start = s.state_.time;
                const sim::StepReport r = sim::step_prepared(*s.model_, s.state_, *ws, opt);
                if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
                {
                    on_non_finite_step(s.state_.tick);
                    break;
                }
                ++counters.steps;
                if (!ms.fixed_step && r.dt >= remaining)
                    s.state_.time = target;  // land exactly, as sim::advance_to
                damp_border(start, r.dt);
            }
            counters.step_seconds += seconds_since(t0);
            next_frame += frame;
            if (quantised_stream())
                adopt_quantised();
            copy_own_to_display(p);
        }
    }

    // --- display and streaming -----------------------------------------------------------------

    /// Quantises leaf `l` of the state into qu, qv (first n entries), and its dequantised values
    /// into xu, xv. \return the node count, or 0 if a value does not fit the int32 range.
    std::size_t quantise_leaf(std::uint32_t l)
    {
        const std::size_t n = s.graph_->node_count(l);
        const double* state_u = s.state_.u.padded().data();
        const double* state_v = s.state_.v.padded().data();
        for_node_runs(l,
                      [&](std::size_t o, std::size_t i, std::size_t c)
                      {
                          copy_run(state_u + o, c, xu.data() + i);
                          copy_run(state_v + o, c, xv.data() + i);
                      });
        const auto su = std::span(qu.data(), n);
        const auto sv = std::span(qv.data(), n);
        if (!net::quantise(std::span(xu.data(), n), settings.u_step_exponent, su) ||
            !net::quantise(std::span(xv.data(), n), settings.v_step_exponent, sv))
            return 0;
        net::dequantise(su, settings.u_step_exponent, std::span(xu.data(), n));
        net::dequantise(sv, settings.v_step_exponent, std::span(xv.data(), n));
        return n;
    }

    /// Fast mode with quantised streaming: the owner's u on its border nodes (those a
    /// neighbour's Dirichlet values come from) becomes what it streams, so both sides of a border
    /// integrate from the same boundary values (docs/protocol.md §5.5, docs/session.md §5.1).
    /// Interior nodes and v keep full precision: rounding every node every frame fed noise of
    /// the step's size into the whole region, which the stream then had to carry (docs/results.md).
    void adopt_quantised()
    {
        const core::TetraGrid& g = s.model_->grid();
        for (const std::uint32_t l : my_leaves)
        {
            const std::size_t n = quantise_leaf(l);
            const auto nodes = s.graph_->nodes(l);
            for (std::size_t k = 0; k < n; ++k)
                if (border_mask[nodes[k].value] != 0)
                {
                    const core::GridCoord c = g.coord(nodes[k]);
                    s.state_.u.at(c.x, c.y) = xu[k];
                }
        }
        s.model_->sync(s.state_.u);
    }

    void copy_own_to_display(const PartitionEntry* p)
    {
        refresh_my_leaves(p);
        for (const std::uint32_t l : my_leaves)
        {
            leaf_epoch[l] = p != nullptr ? p->epoch : 0;
            leaf_tick[l] = s.state_.tick;
            leaf_time[l] = s.state_.time;
            leaf_sender[l] = s.id_.value;
            leaf_coarsen[l] = 0;
            history[l].count = 0;
        }
        // The nodes themselves when the display is next read (flush_display): an exact-coupling
        // peer steps 1,000 times a second and its display is read at the frame rate.
        own_display_pending = true;
    }

    /// Writes our leaves' nodes of the state into the display (copy_own_to_display), if a step
    /// since the last flush left them behind. Every reader of display_u_/display_v_ calls it
    /// first; the other leaves' nodes are written as their states arrive.
    void flush_display()
    {
        if (!own_display_pending || !s.model_)
            return;
        own_display_pending = false;
        const double* su = s.state_.u.padded().data();
        const double* sv = s.state_.v.padded().data();
        double* du = s.display_u_.padded().data();
        double* dv = s.display_v_.padded().data();
        for (const std::uint32_t l : my_leaves)
        {
            // With quantised streaming every peer, this one included, shows the dequantised bits.
            const std::size_t n = quantised_stream() ? quantise_leaf(l) : 0;
            for_node_runs(l,
                          [&](std::size_t o, std::size_t i, std::size_t c)
                          {
                              copy_run(n != 0 ? xu.data() + i : su + o, c, du + o);
                              copy_run(n != 0 ? xv.data() + i : sv + o, c, dv + o);
                          });
        }
        s.model_->sync(s.display_u_);
        s.model_->sync(s.display_v_);
    }

    /// Coarse streaming, receiver side (docs/session.md §5.2): the leaves shown from coarse
    /// states get the butterfly refinement of the display restricted to the coarsest level
    /// received. With K the largest coarsening among the leaves not ours: restrict the display
    /// (twins synced) K levels, then refine level by level; after each refinement to level n - j
    /// (j >= 1), leaves received with a coarsening <= j overwrite their nodes of that level with
    /// what they received, so a finer stream is never made coarser by a coarser neighbour. Our
    /// own leaves only contribute their nodes at level n - K (as if streamed at K too), so what
    /// a participant shows of the others equals what a viewer shows. Finally the leaves received
    /// coarse take the refined values (their received nodes are unchanged: butterfly
    /// interpolates, and restrict/refine copy bits).
    void refine_display()
    {
        if (std::all_of(leaf_coarsen.begin(), leaf_coarsen.end(),
                        [](std::uint8_t k) { return k == 0; }))
            return;
        flush_display();
        // Our leaves as stream() sees them (read only: my_leaves is stream()'s to update).
        const PartitionEntry* p = stream_partition();
        std::fill(leaf_mine.begin(), leaf_mine.end(), 0);
        if (p != nullptr)
            for (std::size_t l = 0; l < p->owners.size() && l < leaf_mine.size(); ++l)
                leaf_mine[l] = p->owners[l] == s.id_ ? 1 : 0;
        int top = 0;
        for (std::size_t l = 0; l < leaf_coarsen.size(); ++l)
            if (leaf_mine[l] == 0)
                top = std::max(top, static_cast<int>(leaf_coarsen[l]));
        if (top == 0)
            return;
        const core::TetraGrid& g = s.model_->grid();
        const int n = g.level();
        if (coarse_plans.empty())
        {
            coarse_plans = subdiv::make_plans(n - max_coarsen, max_coarsen).value();
            for (int j = 1; j <= max_coarsen; ++j)
            {
                const core::TetraGrid& cg = plan(j).coarse_grid();
                coarse_u.emplace_back(cg, 1);
                coarse_v.emplace_back(cg, 1);
            }
            refined_u = core::Field<double>(g, 1);
            refined_v = core::Field<double>(g, 1);
        }
        refine_plane(top, s.display_u_, coarse_u, refined_u);
        refine_plane(top, s.display_v_, coarse_v, refined_v);
        for (std::size_t l = 0; l < leaf_coarsen.size(); ++l)
        {
            if (leaf_mine[l] != 0 || leaf_coarsen[l] == 0)
                continue;
            for (const core::NodeIndex node : s.graph_->nodes(l))
            {
                const core::GridCoord c = g.coord(node);
                s.display_u_.at(c.x, c.y) = refined_u.at(c.x, c.y);
                s.display_v_.at(c.x, c.y) = refined_v.at(c.x, c.y);
            }
        }
        s.model_->sync(s.display_u_);
        s.model_->sync(s.display_v_);
    }

    /// The plan refining level n - j to n - j + 1.
    const subdiv::ConvolutionPlan& plan(int j) const
    {
        return coarse_plans[static_cast<std::size_t>(max_coarsen - j)];
    }

    void refine_plane(int top, const core::Field<double>& display,
                      std::vector<core::Field<double>>& coarse, core::Field<double>& refined)
    {
        subdiv::restrict(plan(1), display, coarse[0]);
        for (int j = 2; j <= top; ++j)
            subdiv::restrict(plan(j), coarse[static_cast<std::size_t>(j - 2)],
                             coarse[static_cast<std::size_t>(j - 1)]);
        for (int j = top; j >= 1; --j)
        {
            core::Field<double>& out = j == 1 ? refined : coarse[static_cast<std::size_t>(j - 2)];
            subdiv::refine(plan(j), coarse[static_cast<std::size_t>(j - 1)], out);
            const int at = j - 1;  // out is level n - at
            if (at == 0)
                break;
            bool changed = false;
            for (std::size_t l = 0; l < leaf_coarsen.size(); ++l)
            {
                if (leaf_mine[l] != 0 || leaf_coarsen[l] == 0 || leaf_coarsen[l] > at)
                    continue;
                for (const core::NodeIndex node : s.graph_->nodes(l))
                {
                    const core::GridCoord c = s.model_->grid().coord(node);
                    if (on_coarse_level(c, at))
                        out.at(c.x >> at, c.y >> at) = display.at(c.x, c.y);
                }
                changed = true;
            }
            if (changed)
            {
                // out is the coarse level of plan(at), the input of the next refinement.
                core::sync_twins(plan(at).coarse_grid(), out);
                core::fill_ghosts(plan(at).coarse_grid(), out);
            }
        }
    }

    const PartitionEntry* stream_partition() const
    {
        if (s.coupling_ == Coupling::Fast)
            return newest();
        if (!lockstep || !state_exact)
            return nullptr;
        const std::uint64_t t = s.state_.tick;
        return t > exact_from ? partition_at(t - 1) : partition_at(t);
    }

    /// The baseline's u moved on by its v to `time` (u + v dt, then quantised) into pu; the owner
    /// and every receiver compute the same bits (the same doubles, no contraction). \return false
    /// if a value leaves the int32 range (the owner then does not extrapolate).
    bool extrapolate(const QuantisedLeaf& base, double time, std::size_t n)
    {
        const double su = net::quantum(base.u_exponent);
        const double sv = net::quantum(base.v_exponent);
        const double dt = time - base.time;
        for (std::size_t i = 0; i < n; ++i)
            xp[i] =
                static_cast<double>(base.qu[i]) * su + static_cast<double>(base.qv[i]) * sv * dt;
        return net::quantise(std::span(xp.data(), n), base.u_exponent, std::span(pu.data(), n));
    }

    /// The baseline `peer` acknowledged for leaf `l` that we still hold, or null.
    const QuantisedLeaf* acked_baseline(std::uint16_t peer, std::uint32_t l) const
    {
        auto it = acked.find(peer);
        if (it == acked.end() || it->second[l] == 0)
            return nullptr;
        const std::uint64_t tick = it->second[l] - 1;
        for (const QuantisedLeaf& q : sent[l])
            if (q.tick == tick && q.u_exponent == settings.u_step_exponent &&
                q.v_exponent == settings.v_step_exponent)
                return &q;
        return nullptr;
    }

    /// Codes qu, qv (n nodes) against `base` (null: a key state) into `m`. \return false if the
    /// packed residuals do not fit one datagram.
    bool code_leaf(net::LeafState& m, std::size_t n, const QuantisedLeaf* base)
    {
        const auto cu = std::span<const std::int32_t>(qu.data(), n);
        const auto cv = std::span<const std::int32_t>(qv.data(), n);
        auto bu = base != nullptr ? std::span<const std::int32_t>(base->qu) : cu.first(0);
        const auto bv = base != nullptr ? std::span<const std::int32_t>(base->qv) : cv.first(0);
        net::QuantisedDelta& q = m.quantised;
        q.baseline = base != nullptr ? static_cast<std::uint32_t>(s.state_.tick - base->tick) : 0;
        // Temporal prediction of u from the baseline's u and v where it pays.
        q.extrapolated = false;
        if (base != nullptr && extrapolate(*base, s.state_.time, n))
        {
            std::int64_t plain = 0;
            std::int64_t moved = 0;
            for (std::size_t i = 0; i < n; ++i)
            {
                plain += std::llabs(std::int64_t{cu[i]} - base->qu[i]);
                moved += std::llabs(std::int64_t{cu[i]} - pu[i]);
            }
            if (moved < plain)
            {
                q.extrapolated = true;
                bu = std::span<const std::int32_t>(pu.data(), n);
            }
        }
        q.u_exponent = static_cast<std::int8_t>(settings.u_step_exponent);
        q.v_exponent = static_cast<std::int8_t>(settings.v_step_exponent);
        q.predicted = net::prediction_pays(cu, bu, cv, bv);
        if (!net::make_residuals(cu, bu, q.predicted, std::span(ru.data(), n)) ||
            !net::make_residuals(cv, bv, q.predicted, std::span(rv.data(), n)))
            return false;
        q.du.assign(ru.begin(), ru.begin() + static_cast<std::ptrdiff_t>(n));
        q.dv.assign(rv.begin(), rv.begin() + static_cast<std::ptrdiff_t>(n));
        q.packing = settings.stream_packing;
        return q.packing == net::Packing::Rice
                   ? net::pack_residuals_rice(q.du, q.dv, net::k_max_packed_residuals, q.packed)
                   : net::pack_residuals(q.du, q.dv, net::k_max_packed_residuals, q.packed);
    }

    /// Adds quantised leaf state `m` to the LeafBatch being filled for `pid`, first sending that
    /// batch if `m` would take it over one datagram. \return the bytes this adds to the stream
    /// to `pid` (the leaf's record, plus a header and the batch's fixed part when it opens one).
    std::size_t batch_leaf(std::uint16_t pid, net::LeafState&& m, std::uint64_t tick)
    {
        net::BatchLeaf leaf{m.leaf, std::move(m.quantised)};
        const std::size_t record = net::batch_leaf_size(leaf);
        auto it = batch.find(pid);
        if (it != batch.end())
        {
            auto& b = std::get<net::LeafBatch>(it->second.body);
            if (b.leaves.size() < net::k_max_batch_leaves &&
                net::encoded_size(it->second) + record <=
                    net::k_header_size + net::k_max_state_payload)
            {
                b.leaves.push_back(std::move(leaf));
                return record;
            }
            send_to(pid, it->second, net::SendMode::Unsequenced);
            batch.erase(it);
        }
        net::LeafBatch b;
        b.epoch = m.epoch;
        b.time = m.time;
        b.u_exponent = static_cast<std::int8_t>(settings.u_step_exponent);
        b.v_exponent = static_cast<std::int8_t>(settings.v_step_exponent);
        b.leaves.push_back(std::move(leaf));
        batch.emplace(pid, make(b, tick));
        return net::k_header_size + net::k_leaf_batch_fixed + record;
    }

    /// Adds f32 / f64 leaf state `m` (whole leaf) to the ValueBatch being filled for `pid`,
    /// first sending that batch if `m` would take it over one datagram.
    void batch_values(std::uint16_t pid, const net::LeafState& m, std::uint64_t tick)
    {
        net::ValueLeaf leaf{m.leaf, m.u, m.v};
        const std::size_t record = net::value_leaf_size(leaf, m.encoding);
        auto it = batch.find(pid);
        if (it != batch.end())
        {
            auto* b = std::get_if<net::ValueBatch>(&it->second.body);
            if (b != nullptr && b->encoding == m.encoding && b->coarsen == m.coarsen &&
                b->leaves.front().leaf.depth == leaf.leaf.depth &&
                b->leaves.size() < net::k_max_batch_leaves &&
                net::encoded_size(it->second) + record <=
                    net::k_header_size + net::k_max_state_payload)
            {
                b->leaves.push_back(std::move(leaf));
                return;
            }
            send_to(pid, it->second, net::SendMode::Unsequenced);
            batch.erase(it);
        }
        net::ValueBatch b;
        b.epoch = m.epoch;
        b.time = m.time;
        b.encoding = m.encoding;
        b.coarsen = m.coarsen;
        b.leaves.push_back(std::move(leaf));
        batch.emplace(pid, make(b, tick));
    }

    /// Sends every LeafBatch or ValueBatch being filled (the end of a stream period).
    void flush_batches()
    {
        for (const auto& [pid, m] : batch)
            send_to(pid, m, net::SendMode::Unsequenced);
        batch.clear();
    }

    /// Whether a receiver that acknowledged `base` (an entry of `entries`) shows exactly the
    /// leaf's quantised values now (qu, qv: `n` of each): `base` holds them, and so does every
    /// entry sent after it, which the receiver may have taken instead. Comparing values and
    /// not entries: with two receivers acknowledging different entries of a leaf at rest, each
    /// all-zero delta sent to one added an entry the other had not acknowledged, and the leaf
    /// went out every stream period, to each in turn.
    [[nodiscard]] bool shows_now(const std::deque<QuantisedLeaf>& entries,
                                 const QuantisedLeaf& base, std::size_t n) const
    {
        const auto same = [&](const QuantisedLeaf& e)
        {
            return e.qu.size() == n && e.qv.size() == n &&
                   std::equal(e.qu.begin(), e.qu.end(), qu.begin()) &&
                   std::equal(e.qv.begin(), e.qv.end(), qv.begin());
        };
        for (auto it = entries.rbegin(); it != entries.rend(); ++it)
        {
            if (!same(*it))
                return false;
            if (&*it == &base)
                return true;
        }
        return false;  // not in the history (cannot be: acked_baseline returns one of it)
    }

    /// Quantised streaming of leaf `l` to every peer (docs/protocol.md §5.5). \return false if
    /// the leaf's values do not quantise (the caller sends f64).
    bool stream_quantised(const PartitionEntry* p, std::uint32_t l)
    {
        const std::size_t n = quantise_leaf(l);
        if (n == 0)
        {
            sent[l].clear();
            return false;
        }
        const core::LeafId id = s.graph_->leaves()[l];
        const std::uint64_t tick = s.state_.tick;
        bool any = false;
        // A quiescent leaf is re-sent now and then, so receivers can tell it from a lost one.
        const bool refresh = settings.quiescent_refresh_s > 0.0 &&
                             s.state_.time - leaf_sent_time[l] >= settings.quiescent_refresh_s;
        for (const auto& [pid, peer] : peers)
        {
            if (peer.departed || !peer.handle || !peer.has_model)
                continue;
            const QuantisedLeaf* base = acked_baseline(pid, l);
            std::vector<double>* prio = capped() ? &priority[pid] : nullptr;
            if (prio != nullptr)
                prio->resize(s.graph_->size(), 0.0);
            if (base != nullptr && !refresh && shows_now(sent[l], *base, n))
            {
                ++counters.quiescent_skips;  // the receiver shows exactly this already
                if (prio != nullptr)
                    (*prio)[l] = 0.0;
                continue;
            }
            if (prio != nullptr && budget[pid] <= 0.0)
            {
                // Over this peer's budget: wait, more urgently near the action.
                (*prio)[l] += 1.0 + (near_interest[l] != 0 ? settings.interest_boost : 0.0);
                ++counters.capped_skips;
                continue;
            }
            if (base != nullptr && base->tick >= tick)
                base = nullptr;
            net::LeafState m;
            m.epoch = p->epoch;
            m.leaf = net::WireLeafId{id.square, id.depth, id.ix, id.iy};
            m.encoding = net::ValueEncoding::QuantisedDelta;
            m.time = s.state_.time;
            bool coded = code_leaf(m, n, base);
            if (!coded && base != nullptr)
            {
                base = nullptr;
                coded = code_leaf(m, n, nullptr);
            }
            if (!coded)
            {
                // Incompressible: the same dequantised bits as f64, outside the baseline chain.
                m.encoding = net::ValueEncoding::F64;
                m.quantised = {};
                m.u.assign(xu.begin(), xu.begin() + static_cast<std::ptrdiff_t>(n));
                m.v.assign(xv.begin(), xv.begin() + static_cast<std::ptrdiff_t>(n));
            }
            else
            {
                any = true;
                if (base == nullptr)
                    ++counters.key_states_sent;
            }
            ++counters.leaf_states_sent;
            if (coded && settings.batch_leaves)
            {
                const std::size_t bytes = batch_leaf(pid, std::move(m), tick);
                if (prio != nullptr)
                {
                    budget[pid] -= static_cast<double>(bytes);
                    (*prio)[l] = 0.0;
                }
                leaf_sent_time[l] = s.state_.time;
                continue;
            }
            const net::Message msg = make(m, tick);
            if (prio != nullptr)
            {
                budget[pid] -= static_cast<double>(net::encoded_size(msg));
                (*prio)[l] = 0.0;
            }
            send_to(pid, msg, net::SendMode::Unsequenced);
            leaf_sent_time[l] = s.state_.time;
        }
        if (any)
        {
            std::deque<QuantisedLeaf>& h = sent[l];
            if (!h.empty() && h.back().tick == tick)
                h.pop_back();
            if (h.size() >= k_baseline_window)
                h.pop_front();
            h.push_back(QuantisedLeaf{
                s.id_.value, tick, s.state_.time, settings.u_step_exponent,
                settings.v_step_exponent,
                std::vector<std::int32_t>(qu.begin(), qu.begin() + static_cast<std::ptrdiff_t>(n)),
                std::vector<std::int32_t>(qv.begin(),
                                          qv.begin() + static_cast<std::ptrdiff_t>(n))});
        }
        return true;
    }

    [[nodiscard]] bool capped() const noexcept
    {
        return quantised_stream() && settings.bandwidth_cap_mbit_s > 0.0;
    }

    /// Bandwidth cap: refills every peer's budget for one stream period and orders our leaves by
    /// their total priority (highest first, then by index).
    void plan_capped_stream()
    {
        refresh_interest();
        const double per_period =
            settings.bandwidth_cap_mbit_s * 1e6 / 8.0 / settings.stream_rate_hz;
        for (const auto& [pid, peer] : peers)
        {
            if (peer.departed || !peer.handle)
                continue;
            double& b = budget[pid];
            b = std::min(b + per_period, 2.0 * per_period);
        }
        order = my_leaves;
        std::vector<double> total(s.graph_->size(), 0.0);
        for (const auto& [pid, prio] : priority)
            for (const std::uint32_t l : my_leaves)
                if (l < prio.size())
                    total[l] += prio[l];
        std::stable_sort(order.begin(), order.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return total[a] > total[b]; });
    }

    void stream()
    {
        const PartitionEntry* p = stream_partition();
        if (p == nullptr)
            return;
        refresh_my_leaves(p);
        const core::TetraGrid& g = s.model_->grid();
        if (capped())
            plan_capped_stream();
        for (const std::uint32_t l : capped() ? order : my_leaves)
        {
            if (quantised_stream() && stream_quantised(p, l))
                continue;
            // One message for every leaf and period: its vectors keep their capacity.
            if (!std::holds_alternative<net::LeafState>(stream_msg.body))
                stream_msg.body = net::LeafState{};
            stream_msg.header.session = session_id;
            stream_msg.header.sender = s.id_;
            stream_msg.header.tick = s.state_.tick;
            net::LeafState& m = std::get<net::LeafState>(stream_msg.body);
            m.epoch = p->epoch;
            const core::LeafId id = s.graph_->leaves()[l];
            m.leaf = net::WireLeafId{id.square, id.depth, id.ix, id.iy};
            m.encoding = settings.stream_encoding;
            m.coarsen = static_cast<std::uint8_t>(settings.stream_coarsen);
            m.node_offset = 0;
            m.time = s.state_.time;
            m.u.clear();
            m.v.clear();
            if (settings.stream_coarsen == 0)
            {
                const double* su = s.state_.u.padded().data();
                const double* sv = s.state_.v.padded().data();
                m.u.resize(s.graph_->node_count(l));
                m.v.resize(m.u.size());
                for_node_runs(l,
                              [&](std::size_t o, std::size_t i, std::size_t c)
                              {
                                  copy_run(su + o, c, m.u.data() + i);
                                  copy_run(sv + o, c, m.v.data() + i);
                              });
            }
            else
                // Coarse streaming: the leaf's canonical nodes on level n - k, row-major.
                for (const core::NodeIndex n : s.graph_->nodes(l))
                {
                    const core::GridCoord c = g.coord(n);
                    if (!on_coarse_level(c, settings.stream_coarsen))
                        continue;
                    m.u.push_back(s.state_.u.at(c.x, c.y));
                    m.v.push_back(s.state_.v.at(c.x, c.y));
                }
            if (quantised_stream())
                m.encoding = net::ValueEncoding::F64;
            // Coarse leaves are a few nodes each: they go several to a datagram (ValueBatch,
            // docs/protocol.md §6) rather than each with a LeafState's 48 fixed bytes.
            const bool batched = settings.batch_leaves && m.coarsen > 0;
            stream_to.clear();
            for (const auto& [pid, peer] : peers)
                if (!peer.departed && peer.handle && peer.has_model)
                {
                    ++counters.leaf_states_sent;
                    if (batched)
                        batch_values(pid, m, s.state_.tick);
                    else
                        stream_to.push_back(*peer.handle);
                }
            if (!stream_to.empty())
            {
                // Encoded once for every receiver.
                if (auto r = messenger.send(stream_to, stream_msg, net::SendMode::Unsequenced); !r)
                    spdlog::debug("session: stream send failed: {}", r.error().message);
            }
            leaf_sent_time[l] = s.state_.time;
        }
        flush_batches();
    }

    // --- leaving -------------------------------------------------------------------------------

    void finish_leave_soon()
    {
        // The others disconnect us once past the hand-over; a timeout guards against a peer that
        // never does.
        if (last_now - leave_started > k_leave_timeout_s)
            close_all(net::DisconnectReason::Quit);
    }

    void close_all(net::DisconnectReason reason)
    {
        for (const net::PeerHandle h : transport.peers())
            transport.disconnect(h, reason);
        transport.flush();
        s.left_ = true;
    }

    void disconnect_finished_leavers()
    {
        const std::uint64_t t = s.state_.tick;
        for (auto& [id, p] : peers)
            if (p.leaving && !p.departed && p.handle && !member(partition_at(t), net::PeerId{id}) &&
                !member(t > 0 ? partition_at(t - 1) : nullptr, net::PeerId{id}))
            {
                transport.disconnect(*p.handle, net::DisconnectReason::Quit);
                p.departed = true;
            }
    }

    // --- receiving -----------------------------------------------------------------------------

    void on_connected(net::PeerHandle h)
    {
        if (master_handle && h == *master_handle && !welcomed)
        {
            master_connected = true;
            // Asking to be admitted: reliable only (a repeat would be a second joiner).
            net::Message m;
            m.header.sender = net::k_no_peer;
            m.body = make_hello();
            (void)messenger.send(h, m);
            return;
        }
        auto it = dialing.find(h);
        if (it == dialing.end())
        {
            // Someone dialled us: it has k_greeting_deadline_s to say who it is, counted from
            // the caller's next advance() if none has come yet (NaN until then).
            ungreeted[h] = advanced ? last_now : std::numeric_limits<double>::quiet_NaN();
            return;
        }
        (void)messenger.send(h, make(make_hello(), s.state_.tick));
        const std::uint16_t id = it->second;
        bind(h, id);
        dialing.erase(it);
        RemotePeer& p = peers[id];
        if (!p.heard)
            p.hello_repeat_until = last_now + k_greeting_repeat_s;
    }

    /// Closes the incoming connections that have not greeted within k_greeting_deadline_s of the
    /// caller's clock (a bound connection has greeted: its entry is dropped).
    void close_ungreeted()
    {
        for (auto it = ungreeted.begin(); it != ungreeted.end();)
        {
            if (std::isnan(it->second))
                it->second = last_now;
            if (handle_ids.contains(it->first))
                it = ungreeted.erase(it);
            else if (last_now - it->second > k_greeting_deadline_s)
            {
                const auto address = transport.remote_address(it->first);
                spdlog::warn("session: the connection from {} sent no Hello within {:g} s: closed",
                             address ? net::to_string(*address) : std::string("?"),
                             k_greeting_deadline_s);
                ++counters.ungreeted_closed;
                transport.disconnect(it->first, net::DisconnectReason::TimedOut);
                it = ungreeted.erase(it);
            }
            else
                ++it;
        }
    }

    void on_disconnected(net::PeerHandle h, net::DisconnectReason reason)
    {
        ungreeted.erase(h);
        auto ls = last_stats.find(h);
        if (ls != last_stats.end())
        {
            closed_stats.bytes_sent += ls->second.bytes_sent;
            closed_stats.bytes_received += ls->second.bytes_received;
            closed_stats.packets_sent += ls->second.packets_sent;
            closed_stats.packets_received += ls->second.packets_received;
            closed_stats.bad_datagrams += ls->second.bad_datagrams;
            last_stats.erase(ls);
        }
        lose_peer(h, reason);
    }

    /// The session's part of a disconnection (on_disconnected without the traffic counters):
    /// the peer on `h` is gone; the master tells the others and re-partitions.
    void lose_peer(net::PeerHandle h, net::DisconnectReason reason)
    {
        auto it = handle_ids.find(h);
        if (it == handle_ids.end())
        {
            if (master_handle && h == *master_handle && !welcomed)
            {
                // Refused or unreachable: keep why, a joiner's user has nothing else to go on.
                if (!join_lost)
                    join_lost = reason;
                spdlog::debug("session: connection to the master ended before the Welcome ({})",
                              net::to_string(reason));
                s.left_ = true;
            }
            return;
        }
        const std::uint16_t id = it->second;
        handle_ids.erase(it);
        RemotePeer& p = peers[id];
        p.handle.reset();
        p.departed = true;
        spdlog::debug("session: peer {} disconnected ({})", id, net::to_string(reason));
        if (net::PeerId{id} == master_id && s.role_ != SessionRole::Master &&
            reason == net::DisconnectReason::Shutdown)
            close_all(net::DisconnectReason::Shutdown);  // the master ended the session
        else if (net::PeerId{id} == master_id && s.role_ != SessionRole::Master &&
                 reason == net::DisconnectReason::Kicked)
        {
            // The master removed us (exact coupling: we held the lockstep past its
            // max_barrier_wait_s). The others drop us too; taking over as master would split
            // the session.
            refusal =
                "the master removed this peer from the session (in exact coupling, a "
                "peer that publishes no step for its max_barrier_wait_s, 10 s by default, "
                "is removed: was this process stopped or far too slow?)";
            close_all(net::DisconnectReason::Quit);
        }
        else
            lost_pending.emplace_back(id, reason);  // settle_losses(), once the clock is known
        if (leaving && handle_ids.empty())
            s.left_ = true;
    }

    /// Handles the departures lose_peer noticed: a participant or viewer whose master is gone
    /// follows the successor (or becomes it); a master tells the others and re-partitions. Run
    /// from advance(), after the pause check: a process resumed after a stop past its own
    /// transport's longest timeout (ENet: 30 s) sees every peer time out in its first poll(),
    /// before the advance() that shows the gap, and those departures are its own removal, not
    /// the others' (pause_s).
    void settle_losses()
    {
        if (lost_pending.empty())
            return;
        const auto lost = std::move(lost_pending);
        lost_pending.clear();
        if (s.left_ || dropped_after_pause(lost))
            return;
        follow_master();
        if (s.role_ != SessionRole::Master || s.left_)
            return;
        for (const auto& [id, reason] : lost)
        {
            net::PeerLeft msg;
            msg.peer = net::PeerId{id};
            msg.reason =
                reason == net::DisconnectReason::None ? net::DisconnectReason::TimedOut : reason;
            send_all(make(msg, s.state_.tick));
        }
        repartition_pending = true;
        if (s.coupling_ == Coupling::Fast)
            master_repartition(s.state_.tick);
    }

    /// Whether `lost` is this peer's own removal after a pause (SessionSettings::pause_s): the
    /// others dropped it while it did not run and went on without it. Then it leaves, saying
    /// so, instead of following a successor of its own choosing (a master: instead of going on
    /// with what is left), which would split the session in two.
    bool dropped_after_pause(
        const std::vector<std::pair<std::uint16_t, net::DisconnectReason>>& lost)
    {
        if (!pause_suspect)
            return false;
        // Only a loss by timeout tells: a peer that said goodbye (Quit, a leave or a diverged
        // step; Shutdown, handled in lose_peer) left on its own, and Kicked is this master's own
        // removal of a member (wait_at_barrier).
        bool ours = false;
        for (const auto& [id, reason] : lost)
        {
            const RemotePeer& p = peers.at(id);
            if ((reason != net::DisconnectReason::TimedOut &&
                 reason != net::DisconnectReason::None) ||
                p.leaving)
                continue;
            ours = ours || (s.role_ != SessionRole::Master ? net::PeerId{id} == master_id
                                                           : p.info.role == net::Role::Participant);
        }
        if (!ours)
            return false;
        leave_after_pause();
        return true;
    }

    /// The peers whose silence after a pause tells that this peer was dropped: its master, or
    /// (the master) the participants.
    bool pause_witness(std::uint16_t id, const RemotePeer& p) const
    {
        if (p.departed || p.leaving)
            return false;
        return s.role_ == SessionRole::Master ? p.info.role == net::Role::Participant
                                              : net::PeerId{id} == master_id;
    }

    /// While pause_suspect: a message from a witness (pause_witness) clears it; a silence of
    /// every witness's link for k_pause_silence_s since the pause (the transport hears not even
    /// an acknowledgement: the far end dropped this peer) means this peer was dropped.
    void check_pause()
    {
        if (!pause_suspect || s.left_)
            return;
        const double since = last_now - pause_end;
        if (since > k_pause_suspect_s)
        {
            pause_suspect = false;
            return;
        }
        bool any = false;
        bool silent = true;
        for (const auto& [id, p] : peers)
        {
            if (!pause_witness(id, p))
                continue;
            if (p.heard_at > pause_end)
            {
                pause_suspect = false;  // it still sends to us: still a member
                return;
            }
            any = true;
            const auto st = p.handle ? transport.stats(*p.handle) : std::nullopt;
            silent = silent && st && st->silent_s >= k_pause_silence_s;
        }
        if (any && silent && since >= k_pause_silence_s)
            leave_after_pause();
    }

    void leave_after_pause()
    {
        pause_suspect = false;
        const char* who = s.role_ == SessionRole::Master   ? "master"
                          : s.role_ == SessionRole::Viewer ? "viewer"
                                                           : "participant";
        const char* then =
            s.role_ == SessionRole::Master
                ? "it left rather than run a second session beside theirs (their participant "
                  "with the lowest id takes over as master): join their session through it, or "
                  "host a new one"
            : s.role_ == SessionRole::Viewer
                ? "it left: join again (through the master's address: it may have changed)"
                : "it left rather than run a second session beside theirs: join again (through "
                  "the master's address: it may have changed)";
        refusal = fmt::format(
            "this {} did not run for {:.1f} s (the process was stopped, suspended or starved), "
            "longer than the others wait for a silent peer: they dropped it and went on without "
            "it (or left while it was stopped, their goodbye lost); {}",
            who, pause_length, then);
        close_all(net::DisconnectReason::Quit);
    }

    /// Notes a pause (no advance() for SessionSettings::pause_s) ending at `now`, after `gap`.
    void note_pause(double now, double gap)
    {
        pause_end = now;
        pause_length = gap;
        pause_suspect = true;
        ++counters.pauses;
        counters.longest_pause_s = std::max(counters.longest_pause_s, gap);
        // A wait at the barrier restarts: the time this peer did not run is nobody's fault.
        if (barrier_since >= 0.0)
            barrier_since = now;
        spdlog::warn(
            "session: this peer did not run for {:.1f} s (the process was stopped, suspended or "
            "starved); the others drop a peer silent for their transport's timeout (5-30 s)",
            gap);
    }

    // --- failover (docs/session.md §6) ----------------------------------------------------------

    /// The lowest id among the participants this peer knows to be alive and staying, itself
    /// included: the same on every peer once each has noticed the same departures.
    /// `without`: as if that peer were gone too.
    std::optional<net::PeerId> successor(std::optional<net::PeerId> without = std::nullopt) const
    {
        std::optional<net::PeerId> best;
        if (s.role_ != SessionRole::Viewer && !leaving)
            best = s.id_;
        for (const auto& [id, p] : peers)
            if (!p.departed && !p.leaving && p.info.role == net::Role::Participant &&
                (!without || id != without->value) && (!best || id < best->value))
                best = net::PeerId{id};
        return best;
    }

    /// If the master we follow is gone, follows its successor (or becomes it). Called on every
    /// departure, so a successor that was itself lost is replaced in turn.
    void follow_master()
    {
        // A leaver follows too (its hand-over needs the successor's partition), but never
        // becomes master itself (successor() leaves it out).
        if (s.role_ == SessionRole::Master || s.left_)
            return;
        auto it = peers.find(master_id.value);
        if (it != peers.end() && !it->second.departed)
            return;
        const auto next = successor();
        if (leaving && !next)
        {
            close_all(net::DisconnectReason::Quit);  // our leave is done: nobody left to hand to
            return;
        }
        if (!s.model_)
        {
            // Nothing to continue with: the model was still arriving. Said as the refusal, which
            // `pliant join` and the viewer report.
            refusal = "the master (peer " + std::to_string(master_id.value) +
                      ") was lost before this peer had the model; join the session again "
                      "through its new master, the participant with the lowest id";
            spdlog::warn("session: {}", refusal);
            close_all(net::DisconnectReason::Quit);
            return;
        }
        if (!next)
        {
            spdlog::warn("session: master {} lost and no successor; the session ends",
                         master_id.value);
            close_all(net::DisconnectReason::Quit);
            return;
        }
        if (leaving)  // our own leave: nothing the user needs to hear about
            spdlog::debug("session: leaving; master {} gone, following peer {}", master_id.value,
                          next->value);
        else
            spdlog::info("session: master {} lost; peer {} takes over", master_id.value,
                         next->value);
        master_id = *next;
        if (*next == s.id_)
        {
            promote();
            return;
        }
        // Partitions it sent before we noticed the loss.
        auto kept = foreign_partitions.find(next->value);
        if (kept != foreign_partitions.end())
        {
            auto list = std::move(kept->second);
            foreign_partitions.erase(kept);
            for (const auto& [tick, p] : list)
                apply_partition(tick, p);
        }
        foreign_partitions.clear();
    }

    /// This peer becomes master: it partitions from now on (epochs above any seen), admits
    /// joiners (ids above any known) and reports departures. It records nothing: a recording
    /// needs every input from the start.
    void promote()
    {
        s.role_ = SessionRole::Master;
        ++counters.promotions;
        // Joiners from now on must dial this peer: say where (`pliant join` listens on a port
        // of the system's choosing unless given --port).
        if (settings.listen_port != 0)
            spdlog::info("session: this peer (id {}) is the master now; joiners dial it on port {}",
                         s.id_.value, settings.listen_port);
        else
            spdlog::info("session: this peer (id {}) is the master now", s.id_.value);
        foreign_partitions.clear();
        const PartitionEntry* cur = newest();
        if (cur != nullptr)
            next_epoch = std::max(next_epoch, cur->epoch + k_successor_epoch_gap);
        std::uint16_t top = s.id_.value;
        for (const auto& [id, p] : peers)
            top = std::max(top, id);
        next_peer_id = std::max<std::uint16_t>(
            next_peer_id,
            static_cast<std::uint16_t>(std::min<int>(top + k_successor_id_gap, 0xFFFE)));
        // Participants partitioned before are ready even if their points never reached us.
        for (auto& [id, p] : peers)
            if (member(cur, net::PeerId{id}) && p.info.role == net::Role::Participant)
                p.ready = true;
        points_dirty = false;
        repartition_pending = true;
        if (s.coupling_ == Coupling::Exact && !lockstep)
        {
            // Not partitioned yet: start the lockstep from what we show.
            lockstep = true;
            published = false;
            state_exact = true;
            exact_from = s.state_.tick;
            flush_display();
            const core::TetraGrid& g = s.model_->grid();
            for (int y = 0; y < g.ny(); ++y)
                for (int x = 0; x < g.nx(); ++x)
                {
                    s.state_.u.at(x, y) = s.display_u_.at(x, y);
                    s.state_.v.at(x, y) = s.display_v_.at(x, y);
                }
        }
        // Tell the others which departures we saw (they may not have noticed them yet).
        for (const auto& [id, p] : peers)
            if (p.departed && !p.leaving)
            {
                net::PeerLeft msg;
                msg.peer = net::PeerId{id};
                msg.reason = net::DisconnectReason::TimedOut;
                send_all(make(msg, s.state_.tick));
            }
    }

    void on_hello(net::PeerHandle h, const net::Message& m, const net::Hello& hello)
    {
        if (s.role_ == SessionRole::Master && m.header.sender == net::k_no_peer)
        {
            // A Welcome lists every peer, itself and the joiner included, at most
            // k_max_welcome_peers: a joiner beyond that would get a Welcome that cannot be
            // encoded (it waited for ever for its model).
            std::size_t members = 2;  // this master and the joiner
            for (const auto& [oid, op] : peers)
                members += !op.departed && op.info_known ? 1 : 0;
            if (!s.model_ || next_peer_id >= 0xFFFE || members > net::k_max_welcome_peers)
            {
                if (members > net::k_max_welcome_peers && last_now - warned_full_at >= 10.0)
                {
                    warned_full_at = last_now;
                    spdlog::warn(
                        "session: a joiner was refused: the session holds {} peers, "
                        "the most it can",
                        net::k_max_welcome_peers);
                }
                transport.disconnect(h, net::DisconnectReason::SessionFull);
                return;
            }
            const std::uint16_t id = next_peer_id++;
            RemotePeer& p = peers[id];
            p.info.id = net::PeerId{id};
            p.info.role = hello.role;
            const auto addr = transport.remote_address(h);
            p.info.ipv4 = addr ? addr->ipv4 : std::array<std::uint8_t, 4>{127, 0, 0, 1};
            p.info.port = hello.listen_port != 0 ? hello.listen_port : (addr ? addr->port : 1);
            if (p.info.port == 0)
                p.info.port = 1;
            p.info.name = hello.name;
            p.info_known = true;
            bind(h, id);
            send_welcome(id);
            net::PeerJoined joined;
            joined.peer = p.info;
            for (auto& [oid, op] : peers)
                if (oid != id)
                    send_to(oid, make(joined, s.state_.tick));
            return;
        }
        if (m.header.sender == net::k_no_peer)
        {
            // Only the master admits: a joiner that dialled another peer (say, one that knew an
            // old master's successor by the wrong address) is refused at once, not left waiting.
            if (handle_ids.count(h) == 0)
                transport.disconnect(h, net::DisconnectReason::Refused);
            return;
        }
        // A peer greeting us after its Welcome.
        if (handle_ids.count(h) != 0)
            return;
        // Each joiner dials each peer once and ids are never reused: a second connection for
        // an id already connected, or departed, is someone else's claim to that peer's place
        // (its forces, its leaves' halos), refused before it could take the first one's link.
        if (const auto known = peers.find(m.header.sender.value);
            known != peers.end() && (known->second.handle || known->second.departed))
        {
            reject(counters.peer_claim_rejects, h,
                   "a Hello claiming the id of peer " + std::to_string(m.header.sender.value) +
                       ", already connected or departed");
            transport.disconnect(h, net::DisconnectReason::Refused);
            return;
        }
        bind(h, m.header.sender.value);
        RemotePeer& p = peers[m.header.sender.value];
        if (!p.info_known)
        {
            // Its PeerJoined may still be on its way; the master's word replaces this then.
            p.info.role = hello.role;
            p.info.name = hello.name;
        }
        greet_new_peer(m.header.sender.value);
    }

    /// Sends a newly known peer what it needs from us that it cannot have seen: that we can take
    /// leaf states, our points of interest, our newest force.
    void greet_new_peer(std::uint16_t id)
    {
        if (s.model_)
            send_ready(id);
        if (points_sent && s.role_ != SessionRole::Viewer && !leaving)
        {
            net::PointsOfInterest poi;
            poi.points = my_points;
            send_to(id, make(poi, s.state_.tick));
        }
        for (const ForceEntry& e : my_forces)
        {
            net::Force f;
            f.forces = e.forces;
            send_to(id, make(f, e.apply_tick));
        }
    }

    /// Sends the Welcome's blob chunks to the joiners being fed while their connections hold
    /// less than k_feed_window_bytes; a finished feed lets the messages that waited behind it go.
    void feed_blobs()
    {
        if (feeding == 0)
            return;
        for (auto& [id, p] : peers)
        {
            if (!p.feed)
                continue;
            if (!p.handle || p.departed)
            {
                p.feed.reset();
                p.after_feed.clear();
                --feeding;
                continue;
            }
            RemotePeer::BlobFeed& f = *p.feed;
            const std::size_t total = f.model->size() + f.state->size();
            // Bounded: one chunk per pass, at most the window's worth per call.
            for (int guard = 0; guard < 64 && f.next < total &&
                                transport.queued_bytes(*p.handle) < k_feed_window_bytes;
                 ++guard)
            {
                const bool in_model = f.next < f.model->size();
                const std::vector<std::byte>& blob = in_model ? *f.model : *f.state;
                const std::size_t off = in_model ? f.next : f.next - f.model->size();
                net::Blob b;
                b.kind = in_model ? net::BlobKind::Model : net::BlobKind::State;
                b.total_size = static_cast<std::uint32_t>(blob.size());
                b.offset = static_cast<std::uint32_t>(off);
                const std::size_t len = std::min(net::k_max_blob_chunk, blob.size() - off);
                b.data.assign(blob.begin() + static_cast<std::ptrdiff_t>(off),
                              blob.begin() + static_cast<std::ptrdiff_t>(off + len));
                (void)messenger.send(*p.handle, make(b, f.tick));
                f.next += len;
            }
            if (f.next < total)
                continue;
            p.feed.reset();
            --feeding;
            auto waiting = std::move(p.after_feed);
            p.after_feed.clear();
            for (auto& [m, mode] : waiting)
                (void)messenger.send(*p.handle, m, mode);
        }
    }

    std::shared_ptr<const std::vector<std::byte>> model_blob_shared;
    std::size_t feeding = 0;  // peers with a feed

    void send_welcome(std::uint16_t id)
    {
        const core::TetraGrid& g = s.model_->grid();
        if (!model_blob_shared)  // the model never changes: encoded once, shared by every feed
            model_blob_shared = std::make_shared<const std::vector<std::byte>>(
                encode_model(*s.model_, s.coupling_, s.clearance_, settings.max_barrier_wait_s));
        const std::vector<std::byte>& model = *model_blob_shared;
        flush_display();
        auto state = encode_state(g, s.display_u_, s.display_v_, s.state_.tick, s.state_.time);
        net::Welcome w;
        w.your_id = net::PeerId{id};
        w.master_id = s.id_;
        w.grid_level = static_cast<std::uint8_t>(g.level());
        w.leaf_depth = static_cast<std::uint8_t>(s.graph_->depth());
        w.epoch = newest() != nullptr ? newest()->epoch : 0;
        w.time = s.state_.time;
        w.model_size = static_cast<std::uint32_t>(model.size());
        w.model_hash = core::hash_bytes(model);
        w.state_size = static_cast<std::uint32_t>(state.size());
        w.state_hash = core::hash_bytes(state);
        net::PeerInfo me = my_info_known ? my_info : net::PeerInfo{};
        me.id = s.id_;
        me.role = net::Role::Participant;
        if (!my_info_known)
        {
            me.port = settings.listen_port != 0 ? settings.listen_port : 1;
            me.name = settings.name;
        }
        w.peers.push_back(me);
        for (const auto& [oid, op] : peers)
            if (!op.departed && op.info_known && w.peers.size() < net::k_max_welcome_peers)
                w.peers.push_back(op.info);
        send_to(id, make(w, s.state_.tick));
        // The blobs follow as the connection drains (feed_blobs); what is sent to the joiner
        // from here on waits behind them.
        RemotePeer& joiner = peers[id];
        joiner.feed = RemotePeer::BlobFeed{
            model_blob_shared, std::make_shared<const std::vector<std::byte>>(std::move(state)), 0,
            s.state_.tick};
        ++feeding;
        // The partitions the joiner needs to follow the lockstep, then our forces.
        for (const PartitionEntry& p : partitions)
        {
            net::Partition msg;
            msg.epoch = p.epoch;
            msg.leaf_depth = static_cast<std::uint8_t>(s.graph_->depth());
            msg.owners = p.owners;
            send_to(id, make(msg, p.apply_tick));
        }
        greet_new_peer(id);
        feed_blobs();
    }

    void on_welcome(net::PeerHandle h, const net::Message& m, const net::Welcome& w)
    {
        if (welcomed || !master_handle || h != *master_handle)
            return;
        welcomed = true;
        welcome = w;
        welcome_tick = m.header.tick;
        welcome_now = last_now;
        s.id_ = w.your_id;
        master_id = w.master_id;
        session_id = m.header.session;
        messenger.set_session(session_id);
        bind(h, master_id.value);
        model_blob.assign(w.model_size, std::byte{0});
        state_blob.assign(w.state_size, std::byte{0});
        for (const net::PeerInfo& info : w.peers)
        {
            if (info.id == s.id_)
            {
                my_info = info;
                my_info_known = true;
                continue;
            }
            RemotePeer& p = peers[info.id.value];
            p.info = info;
            p.info_known = true;
            if (info.id == master_id)
                continue;
            auto handle = transport.connect(net::Address{info.ipv4, info.port});
            if (handle)
                dialing[*handle] = info.id.value;
        }
    }

    void on_blob(const net::Blob& b)
    {
        if (!welcomed || s.model_ || s.left_)  // left: refused a chunk already
            return;
        std::vector<std::byte>& dst = b.kind == net::BlobKind::Model ? model_blob : state_blob;
        std::size_t& got = b.kind == net::BlobKind::Model ? model_got : state_got;
        // The master sends each blob's chunks in order on the reliable, ordered channel, so each
        // starts where the previous one ended; anything else (a gap, an overlap, another total)
        // is a faulty master, and the blob could complete with a hole or never: refused now.
        if (b.total_size != dst.size() || b.offset != got || b.data.size() > dst.size() - got)
        {
            const char* what = b.kind == net::BlobKind::Model ? "model" : "state";
            spdlog::error(
                "session: the master's {} blob chunk of {} bytes at byte {} of {}, "
                "where byte {} of {} was next",
                what, b.data.size(), b.offset, b.total_size, got, dst.size());
            refusal = std::string("the master sent a chunk of its ") + what + " blob at byte " +
                      std::to_string(b.offset) + " (" + std::to_string(b.data.size()) +
                      " bytes of " + std::to_string(b.total_size) + ") where byte " +
                      std::to_string(got) + " of " + std::to_string(dst.size()) +
                      " was next: chunks must follow each other in order (docs/protocol.md, Blob)";
            close_all(net::DisconnectReason::ProtocolMismatch);
            return;
        }
        std::copy(b.data.begin(), b.data.end(), dst.begin() + b.offset);
        got += b.data.size();
        if (model_got < model_blob.size() || state_got < state_blob.size())
            return;
        if (core::hash_bytes(model_blob) != welcome.model_hash ||
            core::hash_bytes(state_blob) != welcome.state_hash)
        {
            spdlog::error("session: model or state blob hash mismatch");
            refusal = "the master's model or state blob does not match its hash";
            close_all(net::DisconnectReason::ProtocolMismatch);
            return;
        }
        auto decoded = decode_model(model_blob);
        if (!decoded)
        {
            spdlog::error("session: {}", decoded.error().message);
            refusal = decoded.error().message;
            close_all(net::DisconnectReason::ProtocolMismatch);
            return;
        }
        std::optional<DecodedState> state;
        if (!state_blob.empty())
        {
            auto st = decode_state(decoded->model.grid(), state_blob);
            if (!st)
            {
                // The master's state cannot be taken: stepping on from rest would diverge.
                spdlog::error("session: {}", st.error().message);
                refusal = st.error().message;
                close_all(net::DisconnectReason::ProtocolMismatch);
                return;
            }
            state = std::move(*st);
        }
        s.coupling_ = decoded->coupling;
        s.clearance_ = decoded->clearance;
        // The session's limit, which this peer applies if it becomes the master (the joiner's
        // own setting is not used, as for the clearance).
        if (decoded->max_barrier_wait_s)
            settings.max_barrier_wait_s = *decoded->max_barrier_wait_s;
        install_model(std::move(decoded->model));
        const core::TetraGrid& g = s.model_->grid();
        if (s.role_ != SessionRole::Viewer)
            if (auto r =
                    check_coarsen(settings, g, s.graph_->depth(), s.coupling_, "Session::join");
                !r)
            {
                // Known only now (the master chose the level and the coupling): leave at once.
                spdlog::error("session: {}", r.error().message);
                refusal = r.error().message;
                close_all(net::DisconnectReason::Quit);
                return;
            }
        if (state)
        {
            for (int y = 0; y < g.ny(); ++y)
                for (int x = 0; x < g.nx(); ++x)
                {
                    s.display_u_.at(x, y) = state->u.at(x, y);
                    s.display_v_.at(x, y) = state->v.at(x, y);
                }
            s.model_->sync(s.display_u_);
            s.model_->sync(s.display_v_);
            for (int y = 0; y < g.ny(); ++y)
                for (int x = 0; x < g.nx(); ++x)
                {
                    s.state_.u.at(x, y) = s.display_u_.at(x, y);
                    s.state_.v.at(x, y) = s.display_v_.at(x, y);
                }
        }
        s.state_.time = welcome.time;
        s.state_.tick = welcome_tick;  // fast mode: ticks line up with the master's
        std::fill(leaf_time.begin(), leaf_time.end(), welcome.time);
        std::fill(leaf_tick.begin(), leaf_tick.end(), welcome_tick);
        clock_offset = welcome.time - last_now;
        if (s.coupling_ == Coupling::Fast)
        {
            // Fast mode runs on the master's clock: the welcome's time was the master's half a
            // round trip before the Welcome arrived, and the blobs took a while since (seconds
            // over a lossy link); starting from welcome.time now would leave this peer that far
            // behind for the whole session, and age every state it sends (docs/session.md §4.3).
            // The state is not stepped over the gap: the leaves we get start from the newest
            // states streamed to us (fast_advance), the rest is held anyway.
            double half_rtt = 0.0;
            if (master_handle)
                if (const auto st = transport.stats(*master_handle))
                    half_rtt = std::clamp(0.5 * st->rtt_s, 0.0, 0.25);
            clock_offset = welcome.time + half_rtt - welcome_now;
            s.state_.time = last_now + clock_offset;
        }
        clock_set = true;
        next_stream = last_now;
        next_frame = last_now;
        model_blob.clear();
        state_blob.clear();
        // Leaf states may come now: to the peers we are connected to, and to the others (queued
        // until their connection is up) right after our Hello.
        for (const auto& [pid, p] : peers)
            send_ready(pid);
        // Partitions that arrived with the blobs.
        for (auto& m : early)
            handle(m.first, m.second);
        early.clear();
        if (s.role_ == SessionRole::Participant)
        {
            points_dirty = true;
            send_points();
        }
    }

    std::vector<std::pair<net::PeerHandle, net::Message>> early;  // before the model
    double welcome_now = 0.0;  // our clock when the Welcome arrived

    void send_points()
    {
        if (!points_dirty || !s.model_ || s.role_ != SessionRole::Participant || leaving)
            return;
        points_dirty = false;
        points_sent = true;
        net::PointsOfInterest poi;
        poi.points = my_points;
        // To every peer, so that whoever succeeds the master can partition at once.
        send_all(make(poi, s.state_.tick));
    }

    void on_partition(std::uint16_t from, const net::Message& m, const net::Partition& p)
    {
        if (net::PeerId{from} == master_id)
        {
            apply_partition(m.header.tick, p);
            return;
        }
        // Maybe the successor of a master whose loss we have not noticed yet.
        auto& kept = foreign_partitions[from];
        if (kept.size() >= k_max_foreign_partitions)
            kept.erase(kept.begin());
        kept.emplace_back(m.header.tick, p);
    }

    void apply_partition(std::uint64_t tick, const net::Partition& p)
    {
        if (p.leaf_depth != s.graph_->depth() || p.owners.size() != s.graph_->size())
            return;
        add_partition(tick, p.epoch, p.owners);
        if (s.coupling_ == Coupling::Exact && !lockstep && member(newest(), s.id_) &&
            s.role_ == SessionRole::Participant)
            become_member(tick);
    }

    void on_halo(std::uint16_t from, const net::Message& m, const net::Halo& h)
    {
        // An honest peer sends the accepted step's u and v in f64 (send_halos); any other
        // stage or encoding would be taken for those values.
        if (!h.has_u || !h.has_v || h.stage != net::k_max_halo_stage ||
            h.encoding != net::ValueEncoding::F64)
        {
            reject(counters.halo_rejects, from,
                   "a Halo that is not the accepted step's u and v in f64");
            return;
        }
        const core::TetraGrid& g = s.model_->grid();
        for (const net::NodeRange& r : h.ranges)
            if (r.count > 0 && (r.first >= g.node_count() || r.count > g.node_count() - r.first))
                return;  // not our grid: ignore the whole message
        // A buffer of an applied tick, with its capacity: no allocation per halo.
        HaloBuffer buf;
        if (!spare_halos.empty())
        {
            buf = std::move(spare_halos.back());
            spare_halos.pop_back();
        }
        buf.tick = m.header.tick;
        buf.sender = m.header.sender;
        buf.time = h.time;
        buf.ranges.assign(h.ranges.begin(), h.ranges.end());
        buf.u.assign(h.u.begin(), h.u.end());
        buf.v.assign(h.v.begin(), h.v.end());
        // Keep the buffer ordered by tick (arrivals per sender are in order; merge by tick).
        auto it = std::upper_bound(halos.begin(), halos.end(), buf.tick,
                                   [](std::uint64_t t, const HaloBuffer& b) { return t < b.tick; });
        halos.insert(it, std::move(buf));
    }

    /// Quantised LeafState: rebuilds the owner's integers from the baseline it names into qu, qv.
    /// \return false (counted) if the baseline is not held or the values are not acceptable.
    bool rebuild_quantised(std::uint16_t from, std::uint64_t tick, double time, std::size_t l,
                           const net::QuantisedDelta& q, std::size_t n)
    {
        if (q.du.size() != n)
        {
            reject(counters.state_rejects, from, "a leaf state with a wrong node count");
            return false;
        }
        const QuantisedLeaf* base = nullptr;
        if (q.baseline != 0)
        {
            const std::uint64_t want = tick >= q.baseline ? tick - q.baseline : tick;
            for (const QuantisedLeaf& h : held[l])
                if (h.sender == from && h.tick == want && want != tick &&
                    h.u_exponent == q.u_exponent && h.v_exponent == q.v_exponent)
                    base = &h;
            if (base == nullptr)
            {
                ++counters.baseline_misses;
                return false;
            }
        }
        if (q.extrapolated && (base == nullptr || !extrapolate(*base, time, n)))
        {
            reject(counters.state_rejects, from,
                   "an extrapolated leaf state whose values cannot be extrapolated");
            return false;
        }
        const auto bu = base == nullptr  ? std::span<const std::int32_t>()
                        : q.extrapolated ? std::span<const std::int32_t>(pu.data(), n)
                                         : std::span<const std::int32_t>(base->qu);
        const auto bv = base != nullptr ? std::span<const std::int32_t>(base->qv)
                                        : std::span<const std::int32_t>();
        if (!net::apply_residuals(q.du, bu, q.predicted, std::span(qu.data(), n)) ||
            !net::apply_residuals(q.dv, bv, q.predicted, std::span(qv.data(), n)))
        {
            reject(counters.state_rejects, from,
                   "a compressed leaf state whose values leave the 32-bit range");
            return false;
        }
        return true;
    }

    /// Keeps the state just rebuilt (qu, qv) as a baseline and schedules its Ack. A duplicate is
    /// acknowledged again; an older state than one held from the same sender is ignored.
    void hold_quantised(std::uint16_t from, std::uint64_t tick, double time, std::size_t l,
                        const net::QuantisedDelta& q, std::size_t n)
    {
        std::deque<QuantisedLeaf>& h = held[l];
        bool duplicate = false;
        for (const QuantisedLeaf& e : h)
        {
            if (e.sender == from && e.tick > tick)
                return;
            duplicate = duplicate || (e.sender == from && e.tick == tick);
        }
        if (!duplicate)
        {
            if (h.size() >= k_baseline_window)
                h.pop_front();
            const auto end_u = qu.begin() + static_cast<std::ptrdiff_t>(n);
            const auto end_v = qv.begin() + static_cast<std::ptrdiff_t>(n);
            h.push_back(QuantisedLeaf{from, tick, time, q.u_exponent, q.v_exponent,
                                      std::vector<std::int32_t>(qu.begin(), end_u),
                                      std::vector<std::int32_t>(qv.begin(), end_v)});
        }
        std::uint64_t& pending = pending_acks[from][static_cast<std::uint32_t>(l)];
        pending = std::max(pending, tick + 1);
    }

    void send_acks()
    {
        const LeafGraph& graph = *s.graph_;
        for (auto& [to, leaves] : pending_acks)
        {
            net::Ack ack;
            for (const auto& [l, tick_plus_one] : leaves)
            {
                const core::LeafId id = graph.leaves()[l];
                ack.acks.push_back(net::LeafAck{net::WireLeafId{id.square, id.depth, id.ix, id.iy},
                                                tick_plus_one - 1});
                if (ack.acks.size() == net::k_max_acks)
                {
                    send_ack(to, ack);
                    ack.acks.clear();
                }
            }
            if (!ack.acks.empty())
                send_ack(to, ack);
        }
        pending_acks.clear();
    }

    /// Acks count against the bandwidth cap towards that peer, like leaf states.
    void send_ack(std::uint16_t to, const net::Ack& ack)
    {
        const net::Message m = make(ack, s.state_.tick);
        if (capped())
            budget[to] -= static_cast<double>(net::encoded_size(m));
        send_to(to, m);
    }

    void on_ack(std::uint16_t from, const net::Ack& ack)
    {
        std::vector<std::uint64_t>& table = acked[from];
        table.resize(s.graph_->size(), 0);
        const std::size_t side = std::size_t{1} << s.graph_->depth();
        for (const net::LeafAck& a : ack.acks)
        {
            if (a.leaf.depth != s.graph_->depth() || a.leaf.ix >= side || a.leaf.iy >= side)
                continue;
            const std::size_t l =
                s.graph_->index_of(core::LeafId{a.leaf.square, a.leaf.depth, a.leaf.ix, a.leaf.iy});
            if (a.tick != std::numeric_limits<std::uint64_t>::max())
                table[l] = std::max(table[l], a.tick + 1);
        }
    }

    void on_leaf_state(std::uint16_t from, const net::Message& m, const net::LeafState& ls)
    {
        if (ls.leaf.depth != s.graph_->depth())
            return;
        const std::size_t side = std::size_t{1} << ls.leaf.depth;
        if (ls.leaf.ix >= side || ls.leaf.iy >= side)
            return;
        const std::size_t l =
            s.graph_->index_of(core::LeafId{ls.leaf.square, ls.leaf.depth, ls.leaf.ix, ls.leaf.iy});
        const auto nodes = s.graph_->nodes(l);
        if (ls.node_offset + ls.node_count() > nodes.size())
            return;
        // Only the leaf's owner under the partition the state names may send it: the newest
        // (epoch, tick) of a leaf wins, so a state from anyone else, or of an epoch no partition
        // has, would hold the leaf's display (and in fast coupling its Dirichlet values) for
        // good (docs/protocol.md, LeafState).
        const PartitionEntry* named = with_epoch(ls.epoch);
        if (named == nullptr)
        {
            const std::uint32_t last = newest_epoch();
            if (ls.epoch <= last || ls.epoch - last > k_max_epoch_lead)
            {
                ++counters.unknown_epoch_states;  // superseded long ago, or not an epoch
                return;
            }
            // Newer than any partition here: the new owner streamed before the Partition
            // reached us (it is reliable, the states are not). Kept aside, whole leaves only,
            // and shown once the Partition comes and names its sender the owner
            // (settle_provisional_states). Never shown before: a peer that owns nothing could
            // otherwise hold any leaf's display, and in fast coupling its neighbours' Dirichlet
            // values, by streaming states of an epoch that never comes.
        }
        else if (named->owners[l] != net::PeerId{from})
        {
            reject(counters.foreign_states, from,
                   "a state of leaf " + std::to_string(l) + ", which it does not own in epoch " +
                       std::to_string(ls.epoch));
            return;
        }
        const core::TetraGrid& g = s.model_->grid();
        const int kc = ls.coarsen;
        if (kc != 0)
        {
            // Coarse: whole leaves on level n - k only, and never in fast coupling (the values
            // would be Dirichlet values there, docs/session.md §5.2).
            std::size_t expect = 0;
            for (const core::NodeIndex node : nodes)
                expect += on_coarse_level(g.coord(node), kc) ? 1 : 0;
            if (kc > max_coarsen || s.coupling_ == Coupling::Fast || ls.node_offset != 0 ||
                ls.node_count() != expect)
            {
                reject(counters.state_rejects, from,
                       "a coarse leaf state this session cannot take (wrong level, node count "
                       "or coupling)");
                return;
            }
        }
        // Our own leaves come from our own state.
        if (std::find(my_leaves.begin(), my_leaves.end(), l) != my_leaves.end() &&
            stream_partition() != nullptr)
            return;
        const bool quantised = ls.encoding == net::ValueEncoding::QuantisedDelta;
        if (quantised)
        {
            // Whole leaves only: the baseline is a leaf's state.
            const std::size_t n = ls.node_offset == 0 ? nodes.size() : 0;
            if (!rebuild_quantised(from, m.header.tick, ls.time, l, ls.quantised, n))
                return;
            hold_quantised(from, m.header.tick, ls.time, l, ls.quantised, n);
            net::dequantise(std::span(qu.data(), n), ls.quantised.u_exponent,
                            std::span(xu.data(), n));
            net::dequantise(std::span(qv.data(), n), ls.quantised.v_exponent,
                            std::span(xv.data(), n));
        }
        const double* from_u = quantised ? xu.data() : ls.u.data();
        const double* from_v = quantised ? xv.data() : ls.v.data();
        if (named == nullptr)
        {
            set_aside(l, from, m.header.tick, ls, from_u, from_v);
            return;
        }
        // Unsequenced: per leaf, the newest by (epoch, tick) wins; ticks are per sender in
        // fast mode, and a leaf changes sender only with the epoch.
        if (ls.epoch < leaf_epoch[l] || (ls.epoch == leaf_epoch[l] && m.header.tick < leaf_tick[l]))
        {
            ++counters.stale_states;
            return;
        }
        mark_shown(l, ls.epoch, m.header.tick, ls.time, from, kc);
        if (kc != 0)
        {
            // The received nodes go to their places on the grid; refine_display fills the rest.
            std::size_t k = 0;
            for (const core::NodeIndex node : nodes)
            {
                const core::GridCoord c = g.coord(node);
                if (!on_coarse_level(c, kc))
                    continue;
                s.display_u_.at(c.x, c.y) = ls.u[k];
                s.display_v_.at(c.x, c.y) = ls.v[k];
                ++k;
            }
            display_dirty = true;
            return;
        }
        show(l, ls.node_offset, ls.node_count(), from_u, from_v);
    }

    /// Leaf l's shown state is now (epoch, tick) from `from`.
    void mark_shown(std::size_t l, std::uint32_t epoch, std::uint64_t tick, double time,
                    std::uint16_t from, int coarsen)
    {
        leaf_epoch[l] = epoch;
        leaf_tick[l] = tick;
        leaf_time[l] = time;
        leaf_sender[l] = from;
        leaf_coarsen[l] = static_cast<std::uint8_t>(coarsen);
        if (updated_flag[l] == 0)
        {
            updated_flag[l] = 1;
            updated.push_back(static_cast<std::uint32_t>(l));
        }
    }
    /// Writes the values of leaf l's nodes offset .. offset + count into the display.
    void show(std::size_t l, std::size_t offset, std::size_t count, const double* u,
              const double* v)
    {
        double* du = s.display_u_.padded().data();
        double* dv = s.display_v_.padded().data();
        for_node_runs(l, offset, offset + count,
                      [&](std::size_t o, std::size_t i, std::size_t c)
                      {
                          copy_run(u + (i - offset), c, du + o);
                          copy_run(v + (i - offset), c, dv + o);
                      });
        display_dirty = true;
    }
    /// Keeps a state of an epoch ahead of every partition held aside (the newest per leaf by
    /// (epoch, tick)); a part of a leaf or a coarse one is dropped, since only whole leaves are
    /// kept.
    void set_aside(std::size_t l, std::uint16_t from, std::uint64_t tick, const net::LeafState& ls,
                   const double* u, const double* v)
    {
        const std::size_t n = s.graph_->nodes(l).size();
        AsideState& h = aside[l];
        if (ls.coarsen != 0 || ls.node_offset != 0 || ls.node_count() != n)
        {
            ++counters.unknown_epoch_states;
            return;
        }
        if (h.until != 0.0 && (ls.epoch < h.epoch || (ls.epoch == h.epoch && tick < h.tick)))
        {
            ++counters.stale_states;
            return;
        }
        // Its epoch has k_provisional_s from the first state of it set aside: newer ticks do not
        // extend the wait, so a forger streaming one epoch that never comes is dropped and
        // counted every k_provisional_s rather than held for good.
        if (h.until == 0.0 || ls.epoch != h.epoch)
            h.until = last_now + k_provisional_s;
        h.epoch = ls.epoch;
        h.tick = tick;
        h.time = ls.time;
        h.sender = from;
        h.u.assign(u, u + n);
        h.v.assign(v, v + n);
        if (provisional_listed[l] == 0)
        {
            provisional_listed[l] = 1;
            provisional_leaves.push_back(static_cast<std::uint32_t>(l));
        }
    }

    /// A LeafBatch: each of its leaves as the quantised LeafState it stands for.
    void on_leaf_batch(std::uint16_t from, const net::Message& m, const net::LeafBatch& b)
    {
        net::LeafState ls;
        ls.epoch = b.epoch;
        ls.encoding = net::ValueEncoding::QuantisedDelta;
        ls.time = b.time;
        for (const net::BatchLeaf& leaf : b.leaves)
        {
            ls.leaf = leaf.leaf;
            ls.quantised = leaf.quantised;
            on_leaf_state(from, m, ls);
        }
    }
    /// A ValueBatch: each of its leaves as the f32 / f64 LeafState it stands for.
    void on_value_batch(std::uint16_t from, const net::Message& m, const net::ValueBatch& b)
    {
        net::LeafState ls;
        ls.epoch = b.epoch;
        ls.encoding = b.encoding;
        ls.coarsen = b.coarsen;
        ls.time = b.time;
        for (const net::ValueLeaf& leaf : b.leaves)
        {
            ls.leaf = leaf.leaf;
            ls.u = leaf.u;
            ls.v = leaf.v;
            on_leaf_state(from, m, ls);
        }
    }
    bool display_dirty = false;
    bool behind = false;  ///< the last advance() returned on its wall-time budget (Session::behind)
    std::string refusal;  // why this joiner left on its own (settings refused, a blob refused)
    // A joiner whose connection to the master ended before the Welcome: why (Session::
    // join_failure), and whether the transport had connected it (handshake and key check done).
    std::optional<net::DisconnectReason> join_lost;
    bool master_connected = false;

    void handle(net::PeerHandle h, const net::Message& m)
    {
        auto idit = handle_ids.find(h);
        const bool bound = idit != handle_ids.end();
        switch (m.type())
        {
        case net::MessageType::Hello: on_hello(h, m, std::get<net::Hello>(m.body)); return;
        case net::MessageType::Welcome: on_welcome(h, m, std::get<net::Welcome>(m.body)); return;
        case net::MessageType::Reject:
            // Only the master refuses, and only a joiner it has not welcomed: from anyone else,
            // or later, one datagram would end this peer's session.
            if (welcomed || !master_handle || h != *master_handle)
            {
                if (bound)
                    reject(counters.peer_claim_rejects, idit->second,
                           "a Reject, which only the master sends to a joiner");
                else
                    reject(counters.peer_claim_rejects, h,
                           "a Reject, which only the master sends to a joiner");
                return;
            }
            if (!join_lost)
                join_lost = std::get<net::Reject>(m.body).reason;
            close_all(net::DisconnectReason::Refused);
            return;
        case net::MessageType::Blob:
            // The model and state come from the master only: another peer's chunk (a joiner
            // dials every listed peer while it downloads) could fill the blobs with its bytes.
            if (!master_handle || h != *master_handle)
            {
                if (auto id = handle_ids.find(h); id != handle_ids.end())
                    reject(counters.foreign_blobs, id->second,
                           "a chunk of the model or state, which only the master sends");
                else
                    reject(counters.foreign_blobs, h,
                           "a chunk of the model or state, which only the master sends");
                return;
            }
            on_blob(std::get<net::Blob>(m.body));
            return;
        default: break;
        }
        if (!s.model_ &&
            (m.type() == net::MessageType::LeafState || m.type() == net::MessageType::LeafBatch ||
             m.type() == net::MessageType::ValueBatch))
        {
            // Cannot be shown yet, and superseded by the next stream period, which resends every
            // leaf we have not acknowledged. (Peers stream to us only after our Ready; these came
            // from a peer that does not wait for it.)
            ++counters.early_states_dropped;
            return;
        }
        if (!bound)
            return;
        const std::uint16_t from = idit->second;
        peers[from].heard = true;
        peers[from].heard_at = last_now;
        if (m.type() == net::MessageType::Ready)
        {
            peers[from].has_model = true;
            return;
        }
        if (!s.model_)
        {
            early.emplace_back(h, m);
            return;
        }
        RemotePeer& p = peers[from];
        switch (m.type())
        {
        case net::MessageType::PeerJoined:
        {
            // Only the master admits peers. From anyone else it could rename or re-role a
            // member (a participant taken for a viewer has its forces dropped here only: the
            // peers' states part) or add phantoms that every reliable message is queued for.
            if (net::PeerId{from} != master_id)
            {
                reject(counters.peer_claim_rejects, from,
                       "a PeerJoined, which only the master sends");
                return;
            }
            const auto& pj = std::get<net::PeerJoined>(m.body);
            if (pj.peer.id == s.id_)
                return;
            RemotePeer& np = peers[pj.peer.id.value];
            np.info = pj.peer;
            np.info_known = true;
            greet_new_peer(pj.peer.id.value);
            return;
        }
        case net::MessageType::PeerLeft:
        {
            // The master dropped a peer. Follow it (so a peer that lost only the master's link
            // cannot split the session), except for an exact-mode leaver finishing its
            // hand-over, which we disconnect ourselves once past it.
            const auto& pl = std::get<net::PeerLeft>(m.body);
            auto it = peers.find(pl.peer.value);
            if (it == peers.end() || pl.peer == s.id_ || it->second.departed)
                return;
            if (pl.peer == master_id && s.role_ != SessionRole::Master &&
                successor(master_id) == net::PeerId{from})
            {
                // Our master's successor says it is gone: believe it now rather than wait for our
                // own timeout (ENet's differ by peer, 5-30 s), so no leaf waits on a peer that
                // still follows a dead master.
                it->second.departed = true;
                if (it->second.handle)
                    transport.disconnect(*it->second.handle, net::DisconnectReason::TimedOut);
                follow_master();
                return;
            }
            if (net::PeerId{from} != master_id)
                return;
            RemotePeer& gone = it->second;
            if (s.coupling_ == Coupling::Exact &&
                (gone.leaving || pl.reason == net::DisconnectReason::Quit))
                return;
            gone.departed = true;
            if (gone.handle)
                transport.disconnect(*gone.handle, net::DisconnectReason::Kicked);
            return;
        }
        case net::MessageType::PointsOfInterest:
            // Every peer keeps every participant's points: a successor partitions with them.
            if (p.info.role == net::Role::Participant && !p.leaving)
            {
                p.points = std::get<net::PointsOfInterest>(m.body).points;
                const bool admitted = p.ready;
                p.ready = true;
                if (s.role_ == SessionRole::Master)
                {
                    if (admitted && last_now - p.points_applied_at < k_points_interval_s)
                    {
                        if (!p.points_waiting)
                            ++counters.points_waits;
                        p.points_waiting = true;  // apply_waiting_points takes them later
                        return;
                    }
                    p.points_applied_at = last_now;
                    p.points_waiting = false;
                    repartition_pending = true;
                    if (s.coupling_ == Coupling::Fast)
                        master_repartition(s.state_.tick);
                }
            }
            return;
        case net::MessageType::Partition:
            if (s.role_ != SessionRole::Master)
                on_partition(from, m, std::get<net::Partition>(m.body));
            return;
        case net::MessageType::Force:
            // A viewer only watches (docs/session.md §1): its forces, a modified peer's or a
            // forger's, are dropped, not applied by every member and recorded.
            if (p.info.role == net::Role::Viewer)
            {
                reject(counters.viewer_forces, from, "forces, though it joined as a viewer");
                return;
            }
            p.forces.push_back(ForceEntry{m.header.tick, std::get<net::Force>(m.body).forces});
            count_limited(p.forces.back().forces, from, p.warned_force_limit);
            // A list from after its forces ended never applies, so the replay must not see it.
            if (recording && !(p.forces_end && m.header.tick >= *p.forces_end))
                force_log.push_back(
                    ForceRecord{from, m.header.tick, std::get<net::Force>(m.body).forces});
            trim(p.forces);
            return;
        case net::MessageType::Leave:
            p.leaving = true;
            if (s.role_ == SessionRole::Master)
            {
                repartition_pending = true;
                if (s.coupling_ == Coupling::Fast)
                    master_repartition(s.state_.tick);
            }
            if (s.coupling_ == Coupling::Fast || s.role_ == SessionRole::Viewer || !lockstep)
            {
                if (p.handle)
                    transport.disconnect(*p.handle, net::DisconnectReason::Quit);
                p.departed = true;
            }
            return;
        case net::MessageType::LeafBatch:
            p.streams_to_us = true;
            on_leaf_batch(from, m, std::get<net::LeafBatch>(m.body));
            return;
        case net::MessageType::LeafState:
            p.streams_to_us = true;
            on_leaf_state(from, m, std::get<net::LeafState>(m.body));
            return;
        case net::MessageType::ValueBatch:
            p.streams_to_us = true;
            on_value_batch(from, m, std::get<net::ValueBatch>(m.body));
            return;
        case net::MessageType::Ack: on_ack(from, std::get<net::Ack>(m.body)); return;
        case net::MessageType::Halo: on_halo(from, m, std::get<net::Halo>(m.body)); return;
        case net::MessageType::Heartbeat:
            if (!p.has_heartbeat || m.header.tick > p.heartbeat)
                p.heartbeat = m.header.tick;
            p.has_heartbeat = true;
            return;
        case net::MessageType::Ping:
        {
            net::Pong pong;
            pong.nonce = std::get<net::Ping>(m.body).nonce;
            pong.time_us = std::get<net::Ping>(m.body).time_us;
            send_to(from, make(pong, s.state_.tick));
            return;
        }
        default: return;
        }
    }

    void poll()
    {
        for (int guard = 0; guard < 100000; ++guard)
        {
            auto ev = messenger.poll(0);
            if (!ev)
                break;
            switch (ev->kind)
            {
            case net::MessengerEvent::Kind::Connected: on_connected(ev->peer); break;
            case net::MessengerEvent::Kind::Disconnected:
                on_disconnected(ev->peer, ev->reason);
                break;
            case net::MessengerEvent::Kind::Received: handle(ev->peer, ev->message); break;
            }
        }
        settle_provisional_states();
        if (display_dirty && s.model_)
        {
            s.model_->sync(s.display_u_);
            s.model_->sync(s.display_v_);
            refine_display();
            display_dirty = false;
        }
        record_history();
        feed_blobs();
        for (const net::PeerHandle h : transport.peers())
            if (auto st = transport.stats(h))
                last_stats[h] = *st;
    }

    /// The states kept aside (set_aside): once their epoch's Partition is here, one from its leaf's
    /// owner is shown (if still the newest) and any other dropped; one whose epoch never came
    /// (skipped, or k_provisional_s passed) is dropped too, each counted.
    void settle_provisional_states()
    {
        if (provisional_leaves.empty())
            return;
        const std::uint32_t last = newest_epoch();
        std::erase_if(provisional_leaves,
                      [&](std::uint32_t l)
                      {
                          const bool keep = settle_leaf(l, last);
                          provisional_listed[l] = keep ? 1 : 0;
                          return !keep;
                      });
    }
    /// One leaf of settle_provisional_states. \return whether its state stays aside.
    bool settle_leaf(std::uint32_t l, std::uint32_t last)
    {
        AsideState& h = aside[l];
        if (h.until == 0.0)
            return false;
        const PartitionEntry* named = with_epoch(h.epoch);
        const bool owner_known = named != nullptr;
        if (!owner_known && h.epoch > last && last_now < h.until)
            return true;  // its Partition is still on the way
        h.until = 0.0;
        if (!owner_known)
        {
            ++counters.unknown_epoch_states;
            return false;
        }
        if (named->owners[l] != net::PeerId{h.sender})
        {
            reject(counters.foreign_states, h.sender,
                   "a state of leaf " + std::to_string(l) + ", which it does not own in epoch " +
                       std::to_string(h.epoch));
            return false;
        }
        const bool mine = std::find(my_leaves.begin(), my_leaves.end(), l) != my_leaves.end() &&
                          stream_partition() != nullptr;
        if (mine || h.epoch < leaf_epoch[l] || (h.epoch == leaf_epoch[l] && h.tick < leaf_tick[l]))
        {
            ++counters.stale_states;
            return false;
        }
        mark_shown(l, h.epoch, h.tick, h.time, h.sender, 0);
        show(l, 0, h.u.size(), h.u.data(), h.v.data());
        return false;
    }
    std::uint32_t newest_epoch() const
    {
        const PartitionEntry* p = newest();
        return p != nullptr ? p->epoch : 0;
    }

    // --- smooth display (docs/session.md §5.3) -------------------------------------------------

    /// Keeps the shown state of every leaf updated by this poll (not ours) for interpolation,
    /// and the newest time received per sender.
    void record_history()
    {
        if (!s.model_ || !settings.interpolate_view)
        {
            for (const std::uint32_t l : updated)
                updated_flag[l] = 0;
            updated.clear();
            return;
        }
        const double* du = s.display_u_.padded().data();
        for (const std::uint32_t l : updated)
        {
            updated_flag[l] = 0;
            const std::size_t n = s.graph_->node_count(l);
            ViewHistory& h = history[l];
            if (h.sender == leaf_sender[l] && h.count > 0 && leaf_time[l] == h.time_of(h.count - 1))
                continue;  // the same state again (a duplicate, or re-sent unchanged)
            if (h.sender != leaf_sender[l] ||
                (h.count > 0 && leaf_time[l] < h.time_of(h.count - 1)))
                h.count = 0;  // another sender's clock: start over
            h.sender = leaf_sender[l];
            if (h.u.size() != k_view_history * n)
                h.u.assign(k_view_history * n, 0.0);
            if (h.count == k_view_history)
            {
                // Drop the oldest: its slot takes the new state.
                h.first = (h.first + 1) % k_view_history;
                --h.count;
            }
            const auto k = static_cast<std::size_t>(h.slot(h.count));
            for_node_runs(l, [&](std::size_t o, std::size_t i, std::size_t c)
                          { copy_run(du + o, c, h.u.data() + k * n + i); });
            h.time[k] = leaf_time[l];
            ++h.count;
            Playout& pl = playout[h.sender];
            if ((!pl.set && !pl.fresh) || leaf_time[l] > pl.newest)
            {
                if ((pl.set || pl.fresh) && leaf_time[l] > pl.newest)
                    pl.grew(leaf_time[l] - pl.newest);
                pl.newest = leaf_time[l];
                pl.fresh = true;
            }
        }
        updated.clear();
    }

    /// The view: the display, with every leaf not ours interpolated linearly in time between
    /// the two states received around its sender's playout time (held at the newest or oldest
    /// outside them). A sender's playout time is now + offset, the offset slewed towards the
    /// smallest lead of its newest state over now (sampled when it grows, recovering at
    /// k_view_leak) minus k_view_periods of the sender's stream periods (Playout::period, as
    /// observed here), so that a state is usually there on
    /// both sides even when one is late or lost; it never goes backwards (a sender slower than
    /// real time, such as a lockstep, is then shown at its newest states). Linear, not cubic
    /// Hermite with the received v: the grid's fastest modes have |v| / |u| up to ~150/s, and v
    /// times a stream period would overshoot by more than |u|.
    /// At the frame rate: the playout times (and the view delay they give); the view's nodes
    /// follow when the view is next read (materialize_view), so a peer that draws nothing (a
    /// headless `pliant host` or `join`) does not compute them.
    void update_view(double now)
    {
        view_due = true;
        if (!settings.interpolate_view)
            return;
        double delay = 0.0;
        for (auto& [sender, pl] : playout)
        {
            if (!pl.set && !pl.fresh)
                continue;
            // Two of the sender's periods as observed (this peer's own until one is).
            const double observed = pl.period();
            const double margin =
                k_view_periods * (observed > 0.0 ? observed : 1.0 / settings.stream_rate_hz);
            const double dt = pl.set ? std::max(0.0, now - pl.last_now) : 0.0;
            pl.last_now = now;
            if (!pl.set)
            {
                pl.lead = pl.newest - now;
                pl.offset = pl.lead - margin;
                pl.render = now + pl.offset;
                pl.set = true;
            }
            pl.lead += k_view_leak * dt;
            // A lead far above the one held is no jitter: the sender's clock jumped (it caught
            // up after a hold, or is another peer's now); follow at once.
            if (pl.fresh)
                pl.lead = pl.newest - now > pl.lead + k_view_snap_s
                              ? pl.newest - now
                              : std::min(pl.lead, pl.newest - now);
            pl.fresh = false;
            const double target = pl.lead - margin;
            const double step = k_view_slew * dt;
            if (std::fabs(target - pl.offset) > k_view_snap_s)
                pl.offset = target;
            else
                pl.offset += std::clamp(target - pl.offset, -step, step);
            pl.render = std::max(pl.render, now + pl.offset);
            delay = std::max(delay, pl.newest - pl.render);
        }
        counters.view_delay_s = delay;
    }

    /// The view of the last update_view's playout times, from the display and the states
    /// received up to now; once per update_view, when the view is read (Session::view_u,
    /// view_time).
    void materialize_view()
    {
        if (!view_due || !s.model_)
            return;
        view_due = false;
        flush_display();
        if (!settings.interpolate_view)
        {
            view_u = s.display_u_;
            std::copy(leaf_time.begin(), leaf_time.end(), view_time.begin());
            return;
        }
        // Leaf by leaf, the display's nodes or the interpolated ones; then the twins and ghosts
        // (a copy of the whole display first cost as much as the rest together at level 8).
        double* vu = view_u.padded().data();
        const double* du = s.display_u_.padded().data();
        for (std::size_t l = 0; l < s.graph_->size(); ++l)
        {
            const ViewHistory& h = history[l];
            view_time[l] = leaf_time[l];
            if (h.count == 0 || leaf_sender[l] == s.id_.value || h.sender != leaf_sender[l])
            {
                for_node_runs(l, [&](std::size_t o, std::size_t, std::size_t c)
                              { copy_run(du + o, c, vu + o); });
                continue;
            }
            const double t = playout[h.sender].render;
            int a = 0;  // states a and b = a + 1 bracket t, or a = b at either end
            int b = 0;
            double w = 0.0;
            if (t >= h.time_of(h.count - 1))
                a = b = h.count - 1;
            else if (t > h.time_of(0))
            {
                while (h.time_of(b) <= t)
                    ++b;
                a = b - 1;
                w = (t - h.time_of(a)) / (h.time_of(b) - h.time_of(a));
            }
            view_time[l] = (1.0 - w) * h.time_of(a) + w * h.time_of(b);
            const std::size_t n = s.graph_->node_count(l);
            const double* ua = h.u.data() + static_cast<std::size_t>(h.slot(a)) * n;
            const double* ub = h.u.data() + static_cast<std::size_t>(h.slot(b)) * n;
            for_node_runs(l,
                          [&](std::size_t o, std::size_t i, std::size_t c)
                          {
                              for (std::size_t j = 0; j < c; ++j)
                                  vu[o + j] = ua[i + j] + w * (ub[i + j] - ua[i + j]);
                          });
        }
        s.model_->sync(view_u);
    }

    /// Master: the points of interest that waited for k_points_interval_s re-partition now.
    void apply_waiting_points()
    {
        for (auto& [id, p] : peers)
            if (p.points_waiting && last_now - p.points_applied_at >= k_points_interval_s)
            {
                p.points_waiting = false;
                p.points_applied_at = last_now;
                if (!p.departed && !p.leaving)
                    repartition_pending = true;
            }
    }

    void advance(double now)
    {
        if (advanced && settings.pause_s > 0.0 && now - last_now >= settings.pause_s && !s.left_)
            note_pause(now, now - last_now);
        last_now = now;
        advanced = true;
        check_pause();
        settle_losses();
        behind = false;
        if (!ungreeted.empty())
            close_ungreeted();
        // Also while the model is arriving: the Hellos to the peers the Welcome listed go out
        // before it (a download can outlast their k_greeting_repeat_s).
        if (now >= next_greeting_repeat && !s.left_)
        {
            repeat_greetings();
            next_greeting_repeat = std::max(next_greeting_repeat + 1.0 / settings.stream_rate_hz,
                                            now - 1.0 / settings.stream_rate_hz);
        }
        if (!s.model_ || s.left_)
            return;
        if (!clock_set)
        {
            clock_offset = s.state_.time - now;
            clock_set = true;
            next_stream = now;
            next_frame = now;
        }
        send_points();
        if (s.role_ == SessionRole::Master)
            apply_waiting_points();
        if (s.role_ == SessionRole::Master && repartition_pending && s.coupling_ == Coupling::Fast)
            master_repartition(s.state_.tick);
        if (s.coupling_ == Coupling::Exact)
        {
            if (lockstep || s.role_ == SessionRole::Master)
                exact_advance();
        }
        else if (s.role_ != SessionRole::Viewer)
        {
            flush_forces(0);
            fast_advance();
        }
        if (s.diverged_tick_)
        {
            drop_out_diverged();
            return;
        }
        if (leaving && s.coupling_ == Coupling::Fast)
            close_all(net::DisconnectReason::Quit);
        if (leaving && !lockstep && s.coupling_ == Coupling::Exact)
            finish_leave_soon();
        if (!pending_acks.empty() && now >= next_ack && !s.left_)
        {
            send_acks();
            next_ack =
                std::max(next_ack + 1.0 / settings.ack_rate_hz, now - 1.0 / settings.ack_rate_hz);
        }
        if (now >= next_stream && s.role_ != SessionRole::Viewer && !s.left_)
        {
            stream();
            next_stream = std::max(next_stream + 1.0 / settings.stream_rate_hz,
                                   now - 1.0 / settings.stream_rate_hz);
        }
        if (s.model_ && !s.left_ && now >= next_view)
        {
            // At the frame rate: a caller pumping faster (the CLI loop runs ~5 kHz) would
            // otherwise copy and interpolate the whole object on every call.
            update_view(now);
            next_view = std::max(next_view + 1.0 / settings.frame_rate_hz,
                                 now - 1.0 / settings.frame_rate_hz);
        }
        feed_blobs();
        transport.flush();
    }
};

Session::Session() = default;
Session::~Session() = default;

core::Result<std::unique_ptr<Session>> Session::host(net::Transport& transport,
                                                     const core::TetraGrid& grid,
                                                     const core::Vec3Field<double>& rest,
                                                     const sim::MembraneSettings& material,
                                                     const SessionSettings& settings,
                                                     const sim::MembraneState* start)
{
    if (start != nullptr)
    {
        if (start->u.level() != grid.level() || start->v.level() != grid.level())
            return core::fail(core::ErrorCode::InvalidArgument,
                              "Session::host: the start state is of level " +
                                  std::to_string(start->u.level()) + ", the grid of level " +
                                  std::to_string(grid.level()));
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
                if (!std::isfinite(start->u.at(x, y)) || !std::isfinite(start->v.at(x, y)))
                    return core::fail(core::ErrorCode::InvalidArgument,
                                      "Session::host: the start state is not finite at node (" +
                                          std::to_string(x) + ", " + std::to_string(y) + ")");
    }
    if (auto r = check_settings(settings, "Session::host"); !r)
        return core::fail(r.error().code, r.error().message);
    if (auto r = check_coarsen(settings, "Session::host"); !r)
        return core::fail(r.error().code, r.error().message);
    sim::MembraneSettings m = material;
    m.threads = settings.threads;
    // Every peer steps in double (docs/physics.md §9): the model blob carries no precision, and
    // exact coupling equals one process's double steps bit for bit.
    m.precision = sim::Precision::Double;
    m.max_force = settings.max_force ? *settings.max_force : sim::default_max_force(grid, rest, m);
    if (settings.coupling == Coupling::Exact)
    {
        // Lockstep needs a common fixed step, and re-assembly would need the whole state.
        m.fixed_step = true;
        m.reassemble_every = 0;
    }
    auto model = sim::MembraneModel::create(grid, rest, m);
    if (!model)
        return core::fail(model.error().code, model.error().message);
    std::unique_ptr<Session> s(new Session());
    s->impl_ = std::make_unique<Impl>(*s, transport, settings);
    Impl& im = *s->impl_;
    s->role_ = SessionRole::Master;
    s->id_ = net::PeerId{0};
    s->coupling_ = settings.coupling;
    s->clearance_ = settings.point_clearance;
    im.session_id = settings.session_id != 0 ? settings.session_id : 0x5E55u;
    im.messenger.set_session(im.session_id);
    im.master_id = s->id_;
    im.welcomed = true;
    im.install_model(std::move(model).value());
    if (auto r = check_coarsen(settings, s->model_->grid(), s->graph_->depth(), settings.coupling,
                               "Session::host");
        !r)
        return core::fail(r.error().code, r.error().message);
    if (start != nullptr)
    {
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
            {
                s->state_.u.at(x, y) = start->u.at(x, y);
                s->state_.v.at(x, y) = start->v.at(x, y);
            }
        s->model_->sync(s->state_.u);
        s->model_->sync(s->state_.v);
        s->resumed_ = true;
    }
    im.add_partition(0, im.next_epoch++, im.compute_partition());
    im.lockstep = settings.coupling == Coupling::Exact;
    im.copy_own_to_display(im.newest());
    return s;
}

core::Result<std::unique_ptr<Session>> Session::join(net::Transport& transport,
                                                     const net::Address& master, net::Role role,
                                                     const SessionSettings& settings)
{
    if (auto r = check_settings(settings, "Session::join"); !r)
        return core::fail(r.error().code, r.error().message);
    if (auto r = check_coarsen(settings, "Session::join"); !r)
        return core::fail(r.error().code, r.error().message);
    std::unique_ptr<Session> s(new Session());
    s->impl_ = std::make_unique<Impl>(*s, transport, settings);
    s->role_ = role == net::Role::Viewer ? SessionRole::Viewer : SessionRole::Participant;
    auto h = transport.connect(master);
    if (!h)
        return core::fail(h.error().code, h.error().message);
    s->impl_->master_handle = *h;
    return s;
}

std::string Session::refusal() const
{
    return impl_->refusal;
}

std::optional<JoinFailure> Session::join_failure() const
{
    if (!impl_->join_lost)
        return std::nullopt;
    return JoinFailure{*impl_->join_lost, impl_->master_connected};
}

void Session::poll()
{
    impl_->poll();
}
void Session::wait(double max_s) noexcept
{
    impl_->transport.wait(max_s);
}
void Session::advance(double now_s)
{
    impl_->advance(now_s);
}

bool Session::behind() const noexcept
{
    return impl_->behind;
}

double Session::max_barrier_wait() const noexcept
{
    return impl_->settings.max_barrier_wait_s;
}

bool Session::at_max_ticks() const noexcept
{
    return impl_->settings.max_ticks != 0 && state_.tick >= impl_->settings.max_ticks;
}

void Session::set_points_of_interest(std::vector<net::Target> points)
{
    if (points.size() > net::k_max_points)
        points.resize(net::k_max_points);
    impl_->my_points = std::move(points);
    impl_->points_dirty = true;
    if (role_ == SessionRole::Master)
    {
        impl_->repartition_pending = true;
        impl_->points_dirty = false;
    }
}

core::Result<void> Session::set_forces(std::vector<net::UserForce> forces, std::uint64_t from_tick)
{
    if (role_ == SessionRole::Viewer)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "set_forces: a viewer only watches; the others drop its forces");
    if (forces.size() > net::k_max_points)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "set_forces: " + std::to_string(forces.size()) + " forces, at most " +
                              std::to_string(net::k_max_points) + " fit one Force message");
    const std::int64_t faces = model_ != nullptr
                                   ? static_cast<std::int64_t>(model_->grid().face_count())
                                   : std::numeric_limits<std::int64_t>::max();
    std::array<sim::Force, net::k_max_points> checked{};
    for (std::size_t k = 0; k < forces.size(); ++k)
        checked[k] = to_sim_force(forces[k]);
    if (auto ok = sim::validate_forces(faces, std::span(checked.data(), forces.size())); !ok)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "set_forces: " + ok.error().message);  // "force K: the rule"
    impl_->pending_forces.push_back(ForceEntry{from_tick, std::move(forces)});
    return {};
}

void Session::leave()
{
    if (left_ || impl_->leaving)
        return;
    if (role_ == SessionRole::Master)
    {
        // Hand over: our leaves' newest state goes out, then the others promote a successor that
        // takes them over from it (docs/session.md §6). Disconnecting with Quit, not Shutdown,
        // is what tells them the session goes on.
        if (model_ != nullptr)
            impl_->stream();
        impl_->close_all(net::DisconnectReason::Quit);
        return;
    }
    impl_->leaving = true;
    impl_->leave_started = impl_->last_now;
    net::Leave msg;
    msg.reason = net::DisconnectReason::Quit;
    impl_->send_all(impl_->make(msg, state_.tick));
    impl_->transport.flush();
    if (!impl_->lockstep || coupling_ == Coupling::Fast)
        left_ = impl_->handle_ids.empty();
}

core::Result<void> Session::start_recording()
{
    if (role_ != SessionRole::Master || coupling_ != Coupling::Exact || state_.tick != 0 ||
        !impl_->my_forces.empty())
        return core::fail(core::ErrorCode::InvalidArgument,
                          "recording needs the master of an exact-mode session, before its first "
                          "step");
    if (resumed_)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "recording needs a session that starts at rest (a replay starts there); "
                          "this one started from a saved state");
    impl_->recording = true;
    return {};
}

Recording Session::recording() const
{
    Recording r;
    if (model_ != nullptr)
        r.model = encode_model(*model_, coupling_, clearance_, impl_->settings.max_barrier_wait_s);
    r.final_tick = state_.tick;
    r.forces = impl_->force_log;
    return r;
}

void Session::shutdown()
{
    // A peer that left already (a diverged master's drop-out handed the session over with
    // Quit) must not end it for the others now.
    if (!left_)
        impl_->close_all(net::DisconnectReason::Shutdown);
}

const core::Field<double>& Session::display_u() const noexcept
{
    impl_->flush_display();
    return display_u_;
}

const core::Field<double>& Session::display_v() const noexcept
{
    impl_->flush_display();
    return display_v_;
}

const core::Field<double>& Session::view_u() const noexcept
{
    impl_->materialize_view();
    return impl_->view_u;
}

std::span<const double> Session::view_time() const noexcept
{
    impl_->materialize_view();
    return impl_->view_time;
}

net::PeerId Session::master() const noexcept
{
    return impl_->master_id;
}

std::uint32_t Session::epoch() const noexcept
{
    const PartitionEntry* p = impl_->newest();
    return p != nullptr ? p->epoch : 0;
}

std::vector<net::PeerId> Session::owners() const
{
    const PartitionEntry* p = impl_->newest();
    return p != nullptr ? p->owners : std::vector<net::PeerId>{};
}

double Session::shown_time() const
{
    if (role_ != SessionRole::Viewer)
        return state_.time;
    double t = state_.time;
    for (const double leaf : impl_->leaf_time)
        t = std::max(t, leaf);
    return t;
}

std::uint64_t Session::shown_tick() const
{
    if (role_ != SessionRole::Viewer)
        return state_.tick;
    std::uint64_t t = state_.tick;
    for (const std::uint64_t leaf : impl_->leaf_tick)
        t = std::max(t, leaf);
    return t;
}

std::vector<net::PeerId> Session::state_owners() const
{
    const PartitionEntry* p = impl_->stream_partition();
    return p != nullptr ? p->owners : std::vector<net::PeerId>{};
}

std::vector<net::PeerId> Session::peers() const
{
    std::vector<net::PeerId> out;
    for (const auto& [id, p] : impl_->peers)
        if (!p.departed)
            out.push_back(net::PeerId{id});
    return out;
}

std::vector<PeerStatus> Session::peer_status() const
{
    std::vector<PeerStatus> out;
    for (const auto& [id, p] : impl_->peers)
        if (!p.departed)
            out.push_back(PeerStatus{net::PeerId{id}, p.info.role, p.info.name,
                                     net::PeerId{id} == impl_->master_id, p.handle.has_value(),
                                     p.has_model, p.streams_to_us, p.rejected});
    return out;
}

SessionStats Session::stats() const
{
    SessionStats st = impl_->counters;
    net::PeerStats sum = impl_->closed_stats;
    for (const auto& [h, ps] : impl_->last_stats)
    {
        sum.bytes_sent += ps.bytes_sent;
        sum.bytes_received += ps.bytes_received;
        sum.packets_sent += ps.packets_sent;
        sum.packets_received += ps.packets_received;
        sum.bad_datagrams += ps.bad_datagrams;
    }
    st.bytes_sent = sum.bytes_sent;
    st.bytes_received = sum.bytes_received;
    st.packets_sent = sum.packets_sent;
    st.packets_received = sum.packets_received;
    st.bad_datagrams = sum.bad_datagrams;
    for (const auto& [id, p] : impl_->peers)
        st.peers_connected += p.handle && !p.departed ? 1 : 0;
    if (impl_->barrier_since >= 0.0 && !left_)
    {
        const auto missing = impl_->barrier_missing(impl_->barrier_tick);
        if (!missing.empty())
        {
            st.barrier_wait_s = impl_->last_now - impl_->barrier_since;
            st.barrier_peer = net::PeerId{missing.front()};
        }
    }
    if (model_)
    {
        // Age of the oldest leaf shown that this peer does not compute, against its own time
        // (participants) or the newest leaf received (viewers).
        const PartitionEntry* p = impl_->newest();
        double newest_leaf = state_.time;
        if (role_ == SessionRole::Viewer)
            for (const double t : impl_->leaf_time)
                newest_leaf = std::max(newest_leaf, t);
        double age = 0.0;
        if (p != nullptr)
            for (std::size_t l = 0; l < p->owners.size(); ++l)
            {
                if (p->owners[l] == id_)
                    st.owned_nodes += graph_->node_count(l);
                else
                    age = std::max(age, newest_leaf - impl_->leaf_time[l]);
            }
        st.halo_age_s = age;
    }
    return st;
}

}  // namespace pliant::session
