// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The model and state blobs of the Welcome and of recordings (encode_model, decode_model,
// encode_state, decode_state; docs/protocol.md §6), and forces from the wire (to_sim_force,
// append_valid_forces).
#include <pliant/session/session.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace pliant::session
{

namespace
{

constexpr std::uint32_t k_model_magic = 0x4D534C50;  // "PLSM"
/// Version 2 adds the point clearance byte after the coupling; version 3 the force limit after
/// the step settings; version 4 the session's barrier limit after it. Older blobs (recordings
/// made before them) still decode: version 1 with the coupling's rule, versions 1 and 2 with
/// no force limit (as they were made), versions 1 to 3 with no barrier limit (a joiner keeps
/// its own).
constexpr std::uint8_t k_model_version = 4;
// --- little-endian byte writer/reader for the blobs -------------------------------------------

struct Writer
{
    std::vector<std::byte> out;
    void u8(std::uint8_t v) { out.push_back(static_cast<std::byte>(v)); }
    void u32(std::uint32_t v)
    {
        for (int k = 0; k < 4; ++k)
            u8(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void u64(std::uint64_t v)
    {
        for (int k = 0; k < 8; ++k)
            u8(static_cast<std::uint8_t>(v >> (8 * k)));
    }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
};

struct Reader
{
    std::span<const std::byte> in;
    std::size_t pos = 0;
    bool ok = true;
    std::uint8_t u8()
    {
        if (pos >= in.size())
        {
            ok = false;
            return 0;
        }
        return static_cast<std::uint8_t>(in[pos++]);
    }
    std::uint32_t u32()
    {
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k)
            v |= static_cast<std::uint32_t>(u8()) << (8 * k);
        return v;
    }
    std::uint64_t u64()
    {
        std::uint64_t v = 0;
        for (int k = 0; k < 8; ++k)
            v |= static_cast<std::uint64_t>(u8()) << (8 * k);
        return v;
    }
    double f64()
    {
        const double v = std::bit_cast<double>(u64());
        if (!std::isfinite(v))
            ok = false;
        return v;
    }
};

/// The clearance byte of a version-2 model blob: 0 the coupling's rule, 1 AsGrown, 2 Inside.
std::uint8_t clearance_byte(std::optional<PointClearance> c)
{
    if (!c)
        return 0;
    return *c == PointClearance::AsGrown ? 1 : 2;
}

}  // namespace

std::vector<std::byte> encode_model(const sim::MembraneModel& model, Coupling coupling,
                                    std::optional<PointClearance> clearance,
                                    double max_barrier_wait_s)
{
    const core::TetraGrid& g = model.grid();
    const sim::MembraneSettings& s = model.settings();
    Writer w;
    w.u32(k_model_magic);
    w.u8(k_model_version);
    w.u8(static_cast<std::uint8_t>(g.level()));
    w.u8(static_cast<std::uint8_t>(coupling));
    w.u8(clearance_byte(clearance));
    w.u8(s.fixed_step ? 1 : 0);
    w.u32(static_cast<std::uint32_t>(std::max(0, s.reassemble_every)));
    for (const double v :
         {s.T, s.rho, s.beta, s.k_f, s.rtol, s.atol, s.dt_min, s.dt_max, s.dt_initial, s.safety,
          s.max_growth, s.min_shrink, s.fixed_dt, s.max_force, max_barrier_wait_s})
        w.f64(v);
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            for (int c = 0; c < 3; ++c)
                w.f64(model.rest_positions()[static_cast<std::size_t>(c)].at(x, y));
    return std::move(w.out);
}

core::Result<DecodedModel> decode_model(std::span<const std::byte> blob)
{
    const auto refuse = [](const std::string& why)
    { return core::fail(core::ErrorCode::InvalidArgument, "model blob: " + why); };
    Reader r{blob};
    const std::uint32_t magic = r.u32();
    const std::uint8_t version = r.u8();
    if (!r.ok)
        return refuse(std::to_string(blob.size()) + " bytes, shorter than its header");
    if (magic != k_model_magic)
        return refuse("it does not begin with PLSM");
    if (version < 1 || version > k_model_version)
        return refuse("version " + std::to_string(version) + ", this build reads 1 to " +
                      std::to_string(k_model_version));
    const int level = r.u8();
    const std::uint8_t coupling = r.u8();
    const std::uint8_t clearance = version >= 2 ? r.u8() : 0;
    const std::uint8_t fixed = r.u8();
    if (!r.ok)
        return refuse(std::to_string(blob.size()) + " bytes, shorter than its header");
    if (level < core::k_min_level || level > core::k_max_level)
        return refuse("grid level " + std::to_string(level) + ", pliant's grids are of levels " +
                      std::to_string(core::k_min_level) + " to " +
                      std::to_string(core::k_max_level));
    if (coupling < 1 || coupling > 2)
        return refuse("coupling " + std::to_string(coupling) + ", 1 (exact) or 2 (fast)");
    if (clearance > 2)
        return refuse("point clearance " + std::to_string(clearance) +
                      ", 0 (the coupling's rule), 1 (grown) or 2 (inside)");
    if (fixed > 1)
        return refuse("fixed-step flag " + std::to_string(fixed) + ", 0 or 1");
    const core::TetraGrid g = core::TetraGrid::create(level).value();
    const std::size_t settings_count = version >= 4 ? 15 : version >= 3 ? 14 : 13;
    const std::size_t expect = (version >= 2 ? 13 : 12) + settings_count * 8 + g.node_count() * 24;
    if (blob.size() != expect)
        return refuse(std::to_string(blob.size()) + " bytes; a version-" + std::to_string(version) +
                      " model of level " + std::to_string(level) + " takes " +
                      std::to_string(expect));
    sim::MembraneSettings s;
    s.fixed_step = fixed == 1;
    const std::uint32_t reassemble = r.u32();
    if (reassemble > (1u << 30))
        return refuse("re-assembly every " + std::to_string(reassemble) + " steps, at most 2^30");
    s.reassemble_every = static_cast<int>(reassemble);
    const std::pair<const char*, double*> settings[] = {{"tension T", &s.T},
                                                        {"density rho", &s.rho},
                                                        {"damping beta", &s.beta},
                                                        {"foundation k_f", &s.k_f},
                                                        {"rtol", &s.rtol},
                                                        {"atol", &s.atol},
                                                        {"dt_min", &s.dt_min},
                                                        {"dt_max", &s.dt_max},
                                                        {"dt_initial", &s.dt_initial},
                                                        {"safety", &s.safety},
                                                        {"max_growth", &s.max_growth},
                                                        {"min_shrink", &s.min_shrink},
                                                        {"fixed_dt", &s.fixed_dt}};
    for (const auto& [name, value] : settings)
    {
        *value = r.f64();
        if (!r.ok)
            return refuse(std::string("setting ") + name + " is not finite");
    }
    if (version >= 3)
    {
        s.max_force = r.f64();
        if (!r.ok)
            return refuse("setting max_force is not finite");
    }
    std::optional<double> barrier;
    if (version >= 4)
    {
        barrier = r.f64();
        if (!r.ok)
            return refuse("setting max_barrier_wait_s is not finite");
        if (*barrier < 0.0)
            return refuse("max_barrier_wait_s " + std::to_string(*barrier) +
                          ", which must be >= 0 s (0: never)");
    }
    core::Vec3Field<double> rest{core::Field<double>(g), core::Field<double>(g),
                                 core::Field<double>(g)};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
            for (int c = 0; c < 3; ++c)
            {
                rest[static_cast<std::size_t>(c)].at(x, y) = r.f64();
                if (!r.ok)
                    return refuse("the rest position of node (" + std::to_string(x) + "," +
                                  std::to_string(y) + ") is not finite");
            }
    for (const core::TwinPair& t : g.twins())
        for (const core::Field<double>& plane : rest)
            if (plane[t.twin] != plane[t.canonical] ||
                std::signbit(plane[t.twin]) != std::signbit(plane[t.canonical]))
            {
                const core::GridCoord a = g.coord(t.twin);
                return core::fail(core::ErrorCode::InvalidArgument,
                                  "model blob: twin node (" + std::to_string(a.x) + "," +
                                      std::to_string(a.y) +
                                      ") has another rest position than its canonical node");
            }
    auto model = sim::MembraneModel::create(g, rest, s);
    if (!model)
        return core::fail(model.error().code, "model blob: " + model.error().message);
    std::optional<PointClearance> clear;
    if (clearance != 0)
        clear = clearance == 1 ? PointClearance::AsGrown : PointClearance::Inside;
    return DecodedModel{std::move(model).value(), static_cast<Coupling>(coupling), clear, barrier};
}

std::vector<std::byte> encode_state(const core::TetraGrid& grid, const core::Field<double>& u,
                                    const core::Field<double>& v, std::uint64_t tick, double time)
{
    Writer w;
    w.u64(tick);
    w.f64(time);
    for (int y = 0; y < grid.ny(); ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            w.f64(u.at(x, y));
            w.f64(v.at(x, y));
        }
    return std::move(w.out);
}

core::Result<DecodedState> decode_state(const core::TetraGrid& grid,
                                        std::span<const std::byte> blob)
{
    if (blob.size() != 16 + grid.node_count() * 16)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "state blob: " + std::to_string(blob.size()) + " bytes, level " +
                              std::to_string(grid.level()) + " needs " +
                              std::to_string(16 + grid.node_count() * 16));
    Reader r{blob};
    DecodedState out{r.u64(), r.f64(), core::Field<double>(grid), core::Field<double>(grid)};
    for (int y = 0; y < grid.ny() && r.ok; ++y)
        for (int x = 0; x < grid.nx(); ++x)
        {
            out.u.at(x, y) = r.f64();
            out.v.at(x, y) = r.f64();
        }
    if (!r.ok)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "state blob: a non-finite value near byte " + std::to_string(r.pos));
    return out;
}

sim::Force to_sim_force(const net::UserForce& f)
{
    sim::Force out;
    if (f.target.kind == net::TargetKind::Face)
        out.face = static_cast<std::int64_t>(f.target.face);
    else
    {
        out.face = -1;
        out.point = {f.target.position[0], f.target.position[1], f.target.position[2]};
        out.radius = f.target.radius;
    }
    out.vector = {f.force[0], f.force[1], f.force[2]};
    return out;
}

std::size_t append_valid_forces(const sim::MembraneModel& model,
                                std::span<const net::UserForce> forces,
                                std::vector<sim::Force>& out)
{
    std::size_t dropped = 0;
    for (const net::UserForce& f : forces)
    {
        const sim::Force force = to_sim_force(f);
        if (sim::validate_forces(model, std::span(&force, 1)))
            out.push_back(force);
        else
            ++dropped;
    }
    return dropped;
}

}  // namespace pliant::session
