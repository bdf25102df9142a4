// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/assert.h>
#include <pliant/session/partition.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <utility>

namespace pliant::session
{

std::size_t max_leaf_nodes(const core::TetraGrid& grid, int depth)
{
    std::size_t best = 0;
    for (const core::LeafId& leaf : grid.leaves(depth))
    {
        const core::Region r = grid.leaf_region(leaf);
        std::size_t n = 0;
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
                n += grid.is_canonical(grid.index(x, y)) ? 1U : 0U;
        best = std::max(best, n);
    }
    return best;
}

int leaf_depth_for(const core::TetraGrid& grid, net::ValueEncoding encoding)
{
    const std::size_t cap =
        encoding == net::ValueEncoding::F64 ? net::k_max_leaf_nodes_f64 : net::k_max_leaf_nodes_f32;
    const int deepest = std::min(grid.level(), net::k_max_partition_depth);
    for (int d = 0; d < deepest; ++d)
        if (max_leaf_nodes(grid, d) <= cap)
            return d;
    return deepest;
}

LeafGraph::LeafGraph(const core::TetraGrid& grid, int depth) : depth_(depth)
{
    PLIANT_ASSERT(depth >= 0 && depth <= grid.level(), "LeafGraph: depth out of range");
    leaves_ = grid.leaves(depth);
    regions_.reserve(leaves_.size());
    leaf_of_.assign(grid.node_count(), std::numeric_limits<std::uint32_t>::max());
    node_begin_.push_back(0);
    for (std::size_t l = 0; l < leaves_.size(); ++l)
    {
        const core::Region r = grid.leaf_region(leaves_[l]);
        regions_.push_back(r);
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x)
            {
                const core::NodeIndex n = grid.index(x, y);
                if (!grid.is_canonical(n))
                    continue;
                PLIANT_ASSERT(leaf_of_[n.value] == std::numeric_limits<std::uint32_t>::max(),
                              "LeafGraph: a canonical node lies in two leaves");
                leaf_of_[n.value] = static_cast<std::uint32_t>(l);
                leaf_nodes_.push_back(n);
            }
        node_begin_.push_back(leaf_nodes_.size());
    }
    for (std::uint32_t i = 0; i < leaf_of_.size(); ++i)
    {
        const std::uint32_t c = grid.canonical(core::NodeIndex{i}).value;
        PLIANT_ASSERT(leaf_of_[c] != std::numeric_limits<std::uint32_t>::max(),
                      "LeafGraph: a canonical node lies in no leaf");
        leaf_of_[i] = leaf_of_[c];
    }
    // Leaf adjacency from the grid edges through the ghost map.
    std::vector<std::vector<std::uint32_t>> adj(leaves_.size());
    for (const core::NodeIndex n : leaf_nodes_)
    {
        const core::GridCoord c = grid.coord(n);
        const std::uint32_t a = leaf_of_[n.value];
        for (const core::NodeIndex m : core::grid_neighbours(grid, c.x, c.y))
        {
            const std::uint32_t b = leaf_of_[m.value];
            if (b != a)
                adj[a].push_back(b);
        }
    }
    adj_begin_.push_back(0);
    for (auto& list : adj)
    {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        adjacency_.insert(adjacency_.end(), list.begin(), list.end());
        adj_begin_.push_back(adjacency_.size());
    }
}

std::size_t LeafGraph::index_of(const core::LeafId& leaf) const noexcept
{
    const std::size_t side = std::size_t{1} << depth_;
    return (leaf.square * side + leaf.iy) * side + leaf.ix;
}

namespace
{

constexpr std::uint32_t k_unowned = std::numeric_limits<std::uint32_t>::max();

/// Hop distance from a set of sources (k_unowned where unreachable).
std::vector<std::uint32_t> hops_from(const LeafGraph& g, std::span<const std::uint32_t> sources)
{
    std::vector<std::uint32_t> dist(g.size(), k_unowned);
    std::deque<std::uint32_t> queue;
    for (const std::uint32_t s : sources)
        if (dist[s] == k_unowned)
        {
            dist[s] = 0;
            queue.push_back(s);
        }
    while (!queue.empty())
    {
        const std::uint32_t a = queue.front();
        queue.pop_front();
        for (const std::uint32_t b : g.neighbours(a))
            if (dist[b] == k_unowned)
            {
                dist[b] = dist[a] + 1;
                queue.push_back(b);
            }
    }
    return dist;
}

/// The first unowned leaf in BFS order from `start` (neighbours increasing).
std::uint32_t nearest_free(const LeafGraph& g, std::uint32_t start,
                           const std::vector<std::uint32_t>& owner)
{
    std::vector<bool> seen(g.size(), false);
    std::deque<std::uint32_t> queue{start};
    seen[start] = true;
    while (!queue.empty())
    {
        const std::uint32_t a = queue.front();
        queue.pop_front();
        if (owner[a] == k_unowned)
            return a;
        for (const std::uint32_t b : g.neighbours(a))
            if (!seen[b])
            {
                seen[b] = true;
                queue.push_back(b);
            }
    }
    return k_unowned;
}

/// max |count - mean| / mean.
double imbalance_of(std::span<const std::size_t> count)
{
    double total = 0.0;
    for (const std::size_t c : count)
        total += static_cast<double>(c);
    const double mean = total / static_cast<double>(count.size());
    double worst = 0.0;
    for (const std::size_t c : count)
        worst = std::max(worst, std::abs(static_cast<double>(c) - mean));
    return mean > 0.0 ? worst / mean : 0.0;
}

/// Whether seat `s`'s leaves other than `without` are one connected piece (`owner` by seat).
bool connected_without(const LeafGraph& graph, std::span<const std::uint32_t> owner,
                       std::uint32_t s, std::uint32_t start, std::uint32_t without,
                       std::size_t leaves, std::vector<std::uint32_t>& mark, std::uint32_t stamp)
{
    std::deque<std::uint32_t> queue{start};
    mark[start] = stamp;
    std::size_t reached = 1;
    while (!queue.empty())
    {
        const std::uint32_t a = queue.front();
        queue.pop_front();
        for (const std::uint32_t b : graph.neighbours(a))
            if (b != without && owner[b] == s && mark[b] != stamp)
            {
                mark[b] = stamp;
                ++reached;
                queue.push_back(b);
            }
    }
    return reached + 1 == leaves;
}

/// Smallest-first growth keeps counts within about a leaf unless a front closes early: a seat
/// walled in by its neighbours' shares (points close together, or next to each other on a
/// small grid) stops while the others take the rest (at level 6 with 4 random points, 1 layout
/// in 10 ended 10-26 % off the mean). Where the shares end more than `k_grown_balance` off,
/// leaves move across borders: of the moves that keep the giving share connected and its seed
/// leaf, and take from a share more than one leaf's nodes larger than the taker's (so that
/// the sum of squared counts falls and the loop ends), the pair with the largest gap goes
/// first, then the leaf with the most neighbours in the taking share (compact borders), then
/// the lowest leaf and taker (deterministic), until within `k_grown_target`.
void rebalance(const LeafGraph& graph, std::span<const std::uint32_t> seed,
               std::vector<std::uint32_t>& owner, std::vector<std::size_t>& count)
{
    constexpr double k_grown_balance = 0.10;
    constexpr double k_grown_target = 0.05;
    const std::size_t p = count.size();
    const std::size_t n = graph.size();
    if (p < 2 || imbalance_of(count) <= k_grown_balance)
        return;
    std::vector<bool> is_seed(n, false);
    for (const std::uint32_t l : seed)
        if (l != k_unowned)
            is_seed[l] = true;
    std::vector<std::size_t> leaves(p, 0);
    for (const std::uint32_t o : owner)
        ++leaves[o];
    struct Move
    {
        std::size_t gap;
        std::uint32_t ties;  // the leaf's neighbours in the taking share
        std::uint32_t leaf;
        std::uint32_t to;
    };
    std::vector<Move> moves;
    std::vector<std::uint32_t> mark(n, 0);
    std::uint32_t stamp = 0;
    for (std::size_t round = 0; round < n * p && imbalance_of(count) > k_grown_target; ++round)
    {
        moves.clear();
        for (std::uint32_t l = 0; l < n; ++l)
        {
            const std::uint32_t from = owner[l];
            if (is_seed[l] || leaves[from] < 2)
                continue;
            for (const std::uint32_t b : graph.neighbours(l))
            {
                const std::uint32_t to = owner[b];
                if (to == from || count[from] <= count[to] + graph.node_count(l))
                    continue;
                std::uint32_t ties = 0;
                for (const std::uint32_t c : graph.neighbours(l))
                    ties += owner[c] == to ? 1U : 0U;
                moves.push_back({count[from] - count[to], ties, l, to});
            }
        }
        std::sort(moves.begin(), moves.end(),
                  [](const Move& a, const Move& b)
                  {
                      if (a.gap != b.gap)
                          return a.gap > b.gap;
                      if (a.ties != b.ties)
                          return a.ties > b.ties;
                      return a.leaf != b.leaf ? a.leaf < b.leaf : a.to < b.to;
                  });
        bool moved = false;
        for (const Move& m : moves)  // the first that keeps its giver in one piece
        {
            const std::uint32_t from = owner[m.leaf];
            std::uint32_t start = k_unowned;  // any other leaf of the giving share
            for (const std::uint32_t b : graph.neighbours(m.leaf))
                if (owner[b] == from)
                {
                    start = b;
                    break;
                }
            if (start == k_unowned ||
                !connected_without(graph, owner, from, start, m.leaf, leaves[from], mark, ++stamp))
                continue;
            owner[m.leaf] = m.to;
            count[from] -= graph.node_count(m.leaf);
            count[m.to] += graph.node_count(m.leaf);
            --leaves[from];
            ++leaves[m.to];
            moved = true;
            break;
        }
        if (!moved)
            return;
    }
}

/// The balanced BFS growth from the seats' leaves (the file comment of partition.h), rebalanced
/// where a front closed early, as a seat index per leaf. With `row_hop` > 1 (the wide shares),
/// each seat's front is ordered by a distance from its seed in which a hop to another leaf row
/// costs `row_hop` and a hop along a leaf row 1 (ties: first discovered first), so the shares
/// grow along the rows: fewer grid rows, hence fewer row segments, for the same nodes.
/// \pre seats sorted by peer id, non-empty; row_hop >= 1.
std::vector<std::uint32_t> grow_seats(const core::TetraGrid& grid, const LeafGraph& graph,
                                      std::span<const Seat> seats, std::uint32_t row_hop = 1)
{
    const std::size_t p = seats.size();
    const std::size_t n = graph.size();
    std::vector<std::uint32_t> owner(n, k_unowned);  // seat index
    std::vector<std::uint32_t> seed(p, k_unowned);
    std::vector<std::uint32_t> placed;

    // Seeds: declared points first (in peer order), then the rest at the farthest free leaf.
    auto take = [&](std::size_t s, std::uint32_t leaf)
    {
        seed[s] = leaf;
        owner[leaf] = static_cast<std::uint32_t>(s);
        placed.push_back(leaf);
    };
    for (std::size_t s = 0; s < p && placed.size() < n; ++s)
        if (seats[s].seed)
        {
            PLIANT_ASSERT(seats[s].seed->value < grid.node_count(), "partition_leaves: bad seed");
            take(s, nearest_free(graph, graph.leaf_of(*seats[s].seed), owner));
        }
    for (std::size_t s = 0; s < p && placed.size() < n; ++s)
        if (!seats[s].seed)
        {
            std::uint32_t best = 0;
            if (!placed.empty())
            {
                const auto dist = hops_from(graph, placed);
                std::uint32_t far = 0;
                for (std::uint32_t l = 0; l < n; ++l)
                    if (owner[l] == k_unowned && dist[l] != k_unowned && dist[l] > far)
                    {
                        far = dist[l];
                        best = l;
                    }
            }
            take(s, best);
        }

    // Balanced growth along each seat's own front: (distance from the seed, discovery order,
    // leaf), smallest first. With row_hop 1 the distance is the BFS hop count and discovery
    // order already sorts the front, which is then the plain BFS queue.
    using Entry = std::array<std::uint64_t, 3>;
    std::vector<std::vector<Entry>> front(p);  // min-heaps
    std::vector<std::vector<std::uint64_t>> dist(p, std::vector<std::uint64_t>(n, UINT64_MAX));
    std::vector<std::size_t> count(p, 0);
    std::uint64_t discovered = 0;
    const int side = grid.w() >> graph.depth();
    const auto regions = graph.regions();
    const auto later = [](const Entry& a, const Entry& b) { return a > b; };
    auto grow_from = [&](std::size_t s, std::uint32_t leaf)
    {
        count[s] += graph.node_count(leaf);
        for (const std::uint32_t b : graph.neighbours(leaf))
        {
            const bool same_row = regions[b].y0 / side == regions[leaf].y0 / side;
            const std::uint64_t d = dist[s][leaf] + (same_row ? 1U : row_hop);
            if (d < dist[s][b])
            {
                dist[s][b] = d;
                front[s].push_back({d, discovered++, b});
                std::push_heap(front[s].begin(), front[s].end(), later);
            }
        }
    };
    for (std::size_t s = 0; s < p; ++s)
        if (seed[s] != k_unowned)
        {
            dist[s][seed[s]] = 0;
            grow_from(s, seed[s]);
        }
    std::size_t free_left = n - placed.size();
    // Wide shares reach the rows above and below a point late, so a point's seat first takes
    // the free neighbours of its leaf (the clearance every other candidate keeps).
    if (row_hop > 1)
        for (std::size_t s = 0; s < p; ++s)
            if (seats[s].seed && seed[s] != k_unowned)
                for (const std::uint32_t b : graph.neighbours(seed[s]))
                    if (owner[b] == k_unowned)
                    {
                        owner[b] = static_cast<std::uint32_t>(s);
                        dist[s][b] = std::min(dist[s][b], std::uint64_t{row_hop});
                        grow_from(s, b);
                        --free_left;
                    }
    while (free_left > 0)
    {
        std::size_t pick = p;
        for (std::size_t s = 0; s < p; ++s)
        {
            // Drop taken leaves and entries a shorter path has superseded.
            while (!front[s].empty() && (owner[front[s].front()[2]] != k_unowned ||
                                         front[s].front()[0] != dist[s][front[s].front()[2]]))
            {
                std::pop_heap(front[s].begin(), front[s].end(), later);
                front[s].pop_back();
            }
            if (!front[s].empty() && (pick == p || count[s] < count[pick]))
                pick = s;
        }
        if (pick == p)
            break;  // every front is closed (cannot happen on a connected graph)
        const auto leaf = static_cast<std::uint32_t>(front[pick].front()[2]);
        std::pop_heap(front[pick].begin(), front[pick].end(), later);
        front[pick].pop_back();
        owner[leaf] = static_cast<std::uint32_t>(pick);
        grow_from(pick, leaf);
        --free_left;
    }
    for (std::uint32_t l = 0; l < n; ++l)
        if (owner[l] == k_unowned)
        {
            const auto smallest = std::min_element(count.begin(), count.end()) - count.begin();
            owner[l] = static_cast<std::uint32_t>(smallest);
            count[static_cast<std::size_t>(smallest)] += graph.node_count(l);
        }
    // The wide shares skip it: at level 10 their fronts leave 8 shares far enough apart that
    // the pass took up to 0.9 s; they are a candidate only where the growth alone balances.
    if (row_hop == 1)
        rebalance(graph, seed, owner, count);
    return owner;
}

/// The leaves in row-major order (leaf rows top to bottom, x increasing).
std::vector<std::uint32_t> row_major_leaves(const LeafGraph& graph)
{
    std::vector<std::uint32_t> order(graph.size());
    for (std::uint32_t l = 0; l < order.size(); ++l)
        order[l] = l;
    const auto regions = graph.regions();
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b)
              {
                  return regions[a].y0 != regions[b].y0 ? regions[a].y0 < regions[b].y0
                                                        : regions[a].x0 < regions[b].x0;
              });
    return order;
}

/// Slabs: runs of the leaves in row-major order started at position `shift` and wrapping
/// round (the order is a cycle), one per seat, cut where the running node count passes k/p of
/// the total, seats ordered by the position of their point; each cut then moves (leaf by leaf)
/// as far as needed to put every point's leaf and its neighbouring leaves in its own seat's
/// slab. A seat index per leaf, or nothing when that needs a slab outside k_slab_balance of the
/// mean (the growth is used then). \pre seats sorted by peer id.
std::optional<std::vector<std::uint32_t>> slab_seats(const core::TetraGrid& grid,
                                                     const LeafGraph& graph,
                                                     std::span<const std::uint32_t> row_major,
                                                     std::span<const Seat> seats, std::size_t shift,
                                                     bool whole_rows)
{
    const std::size_t p = seats.size();
    const std::size_t n = graph.size();
    if (p > n || shift >= n)
        return std::nullopt;
    std::vector<std::uint32_t> order(row_major.begin(), row_major.end());
    std::rotate(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(shift), order.end());
    std::vector<std::size_t> rank(n);        // leaf -> position in `order`
    std::vector<std::size_t> before(n + 1);  // nodes of order[0 .. k)
    for (std::size_t k = 0; k < n; ++k)
    {
        rank[order[k]] = k;
        before[k + 1] = before[k] + graph.node_count(order[k]);
    }
    const std::size_t total = before[n];
    // Balanced cuts: slab k starts at cut[k] (cut[0] = 0, cut[p] = n), at the leaf boundary
    // nearest to k/p of the nodes.
    std::vector<std::size_t> cut(p + 1, 0);
    cut[p] = n;
    for (std::size_t k = 1; k < p; ++k)
    {
        const double goal =
            static_cast<double>(total) * static_cast<double>(k) / static_cast<double>(p);
        std::size_t c = cut[k - 1] + 1;
        while (c < n - (p - k) && static_cast<double>(before[c + 1]) <= goal)
            ++c;
        if (c < n - (p - k) &&
            goal - static_cast<double>(before[c]) > static_cast<double>(before[c + 1]) - goal)
            ++c;
        cut[k] = c;
    }
    // Whether a leaf row starts at position k of `order` (0 < k < n).
    const auto regions = graph.regions();
    const auto row_start = [&](std::size_t k)
    { return regions[order[k]].y0 != regions[order[k - 1]].y0; };
    if (whole_rows)
    {
        // Each cut to the nearest position where a leaf row starts (by nodes), in order.
        for (std::size_t k = 1; k < p; ++k)
        {
            std::size_t down = cut[k];
            while (down > cut[k - 1] + 1 && !row_start(down))
                --down;
            std::size_t up = cut[k];
            while (up < n - (p - k) && !row_start(up))
                ++up;
            const bool down_ok = row_start(down);
            const bool up_ok = up < n && row_start(up);
            if (!down_ok && !up_ok)
                return std::nullopt;
            const double goal =
                static_cast<double>(total) * static_cast<double>(k) / static_cast<double>(p);
            cut[k] = !up_ok || (down_ok && goal - static_cast<double>(before[down]) <=
                                               static_cast<double>(before[up]) - goal)
                         ? down
                         : up;
            if (cut[k] <= cut[k - 1])
                return std::nullopt;
        }
    }
    // Slab positions: seats with a point in the order of their point's leaf (ties: peer id),
    // each at the slab holding its point or the next free one, the rest in peer order.
    std::vector<std::size_t> with_point;
    for (std::size_t s = 0; s < p; ++s)
        if (seats[s].seed)
        {
            PLIANT_ASSERT(seats[s].seed->value < grid.node_count(), "partition_leaves: bad seed");
            with_point.push_back(s);
        }
    const auto seed_rank = [&](std::size_t s) { return rank[graph.leaf_of(*seats[s].seed)]; };
    std::stable_sort(with_point.begin(), with_point.end(),
                     [&](std::size_t a, std::size_t b) { return seed_rank(a) < seed_rank(b); });
    const std::size_t q = with_point.size();
    std::vector<std::size_t> pos(q);
    for (std::size_t i = 0; i < q; ++i)
    {
        const std::size_t natural = static_cast<std::size_t>(
            std::upper_bound(cut.begin() + 1, cut.end() - 1, seed_rank(with_point[i])) -
            (cut.begin() + 1));
        pos[i] = std::max(natural, i > 0 ? pos[i - 1] + 1 : 0);
    }
    for (std::size_t i = q; i-- > 0;)
        pos[i] = std::min(pos[i], std::min(p - q + i, i + 1 < q ? pos[i + 1] - 1 : p - 1));
    std::vector<std::uint32_t> seat_at(p, k_unowned);
    for (std::size_t i = 0; i < q; ++i)
        seat_at[pos[i]] = static_cast<std::uint32_t>(with_point[i]);
    std::size_t next = 0;
    for (std::size_t s = 0; s < p; ++s)
        if (!seats[s].seed)
        {
            while (seat_at[next] != k_unowned)
                ++next;
            seat_at[next] = static_cast<std::uint32_t>(s);
        }
    // Move the cuts so that every point's leaf and its neighbours lie in its seat's slab:
    // cut[k] <= rank < cut[k + 1] for all of them (the rank range [lo, hi] of the point).
    std::vector<std::pair<std::size_t, std::size_t>> span(q);
    for (std::size_t i = 0; i < q; ++i)
    {
        const std::uint32_t leaf = graph.leaf_of(*seats[with_point[i]].seed);
        span[i] = {rank[leaf], rank[leaf]};
        for (const std::uint32_t b : graph.neighbours(leaf))
            span[i] = {std::min(span[i].first, rank[b]), std::max(span[i].second, rank[b])};
        std::size_t lo = std::min(cut[pos[i]], span[i].first);
        std::size_t hi = std::max(cut[pos[i] + 1], span[i].second + 1);
        if (whole_rows)  // moved cuts stay between leaf rows
        {
            while (lo > 0 && !row_start(lo))
                --lo;
            while (hi < n && !row_start(hi))
                ++hi;
        }
        cut[pos[i]] = lo;
        cut[pos[i] + 1] = hi;
    }
    // Points whose spans overlap pull a cut both ways: the later move wins, so check them all
    // again. A violated span, an empty slab or one out of balance rules the slabs out.
    for (std::size_t i = 0; i < q; ++i)
        if (span[i].first < cut[pos[i]] || span[i].second >= cut[pos[i] + 1])
            return std::nullopt;
    const double mean = static_cast<double>(total) / static_cast<double>(p);
    for (std::size_t k = 0; k < p; ++k)
    {
        if (cut[k + 1] <= cut[k])
            return std::nullopt;
        const double nodes = static_cast<double>(before[cut[k + 1]] - before[cut[k]]);
        if (std::abs(nodes - mean) > k_slab_balance * mean)
            return std::nullopt;
    }
    std::vector<std::uint32_t> owner(n);
    for (std::size_t k = 0; k < p; ++k)
        for (std::size_t i = cut[k]; i < cut[k + 1]; ++i)
            owner[order[i]] = seat_at[k];
    return owner;
}

/// Whether every seat's point has its leaf and the leaf's neighbours in its own share (`owner`
/// by seat index).
bool points_inside(const LeafGraph& graph, std::span<const std::uint32_t> owner,
                   std::span<const Seat> seats)
{
    for (std::size_t s = 0; s < seats.size(); ++s)
        if (seats[s].seed)
        {
            const std::uint32_t leaf = graph.leaf_of(*seats[s].seed);
            if (owner[leaf] != s)
                return false;
            for (const std::uint32_t b : graph.neighbours(leaf))
                if (owner[b] != s)
                    return false;
        }
    return true;
}

/// Blocks: bands of whole leaf rows, one per part of `parts` (a composition of the seat count,
/// top to bottom), each cut into as many runs of whole leaf columns as its part (x is periodic:
/// the runs start at a shift, and the run across x = 0 then wraps), so that every share is a
/// rectangle of leaves: one x-run per grid row, over 1/B of the rows. Each band cut starts at the
/// leaf-row boundary nearest to its share of the nodes and moves, nearest first, off any point's
/// leaf row (a cut next to a point's row would put its neighbours across it); the column runs
/// are balanced within their band, from the first shift (0, 1, C - 1, 2, ...) at which no run
/// boundary is next to a point's column and no run holds two points. Seats with a point take the
/// block of their point; the others the rest, in peer order, band by band. A seat index per
/// leaf, or nothing when a band holds more points than seats, no shift works, a point's leaf or
/// one of its neighbours lies in another seat's block, or a seat is farther than
/// `k_slab_balance` from the mean node count. \pre seats sorted by peer id; parts sum to
/// seats.size(), none 0.
std::optional<std::vector<std::uint32_t>> block_seats(const core::TetraGrid& grid,
                                                      const LeafGraph& graph,
                                                      std::span<const Seat> seats,
                                                      std::span<const std::size_t> parts)
{
    const std::size_t p = seats.size();
    const std::size_t n = graph.size();
    const int side = grid.w() >> graph.depth();  // a leaf's width in cells
    const auto rows = std::size_t{1} << graph.depth();
    const std::size_t cols = 2 * rows;
    if (p > n || parts.size() > rows)
        return std::nullopt;
    // The leaf at (row, col).
    std::vector<std::uint32_t> at(rows * cols, k_unowned);
    const auto regions = graph.regions();
    for (std::uint32_t l = 0; l < n; ++l)
        at[static_cast<std::size_t>(regions[l].y0 / side) * cols +
           static_cast<std::size_t>(regions[l].x0 / side)] = l;
    const auto row_of = [&](std::uint32_t l)
    { return static_cast<std::size_t>(regions[l].y0 / side); };
    const auto col_of = [&](std::uint32_t l)
    { return static_cast<std::size_t>(regions[l].x0 / side); };
    std::vector<std::uint32_t> point_leaf(p, k_unowned);
    std::vector<bool> point_row(rows, false);
    for (std::size_t s = 0; s < p; ++s)
        if (seats[s].seed)
        {
            PLIANT_ASSERT(seats[s].seed->value < grid.node_count(), "partition_leaves: bad seed");
            point_leaf[s] = graph.leaf_of(*seats[s].seed);
            point_row[row_of(point_leaf[s])] = true;
        }
    // Band cuts: band k holds the leaf rows [cut[k], cut[k + 1]).
    std::vector<std::size_t> before(rows + 1, 0);  // nodes of the leaf rows [0, r)
    for (std::size_t r = 0; r < rows; ++r)
    {
        before[r + 1] = before[r];
        for (std::size_t c = 0; c < cols; ++c)
            before[r + 1] += graph.node_count(at[r * cols + c]);
    }
    const std::size_t bands = parts.size();
    std::vector<std::size_t> cut(bands + 1, 0);
    cut[bands] = rows;
    std::size_t seats_above = 0;
    for (std::size_t k = 1; k < bands; ++k)
    {
        seats_above += parts[k - 1];
        const double goal = static_cast<double>(before[rows]) * static_cast<double>(seats_above) /
                            static_cast<double>(p);
        std::size_t nearest = cut[k - 1] + 1;
        for (std::size_t r = nearest; r < rows; ++r)
            if (std::abs(static_cast<double>(before[r]) - goal) <
                std::abs(static_cast<double>(before[nearest]) - goal))
                nearest = r;
        // Off the points' rows: a cut at r lies between rows r - 1 and r.
        const auto clear = [&](std::size_t r) {
            return r > cut[k - 1] && r + (bands - k) <= rows - 1 && !point_row[r - 1] &&
                   !point_row[r];
        };
        std::size_t chosen = 0;
        for (std::size_t d = 0; d < rows && chosen == 0; ++d)
        {
            if (nearest >= d && clear(nearest - d))
                chosen = nearest - d;
            else if (clear(nearest + d))
                chosen = nearest + d;
        }
        if (chosen == 0)
            return std::nullopt;
        cut[k] = chosen;
    }
    // The blocks, band by band: owner[l] is a block number until the seats are placed.
    std::vector<std::uint32_t> owner(n, k_unowned);
    std::vector<std::uint32_t> block_seat;  // per block: the seat with its point, or k_unowned
    for (std::size_t k = 0; k < bands; ++k)
    {
        const std::size_t r0 = cut[k];
        const std::size_t r1 = cut[k + 1];
        std::vector<std::size_t> col_nodes(cols, 0);
        for (std::size_t r = r0; r < r1; ++r)
            for (std::size_t c = 0; c < cols; ++c)
                col_nodes[c] += graph.node_count(at[r * cols + c]);
        std::vector<std::size_t> band_points;  // seats whose point lies in this band
        for (std::size_t s = 0; s < p; ++s)
            if (point_leaf[s] != k_unowned && row_of(point_leaf[s]) >= r0 &&
                row_of(point_leaf[s]) < r1)
                band_points.push_back(s);
        const std::size_t m = parts[k];
        if (band_points.size() > m || m > cols)
            return std::nullopt;
        // Column run of every column for one shift (the runs' boundaries are the shift and the
        // balanced cuts after it), or nothing when a boundary is next to a point's column or a
        // run holds two points.
        const auto runs_for = [&](std::size_t shift) -> std::optional<std::vector<std::size_t>>
        {
            std::vector<std::size_t> run(cols, 0);
            std::vector<bool> boundary(cols, false);  // a run starts at this column
            boundary[shift] = true;
            std::size_t total = 0;
            for (const std::size_t c : col_nodes)
                total += c;
            std::size_t sum = 0;
            std::size_t index = 0;
            for (std::size_t i = 0; i < cols; ++i)
            {
                const std::size_t c = (shift + i) % cols;
                // A new run starts here when the running count is nearer the next goal before
                // this column than after it.
                if (i > 0 && index + 1 < m)
                {
                    const double goal = static_cast<double>(total) *
                                        static_cast<double>(index + 1) / static_cast<double>(m);
                    if (std::abs(static_cast<double>(sum) - goal) <=
                            std::abs(static_cast<double>(sum + col_nodes[c]) - goal) ||
                        cols - i == m - index - 1)
                    {
                        ++index;
                        boundary[c] = true;
                    }
                }
                run[c] = index;
                sum += col_nodes[c];
            }
            if (index + 1 != m)
                return std::nullopt;
            std::vector<std::size_t> points_in(m, 0);
            for (const std::size_t s : band_points)
            {
                const std::size_t c = col_of(point_leaf[s]);
                if (m > 1 && (boundary[c] || boundary[(c + 1) % cols]))
                    return std::nullopt;
                if (++points_in[run[c]] > 1)
                    return std::nullopt;
            }
            return run;
        };
        std::optional<std::vector<std::size_t>> run;
        if (m == 1)
            run = std::vector<std::size_t>(cols, 0);
        for (std::size_t d = 0; d <= cols / 2 && !run; ++d)
        {
            run = runs_for(d);
            if (!run && d > 0 && d < cols - d)
                run = runs_for(cols - d);
        }
        if (!run)
            return std::nullopt;
        const std::size_t first = block_seat.size();
        block_seat.resize(first + m, k_unowned);
        for (std::size_t r = r0; r < r1; ++r)
            for (std::size_t c = 0; c < cols; ++c)
                owner[at[r * cols + c]] = static_cast<std::uint32_t>(first + (*run)[c]);
        for (const std::size_t s : band_points)
            block_seat[first + (*run)[col_of(point_leaf[s])]] = static_cast<std::uint32_t>(s);
    }
    // Seats without a point take the blocks without one, in peer order.
    std::size_t next = 0;
    for (std::size_t s = 0; s < p; ++s)
        if (!seats[s].seed)
        {
            while (next < block_seat.size() && block_seat[next] != k_unowned)
                ++next;
            PLIANT_ASSERT(next < block_seat.size(), "block_seats: more seats than blocks");
            block_seat[next] = static_cast<std::uint32_t>(s);
        }
    std::vector<std::size_t> count(p, 0);
    for (std::size_t l = 0; l < n; ++l)
    {
        owner[l] = block_seat[owner[l]];
        count[owner[l]] += graph.node_count(l);
    }
    if (!points_inside(graph, owner, seats))
        return std::nullopt;
    const double mean = static_cast<double>(before[rows]) / static_cast<double>(p);
    for (const std::size_t c : count)
        if (std::abs(static_cast<double>(c) - mean) > k_slab_balance * mean)
            return std::nullopt;
    return owner;
}

/// The wide shares: the growth with a hop to another leaf row costing `row_hop`, or nothing
/// when a point's leaf or one of its neighbours that its seat holds in the grown shares
/// (`grown`; points too close together share their neighbours there) went to another seat, or
/// a share ended farther than `k_slab_balance` from the mean. \pre seats sorted by peer id.
std::optional<std::vector<std::uint32_t>> wide_seats(const core::TetraGrid& grid,
                                                     const LeafGraph& graph,
                                                     std::span<const Seat> seats,
                                                     std::span<const std::uint32_t> grown,
                                                     std::uint32_t row_hop)
{
    std::vector<std::uint32_t> owner = grow_seats(grid, graph, seats, row_hop);
    for (std::size_t s = 0; s < seats.size(); ++s)
        if (seats[s].seed)
        {
            const std::uint32_t leaf = graph.leaf_of(*seats[s].seed);
            if (grown[leaf] == s && owner[leaf] != s)
                return std::nullopt;
            for (const std::uint32_t b : graph.neighbours(leaf))
                if (grown[b] == s && owner[b] != s)
                    return std::nullopt;
        }
    std::vector<std::size_t> count(seats.size(), 0);
    for (std::size_t l = 0; l < owner.size(); ++l)
        count[owner[l]] += graph.node_count(l);
    if (imbalance_of(count) > k_slab_balance)
        return std::nullopt;
    return owner;
}

std::vector<Seat> sorted_seats(std::span<const Seat> seats_in)
{
    PLIANT_ASSERT(!seats_in.empty(), "partition_leaves: no participant");
    std::vector<Seat> seats(seats_in.begin(), seats_in.end());
    std::sort(seats.begin(), seats.end(),
              [](const Seat& a, const Seat& b) { return a.peer < b.peer; });
    for (std::size_t k = 1; k < seats.size(); ++k)
        PLIANT_ASSERT(seats[k - 1].peer != seats[k].peer, "partition_leaves: duplicate peer");
    return seats;
}

/// Row segments per owner index (`owner[l]` < out.size() for every leaf l): the x-runs of each
/// owner's canonical nodes, row by row, as `node_runs` cuts them for the restricted step (a
/// twin ends a run). One pass over the grid.
void count_row_segments(const core::TetraGrid& grid, const LeafGraph& graph,
                        const std::vector<std::uint32_t>& owner, std::vector<std::size_t>& out)
{
    for (int y = 0; y < grid.ny(); ++y)
    {
        std::uint32_t prev = k_unowned;
        for (int x = 0; x < grid.nx(); ++x)
        {
            const core::NodeIndex n = grid.index(x, y);
            if (!grid.is_canonical(n))
            {
                prev = k_unowned;
                continue;
            }
            const std::uint32_t o = owner[graph.leaf_of(n)];
            if (o != prev)
                ++out[o];
            prev = o;
        }
    }
}

/// Ring nodes per owner index: the canonical nodes of other owners that are grid neighbours
/// (through the ghost map) of its own. Only leaves with a neighbouring leaf of another owner
/// can hold such nodes, so the pass visits those leaves' nodes only.
void count_ring_nodes(const core::TetraGrid& grid, const LeafGraph& graph,
                      const std::vector<std::uint32_t>& owner, std::vector<std::size_t>& out)
{
    for (std::size_t l = 0; l < graph.size(); ++l)
    {
        const std::uint32_t mine = owner[l];
        const auto nb = graph.neighbours(l);
        if (std::all_of(nb.begin(), nb.end(), [&](std::uint32_t b) { return owner[b] == mine; }))
            continue;
        for (const core::NodeIndex n : graph.nodes(l))
        {
            const core::GridCoord c = grid.coord(n);
            std::array<std::uint32_t, 6> foreign{};
            std::size_t count = 0;
            for (const core::NodeIndex m : core::grid_neighbours(grid, c.x, c.y))
            {
                const std::uint32_t o = owner[graph.leaf_of(m)];
                if (o != mine &&
                    std::find(foreign.begin(), foreign.begin() + static_cast<std::ptrdiff_t>(count),
                              o) == foreign.begin() + static_cast<std::ptrdiff_t>(count))
                    foreign[count++] = o;
            }
            // n lies in the first ring of every other owner next to it.
            for (std::size_t i = 0; i < count; ++i)
                ++out[foreign[i]];
        }
    }
}

/// The largest `step_cost` over the seats of a seat-index table.
double busiest_cost(const core::TetraGrid& grid, const LeafGraph& graph,
                    const std::vector<std::uint32_t>& owner, std::size_t seats, double ring_cost)
{
    std::vector<std::size_t> nodes(seats, 0);
    std::vector<std::size_t> segments(seats, 0);
    std::vector<std::size_t> ring(seats, 0);
    for (std::size_t l = 0; l < owner.size(); ++l)
        nodes[owner[l]] += graph.node_count(l);
    count_row_segments(grid, graph, owner, segments);
    if (ring_cost != 0.0)
        count_ring_nodes(grid, graph, owner, ring);
    double worst = 0.0;
    for (std::size_t s = 0; s < seats; ++s)
    {
        PeerShare share;
        share.nodes = nodes[s];
        share.row_segments = segments[s];
        share.ring_nodes = ring[s];
        worst = std::max(worst, step_cost(share, ring_cost));
    }
    return worst;
}

std::vector<net::PeerId> to_peers(const std::vector<std::uint32_t>& owner,
                                  std::span<const Seat> seats)
{
    std::vector<net::PeerId> out(owner.size());
    for (std::size_t l = 0; l < owner.size(); ++l)
        out[l] = seats[owner[l]].peer;
    return out;
}

/// The position in `order` (`row_major_leaves`) nearest to `shift` (around the cycle) at which a
/// leaf row starts.
std::size_t nearest_row_start(const LeafGraph& graph, std::span<const std::uint32_t> order,
                              std::size_t shift)
{
    const std::size_t n = order.size();
    const auto regions = graph.regions();
    const auto starts = [&](std::size_t k)
    { return k == 0 || regions[order[k]].y0 != regions[order[k - 1]].y0; };
    for (std::size_t d = 0; d < n; ++d)
    {
        if (starts((shift + n - d) % n))
            return (shift + n - d) % n;
        if (starts((shift + d) % n))
            return (shift + d) % n;
    }
    return 0;
}

/// `centred_slab_shift` for seats sorted by peer id (`order`: `row_major_leaves`).
std::size_t centred_shift(const LeafGraph& graph, std::span<const std::uint32_t> order,
                          std::span<const Seat> seats)
{
    const std::size_t n = graph.size();
    std::vector<std::size_t> rank(n);
    std::vector<double> before(n + 1, 0.0);  // nodes of order[0 .. k)
    for (std::size_t k = 0; k < n; ++k)
    {
        rank[order[k]] = k;
        before[k + 1] = before[k] + static_cast<double>(graph.node_count(order[k]));
    }
    // Each point's position along the cycle (the middle of its leaf), modulo one slab.
    const double slab = before[n] / static_cast<double>(seats.size());
    std::vector<double> phase;
    for (const Seat& s : seats)
        if (s.seed)
        {
            const std::size_t k = rank[graph.leaf_of(*s.seed)];
            phase.push_back(std::fmod(0.5 * (before[k] + before[k + 1]), slab));
        }
    if (phase.empty())
        return 0;
    std::sort(phase.begin(), phase.end());
    // The widest gap between consecutive phases (round the cycle of one slab): cuts in its
    // middle are the farthest from every point.
    double widest = phase.front() + slab - phase.back();
    double middle = phase.back() + 0.5 * widest;
    for (std::size_t i = 1; i < phase.size(); ++i)
        if (phase[i] - phase[i - 1] > widest)
        {
            widest = phase[i] - phase[i - 1];
            middle = phase[i - 1] + 0.5 * widest;
        }
    middle = std::fmod(middle, slab);
    // The leaf boundary nearest to it.
    const auto above = static_cast<std::size_t>(
        std::lower_bound(before.begin(), before.end(), middle) - before.begin());
    const std::size_t shift =
        above > 0 && middle - before[above - 1] < before[above] - middle ? above - 1 : above;
    return shift % n;
}

}  // namespace

std::vector<net::PeerId> grown_partition(const core::TetraGrid& grid, const LeafGraph& graph,
                                         std::span<const Seat> seats_in)
{
    const std::vector<Seat> seats = sorted_seats(seats_in);
    return to_peers(grow_seats(grid, graph, seats), seats);
}

std::optional<std::vector<net::PeerId>> wide_partition(const core::TetraGrid& grid,
                                                       const LeafGraph& graph,
                                                       std::span<const Seat> seats_in,
                                                       std::uint32_t row_hop)
{
    PLIANT_ASSERT(row_hop >= 1, "wide_partition: row_hop must be at least 1");
    const std::vector<Seat> seats = sorted_seats(seats_in);
    if (auto owner = wide_seats(grid, graph, seats, grow_seats(grid, graph, seats), row_hop))
        return to_peers(*owner, seats);
    return std::nullopt;
}

std::optional<std::vector<net::PeerId>> slab_partition(const core::TetraGrid& grid,
                                                       const LeafGraph& graph,
                                                       std::span<const Seat> seats_in,
                                                       std::size_t shift, bool whole_rows)
{
    const std::vector<Seat> seats = sorted_seats(seats_in);
    if (auto owner = slab_seats(grid, graph, row_major_leaves(graph), seats, shift, whole_rows))
        return to_peers(*owner, seats);
    return std::nullopt;
}

std::optional<std::vector<net::PeerId>> block_partition(const core::TetraGrid& grid,
                                                        const LeafGraph& graph,
                                                        std::span<const Seat> seats_in,
                                                        std::span<const std::size_t> parts)
{
    const std::vector<Seat> seats = sorted_seats(seats_in);
    std::size_t sum = 0;
    for (const std::size_t k : parts)
    {
        PLIANT_ASSERT(k > 0, "block_partition: an empty band");
        sum += k;
    }
    PLIANT_ASSERT(sum == seats.size(), "block_partition: the bands' seats are not the seats");
    if (auto owner = block_seats(grid, graph, seats, parts))
        return to_peers(*owner, seats);
    return std::nullopt;
}

std::vector<std::vector<std::size_t>> block_layouts(std::size_t p)
{
    std::vector<std::vector<std::size_t>> out;
    std::vector<std::size_t> parts;
    const auto extend = [&](const auto& self, std::size_t left) -> void
    {
        if (left == 0)
        {
            if (parts.size() < p)
                out.push_back(parts);
            return;
        }
        for (std::size_t k = 1; k <= left; ++k)
        {
            parts.push_back(k);
            self(self, left - k);
            parts.pop_back();
        }
    };
    extend(extend, p);
    return out;
}

std::size_t centred_slab_shift(const LeafGraph& graph, std::span<const Seat> seats)
{
    return centred_shift(graph, row_major_leaves(graph), sorted_seats(seats));
}

std::uint32_t border_hops(const LeafGraph& graph, std::span<const net::PeerId> owners,
                          core::NodeIndex point)
{
    const std::uint32_t start = graph.leaf_of(point);
    std::vector<std::uint32_t> dist(graph.size(), k_unowned);
    std::deque<std::uint32_t> queue{start};
    dist[start] = 0;
    while (!queue.empty())
    {
        const std::uint32_t a = queue.front();
        queue.pop_front();
        if (owners[a] != owners[start])
            return dist[a];
        for (const std::uint32_t b : graph.neighbours(a))
            if (dist[b] == k_unowned)
            {
                dist[b] = dist[a] + 1;
                queue.push_back(b);
            }
    }
    return k_unowned;  // one owner holds every leaf
}

std::vector<net::PeerId> partition_leaves(const core::TetraGrid& grid, const LeafGraph& graph,
                                          std::span<const Seat> seats_in, PointClearance clearance,
                                          double ring_cost)
{
    // O(leaves log leaves) for the candidates (one sort of the leaves into row-major order) and
    // O(grid nodes) for their costs, no node masks: a repartition runs on the master between
    // frames.
    const std::vector<Seat> seats = sorted_seats(seats_in);
    const std::vector<std::uint32_t> grown = grow_seats(grid, graph, seats);
    std::vector<net::PeerId> best = to_peers(grown, seats);
    double best_cost = busiest_cost(grid, graph, grown, seats.size(), ring_cost);
    std::vector<std::uint32_t> grown_hops;  // per seat with a point, in the grown shares
    if (clearance == PointClearance::AsGrown)
        for (const Seat& s : seats)
            if (s.seed)
                grown_hops.push_back(border_hops(graph, best, *s.seed));
    // Candidates: the slabs from the first leaf, and the slabs turned to keep the points
    // farthest from the cuts, each with balanced and with whole-row cuts (turned to the leaf
    // row nearest the centred shift); the cheapest that keeps the clearance, if cheaper than
    // grown.
    const std::vector<std::uint32_t> row_major = row_major_leaves(graph);
    const std::size_t centred = centred_shift(graph, row_major, seats);
    const std::size_t centred_row = nearest_row_start(graph, row_major, centred);
    struct Candidate
    {
        std::size_t shift;
        bool whole_rows;
    };
    std::vector<Candidate> candidates = {{0, false}, {0, true}};
    if (centred != 0)
        candidates.push_back({centred, false});
    if (centred_row != 0)
        candidates.push_back({centred_row, true});
    // Takes `owner` if its busiest step is cheaper and it keeps the clearance.
    const auto consider = [&](const std::optional<std::vector<std::uint32_t>>& owner)
    {
        if (!owner)
            return;
        const double cost = busiest_cost(grid, graph, *owner, seats.size(), ring_cost);
        if (cost >= best_cost)
            return;
        std::vector<net::PeerId> peers = to_peers(*owner, seats);
        if (clearance == PointClearance::AsGrown)
            for (std::size_t s = 0, i = 0; s < seats.size(); ++s)
                if (seats[s].seed && border_hops(graph, peers, *seats[s].seed) < grown_hops[i++])
                    return;
        best = std::move(peers);
        best_cost = cost;
    };
    for (const Candidate& cand : candidates)
        consider(slab_seats(grid, graph, row_major, seats, cand.shift, cand.whole_rows));
    // Without points the slabs hold every seat in a band of its own, which neither the wide
    // shares nor the blocks undercut, so those two are for seats with points.
    const bool any_point =
        std::any_of(seats.begin(), seats.end(), [](const Seat& s) { return s.seed.has_value(); });
    if (any_point)
        for (const std::uint32_t row_hop : k_wide_row_hops)
            consider(wide_seats(grid, graph, seats, grown, row_hop));
    // Then the blocks, for every band layout (up to k_max_block_seats participants). A block is
    // a rectangle of leaves, so its step costs at least its nodes and a row segment for every
    // grid row it spans but the two folded ones (where half the positions are twins): the
    // layouts that cannot win by that bound skip the grid passes of `busiest_cost`.
    const auto regions = graph.regions();
    const auto block_bound = [&](const std::vector<std::uint32_t>& owner)
    {
        std::vector<std::size_t> nodes(seats.size(), 0);
        std::vector<int> y0(seats.size(), grid.ny());
        std::vector<int> y1(seats.size(), 0);
        for (std::size_t l = 0; l < owner.size(); ++l)
        {
            nodes[owner[l]] += graph.node_count(l);
            y0[owner[l]] = std::min(y0[owner[l]], regions[l].y0);
            y1[owner[l]] = std::max(y1[owner[l]], regions[l].y1);
        }
        double bound = 0.0;
        for (std::size_t s = 0; s < seats.size(); ++s)
            bound = std::max(bound, static_cast<double>(nodes[s]) +
                                        k_row_segment_cost * std::max(0, y1[s] - y0[s] - 2));
        return bound;
    };
    if (any_point && seats.size() <= k_max_block_seats)
        for (const std::vector<std::size_t>& parts : block_layouts(seats.size()))
            if (auto blocks = block_seats(grid, graph, seats, parts);
                blocks && block_bound(*blocks) < best_cost)
                consider(blocks);
    return best;
}

PartitionQuality measure_partition(const core::TetraGrid& grid, const LeafGraph& graph,
                                   std::span<const net::PeerId> owners, double ring_cost)
{
    PLIANT_ASSERT(owners.size() == graph.size(), "measure_partition: table size");
    std::map<net::PeerId, PeerShare> shares;
    for (std::size_t l = 0; l < owners.size(); ++l)
    {
        PeerShare& s = shares[owners[l]];
        s.peer = owners[l];
        ++s.leaves;
        s.nodes += graph.node_count(l);
    }
    // Fragments: components of each peer's leaves.
    std::vector<bool> seen(graph.size(), false);
    for (std::size_t l = 0; l < graph.size(); ++l)
    {
        if (seen[l])
            continue;
        ++shares[owners[l]].fragments;
        std::deque<std::size_t> queue{l};
        seen[l] = true;
        while (!queue.empty())
        {
            const std::size_t a = queue.front();
            queue.pop_front();
            for (const std::uint32_t b : graph.neighbours(a))
                if (!seen[b] && owners[b] == owners[l])
                {
                    seen[b] = true;
                    queue.push_back(b);
                }
        }
    }
    // Border edges: unique surface edges (canonical pairs) across owners.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (std::size_t l = 0; l < graph.size(); ++l)
        for (const core::NodeIndex a : graph.nodes(l))
        {
            const core::GridCoord c = grid.coord(a);
            for (const core::NodeIndex b : core::grid_neighbours(grid, c.x, c.y))
                if (a.value < b.value && owners[graph.leaf_of(b)] != owners[l])
                    edges.emplace_back(a.value, b.value);
        }
    // A corner sees some neighbours twice through the ghost map: keep each pair once.
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    // Row segments: the restricted step's x-runs of owned nodes, one per grid row they span.
    {
        std::map<net::PeerId, std::uint32_t> index;
        for (const auto& [id, share] : shares)
            index.emplace(id, static_cast<std::uint32_t>(index.size()));
        std::vector<std::uint32_t> owner(owners.size());
        for (std::size_t l = 0; l < owners.size(); ++l)
            owner[l] = index.at(owners[l]);
        std::vector<std::size_t> segments(index.size(), 0);
        count_row_segments(grid, graph, owner, segments);
        std::vector<std::size_t> ring(index.size(), 0);
        count_ring_nodes(grid, graph, owner, ring);
        for (auto& [id, share] : shares)
        {
            share.row_segments = segments[index.at(id)];
            share.ring_nodes = ring[index.at(id)];
        }
    }
    PartitionQuality q;
    for (const auto& [a, b] : edges)
    {
        ++shares[owners[graph.leaf_of(core::NodeIndex{a})]].border_edges;
        ++shares[owners[graph.leaf_of(core::NodeIndex{b})]].border_edges;
    }
    q.border_edges = edges.size();
    double mean = 0.0;
    for (const auto& [id, s] : shares)
        mean += static_cast<double>(s.nodes);
    mean /= static_cast<double>(shares.size());
    for (const auto& [id, s] : shares)
    {
        q.imbalance = std::max(q.imbalance, std::abs(static_cast<double>(s.nodes) - mean) / mean);
        q.busiest_cost = std::max(q.busiest_cost, step_cost(s, ring_cost));
        q.shares.push_back(s);
    }
    return q;
}

}  // namespace pliant::session
