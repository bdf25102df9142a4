// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The machine-readable output every benchmark program shares (`pliant bench` reads it).
//
// Design: header-only, no dependency beyond the standard library, so that each program (custom
// main or Google Benchmark) adds it with one include. A program keeps printing its human table
// and also records one row per measurement:
//
//   suite, case, level, size, size_unit, metric, value, unit
//
// e.g. `sim,1 thread,8,131841,nodes,ns_per_node_step,31.2,ns`. `level` is the grid level (-1
// where none applies); `size` is the x value the row is plotted against (nodes, vertices,
// triangles, peers) named by `size_unit`. Rows are written as CSV (`--csv FILE`, a header line
// first; commas in text become ';' so that gnuplot's CSV mode needs no quoting) and as JSON
// (`--json FILE`: {"suite", "meta": {...}, "rows": [...]}). `--quick` asks for the program's
// short mode. `Report::parse_args` removes these options from argv so the program's own parser
// (or Google Benchmark's) sees only its options.
//
// Programs with their own arguments also pass a `Usage` (their usage text) to parse_args:
// `--help`/`-h` then prints the text to stdout and the program exits 0 before running anything,
// and an argument error prints one line naming the argument, then the text, to stderr, and the
// program exits 2 (`Usage::error`). `parse_int`/`parse_number` read a whole argument strictly.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace pliant::bench
{

/// The whole of `text` as an integer (decimal, optional '-'), or nothing: "", "5x", " 5", "+5"
/// and values beyond `long long` are refused.
inline std::optional<long long> parse_int(std::string_view text)
{
    long long v = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, v);
    if (text.empty() || ec != std::errc{} || ptr != end)
        return std::nullopt;
    return v;
}

/// The whole of `text` as a finite number ("2", "0.5", "1e-3"), or nothing.
inline std::optional<double> parse_number(std::string_view text)
{
    double v = 0.0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, v);
    if (text.empty() || ec != std::errc{} || ptr != end || !std::isfinite(v))
        return std::nullopt;
    return v;
}

/// A program's name (argv[0] without its folders) and usage text, for `--help` and for argument
/// errors.
class Usage
{
public:
    Usage(const char* argv0, std::string_view text) : text_(text)
    {
        const std::string_view path = argv0 != nullptr ? argv0 : "bench";
        const std::size_t slash = path.find_last_of('/');
        name_ = std::string(slash == std::string_view::npos ? path : path.substr(slash + 1));
    }

    [[nodiscard]] const std::string& name() const noexcept { return name_; }

    /// `--help`: the usage text on stdout.
    void print() const
    {
        std::fwrite(text_.data(), 1, text_.size(), stdout);
        std::fflush(stdout);
    }

    /// "NAME: MESSAGE" and the usage text on stderr. \return 2, the exit status of an argument
    /// error.
    int error(const std::string& message) const
    {
        std::fprintf(stderr, "%s: %s\n", name_.c_str(), message.c_str());
        std::fwrite(text_.data(), 1, text_.size(), stderr);
        return 2;
    }

    /// An argument the program does not take: an unknown option (it starts with '-') or an
    /// extra word. \return 2.
    int unexpected(std::string_view arg) const
    {
        const std::string a(arg);
        return error(!a.empty() && a[0] == '-' ? "unknown option '" + a + "'"
                                               : "unexpected argument '" + a + "'");
    }

    /// `arg` as an integer in [lo, hi] (`what` names it in the error, e.g. "level"). \return
    /// the value, or nothing after printing the error (the program then exits 2).
    [[nodiscard]] std::optional<int> int_in(std::string_view what, std::string_view arg, int lo,
                                            int hi) const
    {
        const std::string range =
            " (expected " + std::to_string(lo) + ".." + std::to_string(hi) + ")";
        const std::optional<long long> v = parse_int(arg);
        if (!v || *v < lo || *v > hi)
        {
            (void)error(std::string(what) + " '" + std::string(arg) + "' is " +
                        (v ? "out of range" : "not a whole number") + range);
            return std::nullopt;
        }
        return static_cast<int>(*v);
    }

    /// `arg` as a finite number in [lo, hi] (above `lo` only, where `lo_open`; `hi` may be
    /// infinite). \return the value, or nothing after printing the error.
    [[nodiscard]] std::optional<double> number_in(std::string_view what, std::string_view arg,
                                                  double lo, double hi, bool lo_open = false) const
    {
        char range[64];
        if (std::isinf(hi))
            std::snprintf(range, sizeof range, "%s %g", lo_open ? ">" : ">=", lo);
        else
            std::snprintf(range, sizeof range, "%s %g and <= %g", lo_open ? ">" : ">=", lo, hi);
        const std::optional<double> v = parse_number(arg);
        if (!v || *v < lo || (lo_open && *v == lo) || *v > hi)
        {
            (void)error(std::string(what) + " '" + std::string(arg) + "' is not a number " + range);
            return std::nullopt;
        }
        return v;
    }

private:
    std::string name_;
    std::string text_;
};

/// One measurement.
struct ReportRow
{
    std::string case_name;  ///< variant measured, e.g. "1 thread", "spot", "exact"
    int level = -1;         ///< grid level, -1 where none applies
    double size = 0.0;      ///< x value of the row (see size_unit)
    std::string size_unit;  ///< "nodes", "vertices", "triangles", "peers", "bytes", ...
    std::string metric;     ///< snake_case name, e.g. "ns_per_node_step"
    double value = 0.0;
    std::string unit;  ///< e.g. "ns", "dB", "B/s", "1" for ratios
};

/// Rows of one suite plus free-form metadata (build flags, GL_RENDERER, ...).
class Report
{
public:
    explicit Report(std::string suite) : suite_(std::move(suite)) {}

    /// Takes `--json FILE`, `--csv FILE` and `--quick` out of argv (argc is updated, argv keeps
    /// the other arguments in order). \return false (after printing why) when a file is missing.
    bool parse_args(int& argc, char** argv)
    {
        std::string error;
        if (take_args(argc, argv, false, error) == Taken::Error)
        {
            std::fprintf(stderr, "%s: %s\n", argv[0], error.c_str());
            return false;
        }
        return true;
    }

    /// The same, and `--help`/`-h` anywhere. \return nothing when the program should go on, or
    /// the status it should exit with: 0 after `--help` (the usage printed to stdout), 2 after
    /// an error (printed with the usage to stderr).
    [[nodiscard]] std::optional<int> parse_args(int& argc, char** argv, const Usage& usage)
    {
        std::string error;
        switch (take_args(argc, argv, true, error))
        {
        case Taken::Help: usage.print(); return 0;
        case Taken::Error: return usage.error(error);
        case Taken::Ok: break;
        }
        return std::nullopt;
    }

    [[nodiscard]] bool quick() const noexcept { return quick_; }
    [[nodiscard]] const std::string& suite() const noexcept { return suite_; }
    /// Names the suite the rows belong to (a program whose modes are separate suites).
    void set_suite(std::string suite) { suite_ = std::move(suite); }
    [[nodiscard]] const std::vector<ReportRow>& rows() const noexcept { return rows_; }

    /// Adds (or replaces) a metadata entry.
    void meta(const std::string& key, const std::string& value)
    {
        for (auto& kv : meta_)
            if (kv.first == key)
            {
                kv.second = value;
                return;
            }
        meta_.emplace_back(key, value);
    }

    void add(ReportRow row) { rows_.push_back(std::move(row)); }

    void add(const std::string& case_name, int level, double size, const std::string& size_unit,
             const std::string& metric, double value, const std::string& unit)
    {
        rows_.push_back({case_name, level, size, size_unit, metric, value, unit});
    }

    /// Writes the files asked for on the command line. \return false if one cannot be written.
    [[nodiscard]] bool write() const
    {
        bool ok = true;
        if (!csv_path_.empty())
            ok = write_file(csv_path_, csv()) && ok;
        if (!json_path_.empty())
            ok = write_file(json_path_, json()) && ok;
        return ok;
    }

    /// The rows grouped by (case, metric), each group in measurement order: gnuplot draws a
    /// series as one line only when its rows are consecutive.
    [[nodiscard]] std::string csv() const
    {
        std::vector<ReportRow> rows = rows_;
        std::stable_sort(rows.begin(), rows.end(),
                         [](const ReportRow& a, const ReportRow& b) {
                             return a.case_name != b.case_name ? a.case_name < b.case_name
                                                               : a.metric < b.metric;
                         });
        std::string s = "suite,case,level,size,size_unit,metric,value,unit\n";
        for (const ReportRow& r : rows)
            s += csv_text(suite_) + ',' + csv_text(r.case_name) + ',' + std::to_string(r.level) +
                 ',' + number(r.size) + ',' + csv_text(r.size_unit) + ',' + csv_text(r.metric) +
                 ',' + number(r.value) + ',' + csv_text(r.unit) + '\n';
        return s;
    }

    [[nodiscard]] std::string json() const
    {
        std::string s = "{\n  \"suite\": " + quoted(suite_) + ",\n  \"meta\": {";
        for (std::size_t i = 0; i < meta_.size(); ++i)
            s += (i ? ", " : "") + quoted(meta_[i].first) + ": " + quoted(meta_[i].second);
        s += "},\n  \"rows\": [";
        for (std::size_t i = 0; i < rows_.size(); ++i)
        {
            const ReportRow& r = rows_[i];
            s += std::string(i ? "," : "") + "\n    {\"case\": " + quoted(r.case_name) +
                 ", \"level\": " + std::to_string(r.level) + ", \"size\": " + json_number(r.size) +
                 ", \"size_unit\": " + quoted(r.size_unit) + ", \"metric\": " + quoted(r.metric) +
                 ", \"value\": " + json_number(r.value) + ", \"unit\": " + quoted(r.unit) + "}";
        }
        s += "\n  ]\n}\n";
        return s;
    }

private:
    enum class Taken
    {
        Ok,
        Help,  ///< --help or -h (only where `help` is set); argv is then left half-sorted
        Error
    };

    Taken take_args(int& argc, char** argv, bool help, std::string& error)
    {
        int out = 1;
        for (int i = 1; i < argc; ++i)
        {
            const char* a = argv[i];
            if (help && (std::strcmp(a, "--help") == 0 || std::strcmp(a, "-h") == 0))
                return Taken::Help;
            if (std::strcmp(a, "--quick") == 0)
                quick_ = true;
            else if (std::strcmp(a, "--json") == 0 || std::strcmp(a, "--csv") == 0)
            {
                if (i + 1 >= argc)
                {
                    error = std::string(a) + " needs a file name";
                    return Taken::Error;
                }
                (a[2] == 'j' ? json_path_ : csv_path_) = argv[++i];
            }
            else
                argv[out++] = argv[i];
        }
        argc = out;
        argv[argc] = nullptr;
        return Taken::Ok;
    }

    static bool write_file(const std::string& path, const std::string& text)
    {
        std::ofstream f(path, std::ios::binary | std::ios::trunc);
        f << text;
        if (!f.flush())
        {
            std::fprintf(stderr, "bench: cannot write %s\n", path.c_str());
            return false;
        }
        return true;
    }

    static std::string number(double v)
    {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6g", v);
        return buf;
    }

    // JSON has no NaN or infinity: such a value (a failed measurement) becomes null.
    static std::string json_number(double v) { return std::isfinite(v) ? number(v) : "null"; }

    static std::string csv_text(const std::string& s)
    {
        std::string out = s;
        for (char& c : out)
            if (c == ',' || c == '\n' || c == '"')
                c = ';';
        return out;
    }

    static std::string quoted(const std::string& s)
    {
        std::string out = "\"";
        for (const char c : s)
        {
            if (c == '"' || c == '\\')
            {
                out += '\\';
                out += c;
            }
            else if (static_cast<unsigned char>(c) < 0x20)
            {
                char buf[8];
                std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
                out += buf;
            }
            else
                out += c;
        }
        return out + '"';
    }

    std::string suite_;
    bool quick_ = false;
    std::string json_path_;
    std::string csv_path_;
    std::vector<std::pair<std::string, std::string>> meta_;
    std::vector<ReportRow> rows_;
};

}  // namespace pliant::bench
