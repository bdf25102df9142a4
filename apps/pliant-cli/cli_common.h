// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Shared pieces of the subcommands: global options, logging set-up, mapping errors to exit
// codes, the bundled mesh, a terminal progress bar, file extensions and the sessions' transport.

#include <pliant/core/error.h>
#include <pliant/core/progress.h>
#include <pliant/core/result.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <memory>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace pliant::net
{
class Transport;
}

namespace pliant::cli
{

/// Options every subcommand understands (given before or after the subcommand name).
struct GlobalOptions
{
    bool verbose = false;
    bool quiet = false;
};

/// Exit codes: 0 success, 1 bad input (the message says which rule), 2 usage error (CLI11),
/// 3 internal or numerical failure.
inline constexpr int k_exit_bad_input = 1;
inline constexpr int k_exit_usage = 2;
inline constexpr int k_exit_failure = 3;
/// Stopped by Ctrl-C (SIGINT) or SIGTERM after winding down cleanly (128 + SIGINT, as a shell
/// reports a process the signal ended).
inline constexpr int k_exit_interrupted = 130;

/// Sets spdlog's level from the global options (warn by default, debug with --verbose, error
/// with --quiet). Messages go to stderr; results go to stdout.
void configure_logging(const GlobalOptions& options);

/// Makes SIGINT (Ctrl-C) and SIGTERM set the returned flag instead of killing the process, so a
/// long-running command can wind down cleanly: a participant hands its leaves over, the master
/// ends the session for everyone, `simulate` keeps the frames written and says so in run.json,
/// `remesh` stops and writes nothing. A second signal kills as usual. System calls the signal
/// interrupts are not restarted: a wait on a FIFO's reader ends (EINTR) rather than going on.
const volatile std::sig_atomic_t* install_interrupt_flag();

/// install_interrupt_flag, but every signal is caught and counted (interrupt_signals), none
/// ends the process: for a command that must still clean up after a second Ctrl-C and ends
/// itself on a later one (`bench`, which otherwise left its running suite program orphaned).
const volatile std::sig_atomic_t* install_counted_interrupt_flag();
/// The signals (SIGINT, SIGTERM) heard since install_interrupt_flag or
/// install_counted_interrupt_flag.
int interrupt_signals();

/// Logs an error and returns its exit code.
int report(const core::Error& error);

/// Warns when `threads` (a -j or a scenario's `threads`) is above the logical cores this machine
/// has: the results are the same, but the threads take turns and the run is slower (-j 1024 on
/// 2 cores ran 22 times slower than -j 2).
void warn_if_more_threads_than_cores(int threads, const std::string& what);  // what: "-j"

/// Says that the command ran out of memory (std::bad_alloc reached it: the memory it had is
/// freed by then) and returns k_exit_failure.
int report_out_of_memory();

/// Wraps a subcommand body `int()` into a CLI11 callback: sets up logging, runs it, and turns a
/// non-zero result into the process's exit code; running out of memory is an error message
/// and exit status 3, not an abort.
template <typename Body>
auto command_callback(const GlobalOptions& global, Body body)
{
    return [&global, body]()
    {
        configure_logging(global);
        int rc = 0;
        try
        {
            rc = body();
        }
        catch (const std::bad_alloc&)
        {
            rc = report_out_of_memory();
        }
        if (rc != 0)
            throw CLI::RuntimeError(rc);
    };
}

/// Checks for floating-point options. CLI11's own `Range`, `PositiveNumber` and
/// `NonNegativeNumber` let "nan" through (every comparison with it is false, so `--duration nan`
/// ran until Ctrl-C) and print their bound as DBL_MAX in full. These refuse anything but a
/// finite number and say which rule the value breaks ("--max-force: -2 is negative; give a
/// number >= 0"); --help shows them as FLOAT:POSITIVE, FLOAT:NONNEGATIVE, FLOAT:[LO, HI].
[[nodiscard]] CLI::Validator positive_number();
[[nodiscard]] CLI::Validator non_negative_number();
/// A whole number in [lo, hi]: "abc is not a whole number", "12 is not in 1 to 10" (CLI11's
/// Range said "Value abc not in range 1 to 10" of text that is no number at all).
[[nodiscard]] CLI::Validator whole_number_in(long long lo, long long hi);
[[nodiscard]] CLI::Validator number_in(double lo, double hi);
/// For unsigned integer options: CLI11 converts "-5" to 2^64 - 5, and saturates a number past
/// 2^64 - 1, without a word, and says "Could not convert" of "1e30" or "abc"; these are each
/// said as what they are.
[[nodiscard]] CLI::Validator no_minus_sign();
/// For --port: a whole number from `lowest` to 65535, said as such ("--port: 70000 is not a UDP
/// port; give a whole number from 1 to 65535"; CLI11 alone said "Could not convert").
[[nodiscard]] CLI::Validator port_number(unsigned lowest);

/// For options naming a file to read (--script, --key-file, --resume, --scenario, --mesh,
/// RECORDING): checked while the command line is parsed, before any work, by
/// core::check_input_file. A missing, folder or unreadable file is bad input, not a usage error:
/// the check throws InputFileError, which main() reports as the commands report their GRID and
/// MESH arguments ("error: --script: plan.txt: no such file [io-error]", exit 1).
struct InputFileError
{
    core::Error error;
};
[[nodiscard]] CLI::Validator existing_input_file(std::string what);

/// An error of a model built on the rest geometry read from `grid_path`: DegenerateFace and
/// NonFiniteCoordinate are about the file's positions, so the file is named first
/// ("flat.pgrid: the rest surface has no normal at node (1, 1): ..."); any other error, or an
/// empty path (a sphere of --level), as it is.
[[nodiscard]] core::Error in_grid_file(const std::string& grid_path, core::Error error);

/// Whether `path` can be written (core::check_output_path: nothing is created), and for a
/// `.gltf` its buffer file too (gltf_buffer_of): checked before a long run starts, so a bad
/// --stats or output path fails at once, with the reason. \return IoError naming `what`, the
/// file and the system's reason.
core::Result<void> check_writable(const std::filesystem::path& path, std::string_view what);

/// Whether `a` and `b` name one file: the same path once resolved (links, `..`), or two names of
/// an existing file (a hard link). For refusing an output that would replace an input.
[[nodiscard]] bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// Where `mesh::export_mesh` writes a `.gltf`'s buffer: `<stem>.bin` beside it.
[[nodiscard]] std::filesystem::path gltf_buffer_of(const std::filesystem::path& gltf);

/// A file a command reads or writes, and the argument or option that names it ("GRID", "-o").
struct NamedFile
{
    std::filesystem::path path;
    std::string_view what;
};

/// The usage rule of every command that reads some files and writes others: no output may
/// replace an input, and no two outputs may be one file. Each output, and a `.gltf`'s buffer
/// file (gltf_buffer_of), is compared with every input and every other output (same_file);
/// empty paths and inputs that do not exist are skipped. \return the first clash, worded for the
/// user ("-o rest.pgrid would replace the input GRID rest.pgrid; give another output file"), or
/// nothing.
[[nodiscard]] std::optional<std::string> file_clash(std::span<const NamedFile> inputs,
                                                    std::span<const NamedFile> outputs);

/// The bundled default mesh (data/spot.obj), found next to the executable's install or in the
/// source tree.
std::filesystem::path bundled_mesh();

/// `text` for a terminal: each control byte (below 0x20 but a newline, and 0x7f) as `\xNN`, so
/// that a file name holding an escape sequence cannot recolour or rewrite the terminal; other
/// bytes (UTF-8 names) as they are.
std::string printable(std::string_view text);

/// The extension of `p` in lower case, with its dot (".ply"), or "" when it has none.
std::string lower_extension(const std::filesystem::path& p);

/// `--passphrase` and `--key-file` (exclusive), for `host` and `join`. An empty passphrase is a
/// usage error: `--passphrase "$SECRET"` with SECRET unset would otherwise open the session to
/// anyone.
void add_secret_options(CLI::App* cmd, std::string& passphrase, std::string& key_file);

/// "N connections refused" for the last line of `host` and `join`, N = the encryption layer's
/// refusals (`auth_refused`) plus the connections ENet closed at once for want of room (the
/// session full, or too many from one address), each kind named when there are any:
/// "3 connections refused (2 without the secret, 1 session full)"; "0 connections refused".
[[nodiscard]] std::string refused_summary(net::Transport& transport, std::uint64_t auth_refused);

/// A progress bar on stderr: redrawn in place on a terminal, a line per 10 % otherwise, nothing
/// with --quiet.
class ProgressBar final : public core::ProgressSink
{
public:
    explicit ProgressBar(const GlobalOptions& options);
    ~ProgressBar() override;
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;
    void update(std::string_view phase, double fraction) noexcept override;
    /// The work stops (ErrorCode::Cancelled) once `*flag` is set (install_interrupt_flag).
    void stop_on(const volatile std::sig_atomic_t* flag) noexcept { stop_ = flag; }
    [[nodiscard]] bool stop_requested() const noexcept override
    {
        return stop_ != nullptr && *stop_ != 0;
    }

private:
    const volatile std::sig_atomic_t* stop_ = nullptr;
    bool enabled_;
    bool tty_;
    std::string phase_;
    int last_step_ = -1;
    std::chrono::steady_clock::time_point phase_start_;
    std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace pliant::cli
