// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for mesh import + validation (docs/style.md §10): bytes in, an error or a valid mesh
// out, never a crash, a hang or a sanitizer report. The first byte picks the format (its value
// mod 6: 0 .obj, 1 .off, 2 .ply, 3 .stl, 4 .gltf, 5 .glb; the seed corpus uses the digits
// '0'..'5'); the rest is written to a temporary file with that extension, because Assimp reads
// files (glTF resolves buffers relative to them) and import_mesh checks sizes on the file.
// Built with libFuzzer under clang (PLIANT_FUZZ=ON), or linked with replay_main.cpp as a corpus
// replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/mesh/io.h>
#include <pliant/mesh/validate.h>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

constexpr const char* k_extensions[] = {".obj", ".off", ".ply", ".stl", ".gltf", ".glb"};
constexpr std::size_t k_max_input = std::size_t{1} << 20;  // larger inputs only slow the search

std::filesystem::path scratch_file(std::size_t format)
{
    static const std::filesystem::path dir = []
    {
        std::error_code ec;
        std::filesystem::path p = std::filesystem::temp_directory_path(ec) /
                                  ("pliant-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(p, ec);
        return p;
    }();
    return dir / (std::string("input") + k_extensions[format]);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0 || size > k_max_input)
        return 0;
    const std::size_t format = data[0] % 6;
    const std::filesystem::path path = scratch_file(format);
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    pliant::mesh::ImportReport report;
    auto mesh = pliant::mesh::import_mesh(path, &report);
    if (mesh)
    {
        // Whatever import accepts, analysis and validation must digest.
        const pliant::mesh::MeshStats stats = pliant::mesh::analyze(*mesh);
        const auto verdict = pliant::mesh::validate(*mesh, "fuzz");
        if (stats.vertices != mesh->vertex_count() || stats.bad_index_faces != 0 ||
            (verdict && !stats.genus))
            std::abort();  // import produced an index out of range, or validate and analyze
                           // disagree: a bug, not bad input
    }
    else if (mesh.error().message.empty())
    {
        std::abort();  // every error must explain itself
    }
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return 0;
}
