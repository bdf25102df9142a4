// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): the display of own leaves and the stream of leaf
// states.
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

/// Quantises leaf `l` of the state into qu, qv (first n entries), and its dequantised values
/// into xu, xv. \return the node count, or 0 if a value does not fit the int32 range.
std::size_t Session::Impl::quantise_leaf(std::uint32_t l)
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
void Session::Impl::adopt_quantised()
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

void Session::Impl::copy_own_to_display(const PartitionEntry* p)
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
void Session::Impl::flush_display()
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
void Session::Impl::refine_display()
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

void Session::Impl::refine_plane(int top, const core::Field<double>& display,
                                 std::vector<core::Field<double>>& coarse,
                                 core::Field<double>& refined)
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

const PartitionEntry* Session::Impl::stream_partition() const
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
bool Session::Impl::extrapolate(const QuantisedLeaf& base, double time, std::size_t n)
{
    const double su = net::quantum(base.u_exponent);
    const double sv = net::quantum(base.v_exponent);
    const double dt = time - base.time;
    for (std::size_t i = 0; i < n; ++i)
        xp[i] = static_cast<double>(base.qu[i]) * su + static_cast<double>(base.qv[i]) * sv * dt;
    return net::quantise(std::span(xp.data(), n), base.u_exponent, std::span(pu.data(), n));
}

/// The baseline `peer` acknowledged for leaf `l` that we still hold, or null.
const QuantisedLeaf* Session::Impl::acked_baseline(std::uint16_t peer, std::uint32_t l) const
{
    auto it = acked.find(peer);
    if (it == acked.end() || it->second[l] == 0)
        return nullptr;
    const std::uint64_t tick = it->second[l] - 1;
    const BaselineRing& h = sent[l];
    for (std::size_t i = 0; i < h.size(); ++i)
        if (h[i].tick == tick && h[i].u_exponent == settings.u_step_exponent &&
            h[i].v_exponent == settings.v_step_exponent)
            return &h[i];
    return nullptr;
}

/// Codes qu, qv (n nodes) against `base` (null: a key state) into `q` (every field; its vectors
/// keep their capacity). \return false if the packed residuals do not fit one datagram.
bool Session::Impl::code_leaf(net::QuantisedDelta& q, std::size_t n, const QuantisedLeaf* base)
{
    const auto cu = std::span<const std::int32_t>(qu.data(), n);
    const auto cv = std::span<const std::int32_t>(qv.data(), n);
    auto bu = base != nullptr ? std::span<const std::int32_t>(base->qu) : cu.first(0);
    const auto bv = base != nullptr ? std::span<const std::int32_t>(base->qv) : cv.first(0);
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

/// Adds the leaf just coded (`coded`: its id and residuals) to the LeafBatch being filled for
/// `pid`, first sending that batch if the leaf would take it over one datagram. `coded` gets
/// spare vectors back, so neither this nor the next code_leaf allocates once the spares have
/// grown. \return the bytes this adds to the stream to `pid` (the leaf's record, plus a header
/// and the batch's fixed part when it opens one).
std::size_t Session::Impl::batch_leaf(std::uint16_t pid, std::uint32_t epoch, std::uint64_t tick)
{
    const std::size_t record = net::batch_leaf_size(coded);
    OutBatch& ob = batch[pid];
    std::size_t bytes = record;
    if (ob.open)
    {
        const auto* b = std::get_if<net::LeafBatch>(&ob.message.body);
        if (b == nullptr || b->leaves.size() >= net::k_max_batch_leaves ||
            net::encoded_size(ob.message) + record > net::k_header_size + net::k_max_state_payload)
            send_batch(pid, ob);
    }
    if (!ob.open)
    {
        if (!std::holds_alternative<net::LeafBatch>(ob.message.body))
            ob.message.body = net::LeafBatch{};
        ob.message.header = net::Header{session_id, s.id_, 0, tick};
        auto& b = std::get<net::LeafBatch>(ob.message.body);
        b.epoch = epoch;
        b.time = s.state_.time;
        b.u_exponent = static_cast<std::int8_t>(settings.u_step_exponent);
        b.v_exponent = static_cast<std::int8_t>(settings.v_step_exponent);
        ob.open = true;
        bytes += net::k_header_size + net::k_leaf_batch_fixed;
    }
    auto& b = std::get<net::LeafBatch>(ob.message.body);
    net::BatchLeaf& leaf = b.leaves.emplace_back();
    leaf.leaf = coded.leaf;
    std::swap(leaf.quantised, coded.quantised);
    if (!spare_deltas.empty())
    {
        coded.quantised = std::move(spare_deltas.back());
        spare_deltas.pop_back();
    }
    return bytes;
}

/// Adds f32 / f64 leaf state `m` (whole leaf) to the ValueBatch being filled for `pid`,
/// first sending that batch if `m` would take it over one datagram.
void Session::Impl::batch_values(std::uint16_t pid, const net::LeafState& m, std::uint64_t tick)
{
    coded_values.leaf = m.leaf;
    coded_values.u.assign(m.u.begin(), m.u.end());
    coded_values.v.assign(m.v.begin(), m.v.end());
    const std::size_t record = net::value_leaf_size(coded_values, m.encoding);
    OutBatch& ob = batch[pid];
    if (ob.open)
    {
        const auto* b = std::get_if<net::ValueBatch>(&ob.message.body);
        if (b == nullptr || b->encoding != m.encoding || b->coarsen != m.coarsen ||
            b->leaves.front().leaf.depth != m.leaf.depth ||
            b->leaves.size() >= net::k_max_batch_leaves ||
            net::encoded_size(ob.message) + record > net::k_header_size + net::k_max_state_payload)
            send_batch(pid, ob);
    }
    if (!ob.open)
    {
        if (!std::holds_alternative<net::ValueBatch>(ob.message.body))
            ob.message.body = net::ValueBatch{};
        ob.message.header = net::Header{session_id, s.id_, 0, tick};
        auto& b = std::get<net::ValueBatch>(ob.message.body);
        b.epoch = m.epoch;
        b.time = m.time;
        b.encoding = m.encoding;
        b.coarsen = m.coarsen;
        ob.open = true;
    }
    auto& b = std::get<net::ValueBatch>(ob.message.body);
    std::swap(b.leaves.emplace_back(), coded_values);
    if (!spare_values.empty())
    {
        coded_values = std::move(spare_values.back());
        spare_values.pop_back();
    }
}

/// Sends the batch being filled for `pid` and closes it, keeping the message and moving its
/// leaves' vectors to the spares.
void Session::Impl::send_batch(std::uint16_t pid, OutBatch& b)
{
    send_to(pid, b.message, net::SendMode::Unsequenced);
    if (auto* lb = std::get_if<net::LeafBatch>(&b.message.body))
    {
        for (net::BatchLeaf& leaf : lb->leaves)
            spare_deltas.push_back(std::move(leaf.quantised));
        lb->leaves.clear();
    }
    else if (auto* vb = std::get_if<net::ValueBatch>(&b.message.body))
    {
        for (net::ValueLeaf& leaf : vb->leaves)
            spare_values.push_back(std::move(leaf));
        vb->leaves.clear();
    }
    b.open = false;
}

/// Sends every LeafBatch or ValueBatch being filled (the end of a stream period).
void Session::Impl::flush_batches()
{
    for (auto& [pid, b] : batch)
        if (b.open)
            send_batch(pid, b);
}

/// Whether a receiver that acknowledged `base` (an entry of `entries`) shows exactly the
/// leaf's quantised values now (qu, qv: `n` of each): `base` holds them, and so does every
/// entry sent after it, which the receiver may have taken instead. Comparing values and
/// not entries: with two receivers acknowledging different entries of a leaf at rest, each
/// all-zero delta sent to one added an entry the other had not acknowledged, and the leaf
/// went out every stream period, to each in turn.
bool Session::Impl::shows_now(const BaselineRing& entries, const QuantisedLeaf& base,
                              std::size_t n) const
{
    const auto same = [&](const QuantisedLeaf& e)
    {
        return e.qu.size() == n && e.qv.size() == n &&
               std::equal(e.qu.begin(), e.qu.end(), qu.begin()) &&
               std::equal(e.qv.begin(), e.qv.end(), qv.begin());
    };
    for (std::size_t i = entries.size(); i-- > 0;)
    {
        if (!same(entries[i]))
            return false;
        if (&entries[i] == &base)
            return true;
    }
    return false;  // not in the history (cannot be: acked_baseline returns one of it)
}

/// Quantised streaming of leaf `l` to every peer (docs/protocol.md §5.5). \return false if
/// the leaf's values do not quantise (the caller sends f64).
bool Session::Impl::stream_quantised(const PartitionEntry* p, std::uint32_t l)
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
        coded.leaf = net::WireLeafId{id.square, id.depth, id.ix, id.iy};
        bool ok = code_leaf(coded.quantised, n, base);
        if (!ok && base != nullptr)
        {
            base = nullptr;
            ok = code_leaf(coded.quantised, n, nullptr);
        }
        if (ok)
        {
            any = true;
            if (base == nullptr)
                ++counters.key_states_sent;
        }
        ++counters.leaf_states_sent;
        if (ok && settings.batch_leaves)
        {
            const std::size_t bytes = batch_leaf(pid, p->epoch, tick);
            if (prio != nullptr)
            {
                budget[pid] -= static_cast<double>(bytes);
                (*prio)[l] = 0.0;
            }
            leaf_sent_time[l] = s.state_.time;
            continue;
        }
        // One LeafState alone, in a message reused for every such send: its `quantised` is
        // default between sends (encode requires it with F64), the coded residuals only swapped
        // in for one.
        if (!std::holds_alternative<net::LeafState>(quantised_msg.body))
            quantised_msg.body = net::LeafState{};
        quantised_msg.header = net::Header{session_id, s.id_, 0, tick};
        net::LeafState& m = std::get<net::LeafState>(quantised_msg.body);
        m.epoch = p->epoch;
        m.leaf = coded.leaf;
        m.time = s.state_.time;
        m.coarsen = 0;
        m.node_offset = 0;
        if (ok)
        {
            m.encoding = net::ValueEncoding::QuantisedDelta;
            m.u.clear();
            m.v.clear();
            std::swap(m.quantised, coded.quantised);
        }
        else
        {
            // Incompressible: the same dequantised bits as f64, outside the baseline chain.
            m.encoding = net::ValueEncoding::F64;
            m.u.assign(xu.begin(), xu.begin() + static_cast<std::ptrdiff_t>(n));
            m.v.assign(xv.begin(), xv.begin() + static_cast<std::ptrdiff_t>(n));
        }
        if (prio != nullptr)
        {
            budget[pid] -= static_cast<double>(net::encoded_size(quantised_msg));
            (*prio)[l] = 0.0;
        }
        send_to(pid, quantised_msg, net::SendMode::Unsequenced);
        if (ok)
            std::swap(m.quantised, coded.quantised);
        leaf_sent_time[l] = s.state_.time;
    }
    if (any)
    {
        BaselineRing& h = sent[l];
        if (!h.empty() && h.back().tick == tick)
            h.pop_back();
        store_quantised(h.push_back(), s.id_.value, tick, s.state_.time, settings.u_step_exponent,
                        settings.v_step_exponent, qu, qv, n);
    }
    return true;
}

/// Bandwidth cap: refills every peer's budget for one stream period and orders our leaves by
/// their total priority (highest first, then by index).
void Session::Impl::plan_capped_stream()
{
    refresh_interest();
    const double per_period = settings.bandwidth_cap_mbit_s * 1e6 / 8.0 / settings.stream_rate_hz;
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

void Session::Impl::stream()
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

}  // namespace pliant::session
