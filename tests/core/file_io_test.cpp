// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// core::write_files: an output is written whole or not at all, and an earlier file survives a
// failed write; core::check_output_path creates nothing.
#include <pliant/core/file_io.h>

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "support/test_paths.h"

#include <algorithm>
#include <climits>
#include <csignal>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

namespace pliant::core
{
namespace
{

namespace fs = std::filesystem;

std::string read(const fs::path& p)
{
    std::ifstream is(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
}

void put(const fs::path& p, const std::string& text)
{
    std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

std::vector<std::string> names_in(const fs::path& dir)
{
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::span<const std::byte> bytes_of(const std::string& s)
{
    return std::as_bytes(std::span<const char>(s.data(), s.size()));
}

/// While alive, a write that grows a file past `bytes` fails with EFBIG (as on a full disk)
/// instead of killing the process with SIGXFSZ.
class FileSizeLimit
{
public:
    explicit FileSizeLimit(rlim_t bytes)
    {
        ::getrlimit(RLIMIT_FSIZE, &old_);
        old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
        rlimit limit = old_;
        limit.rlim_cur = bytes;
        ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    FileSizeLimit(const FileSizeLimit&) = delete;
    FileSizeLimit& operator=(const FileSizeLimit&) = delete;
    ~FileSizeLimit()
    {
        ::setrlimit(RLIMIT_FSIZE, &old_);
        std::signal(SIGXFSZ, old_handler_);
    }

private:
    rlimit old_{};
    void (*old_handler_)(int) = nullptr;
};

TEST(FileIo, WritesANewFileAndReplacesAnOldOneKeepingItsMode)
{
    const fs::path dir = test::scratch_dir("file_io_write");
    ASSERT_TRUE(write_text_file(dir / "a.txt", "first", "test"));
    EXPECT_EQ(read(dir / "a.txt"), "first");
    ::chmod((dir / "a.txt").c_str(), 0640);
    ASSERT_TRUE(write_text_file(dir / "a.txt", "second, longer", "test"));
    EXPECT_EQ(read(dir / "a.txt"), "second, longer");
    struct ::stat st
    {
    };
    ASSERT_EQ(::stat((dir / "a.txt").c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 07777, 0640U);
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"a.txt"}) << "no temporary file left";
}

// The temporary's name (".NAME.PID.N.tmp") is longer than the name: a name the system takes,
// up to NAME_MAX bytes, was refused with "File name too long" from 243 bytes on.
TEST(FileIo, ANameOfTheLongestLengthIsWritten)
{
    const fs::path dir = test::scratch_dir("file_io_long_name");
    const std::string name = std::string(NAME_MAX - 4, 'a') + ".obj";
    ASSERT_TRUE(write_text_file(dir / name, "first", "test"));
    ASSERT_TRUE(write_text_file(dir / name, "second", "test"));  // replacing it too
    EXPECT_EQ(read(dir / name), "second");
    EXPECT_EQ(names_in(dir), std::vector<std::string>{name}) << "no temporary file left";
    const std::string too_long = std::string(NAME_MAX + 1, 'b');
    const auto refused = write_text_file(dir / too_long, "x", "test");
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("File name too long"), std::string::npos)
        << refused.error().message;
    EXPECT_EQ(names_in(dir), std::vector<std::string>{name});
}

TEST(FileIo, AFailedWriteKeepsTheEarlierFileAndLeavesNothingElse)
{
    const fs::path dir = test::scratch_dir("file_io_full");
    put(dir / "out.bin", "KEEP");
    const std::string big(64 * 1024, 'x');
    {
        const FileSizeLimit limit(4096);
        auto written = write_text_file(dir / "out.bin", big, "test");
        ASSERT_FALSE(written);
        EXPECT_EQ(written.error().code, ErrorCode::IoError);
        EXPECT_NE(written.error().message.find("out.bin"), std::string::npos)
            << written.error().message;
        EXPECT_NE(written.error().message.find("File too large"), std::string::npos)
            << written.error().message;
        // A new file that cannot be written whole is not left behind in part either.
        EXPECT_FALSE(write_text_file(dir / "new.bin", big, "test"));
    }
    EXPECT_EQ(read(dir / "out.bin"), "KEEP");
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.bin"});
}

TEST(FileIo, SeveralFilesAreWrittenAllOrNone)
{
    const fs::path dir = test::scratch_dir("file_io_pair");
    put(dir / "m.gltf", "old json");
    put(dir / "m.bin", "old buffer");
    const std::string json = "new json";
    const std::string buffer = "new buffer";
    // The second file's folder does not exist: the first is not replaced either.
    const std::vector<FileContent> bad{{dir / "m.bin", bytes_of(buffer)},
                                       {dir / "missing" / "m.gltf", bytes_of(json)}};
    auto written = write_files(bad, "test");
    ASSERT_FALSE(written);
    EXPECT_NE(written.error().message.find("missing"), std::string::npos)
        << written.error().message;
    EXPECT_EQ(read(dir / "m.bin"), "old buffer");
    EXPECT_EQ(names_in(dir), (std::vector<std::string>{"m.bin", "m.gltf"}));
    const std::vector<FileContent> good{{dir / "m.bin", bytes_of(buffer)},
                                        {dir / "m.gltf", bytes_of(json)}};
    ASSERT_TRUE(write_files(good, "test"));
    EXPECT_EQ(read(dir / "m.bin"), "new buffer");
    EXPECT_EQ(read(dir / "m.gltf"), "new json");
}

TEST(FileIo, ALinkIsFollowedAndADeviceIsWrittenInPlace)
{
    const fs::path dir = test::scratch_dir("file_io_link");
    fs::create_directory(dir / "real");
    put(dir / "real" / "target.txt", "old");
    fs::create_symlink(dir / "real" / "target.txt", dir / "link.txt");
    ASSERT_TRUE(write_text_file(dir / "link.txt", "through the link", "test"));
    EXPECT_TRUE(fs::is_symlink(dir / "link.txt"));
    EXPECT_EQ(read(dir / "real" / "target.txt"), "through the link");
    EXPECT_EQ(names_in(dir / "real"), std::vector<std::string>{"target.txt"});
    // A character device is written in place (no file is made beside it in /dev).
    EXPECT_TRUE(write_text_file("/dev/null", "anything", "test"));
    auto full = write_text_file("/dev/full", "anything", "test");
    ASSERT_FALSE(full);
    EXPECT_NE(full.error().message.find("No space left on device"), std::string::npos)
        << full.error().message;
}

TEST(FileIo, CheckOutputPathCreatesNothingAndSaysWhy)
{
    const fs::path dir = test::scratch_dir("file_io_check");
    EXPECT_TRUE(check_output_path(dir / "new.pgrid", "-o"));
    EXPECT_FALSE(fs::exists(dir / "new.pgrid"));
    EXPECT_TRUE(fs::is_empty(dir)) << "the probe beside it was removed";
    // A folder whose permissions allow writing (to root) where no file can be created: the
    // probe finds out before the work, not write_files after it.
    if (fs::is_directory("/proc"))
    {
        auto proc = check_output_path("/proc/x.pgrid", "-o");
        ASSERT_FALSE(proc);
        EXPECT_NE(proc.error().message.find("-o: cannot write '/proc/x.pgrid'"), std::string::npos)
            << proc.error().message;
    }
    auto folder = check_output_path(dir, "-o");
    ASSERT_FALSE(folder);
    EXPECT_NE(folder.error().message.find("Is a directory"), std::string::npos)
        << folder.error().message;
    auto missing = check_output_path(dir / "no" / "x.pgrid", "--save");
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().message.find("--save: cannot write"), std::string::npos);
    EXPECT_NE(missing.error().message.find("does not exist"), std::string::npos)
        << missing.error().message;
    put(dir / "file", "x");
    auto under_file = check_output_path(dir / "file" / "x.pgrid", "-o");
    ASSERT_FALSE(under_file);
    EXPECT_NE(under_file.error().message.find("not a folder"), std::string::npos)
        << under_file.error().message;
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"file"});
}

TEST(FileIo, CheckInputFileSaysWhyAndOpensNothing)
{
    const fs::path dir = test::scratch_dir("file_io_input");
    put(dir / "plan.txt", "grab 0 0 1\n");
    EXPECT_TRUE(check_input_file(dir / "plan.txt", "--script"));

    auto missing = check_input_file(dir / "none.txt", "--script");
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::IoError);
    EXPECT_EQ(missing.error().message,
              "--script: " + (dir / "none.txt").string() + ": no such file");

    auto folder = check_input_file(dir);
    ASSERT_FALSE(folder);
    EXPECT_EQ(folder.error().message, dir.string() + ": is a folder, not a file");

    put(dir / "file", "x");
    auto under_file = check_input_file(dir / "file" / "x.txt", "--key-file");
    ASSERT_FALSE(under_file);
    EXPECT_NE(under_file.error().message.find("Not a directory"), std::string::npos)
        << under_file.error().message;

    // A FIFO (what a shell's process substitution gives) passes without being opened: opening
    // it for reading here would block, since nobody writes to it.
    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
    EXPECT_TRUE(check_input_file(dir / "fifo", "--key-file"));

    // A device has no end to read to (/dev/zero) or waits on a terminal: refused.
    auto device = check_input_file("/dev/zero", "--resume");
    ASSERT_FALSE(device);
    EXPECT_EQ(device.error().message, "--resume: /dev/zero: is a device, not a file");
    EXPECT_TRUE(check_input_file("/dev/null", "--scenario"));  // reads as an empty file
}

// read_input_file reads a file whole, up to a bound it names when passed, and refuses what
// check_input_file refuses.
TEST(FileIo, ReadInputFileReadsWholeUpToItsBound)
{
    const fs::path dir = test::scratch_dir("file_io_read");
    const std::string text(3 << 20, 'x');  // more than one read's chunk (1 MiB)
    put(dir / "big", text);
    const auto whole = read_input_file(dir / "big", text.size(), "test file");
    ASSERT_TRUE(whole) << whole.error().message;
    ASSERT_EQ(whole->size(), text.size());
    EXPECT_EQ(std::to_integer<char>((*whole)[text.size() - 1]), 'x');

    const auto over = read_input_file(dir / "big", text.size() - 1, "test file");
    ASSERT_FALSE(over);
    EXPECT_EQ(over.error().code, ErrorCode::ParseError);
    EXPECT_EQ(over.error().message, (dir / "big").string() + ": more than " +
                                        std::to_string(text.size() - 1) +
                                        " bytes, larger than any test file");

    const auto device = read_input_file("/dev/zero", 100, "test file");
    ASSERT_FALSE(device);
    EXPECT_EQ(device.error().code, ErrorCode::IoError);
    const auto missing = read_input_file(dir / "missing", 100, "test file");
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::IoError);
}

}  // namespace
}  // namespace pliant::core
