// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Timed input for headless runs of the viewer (`pliant view --script FILE`, docs/viewer.md):
// mouse events in window pixel coordinates (x right, y down from the top-left corner), played
// into the same handlers as the real mouse. One event per line, `#` starts a comment, times in
// seconds from the first frame that shows the object:
//
//     0.5  drag 320 240 -> 360 200 for 1.0   # left button down at (320, 240), moved linearly,
//                                           # released at (360, 200) 1.0 s later
//     2.0  wheel 320 240 -1                  # scroll one click (negative: zoom out)
//     2.5  key p                             # a key: p or f12 (screenshot), e (export), w,
//                                           # c, h, r, space, escape (k_script_keys)
//     2.8  export out.glb                    # export the surface to a file (.obj .ply .gltf
//                                           # .glb; relative to the working folder)
//     3.0  load other.pgrid                  # load another surface, as the Load panel does
//                                           # (a grid or a mesh; remeshed in the background)
//
// Events may overlap in time only if they are not both drags.

#include <pliant/core/result.h>

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::viewer
{

struct ScriptEvent
{
    enum class Kind : unsigned char
    {
        Drag,
        Wheel,
        Key,
        Export,
        Load,
    };
    Kind kind = Kind::Drag;
    double time = 0.0;      ///< s
    double duration = 0.0;  ///< s (drag), >= 0
    double x0 = 0.0, y0 = 0.0;
    double x1 = 0.0, y1 = 0.0;  ///< end point (drag)
    double clicks = 0.0;        ///< wheel
    std::string key;            ///< key name (lower case)
    std::string file;           ///< export: the file to write; load: to read (one word)
    std::size_t line = 0;       ///< line of the script it came from (1-based)
};

/// The key names a script may press (`TIME key NAME`, case-insensitive): those the viewer's
/// key handler knows.
inline constexpr std::array<std::string_view, 9> k_script_keys{"p", "f12", "e",     "w",     "c",
                                                               "h", "r",   "space", "escape"};

/// Parses a script; `source` (the file name) starts every message, `SOURCE:LINE: ...`.
/// \return ParseError naming the line for an unknown command or key, a missing or non-finite
/// number, a negative time or duration, overlapping drags, an export file whose extension is
/// not .obj, .ply, .gltf or .glb, or a file name with a control byte.
core::Result<std::vector<ScriptEvent>> parse_input_script(std::string_view text,
                                                          std::string_view source = "script");
/// Reads and parses a script file. \return IoError or parse_input_script's errors.
core::Result<std::vector<ScriptEvent>> load_input_script(const std::filesystem::path& path);

/// Receives the played events (the viewer's input handlers).
class InputSink
{
public:
    virtual ~InputSink() = default;
    virtual void mouse_move(double x, double y) = 0;
    virtual void mouse_button(bool down, double x, double y) = 0;
    virtual void wheel(double x, double y, double clicks) = 0;
    virtual void key(std::string_view name) = 0;
    /// `TIME export FILE`: write the current surface to FILE (default: ignored).
    virtual void export_file(std::string_view /*file*/) {}
    /// `TIME load FILE`: load FILE in place of the surface shown (default: ignored).
    virtual void load_file(std::string_view /*file*/) {}
};

/// Plays a script against a clock: `play(t)` sends every event due by time t, and for a drag in
/// progress one move to the interpolated point (so a drag becomes as many moves as frames).
class ScriptPlayer
{
public:
    explicit ScriptPlayer(std::vector<ScriptEvent> events);
    void play(double t, InputSink& sink);
    /// Every event was sent and no drag is in progress.
    [[nodiscard]] bool finished() const noexcept;
    /// Time of the end of the last event (s).
    [[nodiscard]] double end_time() const noexcept;

private:
    std::vector<ScriptEvent> events_;
    std::size_t next_ = 0;
    const ScriptEvent* drag_ = nullptr;  ///< the drag in progress
};

}  // namespace pliant::viewer
