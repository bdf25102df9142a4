// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// A tree of oriented bounding boxes over faces of a mesh, for the self-intersection count's
// crowded cells (intersections.cpp): long slanted slivers lying side by side (a finely divided
// cylinder or frustum) fill the boxes of axis-aligned cells and of each other, so any uniform
// grid enumerates about the square of their number; boxes oriented along the faces separate
// them (Gottschalk, Lin and Manocha 1996, "OBBTree"). docs/remesh.md §3.3.

#include <pliant/core/progress.h>
#include <pliant/core/vec3.h>
#include <pliant/mesh/tri_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace pliant::remesh::detail
{

/// An oriented box: the points centre + Σ t_k axis[k] with |t_k| <= half[k], axes orthonormal.
struct Obb
{
    core::Vec3 centre;
    std::array<core::Vec3, 3> axis;
    std::array<double, 3> half{};
};

/// Whether boxes a and b may share a point: false only where one of the separating-axis
/// theorem's 15 axes (the boxes' 6 face normals and the 9 cross products of their axes) shows a
/// gap wider than 1e-12 of the centres' coordinates plus the half extents (a hundred times the
/// test's rounding), so boxes that touch up to the rounding of their coordinates may overlap.
/// Each |axis_a · axis_b| is taken 1e-12 larger, as is usual for near-parallel edge pairs
/// (whose cross product is near zero).
[[nodiscard]] bool obbs_may_overlap(const Obb& a, const Obb& b) noexcept;

/// A lower bound of the squared distance from p to box o: the distance to the box grown by 1e-12
/// of p's and the centre's coordinates plus the half extents, a hundred times the rounding of
/// the bound and of the box's fit, so no point of the box is nearer than it.
[[nodiscard]] inline double obb_distance2_below(const Obb& o, const core::Vec3& p) noexcept
{
    const core::Vec3 d = p - o.centre;
    const auto magnitude = [](const core::Vec3& v) {
        return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    };
    const double slack =
        1e-12 * (magnitude(p) + magnitude(o.centre) + o.half[0] + o.half[1] + o.half[2]);
    double sum = 0.0;
    for (int k = 0; k < 3; ++k)
    {
        const double out = std::fabs(core::dot(d, o.axis[k])) - o.half[k] - slack;
        if (out > 0.0)
            sum += out * out;
    }
    return sum;
}

/// The tree over n items, item i being face `faces[i]` of a mesh. Each node's box holds every
/// corner of its items' faces, up to the rounding of the fit (about 1e-15 of the corners'
/// magnitude, which obbs_may_overlap's slack covers a thousand times). Nodes split their
/// items at the median of the face centroids along the axis of their box where the two halves'
/// extents overlap least (so slivers side by side are split across, not along, their length),
/// down to leaves of at most 4 items.
class ObbTree
{
public:
    /// `flagged`: one flag per item, or empty (every item flagged); pairs of two unflagged items
    /// are skipped whole subtrees at a time. `stop`: polled at every node of more than 2^16
    /// items; once it asks, that node stays a leaf of all its items (the tree stays valid, but
    /// slow to search: the caller, which owns the sink, discards it).
    ObbTree(const mesh::TriMesh& mesh, std::span<const std::uint32_t> faces,
            std::span<const std::uint8_t> flagged, const core::ProgressSink* stop = nullptr);

    /// A share of the work: the pairs within node a (a == b), or across nodes a and b.
    struct Job
    {
        std::uint32_t a;
        std::uint32_t b;
    };

    /// Jobs that together visit every pair of items exactly once (pairs left out only where
    /// their boxes are apart or neither item is flagged), about `target` of them or as many as
    /// the tree's top levels give: the units of a parallel loop.
    [[nodiscard]] std::vector<Job> jobs(std::size_t target) const;

    /// Calls pair(i, j) (items, i != j) for every pair of the job's items whose leaves' boxes may
    /// overlap, each once; returns early, leaving pairs out, once halted() says true (polled at
    /// every node).
    template <typename Pair, typename Halted>
    void visit(Job job, Pair&& pair, Halted&& halted) const;

    /// The least item_distance2(i) over the items (+inf for none), searching nearer boxes first
    /// and skipping boxes whose obb_distance2_below is not below the best so far. Where
    /// item_distance2 is at least the squared distance from p to the item's face up to a relative
    /// 1e-14, the result is the least value over every item, as a search of them all would give.
    template <typename ItemDistance2>
    [[nodiscard]] double nearest2(const core::Vec3& p, ItemDistance2&& item_distance2) const;

    [[nodiscard]] std::size_t node_count() const noexcept { return nodes_.size(); }

private:
    static constexpr std::uint32_t k_leaf = 0;  // `left` of a leaf (the root is never a child)
    static constexpr std::uint32_t k_leaf_items = 4;

    struct Node
    {
        Obb box;
        std::uint32_t begin = 0;  // items order_[begin, end)
        std::uint32_t end = 0;
        std::uint32_t left = k_leaf;
        std::uint32_t right = k_leaf;
        bool flagged = false;
        [[nodiscard]] bool leaf() const noexcept { return left == k_leaf; }
        [[nodiscard]] std::uint32_t size() const noexcept { return end - begin; }
    };

    std::uint32_t build(const mesh::TriMesh& mesh, std::span<const std::uint32_t> faces,
                        std::span<const std::uint8_t> flagged, std::uint32_t begin,
                        std::uint32_t end, std::vector<double>& keys,
                        const core::ProgressSink* stop);
    void expand(Job job, int depth, int max_depth, std::vector<Job>& out) const;

    std::vector<Node> nodes_;
    std::vector<std::uint32_t> order_;  // items, grouped by node
};

template <typename Pair, typename Halted>
void ObbTree::visit(Job job, Pair&& pair, Halted&& halted) const
{
    if (halted())
        return;
    const Node& a = nodes_[job.a];
    if (job.a == job.b)
    {
        if (!a.flagged)
            return;
        if (a.leaf())
        {
            for (std::uint32_t i = a.begin; i < a.end; ++i)
                for (std::uint32_t j = i + 1; j < a.end; ++j)
                    pair(order_[i], order_[j]);
            return;
        }
        visit({a.left, a.left}, pair, halted);
        visit({a.right, a.right}, pair, halted);
        visit({a.left, a.right}, pair, halted);
        return;
    }
    const Node& b = nodes_[job.b];
    if ((!a.flagged && !b.flagged) || !obbs_may_overlap(a.box, b.box))
        return;
    if (a.leaf() && b.leaf())
    {
        for (std::uint32_t i = a.begin; i < a.end; ++i)
            for (std::uint32_t j = b.begin; j < b.end; ++j)
                pair(order_[i], order_[j]);
        return;
    }
    if (b.leaf() || (!a.leaf() && a.size() >= b.size()))
    {
        visit({a.left, job.b}, pair, halted);
        visit({a.right, job.b}, pair, halted);
    }
    else
    {
        visit({job.a, b.left}, pair, halted);
        visit({job.a, b.right}, pair, halted);
    }
}

template <typename ItemDistance2>
double ObbTree::nearest2(const core::Vec3& p, ItemDistance2&& item_distance2) const
{
    double best = std::numeric_limits<double>::infinity();
    if (nodes_.empty())
        return best;
    // Median splits: the depth is at most log2(n) + 2, so 128 entries hold any tree.
    std::array<std::uint32_t, 128> stack{};
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0)
    {
        const Node& n = nodes_[stack[--top]];
        if (obb_distance2_below(n.box, p) >= best)
            continue;
        if (n.leaf())
        {
            for (std::uint32_t i = n.begin; i < n.end; ++i)
                best = std::min(best, item_distance2(order_[i]));
            continue;
        }
        const double dl = obb_distance2_below(nodes_[n.left].box, p);
        const double dr = obb_distance2_below(nodes_[n.right].box, p);
        if (top + 2 > stack.size())
            continue;  // cannot happen (the depth bound above)
        // the farther child first, so the nearer one is searched first
        stack[top++] = dl < dr ? n.right : n.left;
        stack[top++] = dl < dr ? n.left : n.right;
    }
    return best;
}

}  // namespace pliant::remesh::detail
