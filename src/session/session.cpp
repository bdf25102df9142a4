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

#include "session/session_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <set>

namespace pliant::session
{

namespace
{

/// A session id for a master whose settings name none: random, so that two sessions (a host
/// restarted on the same port, another session's peer) tell each other apart (reason 6), and
/// never 0, which only a Hello may carry.
std::uint32_t draw_session_id()
{
    std::random_device entropy;
    std::uint32_t id = 0;
    for (int tries = 0; id == 0 && tries < 64; ++tries)
        id = static_cast<std::uint32_t>(entropy());
    return id != 0 ? id : 0x5E55u;
}

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

}  // namespace

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

// --- Impl: sending, the model, the message loop, advance() ------------------------------------

net::Message Session::Impl::make(net::Body body, std::uint64_t tick) const
{
    net::Message m;
    m.header.session = session_id;
    m.header.sender = s.id_;
    m.header.tick = tick;
    m.body = std::move(body);
    return m;
}

void Session::Impl::send_to(std::uint16_t id, const net::Message& m, net::SendMode mode)
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
void Session::Impl::send_ready(std::uint16_t id)
{
    send_to(id, make(net::Ready{}, s.state_.tick));
    auto it = peers.find(id);
    if (it != peers.end() && !it->second.streams_to_us)
        it->second.ready_repeat_until = last_now + k_greeting_repeat_s;
}

/// The unreliable repeats of our greetings (k_greeting_repeat_s): Ready, and Hello to the
/// peers we dialled.
void Session::Impl::repeat_greetings()
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

net::Hello Session::Impl::make_hello() const
{
    net::Hello hello;
    hello.role = s.role_ == SessionRole::Viewer ? net::Role::Viewer : net::Role::Participant;
    hello.listen_port = settings.listen_port;
    hello.name = settings.name;
    return hello;
}

void Session::Impl::bind(net::PeerHandle h, std::uint16_t id)
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

void Session::Impl::install_model(sim::MembraneModel model)
{
    s.model_ = std::make_unique<sim::MembraneModel>(std::move(model));
    const core::TetraGrid& g = s.model_->grid();
    s.graph_ = std::make_unique<LeafGraph>(g, leaf_depth_for(g, net::ValueEncoding::F64));
    ws = std::make_unique<sim::Rkf45Workspace>(*s.model_, settings.threads);
    forces_in_ws_valid = false;
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

std::string Session::Impl::describe_peer(std::uint16_t id) const
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
void Session::Impl::reject(std::uint64_t& counter, std::uint16_t from, std::string_view what)
{
    if (count_reject(counter, from))
        warn_rejected(from, what);
}

bool Session::Impl::count_reject(std::uint64_t& counter, std::uint16_t from)
{
    ++counter;
    auto it = peers.find(from);
    if (it == peers.end())
        return false;
    ++it->second.rejected;
    if (it->second.warned_rejected)
        return false;
    it->second.warned_rejected = true;
    return true;
}

void Session::Impl::warn_rejected(std::uint16_t from, std::string_view what) const
{
    spdlog::warn(
        "session: {} sent {}: dropped (an honest peer never does; further drops "
        "are counted in the --stats column 'rejected')",
        describe_peer(from), what);
}

/// reject() for a connection not bound to a peer yet: logged with its address, at most once
/// a second.
void Session::Impl::reject(std::uint64_t& counter, net::PeerHandle h, std::string_view what)
{
    if (count_reject(counter, h))
        warn_rejected(h, what);
}

bool Session::Impl::count_reject(std::uint64_t& counter, net::PeerHandle /*h*/)
{
    ++counter;
    if (last_now < next_unbound_warning)
        return false;
    next_unbound_warning = last_now + 1.0;
    return true;
}

void Session::Impl::warn_rejected(net::PeerHandle h, std::string_view what) const
{
    const auto address = transport.remote_address(h);
    spdlog::warn(
        "session: the connection from {} sent {}: dropped (an honest peer never "
        "does; counted in the --stats column 'rejected')",
        address ? net::to_string(*address) : std::string("?"), what);
}

void Session::Impl::handle(net::PeerHandle h, const net::Message& m)
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
        // A Halo has nothing to apply to yet (a joiner is no member before its Ready).
        if (m.type() == net::MessageType::Halo)
            return;
        if (early.size() >= k_max_early_messages)
        {
            reject(counters.early_floods, from,
                   "more messages before the model than an honest peer sends");
            return;
        }
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
            reject(counters.peer_claim_rejects, from, "a PeerJoined, which only the master sends");
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
        if (std::count_if(p.forces.begin(), p.forces.end(),
                          [this](const ForceEntry& e) { return e.apply_tick > s.state_.tick; }) >=
            static_cast<std::ptrdiff_t>(k_max_forces_ahead))
        {
            reject(counters.force_floods, from,
                   "more force lists ahead of this peer's tick than an honest peer sends");
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

void Session::Impl::poll()
{
    for (int guard = 0; guard < 100000; ++guard)
    {
        // The Messenger's reused event: its message is decoded in place (no allocation once its
        // vectors have grown) and valid until the next call; handle() copies what it keeps.
        const net::MessengerEvent* ev = messenger.next(0);
        if (ev == nullptr)
            break;
        switch (ev->kind)
        {
        case net::MessengerEvent::Kind::Connected: on_connected(ev->peer); break;
        case net::MessengerEvent::Kind::Disconnected: on_disconnected(ev->peer, ev->reason); break;
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
    transport.live_peers(live_handles);
    for (const net::PeerHandle h : live_handles)
        if (auto st = transport.stats(h))
            last_stats[h] = *st;
}

/// Master: the points of interest that waited for k_points_interval_s re-partition now.
void Session::Impl::apply_waiting_points()
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

void Session::Impl::advance(double now)
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
    if (acks_pending && now >= next_ack && !s.left_)
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
        next_view =
            std::max(next_view + 1.0 / settings.frame_rate_hz, now - 1.0 / settings.frame_rate_hz);
    }
    feed_blobs();
    transport.flush();
}

// --- Session ---------------------------------------------------------------------------------

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
    im.session_id = settings.session_id != 0 ? settings.session_id : draw_session_id();
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

std::uint64_t Session::max_ticks() const noexcept
{
    return impl_->settings.max_ticks;
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

std::uint32_t Session::session_id() const noexcept
{
    return impl_->session_id;
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
