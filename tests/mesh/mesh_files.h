// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Test-only writers for the formats pliant reads but does not write (OFF, STL, ascii PLY, glTF),
// kept deliberately naive (one record per line, no sharing) so they are an independent source
// of files for the import tests.

#include <pliant/mesh/tri_mesh.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace pliant::test
{

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string read_all(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline std::string fmt_double(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

inline std::string to_off(const mesh::TriMesh& m)
{
    std::string s = "OFF\n# test file\n" + std::to_string(m.positions.size()) + " " +
                    std::to_string(m.faces.size()) + " 0\n";
    for (const auto& p : m.positions)
        s += fmt_double(p.x) + " " + fmt_double(p.y) + " " + fmt_double(p.z) + "\n";
    for (const auto& f : m.faces)
        s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             "\n";
    return s;
}

inline std::string to_ply_ascii(const mesh::TriMesh& m)
{
    std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.positions.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(m.faces.size()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& p : m.positions)
        s += fmt_double(p.x) + " " + fmt_double(p.y) + " " + fmt_double(p.z) + "\n";
    for (const auto& f : m.faces)
        s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             "\n";
    return s;
}

inline std::string to_stl_ascii(const mesh::TriMesh& m)
{
    std::string s = "solid test\n";
    for (const auto& f : m.faces)
    {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for (const auto v : f)
        {
            const auto& p = m.positions[v];
            s += "      vertex " + fmt_double(p.x) + " " + fmt_double(p.y) + " " + fmt_double(p.z) +
                 "\n";
        }
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid test\n";
}

template <typename T>
void append_le(std::string& s, T v)
{
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // the test machines are little-endian (x86-64)
    s.append(b, sizeof(T));
}

inline std::string to_stl_binary(const mesh::TriMesh& m)
{
    std::string s(80, ' ');
    s.replace(0, 11, "binary test");
    append_le(s, static_cast<std::uint32_t>(m.faces.size()));
    for (const auto& f : m.faces)
    {
        for (int k = 0; k < 3; ++k)
            append_le(s, 0.0F);
        for (const auto v : f)
        {
            const auto& p = m.positions[v];
            append_le(s, static_cast<float>(p.x));
            append_le(s, static_cast<float>(p.y));
            append_le(s, static_cast<float>(p.z));
        }
        append_le(s, std::uint16_t{0});
    }
    return s;
}

inline std::string base64(const std::string& in)
{
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < in.size(); i += 3)
    {
        const unsigned n = static_cast<unsigned char>(in[i]) << 16 |
                           static_cast<unsigned char>(in[i + 1]) << 8 |
                           static_cast<unsigned char>(in[i + 2]);
        out += {k[n >> 18], k[(n >> 12) & 63], k[(n >> 6) & 63], k[n & 63]};
    }
    if (i + 1 == in.size())
    {
        const unsigned n = static_cast<unsigned char>(in[i]) << 16;
        out += {k[n >> 18], k[(n >> 12) & 63], '=', '='};
    }
    else if (i + 2 == in.size())
    {
        const unsigned n =
            static_cast<unsigned char>(in[i]) << 16 | static_cast<unsigned char>(in[i + 1]) << 8;
        out += {k[n >> 18], k[(n >> 12) & 63], k[(n >> 6) & 63], '='};
    }
    return out;
}

/// glTF 2.0 with one node, one triangle primitive, an embedded (data URI) buffer; indices of
/// `index_bytes` bytes each: 4 (UNSIGNED_INT, 5125), 2 (UNSIGNED_SHORT, 5123) or 1
/// (UNSIGNED_BYTE, 5121).
inline std::string to_gltf(const mesh::TriMesh& m, int index_bytes = 4)
{
    std::string buffer;
    float lo[3] = {1e30F, 1e30F, 1e30F};
    float hi[3] = {-1e30F, -1e30F, -1e30F};
    for (const auto& p : m.positions)
    {
        const float c[3] = {static_cast<float>(p.x), static_cast<float>(p.y),
                            static_cast<float>(p.z)};
        for (int k = 0; k < 3; ++k)
        {
            append_le(buffer, c[k]);
            lo[k] = c[k] < lo[k] ? c[k] : lo[k];
            hi[k] = c[k] > hi[k] ? c[k] : hi[k];
        }
    }
    const std::size_t pos_bytes = buffer.size();
    for (const auto& f : m.faces)
        for (const auto v : f)
        {
            if (index_bytes == 1)
                append_le(buffer, static_cast<std::uint8_t>(v));
            else if (index_bytes == 2)
                append_le(buffer, static_cast<std::uint16_t>(v));
            else
                append_le(buffer, v);
        }
    const int component = index_bytes == 1 ? 5121 : index_bytes == 2 ? 5123 : 5125;
    const auto num = [](double v) { return fmt_double(v); };
    std::string s = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)";
    s += R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},)";
    s += R"("indices":1,"mode":4}]}],"buffers":[{"byteLength":)" + std::to_string(buffer.size()) +
         R"(,"uri":"data:application/octet-stream;base64,)" + base64(buffer) + R"("}],)";
    s += R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" + std::to_string(pos_bytes) +
         R"(,"target":34962},{"buffer":0,"byteOffset":)" + std::to_string(pos_bytes) +
         R"(,"byteLength":)" + std::to_string(buffer.size() - pos_bytes) + R"(,"target":34963}],)";
    s += R"("accessors":[{"bufferView":0,"componentType":5126,"count":)" +
         std::to_string(m.positions.size()) + R"(,"type":"VEC3","min":[)" + num(lo[0]) + "," +
         num(lo[1]) + "," + num(lo[2]) + R"(],"max":[)" + num(hi[0]) + "," + num(hi[1]) + "," +
         num(hi[2]) + R"(]},{"bufferView":1,"componentType":)" + std::to_string(component) +
         R"(,"count":)" + std::to_string(3 * m.faces.size()) + R"(,"type":"SCALAR"}]})";
    return s;
}

}  // namespace pliant::test
