// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <nlohmann/json.hpp>

#include "mesh/format_scan_internal.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <vector>

namespace pliant::mesh::detail
{

namespace
{

using core::ErrorCode;
using core::fail;

/// The most vertices a face may have in Assimp 5.2's OFF reader; it skips larger ones.
constexpr std::size_t k_off_reader_max_corners = 9;

/// The UTF-8 byte-order mark.
constexpr std::string_view k_utf8_bom = "\xEF\xBB\xBF";

std::string plural(std::size_t n, const char* word)
{
    if (std::string_view(word) == "vertex")
        return std::to_string(n) + (n == 1 ? " vertex" : " vertices");
    return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

/// Splits `text` into lines (without the terminator) and calls `f(line)` for each; stops early
/// when `f` returns false.
template <typename F>
void for_each_line(std::string_view text, F&& f)
{
    std::size_t start = 0;
    while (start < text.size())
    {
        std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos)
            end = text.size();
        std::string_view line = text.substr(start, end - start);
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        if (!f(line))
            return;
        start = end + 1;
    }
}

std::string_view trim(std::string_view s)
{
    const auto is_space = [](char c)
    { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; };
    while (!s.empty() && is_space(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && is_space(s.back()))
        s.remove_suffix(1);
    return s;
}

/// Whitespace-separated tokens of one line.
std::vector<std::string_view> tokens(std::string_view line)
{
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size())
    {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t')
            ++i;
        if (i > start)
            out.push_back(line.substr(start, i - start));
    }
    return out;
}

std::optional<std::size_t> parse_count(std::string_view s)
{
    std::size_t v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc{} || ptr != s.data() + s.size())
        return std::nullopt;
    return v;
}

/// A coordinate as the text readers take it: a decimal or exponent number, "nan" or "inf"
/// (refused later with their face), an optional leading sign.
bool is_number(std::string_view s)
{
    if (!s.empty() && s.front() == '+')
        s.remove_prefix(1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && ptr == s.data() + s.size() &&
           (ec == std::errc{} || ec == std::errc::result_out_of_range);
}

std::optional<long long> parse_integer(std::string_view s)
{
    if (!s.empty() && s.front() == '+')
        s.remove_prefix(1);
    long long v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc{} || ptr != s.data() + s.size())
        return std::nullopt;
    return v;
}

std::string quoted(std::string_view s)
{
    return "'" + std::string(s.substr(0, 40)) + (s.size() > 40 ? "...'" : "'");
}

/// A text format must not contain control bytes other than white space: the usual sign of a
/// binary or random file handed to a text reader.
core::Result<void> check_text(std::string_view bytes, const std::string& name, const char* what)
{
    for (std::size_t i = 0; i < bytes.size(); ++i)
    {
        const auto c = static_cast<unsigned char>(bytes[i]);
        const bool space = c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
        if ((c < 0x20 && !space) || c == 0x7f)
        {
            std::array<char, 8> hex{};
            const auto r = std::to_chars(hex.data(), hex.data() + hex.size(), c, 16);
            return fail(ErrorCode::ParseError,
                        name + ": not a text " + what + " file: control byte 0x" +
                            std::string(hex.data(), r.ptr) + " at offset " + std::to_string(i));
        }
    }
    return {};
}

bool only_space(std::string_view bytes)
{
    return std::all_of(bytes.begin(), bytes.end(),
                       [](char c)
                       { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; });
}

core::Result<ScanResult> scan_obj(std::string_view bytes, const std::string& name)
{
    if (auto text = check_text(bytes, name, "OBJ"); !text)
        return text.error();
    ScanResult r{.format = Format::Obj};
    // A UTF-8 byte-order mark (some Windows editors write one) is not part of the first line.
    // Assimp's OBJ reader does not skip it and so drops that line: it reads the copy without it.
    if (bytes.starts_with(k_utf8_bom))
    {
        bytes.remove_prefix(k_utf8_bom.size());
        r.rewritten = std::string(bytes);
    }
    std::size_t lines = 0;
    // Which `v` records faces use (1-based, negative = relative), for the report.
    std::vector<bool> used;
    // Assimp's OBJ reader says "vertex index out of range" for a bad index and for a bad
    // coordinate alike, without a line; so both are checked here, each with its line. A positive
    // index may refer to a `v` record further down (readers resolve them at the end), so the
    // largest one is checked once every record is counted.
    std::optional<core::Error> error;
    std::size_t max_index = 0;
    std::size_t max_index_line = 0;
    std::vector<std::size_t> forward;  // 0-based indices of records not read yet at their face
    const auto refuse = [&](ErrorCode code, std::string what)
    {
        error = core::Error{code, name + ":" + std::to_string(lines) + ": " + std::move(what)};
        return false;
    };
    for_each_line(
        bytes,
        [&](std::string_view line)
        {
            ++lines;
            line = trim(line);
            if (line.size() < 2 || (line[1] != ' ' && line[1] != '\t'))
                return true;
            if (line[0] == 'v')
            {
                ++r.vertices;
                used.push_back(false);
                const std::vector<std::string_view> t = tokens(line.substr(1));
                if (t.size() < 3)
                    return refuse(ErrorCode::ParseError,
                                  "vertex record " + std::to_string(r.vertices) + " has " +
                                      plural(t.size(), "coordinate") + ", expected x y z");
                for (std::size_t k = 0; k < 3; ++k)
                    if (!is_number(t[k]))
                        return refuse(ErrorCode::ParseError,
                                      "vertex record " + std::to_string(r.vertices) +
                                          ": coordinate " + quoted(t[k]) + " is not a number");
            }
            else if (line[0] == 'f')
            {
                ++r.faces;
                const std::vector<std::string_view> t = tokens(line.substr(1));
                if (t.size() < 3)
                    return refuse(ErrorCode::BadIndex, "face " + std::to_string(r.faces - 1) +
                                                           " has " + plural(t.size(), "corner") +
                                                           ", a face needs at least 3");
                const long long n = static_cast<long long>(used.size());
                for (std::string_view corner : t)
                {
                    const std::string_view v = corner.substr(0, corner.find('/'));
                    const auto index = parse_integer(v);
                    if (!index || *index == 0)
                        return refuse(ErrorCode::BadIndex,
                                      "face " + std::to_string(r.faces - 1) + ": corner " +
                                          quoted(corner) +
                                          " is not a vertex index (1-based, or negative to "
                                          "count back from the last vertex)");
                    if (*index < 0 && -*index > n)
                        return refuse(ErrorCode::BadIndex,
                                      "face " + std::to_string(r.faces - 1) + ": relative index " +
                                          std::to_string(*index) +
                                          " reaches before the first vertex (" +
                                          plural(used.size(), "vertex") + " so far)");
                    if (*index > 0 && static_cast<unsigned long long>(*index) > max_index)
                    {
                        max_index = static_cast<std::size_t>(*index);
                        max_index_line = lines;
                    }
                    const long long k = *index < 0 ? n + *index : *index - 1;
                    if (k < n)
                        used[static_cast<std::size_t>(k)] = true;
                    else  // a `v` record further down, marked once all are counted
                        forward.push_back(static_cast<std::size_t>(k));
                }
            }
            return true;
        });
    if (error)
        return *error;
    if (max_index > r.vertices)
        return fail(ErrorCode::BadIndex, name + ":" + std::to_string(max_index_line) +
                                             ": face refers to vertex " +
                                             std::to_string(max_index) + " but the file has " +
                                             plural(r.vertices, "vertex"));
    for (const std::size_t k : forward)  // every k < r.vertices: checked above
        used[k] = true;
    r.unreferenced = static_cast<std::size_t>(std::count(used.begin(), used.end(), false));
    r.faces_known = true;
    if (r.faces == 0)
        return fail(ErrorCode::EmptyInput, name + ": no faces: no 'f' line in " +
                                               plural(lines, "line") + " (" +
                                               plural(r.vertices, "vertex line") + ")");
    return r;
}

core::Result<ScanResult> scan_off(std::string_view bytes, const std::string& name)
{
    if (auto text = check_text(bytes, name, "OFF"); !text)
        return text.error();
    // Content lines with their line numbers: comments (# to end of line) and blank lines removed.
    struct Line
    {
        std::size_t number;
        std::string_view text;
    };
    std::vector<Line> content;
    std::size_t number = 0;
    for_each_line(bytes,
                  [&](std::string_view line)
                  {
                      ++number;
                      const std::size_t hash = line.find('#');
                      if (hash != std::string_view::npos)
                          line = line.substr(0, hash);
                      line = trim(line);
                      if (!line.empty())
                          content.push_back({number, line});
                      return true;
                  });
    if (content.empty())
        return fail(ErrorCode::EmptyInput, name + ": empty OFF file (no content lines)");
    std::vector<std::string_view> head = tokens(content[0].text);
    const std::string_view key = head.empty() ? std::string_view{} : head[0];
    if (key.size() < 3 || key.substr(key.size() - 3) != "OFF")
        return fail(ErrorCode::ParseError, name + ": not an OFF file: first line is '" +
                                               std::string(content[0].text.substr(0, 40)) +
                                               "', expected 'OFF'");
    std::size_t next = 1;
    head.erase(head.begin());
    if (head.empty() && content.size() > 1)
        head = tokens(content[next++].text);
    if (head.size() < 2)
        return fail(ErrorCode::ParseError,
                    name + ": bad OFF header: expected 'vertices faces edges' counts");
    const auto v = parse_count(head[0]);
    const auto f = parse_count(head[1]);
    if (!v || !f)
        return fail(ErrorCode::ParseError, name + ": bad OFF header: counts '" +
                                               std::string(head[0]) + " " + std::string(head[1]) +
                                               "' are not non-negative integers");
    ScanResult r{.format = Format::Off, .vertices = *v, .faces = *f, .faces_known = true};
    if (*f == 0)
        return fail(ErrorCode::EmptyInput, name + ": no faces: the OFF header declares " +
                                               plural(*v, "vertex") + " and 0 faces");
    const std::size_t data_lines = content.size() - next;
    // Overflow-safe: each count alone is compared first.
    if (*v > data_lines || *f > data_lines || *v + *f > data_lines)
        return fail(ErrorCode::ParseError, name + ": truncated OFF file: the header declares " +
                                               plural(*v, "vertex") + " and " + plural(*f, "face") +
                                               " but only " + plural(data_lines, "data line") +
                                               " follow");
    // Every record is read here: Assimp's OFF reader replaces an out-of-range index with the last
    // vertex, reads a missing or non-numeric index as 0 and skips faces of more than 9 vertices,
    // all silently.
    const auto at = [&](const Line& line)
    { return name + ":" + std::to_string(line.number) + ": "; };
    for (std::size_t i = 0; i < *v; ++i)
    {
        const Line& line = content[next + i];
        const std::vector<std::string_view> t = tokens(line.text);
        if (t.size() < 3)
            return fail(ErrorCode::ParseError, at(line) + "vertex " + std::to_string(i) + " has " +
                                                   plural(t.size(), "coordinate") +
                                                   ", expected x y z");
        for (std::size_t k = 0; k < 3; ++k)
            if (!is_number(t[k]))
                return fail(ErrorCode::ParseError, at(line) + "vertex " + std::to_string(i) +
                                                       ": coordinate " + quoted(t[k]) +
                                                       " is not a number");
    }
    bool large = false;
    for (std::size_t i = 0; i < *f; ++i)
    {
        const Line& line = content[next + *v + i];
        const std::vector<std::string_view> t = tokens(line.text);
        const auto count = parse_integer(t[0]);
        if (!count || *count < 3)
            return fail(ErrorCode::BadIndex, at(line) + "face " + std::to_string(i) +
                                                 ": vertex count " + quoted(t[0]) +
                                                 " is not an integer of at least 3");
        const auto n = static_cast<std::size_t>(*count);
        if (t.size() - 1 < n)
            return fail(ErrorCode::BadIndex, at(line) + "face " + std::to_string(i) + " declares " +
                                                 plural(n, "vertex") + " but lists " +
                                                 std::to_string(t.size() - 1));
        for (std::size_t k = 1; k <= n; ++k)
        {
            const auto index = parse_integer(t[k]);
            if (!index || *index < 0 || static_cast<unsigned long long>(*index) >= *v)
                return fail(ErrorCode::BadIndex, at(line) + "face " + std::to_string(i) +
                                                     ": index " + quoted(t[k]) +
                                                     " is not a vertex (0-based, the file has " +
                                                     plural(*v, "vertex") + ")");
        }
        large = large || n > k_off_reader_max_corners;
    }
    if (!large)
        return r;
    // Faces of more than 9 vertices: fan-split into triangles (0, i, i+1), as the import does with
    // every polygon, in a copy of the file that Assimp reads instead.
    std::string faces;
    std::size_t face_count = 0;
    for (std::size_t i = 0; i < *f; ++i)
    {
        const std::vector<std::string_view> t = tokens(content[next + *v + i].text);
        const auto n = static_cast<std::size_t>(*parse_integer(t[0]));
        if (n <= k_off_reader_max_corners)
        {
            faces.append(content[next + *v + i].text).push_back('\n');
            ++face_count;
            continue;
        }
        for (std::size_t k = 2; k < n; ++k, ++face_count)
            faces.append("3 ")
                .append(t[1])
                .append(" ")
                .append(t[k])
                .append(" ")
                .append(t[k + 1])
                .push_back('\n');
    }
    r.rewritten = "OFF\n" + std::to_string(*v) + " " + std::to_string(face_count) + " 0\n";
    for (std::size_t i = 0; i < *v; ++i)
        r.rewritten.append(content[next + i].text).push_back('\n');
    r.rewritten += faces;
    return r;
}

// ---- PLY ----------------------------------------------------------------------------------

struct PlyProperty
{
    std::string name;
    int size = 0;        ///< bytes of a scalar, or of one list item
    int count_size = 0;  ///< bytes of the list length (0: scalar)
    bool count_signed = false;
    bool item_signed = false;  ///< a signed integer scalar or list item
    bool item_float = false;   ///< a float or double scalar or list item
};

struct PlyElement
{
    std::string name;
    std::size_t count = 0;
    std::vector<PlyProperty> properties;
    std::size_t line = 0;  ///< the header line that declares it
};

/// Bytes of a PLY scalar type, 0 if unknown; `is_signed` set for signed integer types.
int ply_type_size(std::string_view t, bool* is_signed)
{
    *is_signed =
        t == "char" || t == "int8" || t == "short" || t == "int16" || t == "int" || t == "int32";
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8")
        return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16")
        return 2;
    if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" ||
        t == "float32")
        return 4;
    if (t == "double" || t == "float64")
        return 8;
    return 0;
}

bool is_ply_float(std::string_view t)
{
    return t == "float" || t == "float32" || t == "double" || t == "float64";
}

/// The face element's list of vertex indices, under either name readers accept.
bool is_ply_index_list(const PlyElement& e, const PlyProperty& q)
{
    return e.name == "face" && q.count_size != 0 &&
           (q.name == "vertex_indices" || q.name == "vertex_index");
}

/// The properties Assimp's PLY reader needs: a vertex element with scalar x, y and z (it reads a
/// missing one as 0, which flattens the mesh onto a plane, a line or the origin, so its faces
/// degenerate) and a face element with its vertex index list (without one it reads no face at
/// all and says only "Mesh contains no faces"). Messages give the header line of the element.
core::Result<void> check_ply_layout(const std::vector<PlyElement>& elements,
                                    const std::string& name)
{
    const auto vertex = std::find_if(elements.begin(), elements.end(),
                                     [](const PlyElement& e) { return e.name == "vertex"; });
    if (vertex == elements.end())
        return fail(ErrorCode::ParseError, name +
                                               ": the PLY header has no 'vertex' element (a PLY "
                                               "mesh needs one with properties x, y and z)");
    const std::string at = name + ":" + std::to_string(vertex->line) + ": ";
    for (const char* axis : {"x", "y", "z"})
    {
        const auto p = std::find_if(vertex->properties.begin(), vertex->properties.end(),
                                    [axis](const PlyProperty& q) { return q.name == axis; });
        if (p == vertex->properties.end())
            return fail(ErrorCode::ParseError, at + "the vertex element has no property '" + axis +
                                                   "' (a PLY vertex needs x, y and z)");
        if (p->count_size != 0)
            return fail(ErrorCode::ParseError, at + "the vertex element's property '" + axis +
                                                   "' is a list (a PLY vertex needs x, y and z "
                                                   "as single numbers)");
    }
    for (const PlyElement& e : elements)
    {
        if (e.name != "face" || e.count == 0)
            continue;
        if (std::none_of(e.properties.begin(), e.properties.end(),
                         [&e](const PlyProperty& q) { return is_ply_index_list(e, q); }))
            return fail(ErrorCode::ParseError,
                        name + ":" + std::to_string(e.line) +
                            ": the face element has no list property 'vertex_indices' (a PLY "
                            "face lists its vertices in 'vertex_indices' or 'vertex_index')");
    }
    return {};
}

/// Reads an integer of `size` bytes (1, 2 or 4), little- or big-endian, signed or not.
std::int64_t read_integer(const unsigned char* p, int size, bool is_signed, bool big_endian)
{
    std::uint64_t v = 0;
    for (int i = 0; i < size; ++i)
    {
        const int shift = big_endian ? 8 * (size - 1 - i) : 8 * i;
        v |= static_cast<std::uint64_t>(p[i]) << shift;
    }
    if (is_signed && (v >> (8 * size - 1)) != 0)
        return static_cast<std::int64_t>(v) - (std::int64_t{1} << (8 * size));
    return static_cast<std::int64_t>(v);
}

/// Reads a list length of `size` bytes (1, 2 or 4), little- or big-endian. Negative -> nullopt.
std::optional<std::uint64_t> read_count(const unsigned char* p, int size, bool is_signed,
                                        bool big_endian)
{
    const std::int64_t v = read_integer(p, size, is_signed, big_endian);
    if (v < 0)
        return std::nullopt;
    return static_cast<std::uint64_t>(v);
}

/// The 1-based line number of byte `offset` of `bytes`.
std::size_t first_line_of(std::string_view bytes, std::size_t offset)
{
    return 1 + static_cast<std::size_t>(std::count(
                   bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

/// How a message names record `i` of element `e`: "vertex 3", "face 3", "element 'edge' record 3".
std::string ply_record(const PlyElement& e, std::size_t i)
{
    if (e.name == "vertex" || e.name == "face")
        return e.name + " " + std::to_string(i);
    return "element '" + e.name + "' record " + std::to_string(i);
}

std::string ply_bad_index(std::string_view index, std::size_t vertices)
{
    return ": index " + quoted(index) + " is not a vertex (0-based, the file has " +
           plural(vertices, "vertex") + ")";
}

/// Reads every record of an ASCII PLY body (one record per non-blank line, as the readers take
/// it): each value a number, each list as long as its length says, nothing left over, and each
/// face's vertex indices integers that name a vertex. Messages give the file's line.
core::Result<ScanResult> scan_ply_ascii(const std::vector<PlyElement>& elements,
                                        const ScanResult& r, std::string_view body,
                                        std::size_t first_line, const std::string& name)
{
    std::size_t number = first_line - 1;
    std::size_t done = 0;  // data lines read
    auto element = elements.begin();
    std::size_t record = 0;
    std::optional<core::Error> error;
    for_each_line(
        body,
        [&](std::string_view line)
        {
            ++number;
            while (element != elements.end() && record == element->count)
            {
                ++element;
                record = 0;
            }
            if (element == elements.end())
                return false;
            const std::vector<std::string_view> t = tokens(trim(line));
            if (t.empty())
                return true;
            ++done;
            const PlyElement& e = *element;
            const std::string where =
                name + ":" + std::to_string(number) + ": " + ply_record(e, record);
            const auto refuse = [&](ErrorCode code, const std::string& what)
            {
                error = core::Error{code, where + what};
                return false;
            };
            // A record that lacks values on a last line with no line end: the file was cut.
            const bool cut = line.data() + line.size() == body.data() + body.size();
            const auto refuse_short = [&](ErrorCode code, const std::string& what)
            {
                if (cut)
                    return refuse(ErrorCode::ParseError,
                                  ": truncated ASCII PLY file: it ends inside this record");
                return refuse(code, what);
            };
            std::size_t k = 0;
            for (const PlyProperty& q : e.properties)
            {
                if (k == t.size())
                    return refuse_short(ErrorCode::ParseError, ": no value for property '" +
                                                                   q.name + "' (the line has " +
                                                                   plural(t.size(), "value") + ")");
                if (q.count_size == 0)
                {
                    if (!is_number(t[k]))
                        return refuse(ErrorCode::ParseError, ": property '" + q.name + "' value " +
                                                                 quoted(t[k]) + " is not a number");
                    ++k;
                    continue;
                }
                const bool indices = is_ply_index_list(e, q);
                const auto n = parse_integer(t[k]);
                if (indices && (!n || *n < 3))
                    return refuse(ErrorCode::BadIndex, ": vertex count " + quoted(t[k]) +
                                                           " is not an integer of at least 3");
                if (!n || *n < 0)
                    return refuse(ErrorCode::ParseError, ": list '" + q.name + "' length " +
                                                             quoted(t[k]) +
                                                             " is not a non-negative integer");
                ++k;
                const auto count = static_cast<std::size_t>(*n);
                if (t.size() - k < count)
                    return refuse_short(indices ? ErrorCode::BadIndex : ErrorCode::ParseError,
                                        indices ? " declares " + plural(count, "vertex") +
                                                      " but lists " + std::to_string(t.size() - k)
                                                : ": list '" + q.name + "' declares " +
                                                      plural(count, "value") + " but " +
                                                      std::to_string(t.size() - k) + " follow");
                for (std::size_t j = k; j < k + count; ++j)
                {
                    if (!indices)
                    {
                        if (!is_number(t[j]))
                            return refuse(ErrorCode::ParseError, ": list '" + q.name + "' value " +
                                                                     quoted(t[j]) +
                                                                     " is not a number");
                        continue;
                    }
                    const auto index = parse_integer(t[j]);
                    if (!index || *index < 0 ||
                        static_cast<unsigned long long>(*index) >= r.vertices)
                        return refuse(ErrorCode::BadIndex, ply_bad_index(t[j], r.vertices));
                }
                k += count;
            }
            if (k != t.size())
                return refuse(ErrorCode::ParseError, " has " + plural(t.size(), "value") +
                                                         " but the header's properties take " +
                                                         std::to_string(k));
            ++record;
            return true;
        });
    if (error)
        return *error;
    while (element != elements.end() && record == element->count)
    {
        ++element;
        record = 0;
    }
    if (element != elements.end())
        return fail(ErrorCode::ParseError,
                    name + ": truncated ASCII PLY file: the header declares " +
                        plural(r.vertices, "vertex") + " and " + plural(r.faces, "face") +
                        " but only " + plural(done, "data line") + " follow");
    return r;
}

core::Result<ScanResult> scan_ply(std::string_view bytes, const std::string& name)
{
    if (bytes.substr(0, 4) != "ply\n" && bytes.substr(0, 5) != "ply\r\n")
        return fail(ErrorCode::ParseError,
                    name + ": not a PLY file: it does not start with 'ply'" +
                        (bytes.starts_with(k_utf8_bom)
                             ? std::string(" (it starts with a UTF-8 byte order mark, which PLY "
                                           "does not allow: save it without one)")
                             : std::string()));
    const std::size_t end_pos = bytes.find("end_header");
    if (end_pos == std::string_view::npos)
        return fail(ErrorCode::ParseError, name + ": bad PLY header: no 'end_header' line");
    std::size_t data = end_pos + 10;
    if (data < bytes.size() && bytes[data] == '\r')
        ++data;
    if (data >= bytes.size() || bytes[data] != '\n')
    {
        if (data >= bytes.size())
            return fail(ErrorCode::ParseError, name +
                                                   ": truncated PLY file: no data after "
                                                   "'end_header'");
        return fail(ErrorCode::ParseError, name + ": bad PLY header: 'end_header' is not a line");
    }
    ++data;
    const std::string_view header = bytes.substr(0, end_pos);
    if (auto text = check_text(header, name, "PLY header"); !text)
        return text.error();

    std::string encoding;
    std::vector<PlyElement> elements;
    std::optional<core::Error> error;
    std::size_t header_line = 0;
    for_each_line(
        header,
        [&](std::string_view line)
        {
            ++header_line;
            const std::vector<std::string_view> t = tokens(line);
            if (t.empty() || t[0] == "ply" || t[0] == "comment" || t[0] == "obj_info")
                return true;
            const auto bad = [&](const std::string& why)
            {
                error = core::Error{ErrorCode::ParseError, name + ": bad PLY header line '" +
                                                               std::string(line.substr(0, 60)) +
                                                               "': " + why};
                return false;
            };
            if (t[0] == "format")
            {
                if (t.size() < 2)
                    return bad("no encoding");
                encoding = std::string(t[1]);
                return true;
            }
            if (t[0] == "element")
            {
                const auto n = t.size() == 3 ? parse_count(t[2]) : std::nullopt;
                if (!n)
                    return bad("expected 'element NAME COUNT'");
                elements.push_back({std::string(t[1]), *n, {}, header_line});
                return true;
            }
            if (t[0] == "property")
            {
                if (elements.empty())
                    return bad("property before any element");
                PlyProperty p;
                if (t.size() == 5 && t[1] == "list")
                {
                    p.count_size = ply_type_size(t[2], &p.count_signed);
                    p.size = ply_type_size(t[3], &p.item_signed);
                    if (p.count_size == 0 || p.count_size == 8 || p.size == 0 || is_ply_float(t[2]))
                        return bad("unknown list type");
                    p.item_float = is_ply_float(t[3]);
                    p.name = std::string(t[4]);
                }
                else if (t.size() == 3)
                {
                    p.size = ply_type_size(t[1], &p.item_signed);
                    if (p.size == 0)
                        return bad("unknown type '" + std::string(t[1]) + "'");
                    p.item_float = is_ply_float(t[1]);
                    p.name = std::string(t[2]);
                }
                else
                    return bad("expected 'property TYPE NAME'");
                elements.back().properties.push_back(p);
                return true;
            }
            return bad("unknown keyword");
        });
    if (error)
        return *error;

    ScanResult r{};
    bool has_faces = false;
    for (const PlyElement& e : elements)
    {
        if (e.name == "vertex")
            r.vertices = e.count;
        if (e.name == "face")
        {
            r.faces = e.count;
            r.faces_known = true;
        }
        if ((e.name == "face" || e.name == "tristrips") && e.count > 0)
            has_faces = true;
    }
    if (!has_faces)
        return fail(ErrorCode::EmptyInput, name + ": no faces: the PLY header declares " +
                                               plural(r.vertices, "vertex") +
                                               " and no 'face' element with a non-zero count");
    if (auto layout = check_ply_layout(elements, name); !layout)
        return layout.error();

    const std::string_view body = bytes.substr(data);
    if (encoding == "ascii")
    {
        r.format = Format::PlyAscii;
        if (auto text = check_text(body, name, "ASCII PLY"); !text)
            return text.error();
        return scan_ply_ascii(elements, r, body, first_line_of(bytes, data), name);
    }
    if (encoding != "binary_little_endian" && encoding != "binary_big_endian")
        return fail(ErrorCode::UnsupportedFormat,
                    name + ": PLY encoding '" + encoding +
                        "' is not one of ascii, binary_little_endian, binary_big_endian");
    r.format = Format::PlyBinary;
    const bool big = encoding == "binary_big_endian";
    const auto* p = reinterpret_cast<const unsigned char*>(body.data());
    const std::size_t size = body.size();
    std::size_t at = 0;
    for (const PlyElement& e : elements)
    {
        const bool fixed = std::all_of(e.properties.begin(), e.properties.end(),
                                       [](const PlyProperty& q) { return q.count_size == 0; });
        const auto truncated = [&](std::size_t record)
        {
            return fail(ErrorCode::ParseError, name + ": truncated binary PLY file: element '" +
                                                   e.name + "' record " + std::to_string(record) +
                                                   " of " + std::to_string(e.count) +
                                                   " ends beyond the data (" +
                                                   plural(size, "byte") + " after the header)");
        };
        if (fixed)
        {
            std::size_t record = 0;
            for (const PlyProperty& q : e.properties)
                record += static_cast<std::size_t>(q.size);
            if (record == 0)
                continue;
            const std::size_t room = (size - at) / record;
            if (e.count > room)
                return truncated(room);
            at += e.count * record;
            continue;
        }
        // Lists: walk record by record; every list record consumes at least its length bytes,
        // so the loop is bounded by the file size.
        for (std::size_t i = 0; i < e.count; ++i)
        {
            for (const PlyProperty& q : e.properties)
            {
                if (q.count_size == 0)
                {
                    if (size - at < static_cast<std::size_t>(q.size))
                        return truncated(i);
                    at += static_cast<std::size_t>(q.size);
                    continue;
                }
                if (size - at < static_cast<std::size_t>(q.count_size))
                    return truncated(i);
                const auto n = read_count(p + at, q.count_size, q.count_signed, big);
                if (!n)
                    return fail(ErrorCode::ParseError,
                                name + ": bad binary PLY data: element '" + e.name + "' record " +
                                    std::to_string(i) + " has a negative list length");
                const std::size_t record_at = data + at;
                at += static_cast<std::size_t>(q.count_size);
                const std::size_t room = (size - at) / static_cast<std::size_t>(q.size);
                if (*n > room)
                    return truncated(i);
                if (is_ply_index_list(e, q))
                {
                    const std::string where = name + ": face " + std::to_string(i) + " (byte " +
                                              std::to_string(record_at) + ")";
                    if (*n < 3)
                        return fail(
                            ErrorCode::BadIndex,
                            where + ": vertex count " + std::to_string(*n) + " is less than 3");
                    for (std::uint64_t j = 0; j < *n; ++j)
                    {
                        const unsigned char* item = p + at + j * static_cast<std::size_t>(q.size);
                        if (q.item_float)
                        {
                            // An index list of floats (legal PLY): each a whole number naming a
                            // vertex; Assimp truncated 2.7 to 2, read NaN as 0 and reported 77
                            // without the face.
                            const auto bits =
                                static_cast<std::uint64_t>(read_integer(item, q.size, false, big));
                            const double index = q.size == 4
                                                     ? static_cast<double>(std::bit_cast<float>(
                                                           static_cast<std::uint32_t>(bits)))
                                                     : std::bit_cast<double>(bits);
                            // isfinite first: an ordered comparison with NaN raises FE_INVALID.
                            if (!std::isfinite(index) || index < 0.0 ||
                                index >= static_cast<double>(r.vertices) ||
                                index != std::floor(index))
                            {
                                std::array<char, 32> text{};
                                std::snprintf(text.data(), text.size(), "%.9g", index);
                                return fail(ErrorCode::BadIndex,
                                            where + ply_bad_index(text.data(), r.vertices));
                            }
                            continue;
                        }
                        const std::int64_t index = read_integer(item, q.size, q.item_signed, big);
                        if (index < 0 || static_cast<std::uint64_t>(index) >= r.vertices)
                            return fail(ErrorCode::BadIndex,
                                        where + ply_bad_index(std::to_string(index), r.vertices));
                    }
                }
                at += static_cast<std::size_t>(*n) * static_cast<std::size_t>(q.size);
            }
        }
    }
    return r;
}

// ---- STL ----------------------------------------------------------------------------------

core::Result<ScanResult> scan_stl(std::string_view bytes, const std::string& name)
{
    const std::size_t size = bytes.size();
    std::uint64_t n = 0;
    if (size >= 84)
    {
        const auto* p = reinterpret_cast<const unsigned char*>(bytes.data()) + 80;
        n = static_cast<std::uint64_t>(p[0]) | static_cast<std::uint64_t>(p[1]) << 8 |
            static_cast<std::uint64_t>(p[2]) << 16 | static_cast<std::uint64_t>(p[3]) << 24;
        if (84 + 50 * n == size)
        {
            if (n == 0)
                return fail(ErrorCode::EmptyInput,
                            name + ": no faces: the binary STL header declares 0 triangles");
            return ScanResult{
                .format = Format::StlBinary, .vertices = 3 * n, .faces = n, .faces_known = true};
        }
    }
    // An ASCII file may begin with a UTF-8 byte-order mark (some Windows editors write one):
    // not part of `solid`, and Assimp would take the file for a binary one, so it reads a copy
    // without it, as for OBJ.
    std::string_view text = bytes;
    const bool bom = text.starts_with(k_utf8_bom);
    if (bom)
        text.remove_prefix(k_utf8_bom.size());
    const std::string_view start = trim(text.substr(0, std::min<std::size_t>(text.size(), 512)));
    if (start.substr(0, 5) == "solid" && check_text(text, name, "STL"))
    {
        ScanResult r{.format = Format::StlAscii};
        if (bom)
            r.rewritten = std::string(text);
        // Every facet closed with exactly three vertices, and the solid closed: a file cut at a
        // facet boundary otherwise reads as a smaller, open mesh.
        std::optional<core::Error> error;
        std::size_t line_number = 0;
        std::size_t corners = 0;
        bool in_facet = false;
        bool ended = false;
        for_each_line(
            text,
            [&](std::string_view line)
            {
                ++line_number;
                const std::vector<std::string_view> t = tokens(trim(line));
                const auto refuse = [&](const std::string& what)
                {
                    error = core::Error{ErrorCode::ParseError,
                                        name + ":" + std::to_string(line_number) +
                                            ": malformed ASCII STL: " + what};
                    return false;
                };
                if (t.empty())
                    return true;
                if (t[0] == "facet")
                {
                    if (in_facet)
                        return refuse("'facet' inside facet " + std::to_string(r.faces - 1));
                    in_facet = true;
                    corners = 0;
                    ++r.faces;
                }
                else if (t[0] == "vertex")
                    ++corners;
                else if (t[0] == "endfacet")
                {
                    if (!in_facet || corners != 3)
                        return refuse("facet " + std::to_string(r.faces - 1) + " has " +
                                      plural(corners, "vertex") + ", expected 3");
                    in_facet = false;
                }
                else if (t[0] == "endsolid")
                    ended = true;
                return true;
            });
        if (error)
            return *error;
        r.vertices = 3 * r.faces;
        r.faces_known = true;
        if (r.faces == 0)
            return fail(ErrorCode::EmptyInput, name + ": no faces: no 'facet' in the ASCII STL");
        if (in_facet || !ended)
            return fail(
                ErrorCode::ParseError,
                name + ": truncated ASCII STL file: " +
                    (in_facet ? "facet " + std::to_string(r.faces - 1) + " is not closed"
                              : std::string("no 'endsolid' after ") + plural(r.faces, "facet")));
        return r;
    }
    if (size < 84)
        return fail(ErrorCode::ParseError,
                    name + ": not an STL file: neither ASCII ('solid ...') nor binary (" +
                        plural(size, "byte") + ", shorter than the 84-byte binary header)");
    return fail(ErrorCode::ParseError,
                name + ": truncated or malformed binary STL file: the header declares " +
                    plural(static_cast<std::size_t>(n), "triangle") + ", which needs 84 + 50 * " +
                    std::to_string(n) + " = " + std::to_string(84 + 50 * n) +
                    " bytes, but the file has " + std::to_string(size));
}

// ---- glTF ---------------------------------------------------------------------------------

/// Reads JSON without building it (nothing is kept, and the parser nests without recursion) and
/// records where it breaks; never throws.
class JsonBreak final : public nlohmann::json_sax<nlohmann::json>
{
public:
    bool null() override { return true; }
    bool boolean(bool /*value*/) override { return true; }
    bool number_integer(number_integer_t /*value*/) override { return true; }
    bool number_unsigned(number_unsigned_t /*value*/) override { return true; }
    bool number_float(number_float_t /*value*/, const string_t& /*text*/) override { return true; }
    bool string(string_t& /*value*/) override { return true; }
    bool binary(binary_t& /*value*/) override { return true; }
    bool start_object(std::size_t /*elements*/) override { return true; }
    bool key(string_t& /*value*/) override { return true; }
    bool end_object() override { return true; }
    bool start_array(std::size_t /*elements*/) override { return true; }
    bool end_array() override { return true; }
    bool parse_error(std::size_t position, const std::string& /*last_token*/,
                     const nlohmann::detail::exception& e) override
    {
        // `position` counts the characters read, the one that broke the parse (or the end of
        // the input) included.
        offset = position > 0 ? position - 1 : 0;
        // "[json.exception.parse_error.101] parse error at line 1, column 5: syntax error ...":
        // the part after the place, which the message gives itself.
        std::string_view text = e.what();
        const std::size_t column = text.find("column ");
        const std::size_t colon = column == std::string::npos ? column : text.find(": ", column);
        if (colon != std::string::npos)
            text.remove_prefix(colon + 2);
        // Its "last read: '...'" quotes the file's bytes: any that are not printable ASCII are
        // written as \xNN, so that the message stays valid UTF-8 (`pliant info --json`).
        for (const char c : text)
        {
            const auto u = static_cast<unsigned char>(c);
            if (u >= 0x20 && u < 0x7f)
            {
                why.push_back(c);
                continue;
            }
            constexpr std::string_view hex = "0123456789ABCDEF";
            why.append("\\x").push_back(hex[u >> 4]);
            why.push_back(hex[u & 0xF]);
        }
        return false;
    }

    std::size_t offset = 0;
    std::string why;
};

/// Where the glTF JSON `json` (at byte `base` of the file `bytes`) breaks, if it does.
core::Result<void> check_json(std::string_view bytes, std::size_t base, std::string_view json,
                              const std::string& name)
{
    JsonBreak check;
    if (nlohmann::json::sax_parse(json.begin(), json.end(), &check))
        return {};
    const std::size_t at = base + std::min(check.offset, json.size());
    const std::size_t line_start = bytes.rfind('\n', at == 0 ? 0 : at - 1);
    const std::size_t column =
        line_start == std::string_view::npos || at == 0 ? at + 1 : at - line_start;
    const std::string place = "at byte " + std::to_string(at) + " (line " +
                              std::to_string(first_line_of(bytes, at)) + ", column " +
                              std::to_string(column) + ")";
    return fail(ErrorCode::ParseError,
                name + ": the glTF JSON does not parse " + place +
                    (at == bytes.size()         ? ", where the file ends"
                     : at == base + json.size() ? ", where the JSON chunk ends"
                                                : "") +
                    ": " + check.why);
}

/// A `.gltf` is JSON: Assimp's glTF readers do not recognise a file whose JSON does not parse
/// and say only "No suitable reader found", so the scan parses it first and says where it breaks.
core::Result<ScanResult> scan_gltf(std::string_view bytes, const std::string& name)
{
    if (auto text = check_text(bytes, name, "glTF"); !text)
        return text.error();
    if (auto ok = check_json(bytes, 0, bytes, name); !ok)
        return ok.error();
    return ScanResult{.format = Format::Gltf, .json_offset = 0, .json_size = bytes.size()};
}

std::uint32_t read_u32_le(std::string_view bytes, std::size_t at)
{
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data()) + at;
    return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
           static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

/// A GLB file (glTF 2.0 binary): a 12-byte header (magic, version, length), then chunks of an
/// 8-byte header (length, type) and their bytes, the first one JSON. Every chunk must lie within
/// the declared length (a chunk length of 4 GiB in a 712-byte file had Assimp's reader allocate
/// it, and then say only "No suitable reader found"), and the JSON must parse.
core::Result<ScanResult> scan_glb(std::string_view bytes, const std::string& name)
{
    if (bytes.size() < 12 || bytes.substr(0, 4) != "glTF")
        return fail(ErrorCode::ParseError, name +
                                               ": not a GLB file: no 'glTF' magic in the "
                                               "12-byte header");
    const std::uint32_t version = read_u32_le(bytes, 4);
    const std::uint64_t length = read_u32_le(bytes, 8);
    if (length > bytes.size())
        return fail(ErrorCode::ParseError, name + ": truncated GLB file: the header declares " +
                                               plural(static_cast<std::size_t>(length), "byte") +
                                               ", the file has " + std::to_string(bytes.size()));
    if (version != 2)  // glTF 1.0's binary layout has no chunks; Assimp reads it as it is
        return ScanResult{.format = Format::Glb};
    constexpr std::uint32_t k_json_chunk = 0x4E4F534A;  // "JSON"
    ScanResult result{.format = Format::Glb};
    std::size_t chunk = 0;
    for (std::uint64_t at = 12; at < length; ++chunk)
    {
        if (length - at < 8)
            return fail(ErrorCode::ParseError,
                        name + ": GLB chunk " + std::to_string(chunk) + " at byte " +
                            std::to_string(at) + ": its 8-byte header runs past the " +
                            std::to_string(length) + " bytes the file declares");
        const std::uint64_t size = read_u32_le(bytes, static_cast<std::size_t>(at));
        const std::uint32_t type = read_u32_le(bytes, static_cast<std::size_t>(at) + 4);
        if (size > length - at - 8)
            return fail(ErrorCode::ParseError, name + ": GLB chunk " + std::to_string(chunk) +
                                                   " at byte " + std::to_string(at) + " declares " +
                                                   plural(static_cast<std::size_t>(size), "byte") +
                                                   ", past the " + std::to_string(length) +
                                                   " bytes the file declares");
        if (chunk == 0)
        {
            if (type != k_json_chunk)
                return fail(
                    ErrorCode::ParseError, name + ": GLB chunk 0 is not JSON (its type is 0x" +
                                               [type]
                                               {
                                                   std::array<char, 12> hex{};
                                                   std::snprintf(hex.data(), hex.size(), "%08X",
                                                                 type);
                                                   return std::string(hex.data());
                                               }() +
                                               "); a GLB file starts with its JSON chunk");
            const auto offset = static_cast<std::size_t>(at) + 8;
            const std::string_view json = bytes.substr(offset, static_cast<std::size_t>(size));
            if (auto ok = check_json(bytes, offset, json, name); !ok)
                return ok.error();
            result.json_offset = offset;
            result.json_size = json.size();
        }
        // Assimp reads buffer 0 from the chunk after the JSON one, at the JSON's length rounded
        // up to 4 (the chunks' own walk uses the length as it is: they agree when it is a
        // multiple of 4, as glTF requires).
        constexpr std::uint32_t k_bin_chunk = 0x004E4942;  // "BIN\0"
        if (chunk == 1 && type == k_bin_chunk && result.json_size % 4 == 0)
        {
            result.bin_offset = static_cast<std::size_t>(at) + 8;
            result.bin_size = static_cast<std::size_t>(size);
        }
        at += 8 + size;
    }
    if (chunk == 0)
        return fail(ErrorCode::ParseError, name + ": GLB file without chunks (no JSON)");
    return result;
}

/// Collects `buffers[i].uri` and `buffers[i].byteLength` of a glTF JSON (already known to
/// parse) without building it.
class BufferList final : public nlohmann::json_sax<nlohmann::json>
{
public:
    struct Buffer
    {
        std::optional<std::string> uri;
        std::optional<std::uint64_t> byte_length;
    };
    std::vector<Buffer> buffers;

    bool null() override { return value_seen(); }
    bool boolean(bool /*value*/) override { return value_seen(); }
    bool number_integer(number_integer_t /*value*/) override { return value_seen(); }
    bool number_unsigned(number_unsigned_t value) override
    {
        if (in_buffer_field("byteLength"))
            buffers.back().byte_length = value;
        return value_seen();
    }
    bool number_float(number_float_t /*value*/, const string_t& /*text*/) override
    {
        return value_seen();
    }
    bool string(string_t& value) override
    {
        if (in_buffer_field("uri"))
            buffers.back().uri = value;
        return value_seen();
    }
    bool binary(binary_t& /*value*/) override { return value_seen(); }
    bool start_object(std::size_t /*elements*/) override { return open(false); }
    bool key(string_t& value) override
    {
        stack_.back().key = value;
        return true;
    }
    bool end_object() override { return close(); }
    bool start_array(std::size_t /*elements*/) override { return open(true); }
    bool end_array() override { return close(); }
    bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                     const nlohmann::detail::exception& /*e*/) override
    {
        return false;
    }

private:
    struct Level
    {
        bool array = false;
        std::string key;
    };
    std::vector<Level> stack_;

    /// The value being read is field `field` of an element of the top-level "buffers" array.
    [[nodiscard]] bool in_buffer_field(std::string_view field) const
    {
        return stack_.size() == 3 && !stack_[0].array && stack_[0].key == "buffers" &&
               stack_[1].array && !stack_[2].array && stack_[2].key == field;
    }
    bool open(bool array)
    {
        if (stack_.size() == 2 && !stack_[0].array && stack_[0].key == "buffers" &&
            stack_[1].array && !array)
            buffers.emplace_back();
        stack_.push_back({array, {}});
        return true;
    }
    bool close()
    {
        stack_.pop_back();
        return true;
    }
    static bool value_seen() { return true; }
};

}  // namespace

std::optional<std::string> unreadable_file(const std::filesystem::path& path)
{
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status))
        return "no such file";
    if (std::filesystem::is_directory(status))
        return "it is a directory";
    // A FIFO blocks the reader for ever, a device has no end (/dev/zero).
    if (!std::filesystem::is_regular_file(status))
        return "not a regular file (a device, FIFO or socket)";
    return std::nullopt;
}

core::Result<void> check_gltf_buffers(std::string_view json, const std::filesystem::path& folder,
                                      const std::string& name)
{
    BufferList list;
    if (!nlohmann::json::sax_parse(json.begin(), json.end(), &list))
        return {};  // the scan said where it breaks; nothing more to check here
    for (std::size_t i = 0; i < list.buffers.size(); ++i)
    {
        const BufferList::Buffer& b = list.buffers[i];
        if (!b.uri || b.uri->starts_with("data:"))
            continue;  // the GLB's own chunk, or bytes inside the JSON
        // Taken as written: Assimp 5.2 does not decode %-escapes either (mesh::export_mesh
        // refuses to write a name that would need one).
        const std::string& file = *b.uri;
        const std::string what = name + ": buffer " + std::to_string(i) + "'s file '" + file + "'";
        if (const auto why = unreadable_file(folder / file))
            return fail(ErrorCode::IoError, what + ": " + *why);
        std::error_code ec;
        const std::uintmax_t size = std::filesystem::file_size(folder / file, ec);
        if (!ec && b.byte_length && size < *b.byte_length)
            return fail(ErrorCode::ParseError, what + " holds " + plural(size, "byte") +
                                                   ", the glTF declares byteLength " +
                                                   std::to_string(*b.byte_length));
    }
    return {};
}

std::string_view format_name(Format format) noexcept
{
    switch (format)
    {
    case Format::Obj: return "obj";
    case Format::Off: return "off";
    case Format::PlyAscii: return "ply-ascii";
    case Format::PlyBinary: return "ply-binary";
    case Format::StlAscii: return "stl-ascii";
    case Format::StlBinary: return "stl-binary";
    case Format::Gltf: return "gltf";
    case Format::Glb: return "glb";
    }
    return "unknown";
}

core::Result<ScanResult> scan_format(std::string_view bytes, std::string_view ext,
                                     const std::string& name)
{
    if (bytes.empty())
        return fail(ErrorCode::EmptyInput, name + ": empty file (0 bytes)");
    const bool text_format = ext == ".obj" || ext == ".off" || ext == ".gltf";
    if (text_format && only_space(bytes))
        return fail(ErrorCode::EmptyInput,
                    name + ": empty file (" + plural(bytes.size(), "byte") + " of white space)");
    if (ext == ".obj")
        return scan_obj(bytes, name);
    if (ext == ".off")
        return scan_off(bytes, name);
    if (ext == ".ply")
        return scan_ply(bytes, name);
    if (ext == ".stl")
        return scan_stl(bytes, name);
    if (ext == ".glb")
        return scan_glb(bytes, name);
    if (ext == ".gltf")
        return scan_gltf(bytes, name);
    return fail(ErrorCode::UnsupportedFormat,
                name + ": unsupported format '" + std::string(ext) +
                    "' (pliant reads .obj .off .ply .stl .gltf .glb)");
}

}  // namespace pliant::mesh::detail
