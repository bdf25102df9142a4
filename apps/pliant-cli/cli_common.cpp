// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "cli_common.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>

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

int report(const core::Error& error)
{
    spdlog::error("{} [{}]", error.message, core::to_string(error.code));
    switch (error.code)
    {
    case core::ErrorCode::NotConverged:
    case core::ErrorCode::NetworkError: return k_exit_failure;
    default: return k_exit_bad_input;
    }
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
        // redraw at most 20 times a second, and always at the end
        if (percent == last_step_ ||
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
        const int step = percent / 10;  // one line per 10 %
        if (step == last_step_ / 10 && last_step_ >= 0)
            return;
        std::fprintf(stderr, "%s: %d%% (%.1fs)\n", phase_.c_str(), step * 10, elapsed);
        last_step_ = step * 10;
    }
}

namespace
{
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_interrupt(int signal_number)
{
    g_interrupted = 1;
    std::signal(signal_number, SIG_DFL);  // a second Ctrl-C ends the process at once
}
}  // namespace

const volatile std::sig_atomic_t* install_interrupt_flag()
{
    g_interrupted = 0;
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    return &g_interrupted;
}

}  // namespace pliant::cli
