// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/file_io.h>
#include <pliant/core/grid_io.h>
#include <pliant/core/hash.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace pliant::core
{
namespace
{

static_assert(std::endian::native == std::endian::little,
              "grid files are little-endian; add byte swapping for big-endian hosts");

constexpr char k_magic[8] = {'P', 'L', 'I', 'A', 'N', 'T', 'G', '\0'};
constexpr std::uint32_t k_version = 1;
constexpr std::size_t k_name_bytes = 16;
constexpr std::uint32_t k_max_channels = 64;

template <typename T>
void put(std::vector<std::byte>& out, const T& v)
{
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    out.insert(out.end(), p, p + sizeof(T));
}

// A bounds-checked reader over the file's bytes.
class Reader
{
public:
    explicit Reader(std::span<const std::byte> bytes) : bytes_(bytes) {}
    bool read(void* dst, std::size_t n)
    {
        if (n > bytes_.size() - pos_)
            return false;
        std::memcpy(dst, bytes_.data() + pos_, n);
        pos_ += n;
        return true;
    }
    [[nodiscard]] std::size_t pos() const { return pos_; }
    [[nodiscard]] std::size_t remaining() const { return bytes_.size() - pos_; }

private:
    std::span<const std::byte> bytes_;
    std::size_t pos_ = 0;
};

/// "channel 3 ('name')" for messages; bytes outside printable ASCII shown as \xNN, so that a
/// hostile file's name cannot send control sequences to the terminal.
std::string channel_label(std::size_t index, std::string_view name)
{
    std::string out = "channel " + std::to_string(index) + " ('";
    for (const char c : name)
    {
        const auto b = static_cast<unsigned char>(c);
        if (b >= 0x20 && b < 0x7f && c != '\\')
            out += c;
        else
        {
            constexpr char hex[] = "0123456789abcdef";
            out += "\\x";
            out += hex[b >> 4];
            out += hex[b & 15];
        }
    }
    return out + "')";
}

/// The rules of a channel (docs/grid-format.md) that both save_grid and load_grid enforce, so
/// that every file written can be read: a name of 1..15 printable ASCII characters, finite
/// values, twin nodes equal to their canonical nodes: bit for bit when reading (`bitwise`), by
/// value when saving (the writer copies the canonical node's bits onto its twins, so +0 and -0
/// become one). `where` prefixes the message.
Result<void> check_channel(const TetraGrid& grid, std::size_t index, const std::string& name,
                           const Field<double>& values, const std::string& where, bool bitwise)
{
    const bool printable =
        std::all_of(name.begin(), name.end(), [](char c) { return c > 0x20 && c < 0x7f; });
    if (name.empty() || name.size() >= k_name_bytes || !printable)
        return fail(ErrorCode::BadGrid, where + channel_label(index, name) +
                                            ": a name must have 1..15 printable ASCII characters");
    for (std::uint32_t i = 0; i < grid.node_count(); ++i)
        if (!std::isfinite(values[NodeIndex{i}]))
        {
            const GridCoord c = grid.coord(NodeIndex{i});
            return fail(ErrorCode::BadGrid,
                        where + channel_label(index, name) + " has a non-finite value at node (" +
                            std::to_string(c.x) + "," + std::to_string(c.y) + ")");
        }
    for (const TwinPair& t : grid.twins())
        if (bitwise ? std::bit_cast<std::uint64_t>(values[t.twin]) !=
                          std::bit_cast<std::uint64_t>(values[t.canonical])
                    : values[t.twin] != values[t.canonical])
        {
            const GridCoord a = grid.coord(t.twin), b = grid.coord(t.canonical);
            return fail(ErrorCode::BadGrid,
                        where + channel_label(index, name) + ": twin node (" + std::to_string(a.x) +
                            "," + std::to_string(a.y) + ") differs from its canonical node (" +
                            std::to_string(b.x) + "," + std::to_string(b.y) + ")" +
                            (bitwise ? " (twins hold bit-identical values)" : ""));
        }
    return {};
}

}  // namespace

const Field<double>* GridFile::find(std::string_view name) const noexcept
{
    for (const NamedField& f : fields)
        if (f.name == name)
            return &f.values;
    return nullptr;
}

Result<std::vector<std::byte>> encode_grid(const GridFile& file, const std::string& source)
{
    auto grid = TetraGrid::create(file.level);
    if (!grid)
        return grid.error();
    std::vector<std::byte> out;
    out.insert(out.end(), reinterpret_cast<const std::byte*>(k_magic),
               reinterpret_cast<const std::byte*>(k_magic) + sizeof(k_magic));
    put(out, k_version);
    put(out, static_cast<std::uint32_t>(file.level));
    if (file.fields.size() > k_max_channels)
        return fail(ErrorCode::InvalidArgument, source + ": " + std::to_string(file.fields.size()) +
                                                    " channels; a grid file holds at most " +
                                                    std::to_string(k_max_channels));
    put(out, static_cast<std::uint32_t>(file.fields.size()));
    std::vector<double> plane(grid->node_count());
    for (std::size_t i = 0; i < file.fields.size(); ++i)
    {
        const NamedField& f = file.fields[i];
        if (f.values.level() != file.level)
            return fail(ErrorCode::InvalidArgument,
                        source + ": " + channel_label(i, f.name) + " is of level " +
                            std::to_string(f.values.level()) + ", the file of level " +
                            std::to_string(file.level));
        if (auto ok = check_channel(*grid, i, f.name, f.values, source + ": ", false); !ok)
            return fail(ErrorCode::InvalidArgument, ok.error().message);
        if (file.find(f.name) != &f.values)
            return fail(ErrorCode::InvalidArgument,
                        source + ": " + channel_label(i, f.name) + ": the name appears twice");
        char name[k_name_bytes] = {};
        std::memcpy(name, f.name.data(), f.name.size());
        out.insert(out.end(), reinterpret_cast<const std::byte*>(name),
                   reinterpret_cast<const std::byte*>(name) + k_name_bytes);
        f.values.copy_to(plane);
        for (const TwinPair& t : grid->twins())
            plane[t.twin.value] = plane[t.canonical.value];
        const auto bytes = std::as_bytes(std::span<const double>(plane));
        out.insert(out.end(), bytes.begin(), bytes.end());
    }
    put(out, hash_bytes(out));
    return out;
}

Result<void> save_grid(const std::filesystem::path& path, const GridFile& file)
{
    auto out = encode_grid(file, path.string());
    if (!out)
        return out.error();
    return write_file(path, *out, "");
}

Result<GridFile> decode_grid(std::span<const std::byte> bytes, const std::string& source)
{
    const std::string where = source + ": ";
    if (bytes.size() < sizeof(k_magic) + 12 + 8)
        return fail(ErrorCode::ParseError, where + "too short for a pliant grid file (" +
                                               std::to_string(bytes.size()) + " bytes)");
    if (std::memcmp(bytes.data(), k_magic, sizeof(k_magic)) != 0)
        return fail(ErrorCode::ParseError, where + "not a pliant grid file (bad magic)");
    std::uint64_t stored = 0;
    std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
    if (stored != hash_bytes(bytes.first(bytes.size() - 8)))
        return fail(ErrorCode::ParseError, where + "checksum mismatch (truncated or corrupted)");

    Reader r(bytes.first(bytes.size() - 8));
    char magic[8];
    std::uint32_t version = 0, level = 0, channels = 0;
    (void)r.read(magic, 8);
    (void)r.read(&version, 4);
    (void)r.read(&level, 4);
    (void)r.read(&channels, 4);
    if (version != k_version)
        return fail(ErrorCode::ParseError,
                    where + "version " + std::to_string(version) + ", this pliant reads version 1");
    auto grid = TetraGrid::create(static_cast<int>(level));
    if (!grid)
        return fail(ErrorCode::BadGrid,
                    where + "level " + std::to_string(level) + " is outside 1..10");
    const std::size_t plane_bytes = grid->node_count() * sizeof(double);
    if (channels > k_max_channels)
        return fail(ErrorCode::ParseError, where + std::to_string(channels) +
                                               " channels; a grid file holds at most " +
                                               std::to_string(k_max_channels));
    // Sizes of the whole file: header, channels, checksum.
    const std::size_t header_bytes = sizeof(k_magic) + 12;
    const std::size_t expected = header_bytes + channels * (k_name_bytes + plane_bytes) + 8;
    if (bytes.size() != expected)
        return fail(ErrorCode::ParseError, where + std::to_string(channels) + " channel" +
                                               (channels == 1 ? "" : "s") + " of level " +
                                               std::to_string(level) + " make a file of " +
                                               std::to_string(expected) + " bytes; this one has " +
                                               std::to_string(bytes.size()));
    GridFile file;
    file.level = static_cast<int>(level);
    std::vector<double> plane(grid->node_count());
    for (std::uint32_t c = 0; c < channels; ++c)
    {
        char name[k_name_bytes + 1] = {};
        (void)r.read(name, k_name_bytes);
        (void)r.read(plane.data(), plane_bytes);
        NamedField f{std::string(name), Field<double>(*grid)};
        // NUL-padded: a byte after the name's end that is not NUL is not a name this writes.
        if (std::any_of(name + f.name.size(), name + k_name_bytes, [](char ch) { return ch != 0; }))
            return fail(ErrorCode::BadGrid,
                        where + channel_label(c, std::string_view(name, k_name_bytes)) +
                            ": its name field is not padded with NUL bytes");
        f.values.copy_from(plane);
        if (auto ok = check_channel(*grid, c, f.name, f.values, where, true); !ok)
            return ok.error();
        for (const NamedField& other : file.fields)
            if (other.name == f.name)
                return fail(ErrorCode::BadGrid,
                            where + channel_label(c, f.name) + ": the name appears twice");
        file.fields.push_back(std::move(f));
    }
    return file;
}

Result<GridFile> load_grid(const std::filesystem::path& path)
{
    // The largest file: 64 channels of level 10 (a FIFO fed for ever stops there).
    static_assert(k_max_level == 10);
    constexpr std::size_t k_level10_nodes = (2 * 1024 + 1) * (1024 + 1);
    constexpr std::size_t k_max_file =
        sizeof(k_magic) + 12 + k_max_channels * (k_name_bytes + 8 * k_level10_nodes) + 8;
    auto bytes = read_input_file(path, k_max_file, "grid file");
    if (!bytes)
        return bytes.error();
    return decode_grid(*bytes, path.string());
}

GridFile make_geometry_file(const TetraGrid& grid, const Vec3Field<double>& positions)
{
    GridFile file;
    file.level = grid.level();
    const char* names[3] = {"px", "py", "pz"};
    for (int k = 0; k < 3; ++k)
    {
        Field<double> f(grid);
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
                f.at(x, y) = positions[static_cast<std::size_t>(k)].at(x, y);
        file.fields.push_back(NamedField{names[k], std::move(f)});
    }
    return file;
}

Result<Vec3Field<double>> geometry_of(const TetraGrid& grid, const GridFile& file, int ghost)
{
    if (file.level != grid.level())
        return fail(ErrorCode::BadGrid, "geometry_of: file of level " + std::to_string(file.level) +
                                            ", grid of level " + std::to_string(grid.level()));
    Vec3Field<double> out;
    const char* names[3] = {"px", "py", "pz"};
    for (int k = 0; k < 3; ++k)
    {
        const Field<double>* src = file.find(names[k]);
        if (src == nullptr)
            return fail(ErrorCode::BadGrid,
                        std::string("geometry_of: the grid file has no channel '") + names[k] +
                            "' (not a geometry file)");
        Field<double> f(grid, ghost);
        for (int y = 0; y < grid.ny(); ++y)
            for (int x = 0; x < grid.nx(); ++x)
                f.at(x, y) = src->at(x, y);
        fill_ghosts(grid, f);
        out[static_cast<std::size_t>(k)] = std::move(f);
    }
    return out;
}

Result<void> save_pfm(const std::filesystem::path& path, const Vec3Field<double>& positions)
{
    const int nx = positions[0].nx(), ny = positions[0].ny();
    // negative scale: little-endian
    const std::string head = "PF\n" + std::to_string(nx) + " " + std::to_string(ny) + "\n-1.0\n";
    std::vector<std::byte> out(reinterpret_cast<const std::byte*>(head.data()),
                               reinterpret_cast<const std::byte*>(head.data()) + head.size());
    out.reserve(head.size() + static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * 12U);
    // PFM rows run bottom to top, which is the grid's y order.
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            for (int k = 0; k < 3; ++k)
            {
                const auto v = static_cast<float>(positions[static_cast<std::size_t>(k)].at(x, y));
                const auto* b = reinterpret_cast<const std::byte*>(&v);
                out.insert(out.end(), b, b + sizeof v);
            }
    return write_file(path, out, "");
}

}  // namespace pliant::core
