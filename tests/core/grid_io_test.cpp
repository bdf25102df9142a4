// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/grid_io.h>
#include <pliant/core/hash.h>

#include <gtest/gtest.h>

#include "support/test_paths.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace pliant::core
{
namespace
{

Vec3Field<double> some_positions(const TetraGrid& g)
{
    Vec3Field<double> p{Field<double>(g), Field<double>(g), Field<double>(g)};
    for (int y = 0; y < g.ny(); ++y)
        for (int x = 0; x < g.nx(); ++x)
        {
            const NodeIndex c = g.canonical(g.index(x, y));
            const double t = static_cast<double>(c.value);
            p[0].at(x, y) = std::sin(t) / 3.0;  // values that are not exact in float
            p[1].at(x, y) = std::cos(t) * 1e-7;
            p[2].at(x, y) = t * 1.1;
        }
    return p;
}

TEST(GridIo, RoundTripIsBitExact)
{
    const auto dir = test::scratch_dir("grid_io_round_trip");
    const TetraGrid g = TetraGrid::create(5).value();
    const GridFile out = make_geometry_file(g, some_positions(g));
    ASSERT_TRUE(save_grid(dir / "a.pgrid", out).has_value());
    auto in = load_grid(dir / "a.pgrid");
    ASSERT_TRUE(in.has_value()) << in.error().message;
    ASSERT_EQ(in->level, 5);
    ASSERT_EQ(in->fields.size(), 3U);
    for (std::size_t k = 0; k < 3; ++k)
    {
        EXPECT_EQ(in->fields[k].name, out.fields[k].name);
        EXPECT_TRUE(in->fields[k].values == out.fields[k].values);  // bit for bit
    }
    auto geo = geometry_of(g, *in, 2);
    ASSERT_TRUE(geo.has_value());
    EXPECT_EQ((*geo)[2].at(-1, -1), (*geo)[2][g.image(-1, -1)]);
}

TEST(GridIo, RefusesCorruptTruncatedAndForeignFiles)
{
    const auto dir = test::scratch_dir("grid_io_bad");
    const TetraGrid g = TetraGrid::create(2).value();
    ASSERT_TRUE(save_grid(dir / "good.pgrid", make_geometry_file(g, some_positions(g))));
    std::ifstream is(dir / "good.pgrid", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());

    auto write = [&](const char* name, const std::string& content)
    {
        std::ofstream os(dir / name, std::ios::binary);
        os << content;
        return dir / name;
    };
    auto truncated = load_grid(write("trunc.pgrid", bytes.substr(0, bytes.size() / 2)));
    ASSERT_FALSE(truncated.has_value());
    EXPECT_EQ(truncated.error().code, ErrorCode::ParseError);

    std::string flipped = bytes;
    flipped[100] = static_cast<char>(flipped[100] ^ 0x10);
    auto corrupt = load_grid(write("flip.pgrid", flipped));
    ASSERT_FALSE(corrupt.has_value());
    EXPECT_NE(corrupt.error().message.find("checksum"), std::string::npos);

    auto foreign = load_grid(write("foreign.pgrid", "P3\n2 2\n255\n0 0 0 0 0 0 0 0 0 0 0 0\n"));
    ASSERT_FALSE(foreign.has_value());
    EXPECT_NE(foreign.error().message.find("foreign.pgrid"), std::string::npos);

    auto missing = load_grid(dir / "missing.pgrid");
    ASSERT_FALSE(missing.has_value());
    EXPECT_EQ(missing.error().code, ErrorCode::IoError);

    // A directory opens as a stream and used to throw from the first read.
    std::filesystem::create_directories(dir / "folder.pgrid");
    auto folder = load_grid(dir / "folder.pgrid");
    ASSERT_FALSE(folder.has_value());
    EXPECT_EQ(folder.error().code, ErrorCode::IoError);
    EXPECT_NE(folder.error().message.find("folder.pgrid: is a folder, not a file"),
              std::string::npos)
        << folder.error().message;
}

TEST(GridIo, RefusesTwinsThatDiffer)
{
    const auto dir = test::scratch_dir("grid_io_twins");
    const TetraGrid g = TetraGrid::create(2).value();
    auto p = some_positions(g);
    // save_grid writes only what load_grid reads: a twin that no longer equals its canonical
    // node is refused on the way out.
    auto bad = p;
    bad[0].at(2 * g.w(), 1) += 1.0;
    auto saved = save_grid(dir / "bad.pgrid", make_geometry_file(g, bad));
    ASSERT_FALSE(saved);
    EXPECT_EQ(saved.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(saved.error().message.find("twin"), std::string::npos) << saved.error().message;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.pgrid"));

    // The same change made in a file's bytes (checksum recomputed) is refused on the way in.
    ASSERT_TRUE(save_grid(dir / "t.pgrid", make_geometry_file(g, p)));
    std::vector<char> raw;
    {
        std::ifstream is(dir / "t.pgrid", std::ios::binary);
        raw.assign(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
    }
    // Header 20 bytes, then channel px: a 16-byte name and the plane.
    const std::size_t at = 20 + 16 + 8 * static_cast<std::size_t>(g.index(2 * g.w(), 1).value);
    double v = 0.0;
    std::memcpy(&v, raw.data() + at, 8);
    v += 1.0;
    std::memcpy(raw.data() + at, &v, 8);
    const std::uint64_t h =
        hash_bytes(std::as_bytes(std::span<const char>(raw.data(), raw.size() - 8)));
    std::memcpy(raw.data() + raw.size() - 8, &h, 8);
    std::ofstream(dir / "t.pgrid", std::ios::binary | std::ios::trunc)
        .write(raw.data(), static_cast<std::streamsize>(raw.size()));
    auto in = load_grid(dir / "t.pgrid");
    ASSERT_FALSE(in.has_value());
    EXPECT_EQ(in.error().code, ErrorCode::BadGrid);
    EXPECT_NE(in.error().message.find("twin"), std::string::npos) << in.error().message;
}

// A non-finite value is refused both ways, and the message names the node by its grid
// coordinates (x,y), as the twin messages do (it gave a flat index).
TEST(GridIo, NonFiniteValuesAreRefusedNamingTheNode)
{
    const auto dir = test::scratch_dir("grid_io_non_finite");
    const TetraGrid g = TetraGrid::create(2).value();
    auto bad = some_positions(g);
    bad[1].at(3, 1) = std::numeric_limits<double>::quiet_NaN();
    auto saved = save_grid(dir / "bad.pgrid", make_geometry_file(g, bad));
    ASSERT_FALSE(saved);
    EXPECT_EQ(saved.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(saved.error().message.find("channel 1 ('py') has a non-finite value at node (3,1)"),
              std::string::npos)
        << saved.error().message;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.pgrid"));
}

// +0 and -0 compare equal but are different bits: the writer stores the canonical node's bits
// on its twins, and the reader wants them bit for bit (docs/grid-format.md).
TEST(GridIo, TwinsOfOppositeZeroSignsAreWrittenAsOneAndRefusedInAFile)
{
    const auto dir = test::scratch_dir("grid_io_zero_twins");
    const TetraGrid g = TetraGrid::create(2).value();
    auto p = some_positions(g);
    const GridCoord twin = g.coord(g.twins().front().twin);
    const GridCoord canonical = g.coord(g.twins().front().canonical);
    p[1].at(canonical.x, canonical.y) = 0.0;
    p[1].at(twin.x, twin.y) = -0.0;
    ASSERT_TRUE(save_grid(dir / "z.pgrid", make_geometry_file(g, p)));
    auto in = load_grid(dir / "z.pgrid");
    ASSERT_TRUE(in) << in.error().message;
    EXPECT_FALSE(std::signbit(in->find("py")->at(twin.x, twin.y)));

    // The same -0 put into the file's bytes (checksum recomputed) is refused.
    std::vector<char> raw;
    {
        std::ifstream is(dir / "z.pgrid", std::ios::binary);
        raw.assign(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
    }
    const std::size_t plane = 16 + 8 * static_cast<std::size_t>(g.node_count());
    const std::size_t at =
        20 + plane + 16 + 8 * static_cast<std::size_t>(g.index(twin.x, twin.y).value);
    const double minus_zero = -0.0;
    std::memcpy(raw.data() + at, &minus_zero, 8);
    const std::uint64_t h =
        hash_bytes(std::as_bytes(std::span<const char>(raw.data(), raw.size() - 8)));
    std::memcpy(raw.data() + raw.size() - 8, &h, 8);
    auto bad = decode_grid(std::as_bytes(std::span<const char>(raw)), "z.pgrid");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("bit-identical"), std::string::npos) << bad.error().message;
}

// Sizes are told as whole files; a channel count beyond 64 says that rule.
TEST(GridIo, SizeMessagesCountTheWholeFile)
{
    const TetraGrid g = TetraGrid::create(1).value();
    auto bytes = encode_grid(make_geometry_file(g, some_positions(g)), "s.pgrid").value();
    const auto with_channels = [&](std::uint32_t channels, std::size_t extra)
    {
        std::vector<std::byte> b = bytes;
        std::memcpy(b.data() + 16, &channels, 4);
        b.insert(b.end() - 8, extra, std::byte{0});
        const std::uint64_t h = hash_bytes(std::span<const std::byte>(b).first(b.size() - 8));
        std::memcpy(b.data() + b.size() - 8, &h, 8);
        return decode_grid(b, "s.pgrid");
    };
    auto many = with_channels(65, 0);
    ASSERT_FALSE(many);
    EXPECT_NE(many.error().message.find("65 channels; a grid file holds at most 64"),
              std::string::npos)
        << many.error().message;
    auto extra = with_channels(3, 8);
    ASSERT_FALSE(extra);
    EXPECT_NE(
        extra.error().message.find("make a file of " + std::to_string(bytes.size()) +
                                   " bytes; this one has " + std::to_string(bytes.size() + 8)),
        std::string::npos)
        << extra.error().message;
}

TEST(GridIo, ChannelNamesFollowTheFormatBothWays)
{
    const auto dir = test::scratch_dir("grid_io_names");
    const TetraGrid g = TetraGrid::create(2).value();
    GridFile file = make_geometry_file(g, some_positions(g));
    file.fields.push_back({"", Field<double>(g)});
    EXPECT_FALSE(save_grid(dir / "e.pgrid", file));
    file.fields.back().name = "sixteen_chars_xx";
    EXPECT_FALSE(save_grid(dir / "l.pgrid", file));
    file.fields.back().name = "fifteen_chars_x";
    ASSERT_TRUE(save_grid(dir / "ok.pgrid", file));
    EXPECT_TRUE(load_grid(dir / "ok.pgrid"));
}

// The bytes API that save_grid and load_grid wrap: decode_grid(encode_grid(f)) is f, and the
// encoding of what it read is the same bytes (the format is canonical); `source` names the
// input in every message.
TEST(GridIo, BytesRoundTripAndTheEncodingIsCanonical)
{
    const TetraGrid g = TetraGrid::create(3).value();
    GridFile file = make_geometry_file(g, some_positions(g));
    file.fields.push_back({"u", file.fields[0].values});
    const auto bytes = encode_grid(file, "mem");
    ASSERT_TRUE(bytes) << bytes.error().message;
    const auto back = decode_grid(*bytes, "mem");
    ASSERT_TRUE(back) << back.error().message;
    ASSERT_EQ(back->fields.size(), 4U);
    EXPECT_EQ(back->fields[3].name, "u");
    EXPECT_TRUE(back->fields[3].values == file.fields[3].values);
    EXPECT_EQ(encode_grid(*back, "mem").value(), *bytes);
    auto cut = *bytes;
    cut.pop_back();
    const auto refused = decode_grid(cut, "the welcome");
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().message.rfind("the welcome: ", 0), 0U) << refused.error().message;
}

// A name field holds the name, then NUL bytes only; a name appears once. Both rules hold on
// the way out and on the way in (bytes changed, checksum recomputed), so that every file read
// encodes back to its own bytes.
TEST(GridIo, NamesArePaddedWithNulAndDistinct)
{
    const TetraGrid g = TetraGrid::create(2).value();
    GridFile file = make_geometry_file(g, some_positions(g));
    const auto reseal = [](std::vector<std::byte> bytes)
    {
        const std::uint64_t h = hash_bytes(std::span(bytes).first(bytes.size() - 8));
        std::memcpy(bytes.data() + bytes.size() - 8, &h, 8);
        return bytes;
    };
    const auto good = encode_grid(file, "mem").value();
    // Header 20 bytes; channel px's name field is bytes 20..35: "px", then 14 NULs.
    auto padded = good;
    padded[20 + 5] = std::byte{'z'};
    const auto junk = decode_grid(reseal(padded), "mem");
    ASSERT_FALSE(junk);
    EXPECT_EQ(junk.error().code, ErrorCode::BadGrid);
    EXPECT_NE(junk.error().message.find("not padded with NUL"), std::string::npos)
        << junk.error().message;

    const std::size_t plane = 16 + 8 * g.node_count();
    auto twice = good;
    std::memcpy(twice.data() + 20 + plane, "px", 2);  // py's name becomes "px"
    const auto repeated = decode_grid(reseal(twice), "mem");
    ASSERT_FALSE(repeated);
    EXPECT_EQ(repeated.error().code, ErrorCode::BadGrid);
    EXPECT_NE(repeated.error().message.find("channel 1 ('px'): the name appears twice"),
              std::string::npos)
        << repeated.error().message;

    file.fields[1].name = "px";
    const auto out = encode_grid(file, "mem");
    ASSERT_FALSE(out);
    EXPECT_EQ(out.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(out.error().message.find("appears twice"), std::string::npos);

    // A name with a control byte (ESC [ 2 J clears a terminal) is refused with the byte shown
    // as \x1b, naming the channel's index.
    auto escape = good;
    std::memcpy(escape.data() + 20 + plane, "p\x1b[2J", 5);
    const auto hostile = decode_grid(reseal(escape), "mem");
    ASSERT_FALSE(hostile);
    EXPECT_EQ(hostile.error().code, ErrorCode::BadGrid);
    EXPECT_NE(hostile.error().message.find("channel 1 ('p\\x1b[2J')"), std::string::npos)
        << hostile.error().message;
    EXPECT_EQ(hostile.error().message.find('\x1b'), std::string::npos) << hostile.error().message;
}

// The writer refuses what the reader refuses: more than 64 channels (encode_grid wrote them and
// decode_grid refused its own output).
TEST(GridIo, MoreThan64ChannelsAreRefusedOnTheWayOutAsOnTheWayIn)
{
    const TetraGrid g = TetraGrid::create(1).value();
    GridFile file;
    file.level = 1;
    for (int c = 0; c < 64; ++c)
        file.fields.push_back({"c" + std::to_string(c), Field<double>(g)});
    const auto bytes = encode_grid(file, "mem");
    ASSERT_TRUE(bytes) << bytes.error().message;
    EXPECT_TRUE(decode_grid(*bytes, "mem"));
    file.fields.push_back({"c64", Field<double>(g)});
    const auto refused = encode_grid(file, "mem");
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(refused.error().message.find("65 channels; a grid file holds at most 64"),
              std::string::npos)
        << refused.error().message;
}

// A device is refused before any read (/dev/zero has no end: load_grid read it until memory ran
// out).
TEST(GridIo, ADeviceIsRefusedWithoutReading)
{
    const auto dir = test::scratch_dir("grid_io_device");
    const auto zero = dir / "zero.pgrid";
    std::filesystem::remove(zero);
    std::filesystem::create_symlink("/dev/zero", zero);
    const auto device = load_grid(zero);
    ASSERT_FALSE(device);
    EXPECT_EQ(device.error().code, ErrorCode::IoError);
    EXPECT_NE(device.error().message.find("is a device, not a file"), std::string::npos)
        << device.error().message;
}

}  // namespace
}  // namespace pliant::core
