// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): points of interest, partitions and the sets they give
// each peer.
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

/// Marks the leaves within a leaf diameter of a point of interest or of an applied force.
void Session::Impl::refresh_interest()
{
    std::vector<std::pair<core::Vec3, double>> spots;  // position, radius
    const core::TetraGrid& g = s.model_->grid();
    const auto& P = s.model_->rest_positions();
    auto add = [&](const net::Target& t)
    {
        if (t.kind == net::TargetKind::Position)
        {
            spots.emplace_back(core::Vec3{t.position[0], t.position[1], t.position[2]}, t.radius);
            return;
        }
        if (const auto n = seed_of({t}))
        {
            const core::GridCoord c = g.coord(*n);
            spots.emplace_back(core::Vec3{P[0].at(c.x, c.y), P[1].at(c.x, c.y), P[2].at(c.x, c.y)},
                               t.radius);
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

const PartitionEntry* Session::Impl::partition_at(std::uint64_t tick) const
{
    const PartitionEntry* best = nullptr;
    for (const PartitionEntry& p : partitions)
        if (p.apply_tick <= tick && (best == nullptr || p.epoch > best->epoch))
            best = &p;
    return best;
}

const PartitionEntry* Session::Impl::with_epoch(std::uint32_t epoch) const
{
    for (const PartitionEntry& p : partitions)
        if (p.epoch == epoch)
            return &p;
    return nullptr;
}

const PartitionEntry* Session::Impl::newest() const
{
    const PartitionEntry* best = nullptr;
    for (const PartitionEntry& p : partitions)
        if (best == nullptr || p.epoch > best->epoch)
            best = &p;
    return best;
}

void Session::Impl::add_partition(std::uint64_t apply, std::uint32_t epoch,
                                  std::vector<net::PeerId> owners)
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
        std::erase_if(partitions, [&](const PartitionEntry& p) { return p.epoch < base_epoch; });
    }
}

std::optional<core::NodeIndex> Session::Impl::seed_of(const std::vector<net::Target>& pts) const
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
std::vector<net::PeerId> Session::Impl::compute_partition() const
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
void Session::Impl::warn_idle_members(const std::vector<net::PeerId>& owners)
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

void Session::Impl::master_repartition(std::uint64_t apply)
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

std::vector<char> Session::Impl::owned_mask(const PartitionEntry* p, net::PeerId id) const
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

/// Exact mode sets for publishing tick t / stepping from t.
void Session::Impl::refresh_exact_sets(const PartitionEntry* prev, const PartitionEntry* next)
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
std::vector<HaloChunk> Session::Impl::plan_halo(const std::vector<std::uint32_t>& nodes) const
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

void Session::Impl::refresh_my_leaves(const PartitionEntry* p)
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

void Session::Impl::send_points()
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

void Session::Impl::on_partition(std::uint16_t from, const net::Message& m, const net::Partition& p)
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

void Session::Impl::apply_partition(std::uint64_t tick, const net::Partition& p)
{
    if (p.leaf_depth != s.graph_->depth() || p.owners.size() != s.graph_->size())
        return;
    add_partition(tick, p.epoch, p.owners);
    if (s.coupling_ == Coupling::Exact && !lockstep && member(newest(), s.id_) &&
        s.role_ == SessionRole::Participant)
        become_member(tick);
}

}  // namespace pliant::session
