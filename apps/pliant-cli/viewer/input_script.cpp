// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "input_script.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace pliant::viewer
{
namespace
{

std::string hex_byte(unsigned char c)
{
    constexpr char digits[] = "0123456789abcdef";
    return {digits[c >> 4], digits[c & 15]};
}

core::Error parse_error(std::string_view source, std::size_t line, const std::string& what)
{
    return {core::ErrorCode::ParseError,
            std::string(source) + ":" + std::to_string(line) + ": " + what};
}

bool is_known_key(std::string_view key)
{
    return std::find(k_script_keys.begin(), k_script_keys.end(), key) != k_script_keys.end();
}

bool read_number(std::istringstream& in, double& out)
{
    std::string word;
    if (!(in >> word))
        return false;
    char* end = nullptr;
    out = std::strtod(word.c_str(), &end);
    return end != word.c_str() && *end == '\0' && std::isfinite(out);
}

}  // namespace

core::Result<std::vector<ScriptEvent>> parse_input_script(std::string_view text,
                                                          std::string_view source)
{
    std::vector<ScriptEvent> events;
    std::istringstream lines{std::string(text)};
    std::string line;
    std::size_t number = 0;
    while (std::getline(lines, line))
    {
        ++number;
        if (const std::size_t hash = line.find('#'); hash != std::string::npos)
            line.resize(hash);
        std::istringstream in(line);
        ScriptEvent e;
        e.line = number;
        if (!read_number(in, e.time))
        {
            if (line.find_first_not_of(" \t\r") == std::string::npos)
                continue;  // blank or comment
            return parse_error(source, number, "expected a time in seconds first");
        }
        if (e.time < 0.0)
            return parse_error(source, number, "negative time");
        std::string command;
        in >> command;
        if (command == "drag")
        {
            e.kind = ScriptEvent::Kind::Drag;
            std::string arrow;
            std::string for_word;
            if (!read_number(in, e.x0) || !read_number(in, e.y0) || !(in >> arrow) ||
                arrow != "->" || !read_number(in, e.x1) || !read_number(in, e.y1) ||
                !(in >> for_word) || for_word != "for" || !read_number(in, e.duration))
                return parse_error(source, number,
                                   "expected `TIME drag X0 Y0 -> X1 Y1 for SECONDS`");
            if (e.duration < 0.0)
                return parse_error(source, number, "negative drag duration");
        }
        else if (command == "wheel")
        {
            e.kind = ScriptEvent::Kind::Wheel;
            if (!read_number(in, e.x0) || !read_number(in, e.y0) || !read_number(in, e.clicks))
                return parse_error(source, number, "expected `TIME wheel X Y CLICKS`");
        }
        else if (command == "key")
        {
            e.kind = ScriptEvent::Kind::Key;
            if (!(in >> e.key))
                return parse_error(source, number, "expected `TIME key NAME`");
            std::transform(e.key.begin(), e.key.end(), e.key.begin(),
                           [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
            if (!is_known_key(e.key))
                return parse_error(source, number,
                                   "unknown key `" + e.key +
                                       "` (expected p, f12, e, w, c, h, r, space or escape)");
        }
        else if (command == "export" || command == "load")
        {
            e.kind = command == "export" ? ScriptEvent::Kind::Export : ScriptEvent::Kind::Load;
            if (!(in >> e.file))
                return parse_error(source, number, "expected `TIME " + command + " FILE`");
            // A NUL would end the name the system sees early (another file would be written),
            // and other control bytes are no one's file name.
            if (const auto bad =
                    std::find_if(e.file.begin(), e.file.end(),
                                 [](unsigned char c) { return c < 0x20 || c == 0x7f; });
                bad != e.file.end())
                return parse_error(source, number,
                                   command + " file name has a control byte (0x" +
                                       hex_byte(static_cast<unsigned char>(*bad)) +
                                       ") at character " +
                                       std::to_string(bad - e.file.begin() + 1));
            std::string ext = std::filesystem::path(e.file).extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(),
                           [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
            if (e.kind == ScriptEvent::Kind::Export && ext != ".obj" && ext != ".ply" &&
                ext != ".gltf" && ext != ".glb")
                return parse_error(
                    source, number,
                    "export file `" + e.file + "` must end in .obj, .ply, .gltf or .glb");
        }
        else
            return parse_error(
                source, number,
                "unknown command `" + command + "` (expected drag, wheel, key, export or load)");
        std::string extra;
        if (in >> extra)
            return parse_error(source, number, "unexpected `" + extra + "` at the end");
        events.push_back(std::move(e));
    }
    std::stable_sort(events.begin(), events.end(),
                     [](const ScriptEvent& a, const ScriptEvent& b) { return a.time < b.time; });
    const ScriptEvent* previous = nullptr;
    for (const ScriptEvent& e : events)
    {
        if (e.kind != ScriptEvent::Kind::Drag)
            continue;
        if (previous != nullptr && e.time < previous->time + previous->duration)
            return parse_error(source, e.line,
                               "this drag starts before the drag of line " +
                                   std::to_string(previous->line) + " ends");
        previous = &e;
    }
    return events;
}

core::Result<std::vector<ScriptEvent>> load_input_script(const std::filesystem::path& path)
{
    std::ifstream in(path);
    if (!in)
        return core::fail(core::ErrorCode::IoError, "view --script: cannot read " + path.string());
    std::stringstream text;
    text << in.rdbuf();
    return parse_input_script(text.str(), path.string());
}

ScriptPlayer::ScriptPlayer(std::vector<ScriptEvent> events) : events_(std::move(events)) {}

void ScriptPlayer::play(double t, InputSink& sink)
{
    // Finish (or advance) the drag in progress first, so a drag that ends and another event
    // due in the same frame keep their order.
    auto step_drag = [&](double now)
    {
        const ScriptEvent& d = *drag_;
        const double end = d.time + d.duration;
        if (now >= end)
        {
            sink.mouse_move(d.x1, d.y1);
            sink.mouse_button(false, d.x1, d.y1);
            drag_ = nullptr;
            return;
        }
        const double s = d.duration > 0.0 ? (now - d.time) / d.duration : 1.0;
        sink.mouse_move(d.x0 + s * (d.x1 - d.x0), d.y0 + s * (d.y1 - d.y0));
    };
    if (drag_ != nullptr)
        step_drag(t);
    while (next_ < events_.size() && events_[next_].time <= t)
    {
        const ScriptEvent& e = events_[next_++];
        switch (e.kind)
        {
        case ScriptEvent::Kind::Drag:
            sink.mouse_move(e.x0, e.y0);
            sink.mouse_button(true, e.x0, e.y0);
            drag_ = &e;
            // A drag wholly in the past (a long frame) still ends with its release.
            if (t >= e.time + e.duration)
                step_drag(t);
            break;
        case ScriptEvent::Kind::Wheel: sink.wheel(e.x0, e.y0, e.clicks); break;
        case ScriptEvent::Kind::Key: sink.key(e.key); break;
        case ScriptEvent::Kind::Export: sink.export_file(e.file); break;
        case ScriptEvent::Kind::Load: sink.load_file(e.file); break;
        }
    }
}

bool ScriptPlayer::finished() const noexcept
{
    return next_ == events_.size() && drag_ == nullptr;
}

double ScriptPlayer::end_time() const noexcept
{
    double end = 0.0;
    for (const ScriptEvent& e : events_)
        end = std::max(end, e.time + e.duration);
    return end;
}

}  // namespace pliant::viewer
