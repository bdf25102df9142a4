// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant`: the command-line front end. Subcommands live one per file (commands.h).
#include <fcntl.h>
#include <unistd.h>

#include "cli_common.h"
#include "commands.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::cli
{

std::vector<CommandSpec>& command_registry()
{
    static std::vector<CommandSpec> registry;
    return registry;
}

namespace
{

/// Process set-up before anything is opened or written:
/// - a standard stream the caller closed (`2>&-`) is opened on /dev/null, so that the next
///   file opened does not take its number and receive what is printed to it (progress lines
///   went into simulate's energy.csv);
/// - SIGXFSZ is ignored, so that a write past a file-size limit (`ulimit -f`) fails with EFBIG
///   and the command says "File too large" and removes its new file, instead of the process
///   being killed with the new file left beside the output;
/// - SIGPIPE is ignored, so that a reader that goes away (`pliant simulate ... 2>&1 | head`, a
///   pager quit) does not kill the run at its next progress line, with its outputs half
///   written and run.json saying "running": the work goes on to its end, and a lost standard
///   output is reported by finish().
void prepare_process()
{
    for (int fd = 0; fd <= 2; ++fd)
        if (::fcntl(fd, F_GETFD) == -1 && errno == EBADF)
        {
            const int opened = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
            if (opened >= 0 && opened != fd)  // the lowest free number: fd itself
                ::close(opened);
        }
    std::signal(SIGXFSZ, SIG_IGN);
    std::signal(SIGPIPE, SIG_IGN);
}

/// The exit status of a command that ended with `rc`: what it printed to standard output must
/// have been written (a full disk, a closed pipe: `pliant info --json > /dev/full` exited 0 with
/// the answer lost); if not, an error on stderr and status 1 unless `rc` already says failure.
int finish(int rc)
{
    if (std::fflush(stdout) == 0 && std::ferror(stdout) == 0)
        return rc;
    const int error = errno;
    std::fprintf(stderr, "error: pliant: cannot write to standard output: %s [io-error]\n",
                 std::strerror(error != 0 ? error : EIO));
    return rc != 0 ? rc : k_exit_bad_input;
}

/// After a failed parse: "pliant remesh: unknown option '--bogus'" for the first argument that
/// looks like an option and that no option of the command (or, before it, of pliant) took;
/// empty if there is none. A negative number ("-1", "-.5") is a value, not an option.
std::string first_unknown_option(const CLI::App& app)
{
    const auto looks_like_option = [](const std::string& arg)
    {
        return arg.size() > 1 && arg[0] == '-' &&
               std::isdigit(static_cast<unsigned char>(arg[1])) == 0 && arg[1] != '.';
    };
    std::string where = "pliant";
    for (const CLI::App* sub : app.get_subcommands())  // the command given, if any
        where += " " + sub->get_name();
    for (const std::string& arg : app.remaining(true))
        if (looks_like_option(arg))
            return where + ": unknown option '" + arg + "'";
    return {};
}

}  // namespace

}  // namespace pliant::cli

int main(int argc, char** argv)
{
    pliant::cli::prepare_process();
    CLI::App app{
        "pliant " PLIANT_VERSION
        " - real-time deformable objects for collaborative virtual environments.\n"
        "Turns a closed genus-0 triangle mesh into a regular tetrahedral grid, refines it by\n"
        "butterfly subdivision, simulates it as a membrane, and lets several people deform it\n"
        "together over the network.\n\n"
        "Start with `pliant demo`, or `pliant info MESH` to check a mesh.",
        "pliant"};
    app.require_subcommand(1);
    app.fallthrough();  // global options may follow the subcommand
    app.set_version_flag("--version", std::string("pliant ") + PLIANT_VERSION);

    pliant::cli::GlobalOptions global;
    auto* verbose = app.add_flag("-v,--verbose", global.verbose, "Print debug details and timings");
    app.add_flag("-q,--quiet", global.quiet, "Print only errors (no progress bars)")
        ->excludes(verbose);

    auto& registry = pliant::cli::command_registry();
    std::sort(registry.begin(), registry.end(),
              [](const auto& a, const auto& b) { return a.order < b.order; });
    for (const auto& spec : registry)
        spec.add(app, global);

    // An empty argument is never a value pliant takes, and CLI11 reads an empty option value or
    // positional as "not given": `remesh "$MESH" -o x.pgrid` with MESH unset remeshed the bundled
    // mesh, `--report ""` wrote no report, `replay -o ""` wrote nothing, each exiting 0. Refused
    // here, naming the option (--passphrase keeps its own message, cli_common.cpp).
    for (int i = 1; i < argc; ++i)
    {
        const std::string_view arg = argv[i];
        const std::string_view before = i > 1 ? std::string_view(argv[i - 1]) : std::string_view();
        const bool empty_value = arg.empty() || (arg.starts_with("--") && arg.ends_with('='));
        if (!empty_value || before == "--passphrase" || arg == "--passphrase=")
            continue;
        std::string what;
        if (!arg.empty())
            what = "the value of " + std::string(arg.substr(0, arg.size() - 1));
        else if (before.starts_with('-') && before.find('=') == std::string_view::npos &&
                 !(before.size() > 1 &&
                   (std::isdigit(static_cast<unsigned char>(before[1])) != 0 || before[1] == '.')))
            what = "after " + std::string(before);
        else
            what = "a positional argument";
        std::fprintf(stderr,
                     "pliant: argument %d is empty (%s): an unset shell variable? Give a value, "
                     "or leave it out\nRun with --help for more information.\n",
                     i, what.c_str());
        return pliant::cli::k_exit_usage;
    }
    // The global options are flags, so the first argument that is not one names the command;
    // CLI11 alone would answer an unknown one with "A subcommand is required".
    for (int i = 1; i < argc; ++i)
    {
        const std::string_view arg = argv[i];
        if (arg.starts_with('-'))
            continue;
        const auto subs = app.get_subcommands({});
        if (std::none_of(subs.begin(), subs.end(),
                         [&](CLI::App* sub) { return sub->check_name(std::string(arg)); }))
        {
            std::string names;
            for (const CLI::App* sub : subs)
                names += (names.empty() ? "" : ", ") + sub->get_name();
            std::fprintf(stderr,
                         "pliant: unknown command '%s'; the commands are: %s\n"
                         "Run with --help for more information.\n",
                         argv[i], names.c_str());
            return pliant::cli::k_exit_usage;
        }
        break;
    }
    try
    {
        app.parse(argc, argv);
    }
    catch (const CLI::RuntimeError& e)
    {
        return pliant::cli::finish(e.get_exit_code());  // a subcommand's own result
    }
    catch (const pliant::cli::InputFileError& e)
    {
        // A file option's file is missing or unreadable (existing_input_file): bad input, said
        // as the commands say it of their GRID and MESH arguments. Logging is not set up yet.
        std::fprintf(stderr, "error: %s [%s]\n", e.error.message.c_str(),
                     std::string(pliant::core::to_string(e.error.code)).c_str());
        return pliant::cli::k_exit_bad_input;
    }
    catch (const CLI::ParseError& e)
    {
        // An unknown option is the likelier mistake behind any other complaint (CLI11 checks
        // the required options and the subcommand first: `pliant remesh --bogus x` said
        // "--output is required", `pliant --bogus` "A subcommand is required"): name it.
        if (e.get_exit_code() != 0)
            if (const std::string unknown = pliant::cli::first_unknown_option(app);
                !unknown.empty())
            {
                std::fprintf(stderr, "%s\nRun with --help for more information.\n",
                             unknown.c_str());
                return pliant::cli::k_exit_usage;
            }
        // --help and --version exit 0; every other CLI11 error is a usage error, whatever code
        // CLI11 gives it (105 for a bad value, 106 for a missing option...): one documented code.
        const int rc = app.exit(e);
        return pliant::cli::finish(rc == 0 ? 0 : pliant::cli::k_exit_usage);
    }
    return pliant::cli::finish(0);
}
