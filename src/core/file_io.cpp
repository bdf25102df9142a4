// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include <pliant/core/file_io.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <string>
#include <vector>

namespace pliant::core
{

namespace
{

namespace fs = std::filesystem;

std::string reason(int err)
{
    return std::strerror(err);
}

/// Writes all of `bytes` to `fd`; \return 0 or the errno of the failed write. EINTR (a signal
/// whose handler does not restart calls, such as the CLI's Ctrl-C, came while a pipe nobody
/// reads held the write) ends it: retrying would block again. To a pipe or FIFO the bytes go in
/// writes of at most PIPE_BUF, each all or nothing, so that such a signal finds the write with
/// nothing sent and it fails with EINTR (a larger write returns the part sent, and the next one
/// blocks again: the first Ctrl-C did nothing).
int write_all(int fd, std::span<const std::byte> bytes)
{
    struct ::stat st
    {
    };
    const std::size_t chunk =
        ::fstat(fd, &st) == 0 && S_ISFIFO(st.st_mode) ? std::size_t{PIPE_BUF} : bytes.size();
    std::size_t done = 0;
    while (done < bytes.size())
    {
        const ::ssize_t n = ::write(fd, bytes.data() + done, std::min(chunk, bytes.size() - done));
        if (n < 0)
            return errno;
        if (n == 0)
            return EIO;
        done += static_cast<std::size_t>(n);
    }
    return 0;
}

/// Where a file goes and how: the path to replace (a link's target), whether in place.
struct Plan
{
    fs::path target;
    bool in_place = false;
    bool existed = false;
    ::mode_t mode = 0;
    fs::path temporary;
    int fd = -1;
};

Plan plan_for(const fs::path& path)
{
    Plan p;
    p.target = path;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec)))
    {
        const fs::path resolved = fs::canonical(path, ec);
        if (ec)  // a dangling link: opening it creates the file it names
        {
            p.in_place = true;
            return p;
        }
        p.target = resolved;
    }
    struct ::stat st
    {
    };
    if (::stat(p.target.c_str(), &st) == 0)
    {
        p.existed = true;
        p.mode = st.st_mode & 07777;
        p.in_place = !S_ISREG(st.st_mode);
    }
    return p;
}

std::atomic<unsigned> g_counter{0};

/// Opens a new, unique file beside `p.target`; \return 0 or the errno.
int open_temporary(Plan& p)
{
    const fs::path folder = p.target.parent_path();
    for (int attempt = 0; attempt < 100; ++attempt)
    {
        const std::string suffix = "." + std::to_string(::getpid()) + "." +
                                   std::to_string(g_counter.fetch_add(1)) + ".tmp";
        std::string name = "." + p.target.filename().string() + suffix;
        // A name the system takes (up to NAME_MAX, 255 bytes) must not fail for its temporary
        // one; nor a path near PATH_MAX: then a short name ".pliant.PID.N.tmp".
        if (name.size() > NAME_MAX || (folder / name).native().size() >= PATH_MAX)
            name = ".pliant" + suffix;
        p.temporary = folder.empty() ? fs::path(name) : folder / name;
        p.fd = ::open(p.temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (p.fd >= 0)
            return 0;
        if (errno != EEXIST)
            return errno;
    }
    return EEXIST;
}

}  // namespace

Result<void> write_files(std::span<const FileContent> files, std::string_view who)
{
    std::vector<Plan> plans;
    plans.reserve(files.size());
    const auto discard = [&]
    {
        for (Plan& p : plans)
        {
            if (p.fd >= 0)
                ::close(p.fd);
            p.fd = -1;
            if (!p.temporary.empty())
                ::unlink(p.temporary.c_str());
            p.temporary.clear();
        }
    };
    const auto failure = [&](const fs::path& path, const std::string& what, int err)
    {
        discard();
        // A signal ended a wait on a FIFO or pipe: stopped on request, not a broken disk.
        const bool interrupted = err == EINTR;
        return fail(interrupted ? ErrorCode::Cancelled : ErrorCode::IoError,
                    (who.empty() ? std::string() : std::string(who) + ": ") + path.string() + ": " +
                        what + ": " +
                        (interrupted ? "interrupted by a signal while waiting for a reader (a "
                                       "FIFO or pipe that nothing reads)"
                                     : reason(err)));
    };
    // Every new file written and closed first; nothing replaced until all of them are.
    for (const FileContent& f : files)
    {
        plans.push_back(plan_for(f.path));
        Plan& p = plans.back();
        if (p.in_place)
        {
            p.fd = ::open(f.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
            if (p.fd < 0)
                return failure(f.path, "cannot open for writing", errno);
        }
        else
        {
            if (const int err = open_temporary(p); err != 0)
                return failure(f.path, "cannot create a file beside it", err);
            if (p.existed)
                (void)::fchmod(p.fd, p.mode);
        }
        if (const int err = write_all(p.fd, f.bytes); err != 0)
            return failure(f.path, "write failed", err);
        const int fd = p.fd;
        p.fd = -1;
        if (::close(fd) != 0)
            return failure(f.path, "write failed", errno);
    }
    for (std::size_t i = 0; i < plans.size(); ++i)
    {
        Plan& p = plans[i];
        if (p.in_place)
            continue;
        if (::rename(p.temporary.c_str(), p.target.c_str()) != 0)
            return failure(files[i].path, "cannot replace it", errno);
        p.temporary.clear();
    }
    return {};
}

Result<void> write_file(const fs::path& path, std::span<const std::byte> bytes,
                        std::string_view who)
{
    const FileContent file{path, bytes};
    return write_files(std::span<const FileContent>(&file, 1), who);
}

Result<void> write_text_file(const fs::path& path, std::string_view text, std::string_view who)
{
    return write_file(path, std::as_bytes(std::span<const char>(text.data(), text.size())), who);
}

namespace
{

/// Whether `path` is the null device (std::filesystem::equivalent refuses to compare devices).
bool is_dev_null(const fs::path& path)
{
    struct stat a
    {
    };
    struct stat b
    {
    };
    return ::stat(path.c_str(), &a) == 0 && ::stat("/dev/null", &b) == 0 && S_ISCHR(a.st_mode) &&
           a.st_rdev == b.st_rdev;
}

}  // namespace

Result<void> check_input_file(const fs::path& path, std::string_view what)
{
    const auto refuse = [&](const std::string& why)
    {
        return fail(ErrorCode::IoError, (what.empty() ? std::string() : std::string(what) + ": ") +
                                            path.string() + ": " + why);
    };
    if (path.empty())
        return refuse("the path is empty");
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!fs::exists(st))
        return refuse(ec && ec != std::errc::no_such_file_or_directory ? ec.message()
                                                                       : "no such file");
    if (fs::is_directory(st))
        return refuse("is a folder, not a file");
    // A device has no end to read to (/dev/zero, /dev/urandom) or waits on a terminal; /dev/null
    // reads as an empty file (`-s /dev/null`: a scenario of defaults).
    if ((fs::is_character_file(st) || fs::is_block_file(st)) && !is_dev_null(path))
        return refuse("is a device, not a file");
    if (::access(path.c_str(), R_OK) != 0)
        return refuse(reason(errno));
    return {};
}

Result<std::vector<std::byte>> read_input_file(const fs::path& path, std::size_t max_bytes,
                                               std::string_view what)
{
    if (auto readable = check_input_file(path); !readable)
        return readable.error();
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return fail(ErrorCode::IoError, path.string() + ": " + reason(errno));
    std::vector<std::byte> bytes;
    std::vector<std::byte> chunk(std::size_t{1} << 20);
    for (;;)
    {
        const ::ssize_t n = ::read(fd, chunk.data(), chunk.size());
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
        {
            const int err = errno;
            ::close(fd);
            return fail(ErrorCode::IoError, path.string() + ": " + reason(err));
        }
        if (n == 0)
            break;
        if (static_cast<std::size_t>(n) > max_bytes - std::min(max_bytes, bytes.size()))
        {
            ::close(fd);
            return fail(ErrorCode::ParseError, path.string() + ": more than " +
                                                   std::to_string(max_bytes) +
                                                   " bytes, larger than any " + std::string(what));
        }
        bytes.insert(bytes.end(), chunk.begin(), chunk.begin() + n);
    }
    ::close(fd);
    return bytes;
}

namespace
{

/// What write_files will do first, tried: a new file beside `path` (for a regular file or a new
/// one), created and removed at once. Permission bits and access() can say yes where the
/// creation fails (/proc, a read-only or full file system for root, an immutable folder).
template <typename Refuse>
Result<void> probe_beside(const fs::path& path, const Refuse& refuse)
{
    Plan p = plan_for(path);
    if (p.in_place)
        return {};
    if (const int err = open_temporary(p); err != 0)
        return refuse(reason(err));
    ::close(p.fd);
    ::unlink(p.temporary.c_str());
    return {};
}

}  // namespace

Result<void> check_output_path(const fs::path& path, std::string_view what)
{
    const auto refuse = [&](const std::string& why)
    {
        return fail(ErrorCode::IoError,
                    std::string(what) + ": cannot write '" + path.string() + "': " + why);
    };
    if (path.empty())
        return refuse("the path is empty");
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (fs::is_directory(st))
        return refuse(reason(EISDIR));
    if (fs::exists(st))
    {
        if (::access(path.c_str(), W_OK) != 0)
            return refuse(reason(errno));
        return probe_beside(path, refuse);
    }
    const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const fs::file_status fst = fs::status(folder, ec);
    if (!fs::exists(fst))
        return refuse("its folder " + folder.string() + " does not exist");
    if (!fs::is_directory(fst))
        return refuse(folder.string() + " is not a folder");
    if (::access(folder.c_str(), W_OK) != 0)
        return refuse("its folder " + folder.string() + ": " + reason(errno));
    return probe_beside(path, refuse);
}

}  // namespace pliant::core
