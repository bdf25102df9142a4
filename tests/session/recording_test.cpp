// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Recording and replay: a recorded exact-mode session replays bit for bit on one process; the
// file round-trips exactly and refuses corruption; the replay's force rule equals the obvious
// reference schedule.
#include <pliant/core/hash.h>
#include <pliant/session/recording.h>

#include <gtest/gtest.h>

#include "session_harness.h"
#include "support/fp_traps.h"
#include "support/test_paths.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

namespace pliant::session::test
{
namespace
{

constexpr int k_recording_level = 4;
constexpr std::uint64_t k_recording_ticks = 300;

SessionSettings exact(const char* name)
{
    SessionSettings s;
    s.max_ticks = k_recording_ticks;
    s.name = name;
    return s;
}

/// Runs master + 2 participants with forces from every peer, the master recording.
struct RecordedRun
{
    Harness h;
    Recording recording;
    core::Field<double> u, v;  ///< the whole state assembled from every owner
};

void record_session(RecordedRun& run)
{
    Harness& h = run.h;
    Session& master = h.host(k_recording_level, exact("master"));
    ASSERT_TRUE(master.start_recording());
    for (int k = 0; k < 2; ++k)
    {
        Session& p = h.join(net::Role::Participant, exact("part"));
        p.set_points_of_interest({net::Target{
            net::TargetKind::Face, static_cast<std::uint32_t>(100 + 400 * k), {0, 0, 0}, 0.0}});
    }
    EXPECT_TRUE(h.peers[0]->set_forces({point_push(0.0, 0.0, 1.0, 0.4, 0.4)}, 40));
    EXPECT_TRUE(h.peers[1]->set_forces({face_pull(100, 0.7)}, 60));
    EXPECT_TRUE(h.peers[1]->set_forces({}, 180));
    EXPECT_TRUE(
        h.peers[2]->set_forces({point_push(0.0, 0.0, -1.0, 0.3, 0.5), face_pull(500, -0.3)}, 90));
    ASSERT_TRUE(h.pump_until(
        [&]
        {
            for (const auto& p : h.peers)
                if (p->tick() < k_recording_ticks)
                    return false;
            return true;
        },
        40000));
    run.recording = master.recording();
    const core::TetraGrid& g = master.model()->grid();
    run.u = core::Field<double>(g);
    run.v = core::Field<double>(g);
    for (const auto& p : h.peers)
    {
        const auto owners = p->owners();
        for (const core::NodeIndex n : g.node_of_unique())
            if (owners[p->leaf_graph()->leaf_of(n)] == p->id())
            {
                const core::GridCoord c = g.coord(n);
                run.u.at(c.x, c.y) = p->state().u.at(c.x, c.y);
                run.v.at(c.x, c.y) = p->state().v.at(c.x, c.y);
            }
    }
    run.recording.final_hash = state_hash(g, run.u, run.v);
}

TEST(Recording, ReplayOfARecordedSessionIsBitIdentical)
{
    RecordedRun run;
    record_session(run);
    if (HasFatalFailure())
        return;
    EXPECT_EQ(run.recording.final_tick, k_recording_ticks);
    // Four lists: the master's, participant 1's two, participant 2's.
    ASSERT_EQ(run.recording.forces.size(), 4U);
    auto replayed = replay(run.recording);
    ASSERT_TRUE(replayed) << replayed.error().message;
    const core::TetraGrid& g = replayed->model.grid();
    EXPECT_EQ(replayed->coupling, Coupling::Exact);
    EXPECT_EQ(replayed->state.tick, k_recording_ticks);
    const Diff du = compare(g, replayed->state.u, run.u, {});
    EXPECT_EQ(du.max_abs, 0.0);
    EXPECT_GT(du.max_ref, 1e-4);  // the forces moved the surface
    EXPECT_EQ(compare(g, replayed->state.v, run.v, {}).max_abs, 0.0);
    EXPECT_EQ(state_hash(g, replayed->state.u, replayed->state.v), run.recording.final_hash);
    // And with two threads (the sim is thread-count independent).
    auto two = replay(run.recording, 2);
    ASSERT_TRUE(two);
    EXPECT_EQ(state_hash(g, two->state.u, two->state.v), run.recording.final_hash);
}

TEST(Recording, ReplayRuleEqualsTheReferenceSchedule)
{
    // A hand-made recording (no session) against reference_run's independent rule.
    const std::vector<Scheduled> sched{{0, 10, {point_push(0.0, 0.0, 1.0, 0.4, 0.5)}},
                                       {2, 30, {face_pull(200, 0.5)}},
                                       {0, 80, {}},
                                       {2, 30, {face_pull(201, -0.5)}},  // same tick: later wins
                                       {1, 50, {point_push(1.0, 0.0, 0.0, 0.3, 0.2)}}};
    const core::TetraGrid grid = core::TetraGrid::create(k_recording_level).value();
    auto model =
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value();
    Recording rec;
    rec.model = encode_model(model, Coupling::Exact);
    rec.final_tick = 150;
    for (const Scheduled& s : sched)
        rec.forces.push_back(ForceRecord{s.sender, s.from, s.forces});
    auto replayed = replay(rec);
    ASSERT_TRUE(replayed) << replayed.error().message;
    // reference_run takes, per sender, the entry with the greatest `from` (ties: the later one).
    const sim::MembraneState ref = reference_run(k_recording_level, 150, sched);
    EXPECT_EQ(compare(grid, replayed->state.u, ref.u, {}).max_abs, 0.0);
    EXPECT_EQ(compare(grid, replayed->state.v, ref.v, {}).max_abs, 0.0);
    EXPECT_GT(compare(grid, replayed->state.u, ref.u, {}).max_ref, 1e-5);
    // Part of it: up to tick 60 equals the reference's 60 ticks, and up to tick 0 is the rest
    // state (0 once meant "to the end").
    auto part = replay(rec, 1, 60);
    ASSERT_TRUE(part);
    EXPECT_EQ(part->state.tick, 60U);
    const sim::MembraneState ref60 = reference_run(k_recording_level, 60, sched);
    EXPECT_EQ(compare(grid, part->state.u, ref60.u, {}).max_abs, 0.0);
    EXPECT_GT(compare(grid, part->state.u, ref60.u, {}).max_ref, 1e-6);
    auto none = replay(rec, 1, 0);
    ASSERT_TRUE(none);
    EXPECT_EQ(none->state.tick, 0U);
    EXPECT_EQ(compare(grid, none->state.u, core::Field<double>(grid), {}).max_abs, 0.0);
}

// A stop asked for through the progress sink ends the replay within 16 steps, with Cancelled
// and the tick it stopped at, and no result.
TEST(Recording, AStopAskedForEndsTheReplayWithinSixteenSteps)
{
    struct StopAtThirdReport final : core::ProgressSink
    {
        int reports = 0;
        void update(std::string_view phase, double) noexcept override
        {
            EXPECT_EQ(phase, "replay");
            ++reports;
        }
        bool stop_requested() const noexcept override { return reports >= 3; }
    };
    const core::TetraGrid grid = core::TetraGrid::create(k_recording_level).value();
    auto model =
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value();
    Recording rec;
    rec.model = encode_model(model, Coupling::Exact);
    rec.final_tick = 1'000'000;  // minutes of steps if the stop went unheard
    rec.forces.push_back(ForceRecord{0, 0, {face_pull(200, 0.5)}});
    StopAtThirdReport sink;
    const auto replayed = replay(rec, 1, std::nullopt, &sink);
    ASSERT_FALSE(replayed);
    EXPECT_EQ(replayed.error().code, core::ErrorCode::Cancelled);
    // Reports every 10,000 ticks: the third is at tick 20,000, where the stop is heard at once.
    EXPECT_EQ(replayed.error().message, "replay: cancelled during tick 20000 of 1000000");
    EXPECT_EQ(sink.reports, 3);
}

// A recording no session made (a fixed step far above the stable one): the replay stops at the
// first step that gives non-finite values and says so, holding the last finite state; before,
// it stepped on to the end without a word and only the hash check failed.
TEST(Recording, AReplayThatDivergesStopsThereOnTheLastFiniteState)
{
    const core::TetraGrid grid = core::TetraGrid::create(k_recording_level).value();
    sim::MembraneSettings m = material();
    m.fixed_dt = 1.0;  // the stable step at this level is a few hundredths of a second
    auto model = sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), m).value();
    Recording rec;
    rec.model = encode_model(model, Coupling::Exact);
    rec.final_tick = 2'000;
    rec.forces.push_back(ForceRecord{0, 0, {face_pull(200, 0.5)}});
    pliant::test::FpTrapsOff traps_off;  // the diverging trials compute inf and NaN
    const auto replayed = replay(rec);
    ASSERT_TRUE(replayed) << replayed.error().message;
    ASSERT_TRUE(replayed->diverged.has_value());
    EXPECT_LT(*replayed->diverged, rec.final_tick);
    EXPECT_EQ(replayed->state.tick, *replayed->diverged);
    for (const core::NodeIndex n : grid.node_of_unique())
    {
        ASSERT_TRUE(std::isfinite(replayed->state.u[n]));
        ASSERT_TRUE(std::isfinite(replayed->state.v[n]));
    }
    // A stable recording does not set it.
    rec.model = encode_model(
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value(),
        Coupling::Exact);
    rec.final_tick = 50;
    const auto stable = replay(rec);
    ASSERT_TRUE(stable);
    EXPECT_FALSE(stable->diverged.has_value());
    EXPECT_EQ(stable->state.tick, 50U);
}

std::vector<char> read_all(const std::filesystem::path& p)
{
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_all(const std::filesystem::path& p, const std::vector<char>& bytes)
{
    std::ofstream(p, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// `bytes` with its last 8 bytes replaced by the checksum of the rest.
std::vector<char> resealed(std::vector<char> bytes)
{
    const std::uint64_t h =
        core::hash_bytes(std::as_bytes(std::span<const char>(bytes.data(), bytes.size() - 8)));
    for (int k = 0; k < 8; ++k)
        bytes[bytes.size() - 8 + static_cast<std::size_t>(k)] =
            static_cast<char>((h >> (8 * k)) & 0xFF);
    return bytes;
}

/// A recording of the level-3 sphere's model (exact coupling) at `final_tick` with `final_hash`,
/// no force lists.
Recording sphere_recording(std::uint64_t final_tick, std::uint64_t final_hash)
{
    const core::TetraGrid grid = core::TetraGrid::create(3).value();
    Recording rec;
    rec.model = encode_model(
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value(),
        Coupling::Exact);
    rec.final_tick = final_tick;
    rec.final_hash = final_hash;
    return rec;
}

TEST(Recording, FileRoundTripsExactlyAndRefusesCorruption)
{
    const core::TetraGrid grid = core::TetraGrid::create(3).value();
    Recording rec = sphere_recording(1234, 0x0123456789ABCDEFULL);
    rec.forces.push_back(ForceRecord{0, 5, {point_push(0.1, 0.2, 0.9, 0.25, 0.5)}});
    rec.forces.push_back(ForceRecord{3, 77, {face_pull(12, 0.25), face_pull(13, -0.5)}});
    rec.forces.push_back(ForceRecord{3, 90, {}});
    const auto dir = pliant::test::scratch_dir("recording");
    const auto path = dir / "a.prec";
    ASSERT_TRUE(save_recording(path, rec));
    auto back = load_recording(path);
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(back->model, rec.model);
    EXPECT_EQ(back->final_tick, rec.final_tick);
    EXPECT_EQ(back->final_hash, rec.final_hash);
    EXPECT_TRUE(back->hash_mask.empty());
    EXPECT_EQ(back->forces, rec.forces);

    // A hash over part of the nodes keeps its mask; a file of version 1 (no mask: every node)
    // still loads.
    Recording masked = rec;
    ASSERT_EQ(grid.unique_count(), 130U);  // 17 bytes of mask, 2 bits used in the last
    masked.hash_mask.assign(17, 0);
    masked.hash_mask[0] = 0x05;
    masked.hash_mask[16] = 0x02;
    ASSERT_TRUE(save_recording(dir / "masked.prec", masked));
    auto masked_back = load_recording(dir / "masked.prec");
    ASSERT_TRUE(masked_back) << masked_back.error().message;
    EXPECT_EQ(masked_back->hash_mask, masked.hash_mask);
    EXPECT_EQ(masked_back->forces, rec.forces);
    {
        std::vector<char> v1 = read_all(path);
        v1[8] = 1;                                   // version
        v1.erase(v1.begin() + 28, v1.begin() + 32);  // the mask size
        write_all(dir / "v1.prec", resealed(v1));
        auto old = load_recording(dir / "v1.prec");
        ASSERT_TRUE(old) << old.error().message;
        EXPECT_EQ(old->final_hash, rec.final_hash);
        EXPECT_TRUE(old->hash_mask.empty());
        EXPECT_EQ(old->forces, rec.forces);
    }

    const std::vector<char> good = read_all(path);
    auto expect_refused = [&](std::vector<char> bytes, const char* why)
    {
        const auto bad = dir / "bad.prec";
        write_all(bad, bytes);
        auto r = load_recording(bad);
        ASSERT_FALSE(r) << why;
        EXPECT_EQ(r.error().code, core::ErrorCode::ParseError) << why;
        EXPECT_NE(r.error().message.find("bad.prec"), std::string::npos) << r.error().message;
    };
    std::vector<char> flipped = good;
    flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x10);
    expect_refused(flipped, "one flipped bit");
    expect_refused(std::vector<char>(good.begin(), good.end() - 9), "truncated");
    std::vector<char> magic = good;
    magic[0] = 'X';
    expect_refused(magic, "wrong magic");
    expect_refused({}, "empty file");
    EXPECT_EQ(load_recording(dir / "missing.prec").error().code, core::ErrorCode::IoError);
}

// The hash mask holds one bit per canonical node of the model's grid or nothing: a mask of
// another length, one selecting nodes past the grid's, or one selecting none under a non-zero
// hash is refused on the way out and on the way in, naming the byte (before, any mask was taken:
// a mask selecting nothing "verified" any replay, a short one covered only its first nodes). A
// file too short for a header says so, and so do a folder and a device.
TEST(Recording, AHashMaskMustFitTheGridAndSelectANode)
{
    Recording rec = sphere_recording(10, 0x42);
    rec.hash_mask.assign(17, 0);  // 130 canonical nodes at level 3
    rec.hash_mask[3] = 0x10;
    const auto dir = pliant::test::scratch_dir("recording_mask");
    ASSERT_TRUE(save_recording(dir / "good.prec", rec));
    const std::vector<char> good = read_all(dir / "good.prec");
    ASSERT_TRUE(load_recording(dir / "good.prec"));

    const auto refused_on_save =
        [&](std::vector<std::uint8_t> mask, std::uint64_t hash, const std::string& why)
    {
        Recording bad = rec;
        bad.hash_mask = std::move(mask);
        bad.final_hash = hash;
        const auto saved = save_recording(dir / "unsaved.prec", bad);
        ASSERT_FALSE(saved) << why;
        EXPECT_EQ(saved.error().code, core::ErrorCode::InvalidArgument);
        EXPECT_NE(saved.error().message.find(why), std::string::npos) << saved.error().message;
        EXPECT_FALSE(std::filesystem::exists(dir / "unsaved.prec"));
    };
    refused_on_save({0x01}, 0x42,
                    "a hash mask of 1 bytes; the level-3 grid's 130 canonical "
                    "nodes take 17");
    std::vector<std::uint8_t> past(17, 0);
    past[16] = 0x04;  // node 130: there are 130, 0..129
    refused_on_save(past, 0x42, "selects nodes past the grid's 130");
    refused_on_save(std::vector<std::uint8_t>(17, 0), 0x42, "a final hash over no node");
    // Hash 0 is "unknown": a mask is then not checked for a selection.
    Recording unknown = rec;
    unknown.final_hash = 0;
    unknown.hash_mask.assign(17, 0);
    EXPECT_TRUE(save_recording(dir / "unknown.prec", unknown));

    const auto refused_on_load = [&](const std::vector<char>& bytes, const std::string& why)
    {
        write_all(dir / "bad.prec", bytes);
        const auto r = load_recording(dir / "bad.prec");
        ASSERT_FALSE(r) << why;
        EXPECT_EQ(r.error().code, core::ErrorCode::ParseError);
        EXPECT_NE(r.error().message.find(why), std::string::npos) << r.error().message;
    };
    // The mask's 17 bytes begin at byte 32 (after its u32 size at 28): a size is refused at
    // 28, the bits past the last node at the mask's last byte, a mask selecting none at 32.
    std::vector<char> bytes = good;
    bytes[32 + 16] = 0x04;
    refused_on_load(resealed(bytes), "byte 48: a hash mask that selects nodes past");
    bytes = good;
    bytes[32 + 3] = 0;
    refused_on_load(resealed(bytes), "byte 32: a final hash over no node");
    bytes = good;
    bytes[28] = 1;  // a mask of 1 byte: the first of the 17 is kept
    bytes.erase(bytes.begin() + 33, bytes.begin() + 49);
    refused_on_load(resealed(bytes), "byte 28: a hash mask of 1 bytes");

    refused_on_load(std::vector<char>(good.begin(), good.begin() + 10),
                    "truncated: 10 bytes, and no recording is shorter than 44");
    refused_on_load(resealed(std::vector<char>(good.begin(), good.begin() + 16)),
                    "truncated: 16 bytes");
    refused_on_load({'x', 'y'}, "not a pliant recording");

    const auto folder = load_recording(dir);
    ASSERT_FALSE(folder);
    EXPECT_NE(folder.error().message.find("is a folder, not a file"), std::string::npos)
        << folder.error().message;
    std::filesystem::remove(dir / "zero.prec");
    std::filesystem::create_symlink("/dev/zero", dir / "zero.prec");
    const auto device = load_recording(dir / "zero.prec");
    ASSERT_FALSE(device);
    EXPECT_NE(device.error().message.find("is a device, not a file"), std::string::npos)
        << device.error().message;
}

// A recording made by a build of an earlier protocol version (Force's layout is the same since
// version 1) still loads; a force entry of an unknown version does not.
TEST(Recording, ForceEntriesOfEarlierProtocolVersionsStillLoad)
{
    const core::TetraGrid grid = core::TetraGrid::create(3).value();
    auto model =
        sim::MembraneModel::create(grid, scenes::sphere_grid(grid, 1.0), material()).value();
    Recording rec;
    rec.model = encode_model(model, Coupling::Exact);
    rec.final_tick = 10;
    rec.forces.push_back(ForceRecord{0, 5, {point_push(0.1, 0.2, 0.9, 0.25, 0.5)}});
    rec.forces.push_back(ForceRecord{3, 7, {face_pull(12, 0.25)}});
    const auto dir = pliant::test::scratch_dir("recording_versions");
    ASSERT_TRUE(save_recording(dir / "now.prec", rec));
    std::vector<char> bytes = read_all(dir / "now.prec");
    // The force entries: after magic (8), version (4), final tick (8), hash (8), mask size (4,
    // mask empty here), model size (4), the model and the count (4), each a u16 size then the
    // datagram.
    const auto as_version = [&](std::uint8_t version)
    {
        std::vector<char> b = bytes;
        std::size_t at = 8 + 4 + 8 + 8 + 4 + 4 + rec.model.size() + 4;
        for (std::size_t i = 0; i < rec.forces.size(); ++i)
        {
            const std::size_t size =
                static_cast<unsigned char>(b[at]) |
                (static_cast<std::size_t>(static_cast<unsigned char>(b[at + 1])) << 8);
            EXPECT_EQ(static_cast<unsigned char>(b[at + 2 + 4]), net::k_protocol_version);
            b[at + 2 + 4] = static_cast<char>(version);
            at += 2 + size;
        }
        const std::uint64_t h =
            core::hash_bytes(std::as_bytes(std::span<const char>(b.data(), b.size() - 8)));
        for (int k = 0; k < 8; ++k)
            b[b.size() - 8 + static_cast<std::size_t>(k)] =
                static_cast<char>((h >> (8 * k)) & 0xFF);
        const auto path = dir / ("v" + std::to_string(version) + ".prec");
        write_all(path, b);
        return load_recording(path);
    };
    for (std::uint8_t v = 1; v < net::k_protocol_version; ++v)
    {
        auto back = as_version(v);
        ASSERT_TRUE(back) << "version " << int{v} << ": " << back.error().message;
        EXPECT_EQ(back->forces, rec.forces);
    }
    for (const std::uint8_t v :
         {std::uint8_t{0}, static_cast<std::uint8_t>(net::k_protocol_version + 1)})
    {
        auto back = as_version(v);
        ASSERT_FALSE(back);
        EXPECT_NE(back.error().message.find("bad-version"), std::string::npos)
            << back.error().message;
    }
}

TEST(Recording, OnlyTheMasterOfAnExactSessionRecordsFromTheStart)
{
    Harness h;
    Session& master = h.host(3, exact("master"));
    Session& part = h.join(net::Role::Participant, exact("part"));
    EXPECT_FALSE(part.start_recording());
    ASSERT_TRUE(h.pump_until([&] { return master.tick() >= 5; }, 4000));
    EXPECT_FALSE(master.start_recording()) << "a recording starts at rest";
    Harness f;
    SessionSettings fast = exact("fast");
    fast.coupling = Coupling::Fast;
    EXPECT_FALSE(f.host(3, fast).start_recording());
}

}  // namespace
}  // namespace pliant::session::test
