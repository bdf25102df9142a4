// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "cli_common.h"

#include <pliant/core/file_io.h>
#include <pliant/mesh/io.h>
#include <pliant/net/enet_transport.h>
#include <pliant/net/secure_transport.h>
#include <pliant/net/transport.h>

#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

namespace pliant::cli
{

void configure_logging(const GlobalOptions& options)
{
    if (!spdlog::get("pliant"))
        spdlog::set_default_logger(spdlog::stderr_color_mt("pliant"));
    spdlog::set_pattern("%^%l%$: %v");
    spdlog::set_level(options.quiet     ? spdlog::level::err
                      : options.verbose ? spdlog::level::debug
                                        : spdlog::level::info);
}

std::string printable(std::string_view text)
{
    std::string out;
    out.reserve(text.size());
    for (const char c : text)
    {
        const auto b = static_cast<unsigned char>(c);
        if ((b < 0x20 && b != '\n') || b == 0x7f)
        {
            char hex[5];
            std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned>(b));
            out += hex;
        }
        else
            out += c;
    }
    return out;
}

int report(const core::Error& error)
{
    spdlog::error("{} [{}]", printable(error.message), core::to_string(error.code));
    switch (error.code)
    {
    case core::ErrorCode::NotConverged:
    case core::ErrorCode::NetworkError:
    case core::ErrorCode::GraphicsError:
    case core::ErrorCode::OutOfMemory: return k_exit_failure;  // the machine, not the input
    case core::ErrorCode::Cancelled: return k_exit_interrupted;
    default: return k_exit_bad_input;
    }
}

void warn_if_more_threads_than_cores(int threads, const std::string& what)
{
    const unsigned cores = std::thread::hardware_concurrency();
    if (cores > 0 && threads > static_cast<int>(cores))
        spdlog::warn(
            "{} {} is above the {} logical cores of this machine: the result is the "
            "same, but the threads take turns and run slower; give at most {}",
            what, threads, cores, cores);
}

int report_out_of_memory()
{
    // Logged without formatting into new strings where it can be helped: memory is short.
    spdlog::error(
        "out of memory: the command needed more than the system gives this process "
        "(free memory, `ulimit -v`, a container's limit); a lower level or fewer "
        "threads need less [out-of-memory]");
    return k_exit_failure;
}

CLI::Validator existing_input_file(std::string what)
{
    return CLI::Validator(
        [what](std::string& value) -> std::string
        {
            if (auto ok = core::check_input_file(value, what); !ok)
                throw InputFileError{ok.error()};
            return {};
        },
        "FILE");
}

core::Error in_grid_file(const std::string& grid_path, core::Error error)
{
    if (!grid_path.empty() && (error.code == core::ErrorCode::DegenerateFace ||
                               error.code == core::ErrorCode::NonFiniteCoordinate))
        error.message = grid_path + ": " + error.message;
    return error;
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b)
{
    std::error_code ec;
    if (std::filesystem::equivalent(a, b, ec))
        return true;
    const auto resolved = [](const std::filesystem::path& p)
    {
        std::error_code e;
        auto r = std::filesystem::weakly_canonical(p, e);
        return e ? std::filesystem::absolute(p, e).lexically_normal() : r;
    };
    return resolved(a) == resolved(b);
}

core::Result<void> check_writable(const std::filesystem::path& path, std::string_view what)
{
    if (auto ok = core::check_output_path(path, what); !ok)
        return ok;
    // A .gltf's buffer goes to <stem>.bin beside it, named in a URI (mesh::export_mesh).
    if (auto ok = mesh::check_export_name(path); !ok)
        return ok;
    if (lower_extension(path) == ".gltf")
        return core::check_output_path(gltf_buffer_of(path),
                                       std::string(what) + " (the .gltf's buffer)");
    return {};
}

std::filesystem::path gltf_buffer_of(const std::filesystem::path& gltf)
{
    return std::filesystem::path(gltf).replace_extension(".bin");
}

std::optional<std::string> file_clash(std::span<const NamedFile> inputs,
                                      std::span<const NamedFile> outputs)
{
    // Every file the outputs write, a .gltf's buffer as a file of its own.
    struct Written
    {
        std::filesystem::path path;
        std::string what;
    };
    std::vector<Written> written;
    for (const NamedFile& out : outputs)
    {
        if (out.path.empty())
            continue;
        written.push_back({out.path, std::string(out.what) + " " + out.path.string()});
        if (lower_extension(out.path) == ".gltf")
            written.push_back({gltf_buffer_of(out.path), gltf_buffer_of(out.path).string() +
                                                             " (the buffer of " +
                                                             std::string(out.what) + "'s .gltf)"});
    }
    // An input that does not exist is replaced by nothing: reading it fails with its own
    // message ("no such file"), which is the user's real problem.
    std::error_code ec;
    for (const Written& w : written)
        for (const NamedFile& in : inputs)
            if (!in.path.empty() && std::filesystem::exists(in.path, ec) &&
                same_file(w.path, in.path))
                return w.what + " would replace the input " + std::string(in.what) + " " +
                       in.path.string() + "; give another output file";
    for (std::size_t a = 0; a < written.size(); ++a)
        for (std::size_t b = a + 1; b < written.size(); ++b)
            if (same_file(written[a].path, written[b].path))
                return written[a].what + " and " + written[b].what +
                       " are one file: one would overwrite the other; give each output its "
                       "own file";
    return std::nullopt;
}

std::filesystem::path bundled_mesh()
{
    // Installed layout first (<prefix>/share/pliant/spot.obj next to <prefix>/bin/pliant), then
    // the source tree this binary was built from.
    std::error_code ec;
    const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec)
    {
        const auto installed = exe.parent_path().parent_path() / "share" / "pliant" / "spot.obj";
        if (std::filesystem::exists(installed, ec))
            return installed;
    }
    return std::filesystem::path(PLIANT_DATA_DIR) / "spot.obj";
}

ProgressBar::ProgressBar(const GlobalOptions& options)
    : enabled_(!options.quiet), tty_(::isatty(STDERR_FILENO) == 1)
{
}

ProgressBar::~ProgressBar()
{
    if (enabled_ && tty_ && !phase_.empty() && last_step_ >= 0 && last_step_ < 100)
        std::fputc('\n', stderr);
}

void ProgressBar::update(std::string_view phase, double fraction) noexcept
{
    if (!enabled_)
        return;
    const auto now = std::chrono::steady_clock::now();
    if (phase != phase_)
    {
        phase_.assign(phase);
        last_step_ = -1;
        phase_start_ = now;
    }
    fraction = fraction < 0.0 ? 0.0 : (fraction > 1.0 ? 1.0 : fraction);
    const int percent = static_cast<int>(fraction * 100.0);
    const double elapsed = std::chrono::duration<double>(now - phase_start_).count();
    if (tty_)
    {
        // redraw at most 20 times a second, always at the end, and at least every second so
        // that the elapsed time moves while the percentage does not
        if ((percent == last_step_ &&
             (percent >= 100 || now - last_draw_ < std::chrono::seconds(1))) ||
            (percent < 100 && now - last_draw_ < std::chrono::milliseconds(50)))
            return;
        constexpr int k_width = 30;
        const int filled = static_cast<int>(fraction * k_width);
        std::fprintf(stderr, "\r%-22.22s [%.*s%*s] %3d%% %6.1fs", phase_.c_str(), filled,
                     "##############################", k_width - filled, "", percent, elapsed);
        if (percent >= 100)
            std::fputc('\n', stderr);
        std::fflush(stderr);
        last_draw_ = now;
        last_step_ = percent;
    }
    else
    {
        // One line per 10 %, once the phase has run a second (a log of a short phase keeps
        // only its end), and always its end.
        const int step = percent / 10;
        if ((step == last_step_ / 10 && last_step_ >= 0) || (percent < 100 && elapsed < 1.0))
            return;
        std::fprintf(stderr, "%s: %d%% (%.1fs)\n", phase_.c_str(), step * 10, elapsed);
        last_step_ = step * 10;
    }
}

namespace
{
volatile std::sig_atomic_t g_interrupted = 0;
volatile std::sig_atomic_t g_signals = 0;  // signals heard since install_interrupt_flag

extern "C" void on_interrupt(int /*signal_number*/)
{
    g_interrupted = 1;
    g_signals = g_signals + 1;
}

void install_handler(bool reset)
{
    struct sigaction action
    {
    };
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = reset ? SA_RESETHAND : 0;
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
}
}  // namespace

const volatile std::sig_atomic_t* install_interrupt_flag()
{
    g_interrupted = 0;
    g_signals = 0;
    // sigaction, not std::signal: glibc's std::signal restarts an interrupted system call, so
    // a command waiting in open() for a FIFO's reader (or in write() on a full pipe) went on
    // waiting after the first Ctrl-C. Without SA_RESTART the wait ends with EINTR and the
    // command stops (core::write_files says "interrupted"). Waits that poll (ENet's, the
    // transport's ppoll) were never restarted and loop on EINTR as before; std::this_thread::
    // sleep_for, fstreams and condition variables retry. SA_RESETHAND: a second Ctrl-C ends the
    // process at once.
    install_handler(true);
    return &g_interrupted;
}

const volatile std::sig_atomic_t* install_counted_interrupt_flag()
{
    g_interrupted = 0;
    g_signals = 0;
    install_handler(false);
    return &g_interrupted;
}

int interrupt_signals()
{
    return static_cast<int>(g_signals);
}

namespace
{
/// A finite number from all of `text` (as CLI11 converts a double), or why it is not one.
std::variant<double, std::string> finite_number(const std::string& text)
{
    double value = 0.0;
    if (!CLI::detail::lexical_cast(text, value))
        return text + " is not a number";
    if (!std::isfinite(value))
        return text + " is not a finite number";
    return value;
}

/// `%g` of a bound: 0.5, 120, 1e-06.
std::string bound(double v)
{
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", v);
    return buffer;
}
}  // namespace

CLI::Validator positive_number()
{
    return {[](std::string& text)
            {
                auto v = finite_number(text);
                if (const auto* why = std::get_if<std::string>(&v))
                    return *why;
                return std::get<double>(v) > 0.0 ? std::string()
                                                 : text + " is not positive; give a number > 0";
            },
            "POSITIVE", "POSITIVE"};
}

CLI::Validator whole_number_in(long long lo, long long hi)
{
    const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
    return {[lo, hi, range](std::string& text)
            {
                long long v = 0;
                const char* end = text.data() + text.size();
                const auto [p, ec] = std::from_chars(text.data(), end, v);
                if (text.empty() || ec == std::errc::invalid_argument || p != end)
                    return text + " is not a whole number; give one from " + range;
                if (ec == std::errc::result_out_of_range || v < lo || v > hi)
                    return text + " is not in " + range;
                return std::string();
            },
            "INT in [" + std::to_string(lo) + " - " + std::to_string(hi) + "]", "WHOLE_NUMBER_IN"};
}

CLI::Validator non_negative_number()
{
    return {[](std::string& text)
            {
                auto v = finite_number(text);
                if (const auto* why = std::get_if<std::string>(&v))
                    return *why;
                return std::get<double>(v) >= 0.0 ? std::string()
                                                  : text + " is negative; give a number >= 0";
            },
            "NONNEGATIVE", "NONNEGATIVE"};
}

CLI::Validator number_in(double lo, double hi)
{
    const std::string range = "[" + bound(lo) + ", " + bound(hi) + "]";
    return {[lo, hi, range](std::string& text)
            {
                auto v = finite_number(text);
                if (const auto* why = std::get_if<std::string>(&v))
                    return *why;
                const double x = std::get<double>(v);
                return x >= lo && x <= hi ? std::string()
                                          : text + " is outside " + range + "; give a number in it";
            },
            range, "RANGE"};
}

CLI::Validator no_minus_sign()
{
    return {[](std::string& text)
            {
                if (text.find('-') != std::string::npos)
                    return text + " is negative; give a whole number >= 0";
                // CLI11 saturates a number past 2^64 - 1 without a word.
                std::uint64_t v = 0;
                const char* end = text.data() + text.size();
                const auto [p, ec] = std::from_chars(text.data(), end, v);
                if (ec == std::errc::result_out_of_range)
                    return text + " is too large; give a whole number below 2^64";
                // CLI11 alone said "Could not convert: --ticks = 1e30".
                if (ec != std::errc() || p != end)
                    return text + " is not a whole number; give one >= 0 (digits only)";
                return std::string();
            },
            "", "UNSIGNED"};
}

CLI::Validator port_number(unsigned lowest)
{
    return {[lowest](std::string& text)
            {
                unsigned value = 0;
                const char* end = text.data() + text.size();
                const auto [ptr, ec] = std::from_chars(text.data(), end, value);
                if (ec == std::errc() && ptr == end && value >= lowest && value <= 65535U)
                    return std::string();
                const std::string range = "a whole number from " + std::to_string(lowest) +
                                          " to 65535" + (lowest == 0 ? " (0: any free port)" : "");
                if (text.find('-') != std::string::npos)
                    return text + " is negative; a UDP port is " + range;
                return text + " is not a UDP port; give " + range;
            },
            "", "PORT"};
}

std::string lower_extension(const std::filesystem::path& p)
{
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

void add_secret_options(CLI::App* cmd, std::string& passphrase, std::string& key_file)
{
    cmd->add_option("--passphrase", passphrase,
                    "Shared secret of the session (Argon2id); or set PLIANT_PASSPHRASE")
        ->check(
            [](const std::string& s)
            {
                return s.empty() ? std::string(
                                       "an empty passphrase would leave the session "
                                       "open to anyone: give one, or leave the option out")
                                 : std::string();
            });
    cmd->add_option("--key-file", key_file, "File whose bytes are the shared secret")
        ->check(existing_input_file("--key-file"))
        ->excludes("--passphrase");
}

std::string refused_summary(net::Transport& transport, std::uint64_t auth_refused)
{
    net::Transport* wire = &transport;
    if (auto* secure = dynamic_cast<net::SecureTransport*>(&transport))
        wire = &secure->inner();
    const std::optional<net::EnetCounters> enet = net::enet_counters(*wire);
    const std::uint64_t full = enet ? enet->refused_full : 0;
    const std::uint64_t per_source = enet ? enet->refused_per_source : 0;
    std::string kinds;
    const auto kind = [&kinds](std::uint64_t n, const char* what)
    {
        if (n > 0)
            kinds += (kinds.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    kind(auth_refused, "without the secret");
    kind(full, "session full");
    kind(per_source, "too many from one address");
    return std::to_string(auth_refused + full + per_source) + " connections refused" +
           (kinds.empty() ? std::string() : " (" + kinds + ")");
}

}  // namespace pliant::cli
