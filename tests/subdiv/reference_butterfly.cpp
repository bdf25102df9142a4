// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "reference_butterfly.h"

#include <gtest/gtest.h>

#include <map>
#include <utility>

namespace pliant::test
{

ReferenceButterfly::ReferenceButterfly(std::span<const std::array<std::uint32_t, 3>> faces,
                                       std::size_t vertex_count)
{
    const auto hcount = static_cast<std::uint32_t>(3 * faces.size());
    from_.resize(hcount);
    opposite_.assign(hcount, UINT32_MAX);
    valence_.assign(vertex_count, 0);
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> directed;
    for (std::uint32_t f = 0; f < faces.size(); ++f)
        for (std::uint32_t i = 0; i < 3; ++i)
        {
            const std::uint32_t h = 3 * f + i;
            from_[h] = faces[f][i];
            const auto key = std::make_pair(faces[f][i], faces[f][(i + 1) % 3]);
            if (!directed.emplace(key, h).second)
            {
                ADD_FAILURE() << "reference: halfedge " << key.first << "->" << key.second
                              << " appears twice (not an oriented manifold)";
                return;
            }
        }
    for (const auto& [key, h] : directed)
    {
        const auto it = directed.find({key.second, key.first});
        if (it == directed.end())
        {
            ADD_FAILURE() << "reference: boundary halfedge " << key.first << "->" << key.second;
            return;
        }
        opposite_[h] = it->second;
        if (key.first < key.second)
        {
            edges_.push_back(h);
            ++valence_[key.first];
            ++valence_[key.second];
        }
    }
    ok_ = true;
}

ButterflyStencil ReferenceButterfly::stencil(std::uint32_t h) const
{
    const std::uint32_t o = opposite(h);
    ButterflyStencil s;
    s.a0 = from(h);
    s.a1 = to(h);
    s.b0 = apex(h);
    s.b1 = apex(o);
    // The wing of h: the faces across its two other edges; then the wing of o.
    s.c[0] = apex(opposite(next(h)));
    s.c[1] = apex(opposite(prev(h)));
    s.c[2] = apex(opposite(next(o)));
    s.c[3] = apex(opposite(prev(o)));
    return s;
}

double ReferenceButterfly::new_value(std::uint32_t h, std::span<const double> v) const
{
    const ButterflyStencil s = stencil(h);
    return (0.5 * (v[s.a0] + v[s.a1]) + 0.125 * (v[s.b0] + v[s.b1])) -
           0.0625 * ((v[s.c[0]] + v[s.c[1]]) + (v[s.c[2]] + v[s.c[3]]));
}

}  // namespace pliant::test
