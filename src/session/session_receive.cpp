// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): received leaf states, acknowledgements, and the
// smooth view.
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

/// Quantised LeafState: rebuilds the owner's integers from the baseline it names into qu, qv.
/// \return false (counted) if the baseline is not held or the values are not acceptable.
bool Session::Impl::rebuild_quantised(std::uint16_t from, std::uint64_t tick, double time,
                                      std::size_t l, const net::QuantisedDelta& q, std::size_t n)
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
        const BaselineRing& ring = held[l];
        for (std::size_t i = 0; i < ring.size(); ++i)
        {
            const QuantisedLeaf& h = ring[i];
            if (h.sender == from && h.tick == want && want != tick &&
                h.u_exponent == q.u_exponent && h.v_exponent == q.v_exponent)
                base = &h;
        }
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
    const auto bv =
        base != nullptr ? std::span<const std::int32_t>(base->qv) : std::span<const std::int32_t>();
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
void Session::Impl::hold_quantised(std::uint16_t from, std::uint64_t tick, double time,
                                   std::size_t l, const net::QuantisedDelta& q, std::size_t n)
{
    BaselineRing& h = held[l];
    bool duplicate = false;
    for (std::size_t i = 0; i < h.size(); ++i)
    {
        const QuantisedLeaf& e = h[i];
        if (e.sender == from && e.tick > tick)
            return;
        duplicate = duplicate || (e.sender == from && e.tick == tick);
    }
    if (!duplicate)
        store_quantised(h.push_back(), from, tick, time, q.u_exponent, q.v_exponent, qu, qv, n);
    PendingAcks& pending = pending_acks[from];
    if (pending.listed.size() != held.size())
    {
        pending.listed.assign(held.size(), 0);
        pending.tick_plus_one.assign(held.size(), 0);
        pending.leaves.clear();
    }
    if (pending.listed[l] == 0)
    {
        pending.listed[l] = 1;
        pending.tick_plus_one[l] = 0;
        pending.leaves.push_back(static_cast<std::uint32_t>(l));
    }
    pending.tick_plus_one[l] = std::max(pending.tick_plus_one[l], tick + 1);
    acks_pending = true;
}

void Session::Impl::send_acks()
{
    const LeafGraph& graph = *s.graph_;
    if (!std::holds_alternative<net::Ack>(ack_msg.body))
        ack_msg.body = net::Ack{};
    auto& acks = std::get<net::Ack>(ack_msg.body).acks;
    for (auto& [to, pending] : pending_acks)
    {
        // By leaf index, as they were listed in a map before.
        std::sort(pending.leaves.begin(), pending.leaves.end());
        acks.clear();
        for (const std::uint32_t l : pending.leaves)
        {
            const core::LeafId id = graph.leaves()[l];
            acks.push_back(net::LeafAck{net::WireLeafId{id.square, id.depth, id.ix, id.iy},
                                        pending.tick_plus_one[l] - 1});
            pending.listed[l] = 0;
            if (acks.size() == net::k_max_acks)
            {
                send_ack(to);
                acks.clear();
            }
        }
        if (!acks.empty())
            send_ack(to);
        pending.leaves.clear();
    }
    acks_pending = false;
}

/// Sends ack_msg's Ack to `to`. Acks count against the bandwidth cap towards that peer, like
/// leaf states.
void Session::Impl::send_ack(std::uint16_t to)
{
    ack_msg.header = net::Header{session_id, s.id_, 0, s.state_.tick};
    if (capped())
        budget[to] -= static_cast<double>(net::encoded_size(ack_msg));
    send_to(to, ack_msg);
}

void Session::Impl::on_ack(std::uint16_t from, const net::Ack& ack)
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

void Session::Impl::on_leaf_state(std::uint16_t from, const net::Message& m,
                                  const net::LeafState& ls)
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
        if (count_reject(counters.foreign_states, from))
            warn_rejected(from, "a state of leaf " + std::to_string(l) +
                                    ", which it does not own in epoch " + std::to_string(ls.epoch));
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
        net::dequantise(std::span(qu.data(), n), ls.quantised.u_exponent, std::span(xu.data(), n));
        net::dequantise(std::span(qv.data(), n), ls.quantised.v_exponent, std::span(xv.data(), n));
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
void Session::Impl::mark_shown(std::size_t l, std::uint32_t epoch, std::uint64_t tick, double time,
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
void Session::Impl::show(std::size_t l, std::size_t offset, std::size_t count, const double* u,
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
void Session::Impl::set_aside(std::size_t l, std::uint16_t from, std::uint64_t tick,
                              const net::LeafState& ls, const double* u, const double* v)
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
void Session::Impl::on_leaf_batch(std::uint16_t from, const net::Message& m,
                                  const net::LeafBatch& b)
{
    // One LeafState for every leaf of every batch: copying into it reuses its vectors.
    net::LeafState& ls = batch_state;
    ls.epoch = b.epoch;
    ls.encoding = net::ValueEncoding::QuantisedDelta;
    ls.coarsen = 0;
    ls.node_offset = 0;
    ls.time = b.time;
    ls.u.clear();
    ls.v.clear();
    for (const net::BatchLeaf& leaf : b.leaves)
    {
        ls.leaf = leaf.leaf;
        ls.quantised = leaf.quantised;
        on_leaf_state(from, m, ls);
    }
}

/// A ValueBatch: each of its leaves as the f32 / f64 LeafState it stands for.
void Session::Impl::on_value_batch(std::uint16_t from, const net::Message& m,
                                   const net::ValueBatch& b)
{
    net::LeafState& ls = batch_state;
    ls.epoch = b.epoch;
    ls.encoding = b.encoding;
    ls.coarsen = b.coarsen;
    ls.node_offset = 0;
    ls.time = b.time;
    ls.quantised.du.clear();
    ls.quantised.dv.clear();
    ls.quantised.packed.clear();
    for (const net::ValueLeaf& leaf : b.leaves)
    {
        ls.leaf = leaf.leaf;
        ls.u = leaf.u;
        ls.v = leaf.v;
        on_leaf_state(from, m, ls);
    }
}

/// The states kept aside (set_aside): once their epoch's Partition is here, one from its leaf's
/// owner is shown (if still the newest) and any other dropped; one whose epoch never came
/// (skipped, or k_provisional_s passed) is dropped too, each counted.
void Session::Impl::settle_provisional_states()
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
bool Session::Impl::settle_leaf(std::uint32_t l, std::uint32_t last)
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
        if (count_reject(counters.foreign_states, h.sender))
            warn_rejected(h.sender, "a state of leaf " + std::to_string(l) +
                                        ", which it does not own in epoch " +
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

/// Keeps the shown state of every leaf updated by this poll (not ours) for interpolation,
/// and the newest time received per sender.
void Session::Impl::record_history()
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
        if (h.sender != leaf_sender[l] || (h.count > 0 && leaf_time[l] < h.time_of(h.count - 1)))
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
void Session::Impl::update_view(double now)
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
void Session::Impl::materialize_view()
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
            for_node_runs(
                l, [&](std::size_t o, std::size_t, std::size_t c) { copy_run(du + o, c, vu + o); });
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

}  // namespace pliant::session
