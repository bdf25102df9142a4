// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// `pliant view`: the interactive viewer (GLFW + Dear ImGui, docs/viewer.md). Only built when
// viewer.cmake found GLFW and ImGui (PLIANT_HAVE_VIEWER); cmd_view.cpp parses the options.

#include <pliant/net/secure_transport.h>

#include <csignal>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace pliant::sim
{
struct MembraneState;
}

namespace pliant::viewer
{

struct ViewerOptions
{
    /// A `.pgrid`, a mesh file (remeshed at `level`), HOST:PORT (join a session), or empty (the
    /// bundled mesh).
    std::string input;
    std::filesystem::path bundled_mesh;  ///< used when `input` is empty
    int level = 6;                       ///< remeshing level for meshes
    int display_level = -1;              ///< absolute display level; -1: sim level + 1, <= 8
    int width = 1280;
    int height = 720;
    std::filesystem::path script;      ///< timed mouse events (input_script.h)
    std::filesystem::path screenshot;  ///< written at exit
    double exit_after = 0.0;           ///< s after the object first shows; 0: never
    bool participant = false;          ///< join HOST:PORT as a participant (default viewer)
    std::string name = "viewer";       ///< peer name in sessions
    std::uint16_t port = 0;            ///< UDP port for sessions (0: any when joining)
    /// The sessions' shared secret (--passphrase, --key-file, PLIANT_PASSPHRASE): every join
    /// and host goes through net::SecureTransport with it; none: unencrypted, with a warning.
    std::optional<net::SecretKey> secret;
    bool vsync = true;
    bool hide_panels = false;
    bool owner_colors = false;  ///< start in owner colours (default: displacement; C cycles)
    /// A saved state of `input` (its rest grid), checked by the caller, that the first local
    /// simulation starts from; `resume` names its file.
    std::shared_ptr<const sim::MembraneState> resume_state;
    std::filesystem::path resume;
    /// Set (to non-zero) by Ctrl-C (the CLI's install_interrupt_flag): the viewer closes as if
    /// its window were closed (a session left cleanly, the --screenshot written) and returns
    /// 130. Null: Ctrl-C keeps its default (the process ends at once).
    const volatile std::sig_atomic_t* stop = nullptr;
};

/// Runs the viewer until the window closes, `exit_after` or `stop`. \return the process exit
/// code (130 when `stop` ended it).
int run_viewer(const ViewerOptions& options);

/// Whether GLFW can start (a display to open a window on); else `why` says what failed.
bool display_available(std::string* why);

}  // namespace pliant::viewer
