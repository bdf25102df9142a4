// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// Partitioning the quad-tree leaves among participants (docs/design.md §5, issue 6 item 4).
///
/// Design
/// - Leaf size: the smallest quad-tree depth at which every leaf's canonical nodes fit one
///   LeafState datagram (73 nodes with f64 values, 147 with f32; docs/protocol.md §3), so a leaf
///   is the unit of ownership, of streaming and of the wire Partition table.
/// - `LeafGraph` holds, for one grid and depth, the leaves in `TetraGrid::leaves` order (which is
///   the wire order), their canonical node counts, the canonical node -> leaf map and the leaf
///   adjacency: two leaves are neighbours when a grid edge joins their nodes through the ghost
///   map, so leaves across the glued seams of the tetrahedron are neighbours too.
/// - `partition_leaves` is a multi-source region growing (a balanced BFS Voronoi) on that graph:
///   each participant starts from the leaf holding its point of interest (participants without
///   one get the leaf farthest, in hops, from the seeds already placed); then the participant
///   with the fewest owned nodes (ties: the lower peer id) takes the next leaf of its own BFS
///   frontier (first discovered first, neighbours in increasing leaf order). Growing the smallest
///   first balances node counts to within about one leaf; growing along BFS fronts keeps each
///   share compact (short borders) and connected unless it gets enclosed. Everything is a
///   function of (grid, depth, sorted participants), so every peer computing it agrees.
/// - Slabs (`slab_partition`): the leaves in row-major order (leaf rows top to bottom, x
///   increasing) cut into one run per participant, balanced to a leaf; participants with a point
///   take the slabs in the order of their points' rows, and each cut moves as far as needed to
///   put every point's leaf and its neighbouring leaves inside its own slab. Every grid row is a
///   closed loop around the tetrahedron (x is periodic), so a slab is a band like a zone of
///   latitude: connected, bordered by one row loop per cut, and one x-run per grid row.
/// - Turned slabs: the row-major order is a cycle, so the balanced cuts may start at any leaf
///   (`slab_partition`'s `shift`; the slab across the order's end and start is a cap at the
///   top and one at the bottom of the grid). `centred_slab_shift` puts the cuts where they fall
///   farthest from the points, so that points on the plain slabs' cuts get bands about them.
/// - Why slabs: a restricted sim step pays per row segment (one x-run of owned nodes in
///   one grid row) about what 16 nodes cost (`k_row_segment_cost`; 13-15 since the kernels take a
///   row's segments in one call, docs/physics.md §8, kept at 16). A grown share spans most
///   rows, often as two runs (the periodic seam splits it), so half the nodes cost 0.57-0.71 of a
///   full step at levels 6-8; a slab spans 1/p of the rows in one run each.
///   `partition_leaves` takes, of the grown shares, the plain slabs and the turned slabs, the
///   one with the lowest modelled cost of the busiest participant (`step_cost`; ties: the
///   earlier) among those that exist (every point in its own slab within `k_slab_balance`) and,
///   in fast coupling, bring no point closer to a border (in leaf hops) than the grown shares,
///   where it sits at the centre of its share: fast coupling errs most next to borders, so
///   slabs never bring a border nearer a user's grab (`PointClearance`). So the grown shares
///   stay for points in the same rows or too close together for bands of their own, and in
///   fast coupling wherever a band is thinner about a point than its grown share.
/// - Whole-row slabs: the same cuts moved to the nearest leaf-row boundary (each cut one grid
///   row loop, no step of a leaf's width), taken when still within `k_slab_balance`. A cut
///   inside a leaf row adds a row segment per grid row of that leaf row and lengthens the
///   border by two leaf sides; at level 6 with 2 participants without points the straight cut's
///   busiest step costs 0.55 of a full step against 0.57 for the exactly balanced one.
/// - The halo: an exact-coupling peer also computes its neighbours' nearest rings (stages 1-2
///   two rings out, 3-4 one, docs/session.md §4.1), about one ring of the nodes next to its
///   share per step: `step_cost` counts those `ring_nodes` at `k_exact_ring_cost` in exact
///   coupling, so that a share with two borders (a band, or the two caps) costs more than one
///   with one. Fast coupling steps its own nodes only (weight 0).
/// - Wide shares (`wide_partition`): the grown shares' growth with each seat's front ordered by
///   a distance in which a hop to another leaf row costs more (`k_wide_row_hops`), so that the
///   shares grow along the rows and span fewer of them; a seat with a point takes the point's
///   neighbouring leaves first. No rebalancing pass (at level 10 it took up to 0.9 s on these
///   shares), so they exist only where the growth alone balances. Tried with points only; taken
///   where cheaper and, in fast coupling, where no point comes nearer a border than in the
///   grown shares.
/// - Blocks (`block_partition`): bands of whole leaf rows holding several seats each, every
///   band cut into runs of whole leaf columns, so that each share is a rectangle of leaves (one
///   x-run per grid row over a fraction of the rows) holding its point and the point's
///   neighbours. For points that share rows, where no band per seat can hold them; tried for
///   every band layout (composition of the seat count) with points and up to
///   `k_max_block_seats` participants.
/// - Rejected: plain recursive coordinate bisection (balanced but ignores the points of
///   interest and cuts across the seams arbitrarily; the blocks are its point-aware two-level
///   form); METIS-style multilevel partitioning (not in Debian's C++ packages we use, and
///   non-deterministic across versions).

#include <pliant/core/tetra_grid.h>
#include <pliant/net/message.h>
#include <pliant/net/types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace pliant::session
{

/// Largest canonical node count of any leaf at `depth`.
[[nodiscard]] std::size_t max_leaf_nodes(const core::TetraGrid& grid, int depth);

/// The smallest depth (0..min(level, 7)) whose leaves hold at most the nodes one LeafState of
/// `encoding` carries (73 for f64, 147 for f32). Level >= 3 gives level - 3 with f64.
[[nodiscard]] int leaf_depth_for(const core::TetraGrid& grid, net::ValueEncoding encoding);

/// The leaf adjacency graph of one grid at one depth (see the file comment).
class LeafGraph
{
public:
    /// \pre 0 <= depth <= grid.level().
    LeafGraph(const core::TetraGrid& grid, int depth);

    [[nodiscard]] int depth() const noexcept { return depth_; }
    [[nodiscard]] std::size_t size() const noexcept { return leaves_.size(); }
    [[nodiscard]] std::span<const core::LeafId> leaves() const noexcept { return leaves_; }
    [[nodiscard]] std::span<const core::Region> regions() const noexcept { return regions_; }
    /// Canonical nodes of leaf `l`, row-major (the LeafState node order).
    [[nodiscard]] std::span<const core::NodeIndex> nodes(std::size_t l) const noexcept
    {
        return {leaf_nodes_.data() + node_begin_[l], node_begin_[l + 1] - node_begin_[l]};
    }
    [[nodiscard]] std::size_t node_count(std::size_t l) const noexcept
    {
        return node_begin_[l + 1] - node_begin_[l];
    }
    /// Neighbouring leaves of `l`, increasing.
    [[nodiscard]] std::span<const std::uint32_t> neighbours(std::size_t l) const noexcept
    {
        return {adjacency_.data() + adj_begin_[l], adj_begin_[l + 1] - adj_begin_[l]};
    }
    /// The leaf owning a node (twins and ghosts map to their canonical node's leaf).
    [[nodiscard]] std::uint32_t leaf_of(core::NodeIndex n) const noexcept
    {
        return leaf_of_[n.value];
    }
    /// Index of a leaf id in `leaves()` (the wire order).
    [[nodiscard]] std::size_t index_of(const core::LeafId& leaf) const noexcept;

private:
    int depth_ = 0;
    std::vector<core::LeafId> leaves_;
    std::vector<core::Region> regions_;
    std::vector<std::size_t> node_begin_;
    std::vector<core::NodeIndex> leaf_nodes_;
    std::vector<std::uint32_t> leaf_of_;  ///< per grid node (twins: their canonical's leaf)
    std::vector<std::size_t> adj_begin_;
    std::vector<std::uint32_t> adjacency_;
};

/// A participant as the partitioner sees it: its id and, if it declared one, the node of its
/// first point of interest.
struct Seat
{
    net::PeerId peer;
    std::optional<core::NodeIndex> seed;
};

/// The partitioner's model of a restricted sim step's cost per row segment (a maximal x-run of
/// owned nodes in one grid row), in nodes: 0.11-0.13 us per segment against 7.4 ns per node,
/// measured on the development machine (docs/session.md §3).
inline constexpr double k_row_segment_cost = 16.0;
/// The row hops of the wide shares `partition_leaves` tries (`wide_partition`).
inline constexpr std::array<std::uint32_t, 2> k_wide_row_hops = {2, 4};
/// The most participants for which `partition_leaves` tries the blocks: their band layouts (the
/// compositions of the participant count) double with every participant, and with 8 the
/// repartition took up to 77 ms at level 10 (docs/session.md §3).
inline constexpr std::size_t k_max_block_seats = 4;
/// How far from the mean node count a slab may be, as a fraction, after its cuts moved to put
/// the points in their seats' slabs (the balance the partition tests require of every share;
/// the cost comparison in `partition_leaves` counts the extra nodes of the busiest).
inline constexpr double k_slab_balance = 0.10;
/// What an exact-coupling peer pays per node of the ring just outside its share, in nodes (the
/// 2 + 1 + 0 rings of its three stage pairs, about one ring per step; see the file comment).
inline constexpr double k_exact_ring_cost = 1.0;

/// What the slabs must leave around the points of interest to be taken.
enum class PointClearance : std::uint8_t
{
    /// No point fewer `border_hops` from a border than in the grown shares: fast coupling errs
    /// most next to borders (docs/session.md §4.2), so a user's grab keeps its distance.
    AsGrown,
    /// Only each point's leaf and its neighbours in its own slab: exact coupling gives the same
    /// state whatever the borders, so only the cost counts.
    Inside,
};

/// Owner of every leaf (index as `LeafGraph::leaves()`), deterministic in its inputs (the seats
/// are sorted by peer id first; their order does not matter). \pre seats non-empty, ids unique.
/// Of the candidates in the file comment (grown shares, plain and turned slabs, each also with
/// whole-row cuts, then the wide shares and the blocks of each band layout), the one with the
/// lowest busiest `step_cost` (with `ring_cost`: 0 for fast coupling, `k_exact_ring_cost` for
/// exact) among those that meet `clearance` (ties: the earlier).
[[nodiscard]] std::vector<net::PeerId> partition_leaves(
    const core::TetraGrid& grid, const LeafGraph& graph, std::span<const Seat> seats,
    PointClearance clearance = PointClearance::AsGrown, double ring_cost = 0.0);

/// Hops in the leaf graph from the leaf of `point` to the nearest leaf of another owner
/// (UINT32_MAX when one owner holds every leaf).
[[nodiscard]] std::uint32_t border_hops(const LeafGraph& graph, std::span<const net::PeerId> owners,
                                        core::NodeIndex point);

/// The grown shares alone (same contract as `partition_leaves`).
[[nodiscard]] std::vector<net::PeerId> grown_partition(const core::TetraGrid& grid,
                                                       const LeafGraph& graph,
                                                       std::span<const Seat> seats);

/// The wide shares alone: the grown shares' balanced growth with each seat's front ordered by a
/// distance in which a hop to another leaf row costs `row_hop` (1: the grown shares), so that
/// shares grow along the rows (a point's seat takes the point's neighbouring leaves first, and
/// for `row_hop` > 1 no rebalancing pass follows); or nothing when a point's leaf or one of its
/// neighbouring leaves that its seat holds in the grown shares is another seat's, or a share is
/// farther than `k_slab_balance` from the mean node count.
/// \pre row_hop >= 1.
[[nodiscard]] std::optional<std::vector<net::PeerId>> wide_partition(const core::TetraGrid& grid,
                                                                     const LeafGraph& graph,
                                                                     std::span<const Seat> seats,
                                                                     std::uint32_t row_hop);

/// The slabs alone, cut along the row-major leaf order taken as a cycle from its position
/// `shift` (0: from the first leaf; otherwise the slab across the end and the start of the order
/// is a cap at the top and one at the bottom of the grid), or nothing when a slab would be empty
/// or farther than `k_slab_balance` from the mean node count once every point's leaf and its
/// neighbours are inside its own slab. `whole_rows`: every balanced cut first moves to the
/// nearest leaf-row boundary (by nodes; `shift` should then be a leaf row's first leaf).
[[nodiscard]] std::optional<std::vector<net::PeerId>> slab_partition(const core::TetraGrid& grid,
                                                                     const LeafGraph& graph,
                                                                     std::span<const Seat> seats,
                                                                     std::size_t shift = 0,
                                                                     bool whole_rows = false);

/// The blocks alone: bands of whole leaf rows, band k holding `parts[k]` seats (top to bottom),
/// each band cut into `parts[k]` runs of whole leaf columns (one wrapping round x = 0 unless the
/// runs start at column 0), every share a rectangle of leaves holding its seat's point and the
/// point's neighbouring leaves; or nothing when no such cuts exist within `k_slab_balance` of
/// the mean node count (see the file comment). \pre `parts` non-empty, no part 0, summing to the
/// number of seats.
[[nodiscard]] std::optional<std::vector<net::PeerId>> block_partition(
    const core::TetraGrid& grid, const LeafGraph& graph, std::span<const Seat> seats,
    std::span<const std::size_t> parts);

/// The band layouts `partition_leaves` tries for the blocks of `p` participants: every
/// composition of p (ordered parts, each >= 1) into fewer than p parts (p parts of one seat each
/// are the whole-row slabs), in lexicographic order.
[[nodiscard]] std::vector<std::vector<std::size_t>> block_layouts(std::size_t p);

/// The shift (a position in the row-major leaf order) at which balanced slab cuts fall farthest
/// from every point of interest: each point's position along the order (its leaf's middle, in
/// nodes) taken modulo one slab's node count, and the cuts in the middle of the widest gap
/// between those phases. 0 without points.
[[nodiscard]] std::size_t centred_slab_shift(const LeafGraph& graph, std::span<const Seat> seats);

/// Per-peer quality of a partition.
struct PeerShare
{
    net::PeerId peer;
    std::size_t leaves = 0;
    std::size_t nodes = 0;         ///< canonical nodes owned
    std::size_t fragments = 0;     ///< connected components of its leaves in the leaf graph
    std::size_t border_edges = 0;  ///< surface edges with one end owned by it, one by another
    std::size_t row_segments = 0;  ///< x-runs of its canonical nodes, one per grid row
    /// Canonical nodes of other owners that are grid neighbours of its own (its first ring).
    std::size_t ring_nodes = 0;
};

/// The modelled cost of one restricted sim step over a share, in nodes.
[[nodiscard]] constexpr double step_cost(const PeerShare& s, double ring_cost = 0.0) noexcept
{
    return static_cast<double>(s.nodes) + k_row_segment_cost * static_cast<double>(s.row_segments) +
           ring_cost * static_cast<double>(s.ring_nodes);
}

struct PartitionQuality
{
    std::vector<PeerShare> shares;  ///< by increasing peer id
    std::size_t border_edges = 0;   ///< surface edges whose ends have different owners
    /// max |nodes - mean| / mean over the peers.
    double imbalance = 0.0;
    /// The largest `step_cost` of a share (at the `ring_cost` given to measure_partition).
    double busiest_cost = 0.0;
};

/// Measures a leaf -> owner table (every distinct owner gets a share).
[[nodiscard]] PartitionQuality measure_partition(const core::TetraGrid& grid,
                                                 const LeafGraph& graph,
                                                 std::span<const net::PeerId> owners,
                                                 double ring_cost = 0.0);

}  // namespace pliant::session
