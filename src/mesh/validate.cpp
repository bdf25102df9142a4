// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
//
// Mesh statistics and the docs/design.md §2.1 input rules.
//
// Design: one pass over the faces builds two flat record arrays, sorted once:
//   - directed edge records (lo, hi, face, forward): grouping by (lo, hi) gives each undirected
//     edge's face count (boundary = 1, non-manifold > 2) and, for 2-face edges, whether the two
//     faces traverse it in opposite directions (consistent orientation);
//   - corner records (vertex, next, prev): grouping by vertex gives the faces around it, joined
//     into fans across the vertex's 2-face edges (a manifold vertex has one fan).
// Components and boundary loops use a union-find over vertex ids. Everything is O(F log F) with
// no per-vertex containers. A halfedge structure (OpenMesh, pmp) was rejected here: building one
// from a non-manifold mesh either fails or silently duplicates vertices, which is exactly what
// this code must detect and report. OpenMesh is the independent cross-check in the tests.
//
// Invalid data is counted, never trusted: faces with an out-of-range index are left out of the
// topology, geometry is computed only from finite vertices (and with no ordered comparison on a
// NaN, so a caller's FE_INVALID trap does not fire).

#include <pliant/mesh/validate.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

namespace pliant::mesh
{

namespace
{

using core::ErrorCode;
using core::fail;

constexpr std::uint32_t k_none = UINT32_MAX;

/// A triangle counts as zero-area when its height is below this fraction of its longest edge:
/// exactly collinear points land here even after rounding to float, while the skinniest real
/// triangles of the test meshes stay well above it (docs/mesh.md).
constexpr double k_degenerate_ratio = 1e-6;
// Coordinates all below this are said to be beyond what 32-bit floats resolve (the smallest
// normal float is 1.2e-38; a mesh of size 1e-35 keeps only a thousand steps across).
constexpr double k_float_resolved = 1e-32;
/// Coordinates above this many bounding-box diagonals: far enough from the origin that float
/// rounding (one part in 1.7e7) comes within a ten-thousandth of the mesh's size.
constexpr double k_far_from_origin = 1e3;

class UnionFind
{
public:
    explicit UnionFind(std::size_t n) : parent_(n)
    {
        std::iota(parent_.begin(), parent_.end(), 0U);
    }
    std::uint32_t find(std::uint32_t x)
    {
        while (parent_[x] != x)
        {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a != b)
            parent_[std::max(a, b)] = std::min(a, b);
    }

private:
    std::vector<std::uint32_t> parent_;
};

/// Everything `validate` needs beyond the counts: one example per rule.
struct Examples
{
    std::uint32_t bad_index_face = k_none;
    std::uint32_t bad_index_vertex = k_none;
    std::uint32_t non_finite_vertex = k_none;
    std::uint32_t degenerate_face = k_none;
    bool degenerate_repeated = false;
    double degenerate_height_ratio = 0.0;  ///< height / longest edge of a zero-area example
    std::array<std::uint32_t, 2> non_manifold_edge{k_none, k_none};
    std::size_t non_manifold_edge_faces = 0;
    std::uint32_t boundary_vertex = k_none;
    std::uint32_t pinch_vertex = k_none;
    std::size_t pinch_fans = 0;
    std::array<std::uint32_t, 2> inconsistent_edge{k_none, k_none};
    std::array<std::uint32_t, 2> inconsistent_faces{k_none, k_none};
    std::vector<std::size_t> component_faces;  ///< faces per component, largest first
};

struct EdgeRecord
{
    std::uint32_t lo;
    std::uint32_t hi;
    std::uint32_t face;
    bool forward;  ///< the face traverses lo -> hi
};

struct CornerRecord
{
    std::uint32_t vertex;
    std::uint32_t next;
    std::uint32_t prev;
};

bool index_ok(const Face& f, std::size_t n)
{
    return f[0] < n && f[1] < n && f[2] < n;
}

MeshStats analyze_detailed(const TriMesh& mesh, Examples& ex)
{
    MeshStats s;
    const std::size_t nv = mesh.positions.size();
    s.vertices = nv;
    s.faces = mesh.faces.size();

    std::vector<bool> used(nv, false);
    std::vector<EdgeRecord> edges;
    std::vector<CornerRecord> corners;
    edges.reserve(3 * mesh.faces.size());
    corners.reserve(3 * mesh.faces.size());
    std::size_t valid_faces = 0;
    for (std::size_t fi = 0; fi < mesh.faces.size(); ++fi)
    {
        const Face& f = mesh.faces[fi];
        const auto face = static_cast<std::uint32_t>(fi);
        if (!index_ok(f, nv))
        {
            if (s.bad_index_faces++ == 0)
            {
                ex.bad_index_face = face;
                ex.bad_index_vertex = std::max({f[0], f[1], f[2]});
            }
            continue;
        }
        ++valid_faces;
        for (int k = 0; k < 3; ++k)
        {
            const std::uint32_t a = f[static_cast<std::size_t>(k)];
            const std::uint32_t b = f[static_cast<std::size_t>((k + 1) % 3)];
            const std::uint32_t c = f[static_cast<std::size_t>((k + 2) % 3)];
            used[a] = true;
            if (a != b)
                edges.push_back({std::min(a, b), std::max(a, b), face, a < b});
            corners.push_back({a, b, c});
        }
        const bool repeated = f[0] == f[1] || f[1] == f[2] || f[0] == f[2];
        bool zero_area = false;
        double height_ratio = 0.0;
        const core::Vec3& p0 = mesh.positions[f[0]];
        const core::Vec3& p1 = mesh.positions[f[1]];
        const core::Vec3& p2 = mesh.positions[f[2]];
        if (!repeated && core::is_finite(p0) && core::is_finite(p1) && core::is_finite(p2))
        {
            const core::Vec3 n = core::cross(p1 - p0, p2 - p0);
            const double area2 = core::norm(n);
            const double longest =
                std::max({core::norm(p1 - p0), core::norm(p2 - p1), core::norm(p0 - p2)});
            // height / longest = area2 / longest^2
            zero_area = !(area2 > k_degenerate_ratio * longest * longest) || area2 == 0.0;
            height_ratio = longest > 0.0 ? area2 / (longest * longest) : 0.0;
            if (std::isfinite(area2))
                s.surface_area += 0.5 * area2;
        }
        if (repeated || zero_area)
        {
            if (s.degenerate_faces++ == 0)
            {
                ex.degenerate_face = face;
                ex.degenerate_repeated = repeated;
                ex.degenerate_height_ratio = height_ratio;
            }
        }
    }

    // Vertices: finiteness, bounding box.
    bool first = true;
    std::size_t used_count = 0;
    for (std::size_t i = 0; i < nv; ++i)
    {
        if (!used[i])
            continue;
        ++used_count;
        const core::Vec3& p = mesh.positions[i];
        if (!core::is_finite(p))
        {
            if (s.non_finite_vertices++ == 0)
                ex.non_finite_vertex = static_cast<std::uint32_t>(i);
            continue;
        }
        if (first)
        {
            s.bbox_min = s.bbox_max = p;
            first = false;
        }
        s.bbox_min = {std::min(s.bbox_min.x, p.x), std::min(s.bbox_min.y, p.y),
                      std::min(s.bbox_min.z, p.z)};
        s.bbox_max = {std::max(s.bbox_max.x, p.x), std::max(s.bbox_max.y, p.y),
                      std::max(s.bbox_max.z, p.z)};
    }
    s.unreferenced_vertices = nv - used_count;
    s.bbox_diagonal = core::norm(s.bbox_max - s.bbox_min);

    // Edges.
    std::sort(
        edges.begin(), edges.end(),
        [](const EdgeRecord& a, const EdgeRecord& b)
        { return a.lo != b.lo ? a.lo < b.lo : (a.hi != b.hi ? a.hi < b.hi : a.face < b.face); });
    UnionFind boundary(nv);
    std::vector<bool> on_boundary(nv, false);
    for (std::size_t i = 0; i < edges.size();)
    {
        std::size_t j = i;
        while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi)
            ++j;
        const std::size_t count = j - i;
        ++s.edges;
        if (count == 1)
        {
            ++s.boundary_edges;
            boundary.unite(edges[i].lo, edges[i].hi);
            on_boundary[edges[i].lo] = on_boundary[edges[i].hi] = true;
            if (ex.boundary_vertex == k_none)
                ex.boundary_vertex = edges[i].lo;
        }
        else if (count == 2)
        {
            if (edges[i].forward == edges[i + 1].forward)
            {
                if (s.inconsistent_edges++ == 0)
                {
                    ex.inconsistent_edge = {edges[i].lo, edges[i].hi};
                    ex.inconsistent_faces = {edges[i].face, edges[i + 1].face};
                }
            }
        }
        else
        {
            if (s.non_manifold_edges++ == 0)
            {
                ex.non_manifold_edge = {edges[i].lo, edges[i].hi};
                ex.non_manifold_edge_faces = count;
            }
        }
        i = j;
    }
    for (std::size_t v = 0; v < nv; ++v)
    {
        if (on_boundary[v] && boundary.find(static_cast<std::uint32_t>(v)) == v)
            ++s.boundary_loops;
    }

    // Components over faces (sharing a vertex connects).
    UnionFind components(nv);
    for (const Face& f : mesh.faces)
    {
        if (!index_ok(f, nv))
            continue;
        components.unite(f[0], f[1]);
        components.unite(f[1], f[2]);
    }
    std::vector<std::size_t> faces_per_root(nv, 0);
    for (const Face& f : mesh.faces)
    {
        if (index_ok(f, nv))
            ++faces_per_root[components.find(f[0])];
    }
    for (std::size_t v = 0; v < nv; ++v)
    {
        if (used[v] && components.find(static_cast<std::uint32_t>(v)) == v)
            ex.component_faces.push_back(faces_per_root[v]);
    }
    std::sort(ex.component_faces.rbegin(), ex.component_faces.rend());
    s.components = ex.component_faces.size();

    // Fans: the faces around a vertex, joined across the vertex's edges that have exactly two
    // faces. A manifold vertex has one fan (a closed one inside, an open one on a boundary); a
    // pinch has several, and so does an endpoint of a non-manifold edge (so the two-cubes test
    // mesh has 2 non-manifold vertices, as tests/data/meshes/README.md counts them).
    std::vector<std::array<std::uint32_t, 3>> edge_counts;  // (lo, hi, faces), sorted
    for (std::size_t i = 0; i < edges.size();)
    {
        std::size_t j = i;
        while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi)
            ++j;
        edge_counts.push_back({edges[i].lo, edges[i].hi, static_cast<std::uint32_t>(j - i)});
        i = j;
    }
    const auto faces_on_edge = [&](std::uint32_t a, std::uint32_t b)
    {
        const std::array<std::uint32_t, 3> key{std::min(a, b), std::max(a, b), 0};
        const auto it = std::lower_bound(edge_counts.begin(), edge_counts.end(), key,
                                         [](const auto& x, const auto& y)
                                         { return x[0] != y[0] ? x[0] < y[0] : x[1] < y[1]; });
        return it != edge_counts.end() && (*it)[0] == key[0] && (*it)[1] == key[1] ? (*it)[2] : 0U;
    };
    std::sort(corners.begin(), corners.end(),
              [](const CornerRecord& a, const CornerRecord& b) { return a.vertex < b.vertex; });
    std::vector<std::array<std::uint32_t, 2>> spokes;  // (neighbour, local corner)
    std::vector<std::uint32_t> parent;
    for (std::size_t i = 0; i < corners.size();)
    {
        std::size_t j = i;
        while (j < corners.size() && corners[j].vertex == corners[i].vertex)
            ++j;
        const std::uint32_t v = corners[i].vertex;
        spokes.clear();
        for (std::size_t k = i; k < j; ++k)
        {
            const auto local = static_cast<std::uint32_t>(k - i);
            if (corners[k].next != v)
                spokes.push_back({corners[k].next, local});
            if (corners[k].prev != v && corners[k].prev != corners[k].next)
                spokes.push_back({corners[k].prev, local});
        }
        std::sort(spokes.begin(), spokes.end());
        parent.resize(j - i);
        std::iota(parent.begin(), parent.end(), 0U);
        const auto root = [&](std::uint32_t x)
        {
            while (parent[x] != x)
                x = parent[x] = parent[parent[x]];
            return x;
        };
        std::size_t fans = j - i;
        for (std::size_t a = 0; a < spokes.size();)
        {
            std::size_t b = a;
            while (b < spokes.size() && spokes[b][0] == spokes[a][0])
                ++b;
            if (b - a == 2 && faces_on_edge(v, spokes[a][0]) == 2)
            {
                const std::uint32_t x = root(spokes[a][1]);
                const std::uint32_t y = root(spokes[a + 1][1]);
                if (x != y)
                {
                    parent[std::max(x, y)] = std::min(x, y);
                    --fans;
                }
            }
            a = b;
        }
        if (fans > 1)
        {
            if (s.non_manifold_vertices++ == 0)
            {
                ex.pinch_vertex = v;
                ex.pinch_fans = fans;
            }
        }
        i = j;
    }

    s.euler_characteristic =
        static_cast<long>(used_count) - static_cast<long>(s.edges) + static_cast<long>(valid_faces);
    const bool closed_manifold = valid_faces > 0 && s.bad_index_faces == 0 &&
                                 s.boundary_edges == 0 && s.non_manifold_edges == 0 &&
                                 s.non_manifold_vertices == 0 && s.components == 1;
    if (closed_manifold && (2 - s.euler_characteristic) % 2 == 0)
        s.genus = (2 - s.euler_characteristic) / 2;
    return s;
}

std::string point(const TriMesh& mesh, std::uint32_t v)
{
    const core::Vec3& p = mesh.positions[v];
    std::array<char, 96> buf{};
    std::snprintf(buf.data(), buf.size(), "(%g, %g, %g)", p.x, p.y, p.z);
    return buf.data();
}

std::string fmt_number(double v)
{
    std::array<char, 32> buf{};
    std::snprintf(buf.data(), buf.size(), "%g", v);
    return buf.data();
}

std::string plural(std::size_t n, const char* one, const char* many)
{
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

MeshStats analyze(const TriMesh& mesh)
{
    Examples ex;
    return analyze_detailed(mesh, ex);
}

core::Result<void> validate(const TriMesh& mesh, std::string_view source_name)
{
    Examples ex;
    const MeshStats s = analyze_detailed(mesh, ex);
    const std::string src(source_name);
    const auto str = [](std::size_t n) { return std::to_string(n); };

    if (s.bad_index_faces > 0)
        return fail(ErrorCode::BadIndex,
                    src + ": bad vertex index: face " + str(ex.bad_index_face) +
                        " refers to vertex " + str(ex.bad_index_vertex) + " but there are " +
                        plural(s.vertices, "vertex", "vertices") + " (" +
                        plural(s.bad_index_faces, "such face", "such faces") + ")");
    if (s.faces == 0)
        return fail(ErrorCode::EmptyInput,
                    src + ": no faces (" + plural(s.vertices, "vertex", "vertices") + ")");
    if (s.non_finite_vertices > 0)
        return fail(ErrorCode::NonFiniteCoordinate,
                    src + ": non-finite coordinate: vertex " + str(ex.non_finite_vertex) + " " +
                        point(mesh, ex.non_finite_vertex) + " (" +
                        plural(s.non_finite_vertices, "such vertex", "such vertices") + ")");
    // Files are read in single precision (Assimp's float): far from the origin, vertices closer
    // than a float's step there become one, and their faces degenerate or their edges gain
    // faces, so the topology errors below say so too.
    const double reach =
        std::max({std::abs(s.bbox_min.x), std::abs(s.bbox_min.y), std::abs(s.bbox_min.z),
                  std::abs(s.bbox_max.x), std::abs(s.bbox_max.y), std::abs(s.bbox_max.z)});
    const std::string far =
        s.bbox_diagonal > 0.0 && reach > k_far_from_origin * s.bbox_diagonal
            ? "; the mesh lies far from the origin (coordinates up to " + fmt_number(reach) +
                  ", size " + fmt_number(s.bbox_diagonal) +
                  ") and positions are read as 32-bit floats, which merge nearby vertices "
                  "there: move it near the origin"
        : reach == 0.0
            ? "; every vertex is at (0, 0, 0) as read: positions are read as 32-bit floats, and "
              "coordinates below about 1e-45 in the file become 0 (a mesh that small: scale it "
              "up)"
        : reach < k_float_resolved
            ? "; the mesh is tiny (coordinates up to " + fmt_number(reach) +
                  ") and positions are read as 32-bit floats, which resolve nothing below about "
                  "1e-38 and merge nearby vertices well above it: scale it up"
            : std::string();
    if (s.degenerate_faces > 0)
    {
        const Face& f = mesh.faces[ex.degenerate_face];
        return fail(
            ErrorCode::DegenerateFace,
            src + ": degenerate face " + str(ex.degenerate_face) + " (vertices " + str(f[0]) +
                ", " + str(f[1]) + ", " + str(f[2]) + " at " + point(mesh, f[0]) + "): " +
                (ex.degenerate_repeated ? std::string("a repeated vertex")
                 : ex.degenerate_height_ratio > 1e-12  // below: flat up to rounding
                     ? "almost no area: its height is " + fmt_number(ex.degenerate_height_ratio) +
                           " of its longest edge, below the " + fmt_number(k_degenerate_ratio) +
                           " a face needs"
                     : std::string("zero area")) +
                " (" + plural(s.degenerate_faces, "degenerate face", "degenerate faces") + ")" +
                far);
    }
    if (s.non_manifold_edges > 0)
        return fail(
            ErrorCode::NonManifoldEdge,
            src + ": not a 2-manifold: " + plural(s.non_manifold_edges, "edge has", "edges have") +
                " more than two faces (first: edge " + str(ex.non_manifold_edge[0]) + "-" +
                str(ex.non_manifold_edge[1]) + " " + point(mesh, ex.non_manifold_edge[0]) + "-" +
                point(mesh, ex.non_manifold_edge[1]) + " with " + str(ex.non_manifold_edge_faces) +
                " faces)" + far);
    if (s.boundary_edges > 0)
        return fail(ErrorCode::OpenBoundary,
                    src + ": not a closed surface: " +
                        plural(s.boundary_edges, "boundary edge", "boundary edges") + " in " +
                        plural(s.boundary_loops, "loop", "loops") + " (first at vertex " +
                        str(ex.boundary_vertex) + " " + point(mesh, ex.boundary_vertex) + ")" +
                        far);
    if (s.non_manifold_vertices > 0)
        return fail(
            ErrorCode::NonManifoldVertex,
            src + ": not a 2-manifold: " +
                plural(s.non_manifold_vertices, "vertex is a pinch", "vertices are pinches") +
                " (first: vertex " + str(ex.pinch_vertex) + " " + point(mesh, ex.pinch_vertex) +
                ", whose faces form " + str(ex.pinch_fans) + " separate fans)" + far);
    if (s.inconsistent_edges > 0)
        return fail(ErrorCode::InconsistentOrientation,
                    src + ": inconsistent orientation: " +
                        plural(s.inconsistent_edges, "edge is", "edges are") +
                        " traversed the same way by both faces (first: edge " +
                        str(ex.inconsistent_edge[0]) + "-" + str(ex.inconsistent_edge[1]) + " " +
                        point(mesh, ex.inconsistent_edge[0]) + "-" +
                        point(mesh, ex.inconsistent_edge[1]) + " of faces " +
                        str(ex.inconsistent_faces[0]) + " and " + str(ex.inconsistent_faces[1]) +
                        ")" + far);
    if (s.components > 1)
    {
        std::string sizes;
        for (std::size_t i = 0; i < ex.component_faces.size() && i < 5; ++i)
            sizes += (i > 0 ? ", " : "") + str(ex.component_faces[i]);
        if (ex.component_faces.size() > 5)
            sizes += ", ...";
        return fail(ErrorCode::NotConnected, src + ": not connected: " + str(s.components) +
                                                 " components (faces per component: " + sizes +
                                                 ")");
    }
    if (s.euler_characteristic != 2)
    {
        const std::string genus = s.genus ? "genus " + std::to_string(*s.genus)
                                          : std::string("not an orientable surface");
        return fail(ErrorCode::WrongGenus,
                    src + ": wrong topology: Euler characteristic is " +
                        std::to_string(s.euler_characteristic) + ", expected 2: " + genus + " (V " +
                        str(s.vertices - s.unreferenced_vertices) + " - E " + str(s.edges) +
                        " + F " + str(s.faces) + "); pliant needs genus 0");
    }
    return {};
}

}  // namespace pliant::mesh
