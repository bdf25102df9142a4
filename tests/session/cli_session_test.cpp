// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// `pliant host` and two `pliant join` as separate processes on 127.0.0.1 for a few seconds:
// all exit 0 and their statistics show traffic both ways. Bounded by --duration.
#include <gtest/gtest.h>
#include <unistd.h>

#include "support/test_paths.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace
{

std::string read(const std::filesystem::path& p)
{
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Sum of a CSV column over the data rows.
double column_sum(const std::filesystem::path& csv, const std::string& name)
{
    std::ifstream in(csv);
    std::string line;
    if (!std::getline(in, line))
        return -1.0;
    std::vector<std::string> header;
    std::stringstream hs(line);
    for (std::string cell; std::getline(hs, cell, ',');)
        header.push_back(cell);
    std::size_t col = header.size();
    for (std::size_t k = 0; k < header.size(); ++k)
        if (header[k] == name)
            col = k;
    if (col == header.size())
        return -1.0;
    double sum = 0.0;
    while (std::getline(in, line))
    {
        std::stringstream ls(line);
        std::string cell;
        for (std::size_t k = 0; k <= col && std::getline(ls, cell, ','); ++k)
        {
        }
        sum += std::atof(cell.c_str());
    }
    return sum;
}

TEST(SessionCli, HostAndTwoJoinsAsProcessesExchangeTraffic)
{
    const auto dir = pliant::test::scratch_dir("session_cli");
    const int port = 20000 + static_cast<int>(getpid() % 20000);
    {
        std::ofstream(dir / "grab.txt") << "0.3 grab face 700 force 0 0 0.5 for 1.0\n";
    }
    const std::string exe = PLIANT_EXE;
    const std::string d = dir.string();
    const std::string p = std::to_string(port);
    const std::string cmd =
        "cd '" + d + "' && rm -f *.rc *.csv; " + "('" + exe + "' host --level 4 --port " + p +
        " --duration 3 --stats host.csv > host.log 2>&1; echo $? > host.rc) & sleep 0.3; " + "('" +
        exe + "' join 127.0.0.1:" + p +
        " --duration 2.5 --script grab.txt --stats p1.csv > p1.log 2>&1; echo $? > p1.rc) & " +
        "('" + exe + "' join 127.0.0.1:" + p +
        " --viewer --duration 2.5 --stats v.csv > v.log 2>&1; echo $? > v.rc) & wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const std::string host_log = read(dir / "host.log");
    if (host_log.find("bind") != std::string::npos && read(dir / "host.rc") != "0\n")
        GTEST_SKIP() << "cannot bind UDP port " << port << " on this machine: " << host_log;
    for (const char* name : {"host", "p1", "v"})
    {
        EXPECT_EQ(read(dir / (std::string(name) + ".rc")), "0\n")
            << name << ": " << read(dir / (std::string(name) + ".log"));
        const auto csv = dir / (std::string(name) + ".csv");
        EXPECT_GT(column_sum(csv, "bytes_in"), 1000.0) << name;
        EXPECT_GT(column_sum(csv, "packets_in"), 10.0) << name;
    }
    EXPECT_GT(column_sum(dir / "host.csv", "bytes_out"), 1000.0);
    EXPECT_GT(column_sum(dir / "p1.csv", "bytes_out"), 1000.0);  // halos and leaf states
    EXPECT_GT(column_sum(dir / "p1.csv", "steps"), 10.0);
    EXPECT_EQ(column_sum(dir / "v.csv", "steps"), 0.0);  // a viewer simulates nothing
}

}  // namespace
