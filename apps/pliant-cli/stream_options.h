// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The state-stream options `pliant host` and `pliant join` share (--compress, --f32,
// --stream-rate, --cap, --stream-coarsen, --max-halo-age; docs/session.md §4.3, §5.1, §5.2):
// declared once, applied to SessionSettings once.

#include <pliant/session/session.h>

#include <CLI/CLI.hpp>

#include "cli_common.h"

namespace pliant::cli
{

struct StreamOptions
{
    bool compress = false;  ///< quantised-delta leaf states (docs/protocol.md §5.5)
    bool f32 = false;       ///< leaf states as f32 instead of f64
    double stream_rate_hz = session::SessionSettings{}.stream_rate_hz;  ///< per owned leaf
    double cap_mbit = 0.0;   ///< per-peer cap on leaf states and acks, Mbit/s (0: none)
    int stream_coarsen = 0;  ///< leaf states this many levels coarser (docs/session.md §5.2)
    double max_halo_age_s = session::SessionSettings{}.max_halo_age_s;  ///< fast mode, §4.3
};

inline void add_stream_options(CLI::App* cmd, StreamOptions& opt)
{
    cmd->add_flag("--compress", opt.compress,
                  "Stream quantised leaf states (steps 61 um, 0.98 mm/s), delta-coded against\n"
                  "what each receiver acknowledged, Rice-packed, several leaves per datagram:\n"
                  "about 1.4 Mbit/s per peer at level 6 and 60 Hz (docs/session.md §5.1)");
    cmd->add_flag("--f32", opt.f32,
                  "Stream leaf states as f32 instead of f64: half the bytes (18 instead of 34\n"
                  "Mbit/s per peer at level 6 and 60 Hz); what others show, and in fast mode\n"
                  "their boundary values, then carry float rounding (~6e-8 relative)")
        ->excludes("--compress");
    cmd->add_option("--stream-rate", opt.stream_rate_hz,
                    "Leaf states per second that this peer sends for each leaf it owns [Hz]")
        ->check(number_in(1.0, 1000.0))
        ->capture_default_str();
    cmd->add_option("--cap", opt.cap_mbit,
                    "With --compress: leaf-state bytes per peer at most [Mbit/s] (0: no cap)")
        ->check(non_negative_number())
        ->needs("--compress");
    cmd->add_option("--stream-coarsen", opt.stream_coarsen,
                    "Stream leaf states K levels coarser (every 2^K-th node, ~4^-K of the bytes;\n"
                    "0: off); receivers refine them by butterfly subdivision for display. Only in\n"
                    "exact sessions (the master's --mode; refused in fast ones) and not with\n"
                    "--compress; K <= 2 at levels >= 3, K <= 1 at level 2 (docs/session.md §5.2)")
        ->check(whole_number_in(0, 2))
        ->capture_default_str();
    cmd->add_option("--max-halo-age", opt.max_halo_age_s,
                    "Fast mode: the oldest a neighbour's streamed state may be when this peer\n"
                    "steps [s]; older, the peer waits for fresher states (0: no bound;\n"
                    "docs/session.md §4.3)")
        ->check(number_in(0.0, 60.0))
        ->capture_default_str();
}

inline void apply_stream_options(const StreamOptions& opt, session::SessionSettings& settings)
{
    if (opt.compress)
        settings.stream_encoding = net::ValueEncoding::QuantisedDelta;
    else if (opt.f32)
        settings.stream_encoding = net::ValueEncoding::F32;
    settings.stream_rate_hz = opt.stream_rate_hz;
    settings.bandwidth_cap_mbit_s = opt.cap_mbit;
    settings.stream_coarsen = opt.stream_coarsen;
    settings.max_halo_age_s = opt.max_halo_age_s;
}

}  // namespace pliant::cli
