// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/subdiv/convolution_plan.h>

#include <string>
#include <utility>

namespace pliant::subdiv
{

ConvolutionPlan::ConvolutionPlan(core::TetraGrid coarse, core::TetraGrid fine)
    : coarse_(std::move(coarse)), fine_(std::move(fine))
{
    for (int g = k_refine_ghost; g <= core::k_max_ghost; ++g)
    {
        const std::ptrdiff_t stride = coarse_.nx() + 2 * g;
        for (std::size_t d = 0; d < k_direction_count; ++d)
        {
            const Mask& m = mask(static_cast<EdgeDirection>(d));
            for (std::size_t i = 0; i < k_tap_count; ++i)
                offsets_[static_cast<std::size_t>(g)][d][i] =
                    static_cast<std::ptrdiff_t>(m[i].dy) * stride + m[i].dx;
        }
    }
}

core::Result<ConvolutionPlan> ConvolutionPlan::create(int coarse_level)
{
    if (coarse_level < core::k_min_level || coarse_level >= core::k_max_level)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "ConvolutionPlan::create: coarse level " + std::to_string(coarse_level) +
                              " is outside " + std::to_string(core::k_min_level) + ".." +
                              std::to_string(core::k_max_level - 1) +
                              " (the refined level may be at most " +
                              std::to_string(core::k_max_level) + ")");
    auto coarse = core::TetraGrid::create(coarse_level);
    if (!coarse)
        return coarse.error();
    auto fine = core::TetraGrid::create(coarse_level + 1);
    if (!fine)
        return fine.error();
    return ConvolutionPlan(std::move(*coarse), std::move(*fine));
}

core::Result<std::vector<ConvolutionPlan>> make_plans(int coarse_level, int levels)
{
    if (levels < 1 || coarse_level < core::k_min_level || coarse_level + levels > core::k_max_level)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "make_plans: level " + std::to_string(coarse_level) + " + " +
                              std::to_string(levels) + " levels must stay within " +
                              std::to_string(core::k_min_level) + ".." +
                              std::to_string(core::k_max_level) + " with at least one level");
    std::vector<ConvolutionPlan> plans;
    plans.reserve(static_cast<std::size_t>(levels));
    for (int i = 0; i < levels; ++i)
    {
        auto plan = ConvolutionPlan::create(coarse_level + i);
        if (!plan)
            return plan.error();
        plans.push_back(std::move(*plan));
    }
    return plans;
}

}  // namespace pliant::subdiv
