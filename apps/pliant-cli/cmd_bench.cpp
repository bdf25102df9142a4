// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant bench [SUITE...] [--quick] [--out DIR]`: runs the benchmark programs and collects
// their results (docs/results.md).
//
// Design: one implementation per suite. The measurements live in the benchmark programs under
// bench/ (they link Google Benchmark and OpenMesh, which the `pliant` executable must not), and
// every program writes the same rows (bench/common/bench_report.h: suite, case, level, size,
// size_unit, metric, value, unit) with `--json FILE --csv FILE`, and has a `--quick` mode. This
// command only finds the programs (the build tree's bench folder, compiled in; --bench-dir or
// PLIANT_BENCH_DIR override it), runs each as a child process (its console output goes to
// DIR/<suite>.log) with a progress line, gathers DIR/<suite>.csv and .json into DIR/results.json
// with a description of the machine (CPU model, cores, memory, load average before and after,
// GL_RENDERER from the render suite), and runs gnuplot on scripts/plots/*.gp to draw the PNGs.
// Without gnuplot it says how to install it and still writes the data.
#include <pliant/core/file_io.h>

#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace pliant::cli
{
namespace
{

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

/// One suite: its name, the program (in <bench dir>/<folder>/) and what it measures.
struct Suite
{
    const char* name;
    const char* folder;
    const char* program;
    const char* what;
    const char* mode = nullptr;  ///< the program's mode option, if the suite is one of its modes
};

// Cheapest first, so that a quick run shows results early.
constexpr std::array<Suite, 11> k_suites{{
    {"subdiv", "subdiv", "bench_subdiv",
     "butterfly refinement 6->7..9->10 vs OpenMesh and a STREAM copy"},
    {"net", "net", "bench_net",
     "state-streaming bandwidth per level, codec throughput, ENet round trip"},
    {"sim", "sim", "pliant_bench_sim",
     "RKF45 ns per node-step, ms per step, CPU share in real time, 1 and 2 threads"},
    {"mixed", "sim", "pliant_bench_sim",
     "the same in mixed precision (float increments over the double state)", "mixed"},
    {"session", "session", "pliant_bench_session",
     "per-peer compute and bandwidth for 1..4 peers, with and without partitioning"},
    {"steps", "session", "pliant_bench_session",
     "each peer's sim step against one process's, per partition, 2..4 peers, levels 6..8",
     "--steps"},
    {"latency", "session", "pliant_bench_session",
     "grab to change on the other peers (held and drawn), exact and fast, levels 6..8",
     "--latency"},
    {"cpu", "session", "pliant_bench_session",
     "all the work of each peer per simulated second against one peer alone, levels 6..8", "--cpu"},
    {"join", "session", "pliant_bench_session",
     "4 peers joining over ENet through a lossy 100 ms relay: ENet's timers against the "
     "transport's",
     "--join"},
    {"render", "render", "bench_render",
     "fps at 1280x720, texture path vs vertex buffers (offscreen OpenGL)"},
    {"remesh", "remesh", "bench_remesh", "PSNR and seconds per phase per mesh and level"},
}};

/// Plots: the gnuplot script in the plots folder, the CSV files it needs, the PNG it writes.
struct Plot
{
    const char* script;
    const char* needs;
    const char* png;
};

constexpr std::array<Plot, 6> k_plots{{
    {"sim.gp", "sim", "sim.png"},
    {"session.gp", "session", "session.png"},
    {"bandwidth.gp", "net", "bandwidth.png"},
    {"remesh.gp", "remesh", "remesh.png"},
    {"subdiv.gp", "subdiv", "subdiv.png"},
    {"render.gp", "render", "render.png"},
}};

struct BenchOptions
{
    std::vector<std::string> suites;
    bool quick = false;
    fs::path out = "bench-results";
    fs::path bench_dir;
    fs::path plots_dir;
    bool plots = true;
};

std::string read_text(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

/// The first "model name" line of /proc/cpuinfo (x86) or "Hardware"/"cpu model" elsewhere.
std::string cpu_model()
{
    std::istringstream in(read_text("/proc/cpuinfo"));
    std::string line;
    while (std::getline(in, line))
        for (const char* key : {"model name", "Hardware", "cpu model"})
            if (line.rfind(key, 0) == 0)
                if (const auto colon = line.find(':'); colon != std::string::npos)
                {
                    std::string v = line.substr(colon + 1);
                    v.erase(0, v.find_first_not_of(" \t"));
                    return v;
                }
    return "unknown";
}

/// The three load averages of /proc/loadavg (empty if unreadable).
std::vector<double> load_average()
{
    std::istringstream in(read_text("/proc/loadavg"));
    std::vector<double> v(3, 0.0);
    if (!(in >> v[0] >> v[1] >> v[2]))
        return {};
    return v;
}

double memory_gib()
{
    std::istringstream in(read_text("/proc/meminfo"));
    std::string key;
    double kib = 0.0;
    while (in >> key)
    {
        if (key == "MemTotal:" && (in >> kib))
            return kib / (1024.0 * 1024.0);
        in.ignore(256, '\n');
    }
    return 0.0;
}

std::string utc_now()
{
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

Json machine_json()
{
    Json m;
    m["cpu_model"] = cpu_model();
    m["logical_cores"] = std::thread::hardware_concurrency();
    m["memory_gib"] = memory_gib();
    utsname u{};
    if (uname(&u) == 0)
        m["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
    return m;
}

/// An executable on PATH, or empty.
fs::path find_on_path(const std::string& name)
{
    const char* path = std::getenv("PATH");
    std::istringstream in(path != nullptr ? path : "/usr/bin:/bin");
    std::string dir;
    while (std::getline(in, dir, ':'))
    {
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
        if (::access(candidate.c_str(), X_OK) == 0)
            return candidate;
    }
    return {};
}

/// Runs `argv` with stdout and stderr appended to `log`, showing a progress line with the
/// elapsed time. Once `*stop` is set (Ctrl-C) the child is sent SIGINT too (from a terminal it
/// already has it: it is in the same process group) and waited for; a second one kills it
/// (SIGKILL) and pliant winds down as after the first. \return the exit status
/// (128 + signal when killed, 127 when it cannot start).
int run_child(const std::vector<std::string>& argv, const fs::path& log, const std::string& label,
              const GlobalOptions& global, double& seconds,
              const volatile std::sig_atomic_t* stop = nullptr)
{
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    std::vector<char*> args;
    std::vector<std::string> storage = argv;
    for (std::string& s : storage)
        args.push_back(s.data());
    args.push_back(nullptr);
    pid_t pid = 0;
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0)
        return 127;
    const bool tty = ::isatty(STDERR_FILENO) == 1 && !global.quiet;
    int status = 0;
    bool forwarded = false;
    for (;;)
    {
        if (stop != nullptr && *stop != 0 && !forwarded)
        {
            ::kill(pid, SIGINT);
            forwarded = true;
        }
        // A second Ctrl-C ends the program at once (were pliant ended instead, the program
        // would run on, orphaned); a third ends pliant too.
        if (forwarded && interrupt_signals() >= 2)
        {
            ::kill(pid, SIGKILL);
            if (interrupt_signals() >= 3)
            {
                (void)waitpid(pid, &status, 0);
                std::_Exit(k_exit_interrupted);
            }
        }
        const pid_t done = waitpid(pid, &status, WNOHANG);
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (done == pid || done < 0)
            break;
        if (tty)
            std::fprintf(stderr, "\r%s ... %.0f s", label.c_str(), seconds);
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    if (tty)
        std::fprintf(stderr, "\r%*s\r", static_cast<int>(label.size()) + 16, "");
    if (WIFEXITED(status))
        return WEXITSTATUS(status);
    if (WIFSIGNALED(status))
        return 128 + WTERMSIG(status);
    return 127;
}

fs::path default_bench_dir()
{
    if (const char* env = std::getenv("PLIANT_BENCH_DIR"); env != nullptr && *env != '\0')
        return env;
#if defined(PLIANT_BENCH_DIR)
    return PLIANT_BENCH_DIR;
#else
    return "bench";
#endif
}

fs::path default_plots_dir()
{
#if defined(PLIANT_PLOTS_DIR)
    return PLIANT_PLOTS_DIR;
#else
    return "scripts/plots";
#endif
}

/// The program of a suite: <dir>/<folder>/<program>, or <dir>/<program> (a flat folder).
fs::path program_path(const fs::path& dir, const Suite& s)
{
    std::error_code ec;
    const fs::path nested = dir / s.folder / s.program;
    if (fs::is_regular_file(nested, ec))
        return nested;
    const fs::path flat = dir / s.program;
    if (fs::is_regular_file(flat, ec))
        return flat;
    return nested;
}

int run_bench(const BenchOptions& opt, const GlobalOptions& global)
{
    using core::ErrorCode;
    // Which suites, in the table's order, each once.
    std::vector<const Suite*> chosen;
    std::string names;
    for (const Suite& s : k_suites)
        names += std::string(names.empty() ? "" : " ") + s.name;
    for (const std::string& want : opt.suites)
    {
        if (want == "all")
            continue;
        const auto it = std::find_if(k_suites.begin(), k_suites.end(),
                                     [&](const Suite& s) { return want == s.name; });
        if (it == k_suites.end())
        {
            spdlog::error("bench: unknown suite '{}' (suites: {}, or all)", want, names);
            return k_exit_usage;
        }
    }
    const bool all = opt.suites.empty() ||
                     std::find(opt.suites.begin(), opt.suites.end(), "all") != opt.suites.end();
    for (const Suite& s : k_suites)
        if (all || std::find(opt.suites.begin(), opt.suites.end(), s.name) != opt.suites.end())
            chosen.push_back(&s);

    const fs::path bench_dir = opt.bench_dir.empty() ? default_bench_dir() : opt.bench_dir;
    std::vector<fs::path> programs;
    for (const Suite* s : chosen)
    {
        programs.push_back(program_path(bench_dir, *s));
        if (::access(programs.back().c_str(), X_OK) != 0)
            return report(
                {ErrorCode::IoError,
                 "bench: the " + std::string(s->name) + " program " + programs.back().string() +
                     " is missing: build the benchmark programs with the release preset "
                     "(`cmake --preset release && cmake --build --preset release`), or point "
                     "--bench-dir or PLIANT_BENCH_DIR at a build's bench folder"});
    }

    if (opt.out.empty())
    {
        spdlog::error("bench: --out is empty; give a folder (default bench-results)");
        return k_exit_usage;
    }
    std::error_code ec;
    fs::create_directories(opt.out, ec);
    if (ec)
        return report(
            {ErrorCode::IoError, "bench: cannot create " + opt.out.string() + ": " + ec.message()});

    Json results;
    results["pliant_version"] = PLIANT_VERSION;
    results["started_utc"] = utc_now();
    results["quick"] = opt.quick;
    std::string command = "pliant bench";
    for (const Suite* s : chosen)
        command += std::string(" ") + s->name;
    if (opt.quick)
        command += " --quick";
    command += " --out " + opt.out.string();
    results["command"] = command;
    results["machine"] = machine_json();
    results["machine"]["load_average_start"] = load_average();
    results["bench_dir"] = fs::absolute(bench_dir, ec).string();
    results["suites"] = Json::object();

    int failures = 0;
    // Ctrl-C or SIGTERM: the running suite is stopped, no further suite starts, and results.json
    // is written with the suites that completed (their CSV and JSON files stay).
    const volatile std::sig_atomic_t* interrupted = install_counted_interrupt_flag();
    std::string interrupted_in;  // the suite Ctrl-C stopped ("" between suites)
    std::vector<std::string> completed;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < chosen.size() && *interrupted == 0; ++i)
    {
        const Suite& s = *chosen[i];
        // The suite writes beside its final files and they replace an earlier run's only when
        // it completes: a suite that fails or is stopped leaves the earlier results as they
        // were (its console output goes to <suite>-failed.log).
        const fs::path csv_done = opt.out / (std::string(s.name) + ".csv");
        const fs::path json_done = opt.out / (std::string(s.name) + ".json");
        const fs::path log_done = opt.out / (std::string(s.name) + ".log");
        const fs::path csv = opt.out / ("." + std::string(s.name) + ".csv.part");
        const fs::path json = opt.out / ("." + std::string(s.name) + ".json.part");
        fs::path log = opt.out / ("." + std::string(s.name) + ".log.part");
        fs::remove(csv, ec);
        fs::remove(json, ec);
        std::vector<std::string> argv{programs[i].string(), "--json", json.string(), "--csv",
                                      csv.string()};
        if (s.mode != nullptr)
            argv.emplace_back(s.mode);
        if (opt.quick)
            argv.emplace_back("--quick");
        const std::string label = "[" + std::to_string(i + 1) + "/" +
                                  std::to_string(chosen.size()) + "] " + s.name + " (" + s.what +
                                  ")";
        if (!global.quiet)
        {
            std::printf("%s\n", label.c_str());
            std::fflush(stdout);
        }
        double seconds = 0.0;
        const int rc = run_child(argv, log, "      running " + std::string(s.program), global,
                                 seconds, interrupted);
        Json entry;
        entry["program"] = programs[i].string();
        entry["arguments"] = std::vector<std::string>(argv.begin() + 1, argv.end());
        entry["exit_code"] = rc;
        entry["seconds"] = seconds;
        entry["load_average_after"] = load_average();
        Json parsed = Json::parse(read_text(json), nullptr, false);
        const bool done = !(*interrupted != 0 && rc != 0) && rc == 0 && !parsed.is_discarded() &&
                          parsed.contains("rows");
        const auto settle = [&](const fs::path& from, const fs::path& to)
        {
            if (done)
                fs::rename(from, to, ec);
            else
                fs::remove(from, ec);
        };
        settle(csv, csv_done);
        settle(json, json_done);
        const fs::path log_failed = opt.out / (std::string(s.name) + "-failed.log");
        fs::rename(log, done ? log_done : log_failed, ec);
        log = done ? log_done : log_failed;
        if (*interrupted != 0 && rc != 0)
        {
            entry["interrupted"] = true;
            interrupted_in = s.name;
        }
        else if (done)
        {
            completed.emplace_back(s.name);
            entry["meta"] = parsed.value("meta", Json::object());
            entry["rows"] = parsed["rows"];
            if (s.name == std::string("render") && entry["meta"].contains("gl_renderer"))
                results["machine"]["gl_renderer"] = entry["meta"]["gl_renderer"];
            if (!global.quiet)
                std::printf("      %zu rows in %.1f s -> %s, %s (console output: %s)\n",
                            entry["rows"].size(), seconds, csv_done.string().c_str(),
                            json_done.string().c_str(), log.string().c_str());
        }
        else
        {
            ++failures;
            spdlog::error("bench: {} failed (exit code {}) after {:.1f} s; its output is in {}",
                          s.program, rc, seconds, log.string());
        }
        results["suites"][s.name] = entry;
        std::fflush(stdout);
    }
    results["machine"]["load_average_end"] = load_average();
    results["interrupted"] = *interrupted != 0;
    results["total_seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (auto written = core::write_text_file(  // a path that is not UTF-8: U+FFFD, not an abort
            opt.out / "results.json",
            results.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + '\n',
            "bench");
        !written)
        return report(written.error());
    if (*interrupted != 0)
    {
        std::string done;
        for (const std::string& n : completed)
            done += (done.empty() ? "" : ", ") + n;
        spdlog::error("bench: interrupted{}; {} holds the {} suite{} that completed{}",
                      interrupted_in.empty() ? "" : " during " + interrupted_in,
                      (opt.out / "results.json").string(), completed.size(),
                      completed.size() == 1 ? "" : "s", done.empty() ? "" : " (" + done + ")");
        return k_exit_interrupted;
    }
    if (!global.quiet)
        std::printf("all results: %s (%.0f s in all)\n",
                    (opt.out / "results.json").string().c_str(),
                    results["total_seconds"].get<double>());

    if (opt.plots)
    {
        const fs::path gnuplot = find_on_path("gnuplot");
        const fs::path plots_dir = opt.plots_dir.empty() ? default_plots_dir() : opt.plots_dir;
        if (gnuplot.empty())
            std::printf(
                "plots: gnuplot not found; install it with `sudo apt-get install "
                "gnuplot-nox` (or scripts/install-deps.sh) and run the command again. "
                "The CSV and JSON data are written.\n");
        else
            for (const Plot& p : k_plots)
            {
                if (*interrupted != 0)
                    break;
                const fs::path script = plots_dir / p.script;
                if (!fs::exists(opt.out / (std::string(p.needs) + ".csv"), ec) ||
                    !fs::exists(script, ec))
                    continue;
                const std::string vars = "datadir='" + opt.out.string() + "'; outdir='" +
                                         opt.out.string() + "'; quick=" + (opt.quick ? "1" : "0");
                double seconds = 0.0;
                const fs::path log = opt.out / (std::string(p.script) + ".log");
                const int rc = run_child({gnuplot.string(), "-e", vars, script.string()}, log,
                                         "      plotting", global, seconds, interrupted);
                if (*interrupted != 0)
                    break;  // said below
                if (rc == 0)
                {
                    if (!global.quiet)
                        std::printf("plot: %s\n", (opt.out / p.png).string().c_str());
                }
                else
                {
                    ++failures;
                    spdlog::error("bench: gnuplot {} failed (exit code {}); see {}",
                                  script.string(), rc, log.string());
                }
            }
    }
    // Ctrl-C while plotting: the data are written, the other plots are not made, and bench
    // ends as interrupted (it waited for gnuplot and exited 0, or, the signal reaching gnuplot
    // too, reported its end as a failed plot).
    if (*interrupted != 0)
    {
        spdlog::error(
            "bench: interrupted while plotting; {} holds every suite's results (run "
            "the command again for the plots)",
            (opt.out / "results.json").string());
        return k_exit_interrupted;
    }
    return failures == 0 ? 0 : k_exit_failure;
}

void add_bench_command(CLI::App& app, const GlobalOptions& global)
{
    auto opt = std::make_shared<BenchOptions>();
    CLI::App* cmd = app.add_subcommand(
        "bench", "Run the benchmark suites and write CSV, JSON and plots (docs/results.md).");
    std::string list;
    for (const Suite& s : k_suites)
        list += "  " + std::string(s.name) + std::string(9 - std::string(s.name).size(), ' ') +
                s.what + "\n";
    cmd->footer(
        "Suites (default: all):\n" + list +
        "\nEach suite is a program of the build's bench folder, or one of its modes (built by the\n"
        "release preset);\n"
        "--bench-dir or the PLIANT_BENCH_DIR environment variable point elsewhere. DIR gets\n"
        "<suite>.csv, <suite>.json, <suite>.log, results.json (with the machine and its load)\n"
        "and, when gnuplot is installed, PNG plots. Timings on a shared machine vary by +-20 %.\n"
        "Ctrl-C stops the running suite, writes results.json with the suites that completed\n"
        "and exits with status 130; a second Ctrl-C ends the running suite's program at once.\n\n"
        "Examples:\n"
        "  pliant bench --quick                       # every suite, about 3 minutes on 2 cores\n"
        "  pliant bench sim session --out my-results  # two suites, full length");
    std::string names;
    for (const Suite& s : k_suites)
        names += std::string(s.name) + " ";
    cmd->add_option("SUITE", opt->suites, "Suites to run: " + names + "(default: all)");
    cmd->add_flag("--quick", opt->quick, "Short runs (fewer levels and repetitions)");
    cmd->add_option("-o,--out", opt->out, "Output folder")->capture_default_str();
    cmd->add_option("--bench-dir", opt->bench_dir,
                    "Folder of the benchmark programs (default: PLIANT_BENCH_DIR or the build's "
                    "bench folder)");
    cmd->add_option("--plots-dir", opt->plots_dir, "Folder of the gnuplot scripts");
    // A plain flag setting the field (a CLI11 negated flag showed "{false}" in --help).
    cmd->add_flag_function(
        "--no-plots", [opt](std::int64_t) { opt->plots = false; }, "Write the data only");
    cmd->callback(
        command_callback(global, [opt, &global]() -> int { return run_bench(*opt, global); }));
}

const CommandRegistrar k_register_bench{{"bench", 90, &add_bench_command}};

}  // namespace
}  // namespace pliant::cli
