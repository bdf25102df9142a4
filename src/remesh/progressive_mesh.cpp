// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "remesh/progressive_mesh.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <string>

namespace pliant::remesh::detail
{
namespace
{

using core::Vec3;

/// Symmetric 4x4 plane quadric (Garland & Heckbert), upper triangle.
struct Quadric
{
    std::array<double, 10> q{};

    void add_plane(const Vec3& n, double d, double w) noexcept
    {
        const double a = n.x, b = n.y, c = n.z;
        q[0] += w * a * a;
        q[1] += w * a * b;
        q[2] += w * a * c;
        q[3] += w * a * d;
        q[4] += w * b * b;
        q[5] += w * b * c;
        q[6] += w * b * d;
        q[7] += w * c * c;
        q[8] += w * c * d;
        q[9] += w * d * d;
    }
    Quadric& operator+=(const Quadric& o) noexcept
    {
        for (std::size_t i = 0; i < q.size(); ++i)
            q[i] += o.q[i];
        return *this;
    }
    [[nodiscard]] double eval(const Vec3& p) const noexcept
    {
        const double x = p.x, y = p.y, z = p.z;
        return q[0] * x * x + 2.0 * q[1] * x * y + 2.0 * q[2] * x * z + 2.0 * q[3] * x +
               q[4] * y * y + 2.0 * q[5] * y * z + 2.0 * q[6] * y + q[7] * z * z + 2.0 * q[8] * z +
               q[9];
    }
};

struct Candidate
{
    double cost = 0.0;
    std::uint32_t u = 0;
    std::uint32_t v = 0;
    std::uint32_t stamp_u = 0;
    std::uint32_t stamp_v = 0;
    bool operator>(const Candidate& o) const noexcept
    {
        // ties broken by ids so the order is deterministic
        if (cost != o.cost)
            return cost > o.cost;
        if (u != o.u)
            return u > o.u;
        return v > o.v;
    }
};

class Simplifier
{
public:
    explicit Simplifier(const mesh::TriMesh& m)
        : pos_(m.positions),
          faces_(m.faces),
          face_alive_(m.faces.size(), 1),
          vertex_alive_(m.positions.size(), 1),
          vf_(m.positions.size()),
          quadric_(m.positions.size()),
          stamp_(m.positions.size(), 0),
          mark_(m.positions.size(), 0)
    {
        for (std::uint32_t f = 0; f < faces_.size(); ++f)
        {
            const auto& t = faces_[f];
            for (const std::uint32_t v : t)
                vf_[v].push_back(f);
            const Vec3 n = core::cross(pos_[t[1]] - pos_[t[0]], pos_[t[2]] - pos_[t[0]]);
            const double len = core::norm(n);
            if (len > 0.0)
            {
                const Vec3 nn = n / len;
                const double d = -core::dot(nn, pos_[t[0]]);
                // area-weighted planes: large faces dominate, slivers barely count
                for (const std::uint32_t v : t)
                    quadric_[v].add_plane(nn, d, 0.5 * len);
            }
        }
        alive_count_ = m.positions.size();
        Vec3 lo = pos_.empty() ? Vec3{} : pos_[0], hi = lo;
        for (const Vec3& p : pos_)
        {
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        const double diag = core::norm(hi - lo);
        double area = 0.0;
        for (const auto& t : faces_)
            area += 0.5 * core::norm(core::cross(pos_[t[1]] - pos_[t[0]], pos_[t[2]] - pos_[t[0]]));
        // edge-length regulariser: in flat regions (zero quadric error) shorter edges go first,
        // which keeps the coarse meshes evenly sampled; scaled like the area-weighted quadric
        length_weight_ = diag > 0.0 ? 1e-3 * area / (diag * diag) : 0.0;
    }

    core::Result<ProgressiveMesh> run(core::ProgressSink& progress)
    {
        ProgressiveMesh pm;
        const std::size_t total = alive_count_ > 4 ? alive_count_ - 4 : 1;
        bool geometric = true;
        // Each pass drains the queue; a second pass without the normal test finishes meshes
        // whose remaining collapses would all flip a face. Bounded: each pass either collapses
        // something or the next one drops the geometric test, after which it is the last.
        for (int pass = 0; pass < 64 && alive_count_ > 4; ++pass)
        {
            fill_queue();
            const std::size_t before = alive_count_;
            while (!heap_.empty() && alive_count_ > 4)
            {
                const Candidate c = heap_.top();
                heap_.pop();
                if (!vertex_alive_[c.u] || !vertex_alive_[c.v] || stamp_[c.u] != c.stamp_u ||
                    stamp_[c.v] != c.stamp_v)
                    continue;
                if (!link_condition(c.u, c.v))
                    continue;
                if (geometric && !keeps_normals(c.u, c.v))
                    continue;
                collapse(c.u, c.v, pm);
                if (!geometric)
                    ++pm.forced_collapses;
                if ((alive_count_ & 1023U) == 0)
                {
                    if (progress.stop_requested())
                        return core::cancelled("remesh", "simplify");
                    progress.update("simplify", static_cast<double>(pm.collapses.size()) /
                                                    static_cast<double>(total));
                }
            }
            if (alive_count_ == before || pass >= 3)
            {
                if (!geometric && alive_count_ == before)
                    break;
                geometric = false;
            }
        }
        if (alive_count_ != 4)
            return core::fail(core::ErrorCode::NotConverged,
                              "remesh: simplification stopped at " + std::to_string(alive_count_) +
                                  " vertices, expected a tetrahedron (is the mesh a closed "
                                  "genus-0 manifold?)");
        pm.coarse_faces = faces_;
        pm.coarse_alive = face_alive_;
        std::size_t k = 0;
        for (std::uint32_t v = 0; v < vertex_alive_.size(); ++v)
            if (vertex_alive_[v])
                pm.base_vertices[k++] = v;
        progress.update("simplify", 1.0);
        return pm;
    }

private:
    void push(std::uint32_t u, std::uint32_t v)
    {
        Quadric q = quadric_[u];
        q += quadric_[v];
        const Vec3 d = pos_[u] - pos_[v];
        const double cost = std::max(0.0, q.eval(pos_[v])) + length_weight_ * core::dot(d, d);
        heap_.push({cost, u, v, stamp_[u], stamp_[v]});
    }

    void fill_queue()
    {
        heap_ = {};
        for (std::uint32_t f = 0; f < faces_.size(); ++f)
        {
            if (!face_alive_[f])
                continue;
            const auto& t = faces_[f];
            for (int i = 0; i < 3; ++i)
            {
                // each undirected edge appears in two faces; each face pushes its two directions
                push(t[static_cast<std::size_t>(i)], t[static_cast<std::size_t>((i + 1) % 3)]);
            }
        }
    }

    // neighbours of u get mark == tick; returns how many of v's neighbours carry it
    bool link_condition(std::uint32_t u, std::uint32_t v)
    {
        ++tick_;
        for (const std::uint32_t f : vf_[u])
            for (const std::uint32_t w : faces_[f])
                mark_[w] = tick_;
        int common = 0;
        bool adjacent = false;
        ++tick_;  // second stamp so each common neighbour is counted once
        for (const std::uint32_t f : vf_[v])
            for (const std::uint32_t w : faces_[f])
            {
                if (w == u)
                    adjacent = true;
                if (w != u && w != v && mark_[w] == tick_ - 1)
                {
                    mark_[w] = tick_;
                    ++common;
                }
            }
        return adjacent && common == 2;
    }

    bool keeps_normals(std::uint32_t u, std::uint32_t v) const
    {
        for (const std::uint32_t f : vf_[u])
        {
            const auto& t = faces_[f];
            if (t[0] == v || t[1] == v || t[2] == v)
                continue;
            std::array<Vec3, 3> p{pos_[t[0]], pos_[t[1]], pos_[t[2]]};
            const Vec3 n0 = core::cross(p[1] - p[0], p[2] - p[0]);
            for (std::size_t i = 0; i < 3; ++i)
                if (t[i] == u)
                    p[i] = pos_[v];
            const Vec3 n1 = core::cross(p[1] - p[0], p[2] - p[0]);
            const double l0 = core::norm(n0), l1 = core::norm(n1);
            if (!(l1 > 0.0) || core::dot(n0, n1) < 0.2 * l0 * l1)
                return false;
        }
        return true;
    }

    void collapse(std::uint32_t u, std::uint32_t v, ProgressiveMesh& pm)
    {
        Collapse rec;
        rec.removed = u;
        rec.kept = v;
        rec.first_modified = static_cast<std::uint32_t>(pm.modified_faces.size());
        int killed = 0;
        for (const std::uint32_t f : vf_[u])
        {
            auto& t = faces_[f];
            if (t[0] == v || t[1] == v || t[2] == v)
            {
                PLIANT_ASSERT(killed < 2, "collapse: more than two faces on an edge");
                rec.killed_faces[static_cast<std::size_t>(killed++)] = f;
                face_alive_[f] = 0;
                for (const std::uint32_t w : t)
                    if (w != u)
                        std::erase(vf_[w], f);
            }
            else
            {
                for (auto& w : t)
                    if (w == u)
                        w = v;
                vf_[v].push_back(f);
                pm.modified_faces.push_back(f);
            }
        }
        PLIANT_ASSERT(killed == 2, "collapse: an edge without two faces");
        rec.modified_count =
            static_cast<std::uint32_t>(pm.modified_faces.size()) - rec.first_modified;
        vf_[u].clear();
        vertex_alive_[u] = 0;
        --alive_count_;
        quadric_[v] += quadric_[u];
        ++stamp_[u];
        ++stamp_[v];
        pm.collapses.push_back(rec);
        // new candidates for every edge at v (their cost changed with v's quadric)
        ++tick_;
        for (const std::uint32_t f : vf_[v])
            for (const std::uint32_t w : faces_[f])
                if (w != v && mark_[w] != tick_)
                {
                    mark_[w] = tick_;
                    push(v, w);
                    push(w, v);
                }
    }

    const std::vector<Vec3>& pos_;
    std::vector<mesh::Face> faces_;
    std::vector<std::uint8_t> face_alive_;
    std::vector<std::uint8_t> vertex_alive_;
    std::vector<std::vector<std::uint32_t>> vf_;
    std::vector<Quadric> quadric_;
    std::vector<std::uint32_t> stamp_;
    std::vector<std::uint64_t> mark_;
    std::uint64_t tick_ = 0;
    std::size_t alive_count_ = 0;
    double length_weight_ = 0.0;
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> heap_;
};

}  // namespace

core::Result<ProgressiveMesh> build_progressive_mesh(const mesh::TriMesh& mesh,
                                                     core::ProgressSink& progress)
{
    if (mesh.positions.size() < 4 || mesh.faces.size() < 4)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "remesh: a closed mesh needs at least 4 vertices and 4 faces");
    Simplifier s(mesh);
    return s.run(progress);
}

}  // namespace pliant::remesh::detail
