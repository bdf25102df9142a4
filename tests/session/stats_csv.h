// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Reading what `pliant host` / `pliant join` leave behind in the CLI session tests: whole files
// (logs, exit statuses) and the per-second `--stats` CSV (docs/session.md §7) by column name.

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace pliant::session::test
{

inline std::string read(const std::filesystem::path& p)
{
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// One data row of a stats CSV: (column name, value) in column order.
using Row = std::vector<std::pair<std::string, double>>;

/// The data rows of a CSV whose first line names the columns (empty if the file is missing).
inline std::vector<Row> rows(const std::filesystem::path& csv)
{
    std::ifstream in(csv);
    std::string line;
    std::vector<std::string> header;
    std::vector<Row> out;
    if (!std::getline(in, line))
        return out;
    std::stringstream hs(line);
    for (std::string cell; std::getline(hs, cell, ',');)
        header.push_back(cell);
    while (std::getline(in, line))
    {
        std::stringstream ls(line);
        Row row;
        std::string cell;
        for (std::size_t k = 0; k < header.size() && std::getline(ls, cell, ','); ++k)
            row.emplace_back(header[k], std::atof(cell.c_str()));
        out.push_back(std::move(row));
    }
    return out;
}

/// The value of column `name` in `row` (-1 if there is no such column).
inline double value(const Row& row, const std::string& name)
{
    for (const auto& [k, v] : row)
        if (k == name)
            return v;
    return -1.0;
}

/// The sum of column `name` over the data rows (-1 if the file or the column is missing).
inline double column_sum(const std::filesystem::path& csv, const std::string& name)
{
    double sum = 0.0;
    bool found = false;
    for (const Row& r : rows(csv))
        for (const auto& [k, v] : r)
            if (k == name)
            {
                sum += v;
                found = true;
            }
    return found ? sum : -1.0;
}

}  // namespace pliant::session::test
