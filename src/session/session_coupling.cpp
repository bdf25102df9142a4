// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): forces, and the two couplings: exact (halos, barrier)
// and fast (Dirichlet borders).
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

/// Exact coupling: peer `id` is not a member of the partition that applies from `tick`,
/// though it was of the one before: its forces end at `tick` (a recording master logs an
/// empty list for it there, so that the replay ends them too).
void Session::Impl::end_forces(std::uint16_t id, std::uint64_t tick)
{
    auto it = peers.find(id);
    if (it == peers.end() || (it->second.forces_end && *it->second.forces_end <= tick))
        return;
    it->second.forces_end = tick;
    if (recording)
        force_log.push_back(ForceRecord{id, tick, {}});
}

/// The entry with the greatest apply tick <= tick (ties: the later one).
const ForceEntry* Session::Impl::active(const std::vector<ForceEntry>& table, std::uint64_t tick)
{
    const ForceEntry* best = nullptr;
    for (const ForceEntry& e : table)
        if (e.apply_tick <= tick && (best == nullptr || e.apply_tick >= best->apply_tick))
            best = &e;
    return best;
}

const std::vector<sim::Force>& Session::Impl::forces_at(std::uint64_t tick)
{
    // Order: by sender id (the master, id 0, first), then each sender's list order.
    auto& entries = force_entries;
    entries.clear();
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
    forces_now.clear();
    for (const auto& [id, e] : entries)
        if (e != nullptr)
            (void)append_valid_forces(*s.model_, e->forces, forces_now);
    return forces_now;
}

void Session::Impl::prepare_forces()
{
    const auto same = [](const sim::Force& a, const sim::Force& b) {
        return a.face == b.face && a.point == b.point && a.radius == b.radius &&
               a.vector == b.vector;
    };
    if (forces_in_ws_valid && std::equal(forces_now.begin(), forces_now.end(), forces_in_ws.begin(),
                                         forces_in_ws.end(), same))
        return;
    sim::set_forces(*s.model_, *ws, forces_now);
    forces_in_ws = forces_now;
    forces_in_ws_valid = true;
}

/// Counts the forces of `list` above the session's limit (they act scaled down to it) and
/// logs the first of each peer's (`warned`), with the magnitude asked for and the limit.
void Session::Impl::count_limited(std::span<const net::UserForce> list, std::uint16_t from,
                                  bool& warned)
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
void Session::Impl::flush_forces(std::uint64_t earliest)
{
    if (pending_forces.empty())
    {
        if (my_forces.size() > 1)
            trim(my_forces);
        return;
    }
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
void Session::Impl::trim(std::vector<ForceEntry>& table) const
{
    const ForceEntry* cur = active(table, s.state_.tick > 2 ? s.state_.tick - 2 : 0);
    if (cur == nullptr)
        return;
    // In place: no allocation per call (flush_forces runs every tick).
    const std::uint64_t base = cur->apply_tick;
    const auto keep = static_cast<std::size_t>(cur - table.data());
    std::size_t kept = 0;
    for (std::size_t i = 0; i < table.size(); ++i)
        if (i == keep || table[i].apply_tick > base)
        {
            if (kept != i)
                table[kept] = std::move(table[i]);
            ++kept;
        }
    table.resize(kept);
}

void Session::Impl::send_halos(std::uint64_t t)
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
void Session::Impl::barrier_set(std::uint64_t t, std::vector<std::uint16_t>& out) const
{
    out.clear();  // its capacity kept: no allocation per tick
    for (const PartitionEntry* p : {t > 0 ? partition_at(t - 1) : nullptr, partition_at(t)})
        if (p != nullptr)
            for (const net::PeerId m : p->members)
                if (m != s.id_)
                {
                    auto it = peers.find(m.value);
                    if (it != peers.end() && !it->second.departed)
                        out.push_back(m.value);
                }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

void Session::Impl::publish(std::uint64_t t)
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
    std::vector<std::uint16_t>& to = heartbeat_to;
    barrier_set(t, to);
    for (const auto& [id, p] : peers)
        if (!p.departed && p.ready && p.info.role == net::Role::Participant)
            to.push_back(id);
    std::sort(to.begin(), to.end());
    to.erase(std::unique(to.begin(), to.end()), to.end());
    const net::Message beat = make(hb, t);
    for (const std::uint16_t id : to)
        send_to(id, beat, net::SendMode::Reliable);
    published = true;
}

/// The members whose Heartbeat(t) has not arrived, by increasing id (none: the barrier of
/// tick t is passed).
std::vector<std::uint16_t> Session::Impl::barrier_missing(std::uint64_t t) const
{
    std::vector<std::uint16_t> out;  // empty, and so not allocated, once the barrier is passed
    barrier_set(t, barrier_scratch);
    for (const std::uint16_t id : barrier_scratch)
    {
        const RemotePeer& p = peers.at(id);
        if (!p.has_heartbeat || p.heartbeat < t)
            out.push_back(id);
    }
    return out;
}

/// Exact mode, ready to step from `t` but for the members in `missing`: counts the wait,
/// warns once past k_barrier_warn_s, and on the master removes the members that have held
/// the lockstep past max_barrier_wait_s, as lost (docs/session.md §6): a hung or hostile
/// participant whose connection stays up would otherwise stop everyone for good.
void Session::Impl::wait_at_barrier(std::uint64_t t, const std::vector<std::uint16_t>& missing)
{
    if (barrier_since < 0.0 || barrier_tick != t)
    {
        barrier_tick = t;
        barrier_since = last_now;
        barrier_warned = false;
        return;
    }
    const double waited = last_now - barrier_since;
    // Named only when a warning says them (this runs on every call while waiting).
    const auto names = [this](const std::vector<std::uint16_t>& ids)
    {
        std::string out;
        for (const std::uint16_t id : ids)
            out += (out.empty() ? "" : ", ") + describe_peer(id);
        return out;
    };
    if (waited >= k_barrier_warn_s && !barrier_warned)
    {
        barrier_warned = true;
        spdlog::warn(
            "session: waited {:.1f} s at tick {} for {} to publish it (exact coupling steps "
            "every member together){}",
            waited, t, names(missing),
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
    spdlog::warn(
        "session: removing {} from the session: not one step published for {:.1f} s "
        "(tick {}); its leaves go on from their last streamed state",
        names(culprits), waited, t);
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

void Session::Impl::apply_halos(std::uint64_t t)
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
            if (count_reject(counters.halo_rejects, h.sender.value))
                warn_rejected(h.sender.value,
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
bool Session::Impl::owns_every_node(const PartitionEntry* part, const HaloBuffer& h) const
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
void Session::Impl::on_non_finite_step(std::uint64_t tick)
{
    s.diverged_tick_ = tick;
    spdlog::error(
        "session: the step from tick {} (t = {:.6g} s) gives non-finite values on this "
        "peer's nodes: the state diverged (a fixed step above the grid's stable step, "
        "docs/physics.md §5, or forces without a limit, docs/session.md §7); this peer holds "
        "its last finite state, streams it and leaves the session",
        tick, s.state_.time);
}

bool Session::Impl::may_step(std::uint64_t t) const
{
    if (settings.max_ticks != 0 && t >= settings.max_ticks)
        return false;
    if (!clock_set)
        return false;
    const double dt = s.model_->settings().fixed_dt;
    const double sim_now = last_now + clock_offset;
    return (static_cast<double>(t) + 1.0) * dt <= sim_now + 1e-9 * dt;
}

void Session::Impl::exact_advance()
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
        counters.active_forces = forces_at(t).size();
        prepare_forces();
        sim::StepOptions opt;
        opt.owned = integrate_runs;
        opt.needed = own_runs;     // each stage pair only where the own nodes read it
        opt.keep_outside = false;  // the halos and the display rewrite the nodes beyond
        const auto t0 = std::chrono::steady_clock::now();
        const sim::StepReport r = sim::step_prepared(*s.model_, s.state_, *ws, opt);
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
void Session::Impl::adopt_orphans(std::uint64_t t)
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
        spdlog::info("session: tick {}: took over leaves of a lost peer from their last state", t);
    }
}

void Session::Impl::become_member(std::uint64_t apply)
{
    // A joiner (or re-admitted peer) enters the lockstep at `apply`; its state comes from
    // the halos of that tick.
    lockstep = true;
    published = false;
    state_exact = false;
    exact_from = apply;
    s.state_.tick = apply;
}

/// The coupling edges of the owned set `mine` (see border_nodes).
void Session::Impl::refresh_border(const PartitionEntry* p, const std::vector<char>& mine)
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
void Session::Impl::damp_border(double t0, double dt)
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
void Session::Impl::fast_advance()
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
        counters.active_forces = forces_at(s.state_.tick).size();
        prepare_forces();
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

void Session::Impl::on_halo(std::uint16_t from, const net::Message& m, const net::Halo& h)
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
    // Only exact coupling's members exchange halos (send_halos).
    if (s.coupling_ != Coupling::Exact || s.role_ == SessionRole::Viewer)
    {
        reject(counters.halo_rejects, from,
               s.coupling_ != Coupling::Exact ? "a Halo in fast coupling" : "a Halo to a viewer");
        return;
    }
    const core::TetraGrid& g = s.model_->grid();
    for (const net::NodeRange& r : h.ranges)
        if (r.count > 0 && (r.first >= g.node_count() || r.count > g.node_count() - r.first))
            return;  // not our grid: ignore the whole message
    const std::uint64_t tick = m.header.tick;
    if (tick < s.state_.tick)
        return;  // of a tick stepped already: apply_halos would drop it unread
    if (tick - s.state_.tick > k_max_halo_lead)
    {
        reject(counters.halo_rejects, from, "a Halo for a tick far ahead of this peer's");
        return;
    }
    std::size_t held_values = h.u.size();
    for (const HaloBuffer& b : halos)
        if (b.sender.value == from)
            held_values += b.u.size();
    if (held_values > k_max_held_halo_grids * g.node_count())
    {
        reject(counters.halo_rejects, from, "more halo values than a lockstep holds");
        return;
    }
    // A buffer of an applied tick, with its capacity: no allocation per halo.
    HaloBuffer buf;
    if (!spare_halos.empty())
    {
        buf = std::move(spare_halos.back());
        spare_halos.pop_back();
    }
    buf.tick = tick;
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

}  // namespace pliant::session
