// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Fuzz target for the two script readers, text a user hands to pliant (docs/style.md §10): the
// first input byte picks the reader (even: session::parse_script, the timed grabs of `pliant join
// --script`; odd: viewer::parse_input_script, the timed mouse events of `pliant view
// --script`); the rest is the script. A refusal must explain itself with the source and a line;
// an accepted script must hold only what the readers promise (finite, non-negative times,
// durations and radii, finite points and forces, faces below the wire's limit, known keys and
// export formats, session events in time order), and session::check_script must digest it.
// Built with libFuzzer under clang, or as a corpus replayer otherwise (fuzz/CMakeLists.txt).

#include <pliant/session/runner.h>

#include "fuzz_support.h"
#include "viewer/input_script.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{

using namespace pliant;

constexpr const char* k_target = "fuzz_scripts";

bool finite3(const std::array<double, 3>& v)
{
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

void check_refusal(const core::Error& e)
{
    fuzz::require(e.message.rfind("fuzz:", 0) == 0, k_target,
                  "a refusal that does not name the source");
}

void session_script(std::string_view text)
{
    auto events = session::parse_script(text, "fuzz");
    if (!events)
        return check_refusal(events.error());
    double last = 0.0;
    for (const session::ScriptEvent& e : *events)
    {
        fuzz::require(std::isfinite(e.time) && e.time >= last, k_target,
                      "times not finite and in order");
        last = e.time;
        fuzz::require(e.line >= 1, k_target, "an event without its line");
        if (e.kind == session::ScriptEvent::Kind::Leave)
            continue;
        const net::Target& t = e.force.target;
        if (t.kind == net::TargetKind::Face)
            fuzz::require(t.face < net::k_max_face_index, k_target,
                          "a face beyond the wire's limit");
        else
            fuzz::require(finite3(t.position), k_target, "a non-finite point");
        fuzz::require(std::isfinite(t.radius) && t.radius >= 0.0, k_target, "a bad radius");
        if (e.kind == session::ScriptEvent::Kind::Grab)
            fuzz::require(finite3(e.force.force) && std::isfinite(e.duration) && e.duration > 0.0,
                          k_target, "a grab with a bad force or duration");
    }
    for (const auto role : {session::SessionRole::Participant, session::SessionRole::Viewer})
        if (auto ok = session::check_script(*events, 1024, role, "fuzz"); !ok)
            check_refusal(ok.error());
}

void viewer_script(std::string_view text)
{
    auto events = viewer::parse_input_script(text, "fuzz");
    if (!events)
        return check_refusal(events.error());
    for (const viewer::ScriptEvent& e : *events)
    {
        fuzz::require(std::isfinite(e.time) && e.time >= 0.0, k_target, "a bad time");
        fuzz::require(std::isfinite(e.duration) && e.duration >= 0.0, k_target, "a bad duration");
        fuzz::require(std::isfinite(e.x0) && std::isfinite(e.y0) && std::isfinite(e.x1) &&
                          std::isfinite(e.y1) && std::isfinite(e.clicks),
                      k_target, "a non-finite coordinate");
        if (e.kind == viewer::ScriptEvent::Kind::Key)
            fuzz::require(std::find(viewer::k_script_keys.begin(), viewer::k_script_keys.end(),
                                    e.key) != viewer::k_script_keys.end(),
                          k_target, "an unknown key");
        if (e.kind == viewer::ScriptEvent::Kind::Export)
        {
            const std::size_t dot = e.file.rfind('.');
            fuzz::require(dot != std::string::npos, k_target, "an export without an extension");
            std::string ext = e.file.substr(dot);
            for (char& c : ext)
                c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            fuzz::require(ext == ".obj" || ext == ".ply" || ext == ".gltf" || ext == ".glb",
                          k_target, "an export format the viewer cannot write");
            fuzz::require(std::none_of(e.file.begin(), e.file.end(),
                                       [](unsigned char c) { return c < 0x20 || c == 0x7f; }),
                          k_target, "an export file name with a control byte");
        }
        if (e.kind == viewer::ScriptEvent::Kind::Load)
            fuzz::require(!e.file.empty() &&
                              std::none_of(e.file.begin(), e.file.end(),
                                           [](unsigned char c) { return c < 0x20 || c == 0x7f; }),
                          k_target, "a load without a file or with a control byte");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0)
        return 0;
    const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
    if (data[0] % 2 == 0)
        session_script(text);
    else
        viewer_script(text);
    return 0;
}
