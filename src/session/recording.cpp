// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/file_io.h>
#include <pliant/core/hash.h>
#include <pliant/net/codec.h>
#include <pliant/session/recording.h>
#include <pliant/sim/rkf45.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <optional>
#include <string>

namespace pliant::session
{
namespace
{

constexpr std::array<char, 8> k_magic{'P', 'L', 'I', 'A', 'N', 'T', 'R', '\0'};
/// Version 2 added the hash mask after the final hash; version 1 files (no mask: the hash
/// covers every node) still load.
constexpr std::uint32_t k_version = 2;
/// Force's layout has not changed since protocol version 1 (docs/protocol.md, the versions'
/// history), so a recording made by an earlier build, whose force entries carry its protocol
/// version, is read as if they carried this build's.
constexpr std::uint8_t k_force_layout_since = 1;
constexpr std::size_t k_version_byte = 4;  // of a datagram (docs/protocol.md §4)
constexpr std::size_t k_type_byte = 5;

void put(std::vector<std::byte>& out, std::uint64_t value, int bytes)
{
    for (int i = 0; i < bytes; ++i)
        out.push_back(static_cast<std::byte>((value >> (8 * i)) & 0xFFu));
}

/// Bounds-checked little-endian reader; `ok` turns false on the first read past the end.
struct Reader
{
    std::span<const std::byte> data;
    std::size_t pos = 0;
    bool ok = true;

    std::uint64_t get(int bytes)
    {
        if (!ok || data.size() - pos < static_cast<std::size_t>(bytes))
        {
            ok = false;
            return 0;
        }
        std::uint64_t v = 0;
        for (int i = 0; i < bytes; ++i)
            v |= static_cast<std::uint64_t>(data[pos + static_cast<std::size_t>(i)]) << (8 * i);
        pos += static_cast<std::size_t>(bytes);
        return v;
    }
    std::span<const std::byte> take(std::size_t n)
    {
        if (!ok || data.size() - pos < n)
        {
            ok = false;
            return {};
        }
        auto s = data.subspan(pos, n);
        pos += n;
        return s;
    }
};

core::Unexpected bad_file(const std::string& source, std::size_t offset, const std::string& why)
{
    return core::fail(core::ErrorCode::ParseError,
                      source + ": byte " + std::to_string(offset) + ": " + why);
}

/// TetraGrid::unique_count() of a level, without building the grid: 2 W^2 + 2, W = 2^level.
std::size_t unique_node_count(int level) noexcept
{
    const std::size_t w = std::size_t{1} << level;
    return 2 * w * w + 2;
}

/// The bytes before the first entry of a version-1 file with an empty model blob, and the
/// checksum: no recording is shorter.
constexpr std::size_t k_min_size = 8 + 4 + 8 + 8 + 4 + 4 + 8;
/// Where a version-2 file's hash mask size and its bytes begin.
constexpr std::size_t k_mask_size_offset = 8 + 4 + 8 + 8;
constexpr std::size_t k_mask_offset = k_mask_size_offset + 4;

/// Why a hash mask cannot select the nodes a final hash covers, and the offset of the field at
/// fault (the mask's size or its bytes).
struct MaskProblem
{
    std::size_t offset = 0;
    std::string why;
};

/// Why `mask` cannot select the nodes `final_hash` covers for the grid of `model` (a model blob:
/// its level is byte 5), or nothing when it can: empty (every node), or one bit per canonical
/// node, ceil(N / 8) bytes with the bits past N clear; a non-zero hash must cover a node.
std::optional<MaskProblem> mask_problem(std::span<const std::byte> model,
                                        std::span<const std::uint8_t> mask,
                                        std::uint64_t final_hash)
{
    if (mask.empty())
        return std::nullopt;
    if (model.size() < 6)
        return MaskProblem{k_mask_size_offset,
                           "a model blob too short to give its grid's level, on which the hash "
                           "mask's length depends"};
    const int level = std::to_integer<int>(model[5]);
    if (level < core::k_min_level || level > core::k_max_level)
        return MaskProblem{k_mask_size_offset,
                           "a model blob of grid level " + std::to_string(level) +
                               " (pliant's grids: 1 to 10), on which the hash mask's length "
                               "depends"};
    const std::size_t nodes = unique_node_count(level);
    if (mask.size() != (nodes + 7) / 8)
        return MaskProblem{k_mask_size_offset,
                           "a hash mask of " + std::to_string(mask.size()) + " bytes; the level-" +
                               std::to_string(level) + " grid's " + std::to_string(nodes) +
                               " canonical nodes take " + std::to_string((nodes + 7) / 8)};
    if (nodes % 8 != 0 && (mask.back() >> (nodes % 8)) != 0)
        return MaskProblem{
            k_mask_offset + mask.size() - 1,
            "a hash mask that selects nodes past the grid's " + std::to_string(nodes)};
    if (final_hash != 0 &&
        std::all_of(mask.begin(), mask.end(), [](std::uint8_t b) { return b == 0; }))
        return MaskProblem{k_mask_offset,
                           "a final hash over no node (a hash mask that selects none: such a "
                           "recording carries hash 0, unknown)"};
    return std::nullopt;
}

}  // namespace

core::Result<std::vector<std::byte>> encode_recording(const Recording& recording)
{
    if (const auto problem =
            mask_problem(recording.model, recording.hash_mask, recording.final_hash))
        return core::fail(core::ErrorCode::InvalidArgument, "save_recording: " + problem->why);
    std::vector<std::byte> out;
    for (const char c : k_magic)
        out.push_back(static_cast<std::byte>(c));
    put(out, k_version, 4);
    put(out, recording.final_tick, 8);
    put(out, recording.final_hash, 8);
    put(out, recording.hash_mask.size(), 4);
    for (const std::uint8_t b : recording.hash_mask)
        out.push_back(static_cast<std::byte>(b));
    put(out, recording.model.size(), 4);
    out.insert(out.end(), recording.model.begin(), recording.model.end());
    put(out, recording.forces.size(), 4);
    std::vector<std::byte> datagram(net::k_max_datagram_size);
    for (const ForceRecord& r : recording.forces)
    {
        net::Message m;
        m.header.session = 1;
        m.header.sender = net::PeerId{r.sender};
        m.header.tick = r.apply_tick;
        m.body = net::Force{r.forces};
        const auto n = net::encode(m, datagram);
        if (!n)
            return core::fail(core::ErrorCode::InvalidArgument,
                              "save_recording: a force list of peer " + std::to_string(r.sender) +
                                  " breaks the wire's rules");
        put(out, *n, 2);
        out.insert(out.end(), datagram.begin(), datagram.begin() + static_cast<std::ptrdiff_t>(*n));
    }
    put(out, core::hash_bytes(out), 8);
    return out;
}

core::Result<void> save_recording(const std::filesystem::path& path, const Recording& recording)
{
    auto out = encode_recording(recording);
    if (!out)
        return out.error();
    return core::write_file(path, *out, "");
}

core::Result<Recording> load_recording(const std::filesystem::path& path)
{
    // No bound in the format (one entry per force list); 4 GiB stops a FIFO fed for ever.
    auto bytes = core::read_input_file(path, std::size_t{1} << 32, "recording pliant reads");
    if (!bytes)
        return bytes.error();
    return decode_recording(*bytes, path.string());
}

core::Result<Recording> decode_recording(std::span<const std::byte> bytes,
                                         const std::string& source)
{
    if (bytes.size() < k_magic.size() ||
        std::memcmp(bytes.data(), k_magic.data(), k_magic.size()) != 0)
        return bad_file(source, 0, "not a pliant recording (it does not begin with PLIANTR)");
    if (bytes.size() < k_min_size)
        return bad_file(source, bytes.size(),
                        "truncated: " + std::to_string(bytes.size()) +
                            " bytes, and no recording is shorter than " +
                            std::to_string(k_min_size));
    const std::size_t body = bytes.size() - 8;
    Reader tail{bytes.subspan(body)};
    if (tail.get(8) != core::hash_bytes(bytes.first(body)))
        return bad_file(source, body, "checksum mismatch (truncated or corrupted)");
    Reader r{bytes.first(body), k_magic.size()};
    const auto version = r.get(4);
    if (version != 1 && version != k_version)
        return bad_file(source, 8,
                        "version " + std::to_string(version) + ", this build reads 1 to " +
                            std::to_string(k_version));
    Recording rec;
    rec.final_tick = r.get(8);
    rec.final_hash = r.get(8);
    if (version >= 2)
    {
        const auto mask_size = r.get(4);
        for (const std::byte b : r.take(mask_size))
            rec.hash_mask.push_back(std::to_integer<std::uint8_t>(b));
    }
    const auto model_size = r.get(4);
    const auto model = r.take(model_size);
    rec.model.assign(model.begin(), model.end());
    const auto count = r.get(4);
    if (!r.ok)
        return bad_file(source, r.pos, "truncated header");
    if (const auto problem = mask_problem(rec.model, rec.hash_mask, rec.final_hash))
        return bad_file(source, problem->offset, problem->why);
    for (std::uint64_t i = 0; i < count; ++i)
    {
        const std::size_t at = r.pos;
        const auto size = r.get(2);
        const auto datagram = r.take(size);
        if (!r.ok)
            return bad_file(source, at, "truncated force entry " + std::to_string(i));
        std::array<std::byte, net::k_max_datagram_size> current{};
        std::span<const std::byte> entry = datagram;
        if (datagram.size() > k_type_byte &&
            datagram[k_type_byte] == static_cast<std::byte>(net::MessageType::Force) &&
            std::to_integer<std::uint8_t>(datagram[k_version_byte]) >= k_force_layout_since &&
            std::to_integer<std::uint8_t>(datagram[k_version_byte]) < net::k_protocol_version &&
            datagram.size() <= current.size())
        {
            std::copy(datagram.begin(), datagram.end(), current.begin());
            current[k_version_byte] = static_cast<std::byte>(net::k_protocol_version);
            entry = std::span<const std::byte>(current.data(), datagram.size());
        }
        auto m = net::decode(entry);
        if (!m)
            return bad_file(
                source, at,
                "force entry " + std::to_string(i) + ": " + std::string(net::to_string(m.error())));
        const auto* force = std::get_if<net::Force>(&m->body);
        if (force == nullptr)
            return bad_file(source, at, "entry " + std::to_string(i) + " is not a force list");
        rec.forces.push_back(ForceRecord{m->header.sender.value, m->header.tick, force->forces});
    }
    if (r.pos != body)
        return bad_file(source, r.pos, "trailing bytes after the last entry");
    return rec;
}

std::vector<sim::Force> forces_at(const sim::MembraneModel& model,
                                  const std::vector<ForceRecord>& records, std::uint64_t tick)
{
    // Each sender's newest list that applies (ties: the later record), senders by id.
    std::vector<const ForceRecord*> active;
    for (const ForceRecord& r : records)
    {
        if (r.apply_tick > tick)
            continue;
        auto it = std::find_if(active.begin(), active.end(),
                               [&](const ForceRecord* a) { return a->sender == r.sender; });
        if (it == active.end())
            active.push_back(&r);
        else if (r.apply_tick >= (*it)->apply_tick)
            *it = &r;
    }
    std::sort(active.begin(), active.end(),
              [](const ForceRecord* a, const ForceRecord* b) { return a->sender < b->sender; });
    std::vector<sim::Force> out;
    for (const ForceRecord* r : active)
        (void)append_valid_forces(model, r->forces, out);
    return out;
}

core::Result<ReplayResult> replay(const Recording& recording, int threads,
                                  std::optional<std::uint64_t> until, core::ProgressSink* progress)
{
    const std::uint64_t ticks = until.value_or(recording.final_tick);
    auto decoded = decode_model(recording.model);
    if (!decoded)
        return core::fail(decoded.error().code, decoded.error().message);
    sim::MembraneModel model = std::move(decoded->model);
    const Coupling coupling = decoded->coupling;
    if (!model.settings().fixed_step)
        return core::fail(core::ErrorCode::InvalidArgument,
                          "replay: the recorded model is not fixed-step");
    sim::MembraneState state = sim::MembraneState::at_rest(model.grid());
    sim::Rkf45Workspace ws(model, threads);
    // Force lists change rarely: recombine only at ticks where one starts.
    std::vector<std::uint64_t> changes;
    for (const ForceRecord& r : recording.forces)
        changes.push_back(r.apply_tick);
    std::sort(changes.begin(), changes.end());
    std::vector<sim::Force> forces = forces_at(model, recording.forces, 0);
    auto next = std::upper_bound(changes.begin(), changes.end(), std::uint64_t{0});
    const std::uint64_t report_every = std::max<std::uint64_t>(1, ticks / 100);
    for (std::uint64_t t = 0; t < ticks; ++t)
    {
        if (progress != nullptr && t % report_every == 0)
            progress->update("replay", static_cast<double>(t) / static_cast<double>(ticks));
        // A stop asked for (Ctrl-C in `pliant replay`) ends the replay within 16 steps.
        if (t % 16 == 0 && core::stop_requested(progress))
            return core::cancelled("replay",
                                   "tick " + std::to_string(t) + " of " + std::to_string(ticks));
        if (next != changes.end() && *next <= t)
        {
            forces = forces_at(model, recording.forces, t);
            next = std::upper_bound(changes.begin(), changes.end(), t);
        }
        const sim::StepReport r = sim::step(model, state, ws, forces);
        if (sim::has_flag(r.status, sim::StepStatus::NonFinite))
        {
            // The step kept the state as it was: the replay ends on the last finite one.
            if (progress != nullptr)
                progress->update("replay", 1.0);
            return ReplayResult{std::move(model), coupling, std::move(state), t};
        }
    }
    if (progress != nullptr)
        progress->update("replay", 1.0);
    return ReplayResult{std::move(model), coupling, std::move(state), std::nullopt};
}

namespace
{

bool in_mask(std::span<const std::uint8_t> mask, std::size_t k)
{
    return mask.empty() || (k / 8 < mask.size() && ((mask[k / 8] >> (k % 8)) & 1U) != 0);
}

}  // namespace

std::uint64_t state_hash(const core::TetraGrid& grid, const core::Field<double>& u,
                         const core::Field<double>& v, std::span<const std::uint8_t> mask)
{
    // u and v of each node as little-endian f64, so that the hash is the same on any host.
    std::vector<std::byte> bytes;
    bytes.reserve(16 * grid.unique_count());
    const auto nodes = grid.node_of_unique();
    for (std::size_t k = 0; k < nodes.size(); ++k)
    {
        if (!in_mask(mask, k))
            continue;
        const core::GridCoord c = grid.coord(nodes[k]);
        put(bytes, std::bit_cast<std::uint64_t>(u.at(c.x, c.y)), 8);
        put(bytes, std::bit_cast<std::uint64_t>(v.at(c.x, c.y)), 8);
    }
    return core::hash_bytes(bytes);
}

std::size_t hash_mask_count(const core::TetraGrid& grid, std::span<const std::uint8_t> mask)
{
    std::size_t n = 0;
    for (std::size_t k = 0; k < grid.unique_count(); ++k)
        n += in_mask(mask, k) ? 1 : 0;
    return n;
}

}  // namespace pliant::session
