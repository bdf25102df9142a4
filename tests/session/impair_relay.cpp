// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "impair_relay.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <queue>
#include <random>
#include <utility>

namespace pliant::test
{

namespace
{

double now_s()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

sockaddr_in loopback(std::uint16_t port)
{
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    return a;
}

std::uint64_t key_of(const sockaddr_in& a)
{
    return (static_cast<std::uint64_t>(ntohl(a.sin_addr.s_addr)) << 16) | ntohs(a.sin_port);
}

/// A non-blocking UDP socket bound to 127.0.0.1 (any port); -1 on failure.
int open_socket(std::string* error)
{
    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0)
    {
        *error = std::string("socket: ") + std::strerror(errno);
        return -1;
    }
    const sockaddr_in a = loopback(0);
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0)
    {
        *error = std::string("bind 127.0.0.1: ") + std::strerror(errno);
        ::close(fd);
        return -1;
    }
    // Room for bursts (capped by the kernel's rmem_max/wmem_max; failure is harmless).
    const int bytes = 4 << 20;
    (void)::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    (void)::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
    return fd;
}

std::uint16_t port_of(int fd)
{
    sockaddr_in a{};
    socklen_t len = sizeof a;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0)
        return 0;
    return ntohs(a.sin_port);
}

}  // namespace

struct ImpairRelay::State
{
    struct Listener
    {
        int fd = -1;
        sockaddr_in target{};
    };
    struct Upstream
    {
        int fd = -1;
        std::size_t listener = 0;
        sockaddr_in client{};
    };
    struct Pending
    {
        double due = 0.0;
        std::uint64_t order = 0;  // ties keep arrival order
        int fd = -1;
        sockaddr_in to{};
        std::size_t flow = 0;
        std::uint64_t seq = 0;
        double delay = 0.0;
        std::vector<unsigned char> data;
    };
    struct Later
    {
        bool operator()(const Pending& a, const Pending& b) const
        {
            return a.due != b.due ? a.due > b.due : a.order > b.order;
        }
    };

    std::vector<Listener> listeners;
    std::vector<Upstream> upstreams;
    std::map<std::pair<std::size_t, std::uint64_t>, std::size_t> upstream_of;
    std::priority_queue<Pending, std::vector<Pending>, Later> queue;
    std::vector<std::uint64_t> next_seq;  // per flow: 2 * upstream (to target), + 1 (replies)
    std::vector<std::uint64_t> max_sent;  // per flow: highest seq sent + 1
    std::uint64_t order = 0;
    std::mt19937_64 rng;
    std::uniform_real_distribution<double> uniform{0.0, 1.0};
    mutable std::mutex mutex;  // guards counters
    ImpairCounters counters;
};

ImpairRelay::ImpairRelay(const ImpairSettings& settings)
    : settings_(settings), state_(std::make_unique<State>())
{
    state_->rng.seed(settings.seed);
}

ImpairRelay::~ImpairRelay()
{
    stop();
    for (const auto& l : state_->listeners)
        ::close(l.fd);
    for (const auto& u : state_->upstreams)
        ::close(u.fd);
}

std::uint16_t ImpairRelay::add_target(std::uint16_t target_port)
{
    if (thread_.joinable())
    {
        error_ = "add_target after start";
        return 0;
    }
    const int fd = open_socket(&error_);
    if (fd < 0)
        return 0;
    state_->listeners.push_back({fd, loopback(target_port)});
    return port_of(fd);
}

bool ImpairRelay::start()
{
    if (thread_.joinable() || state_->listeners.empty())
        return false;
    stop_ = false;
    thread_ = std::thread([this] { run(); });
    return true;
}

void ImpairRelay::stop()
{
    stop_ = true;
    if (thread_.joinable())
        thread_.join();
}

ImpairCounters ImpairRelay::counters() const
{
    const std::lock_guard<std::mutex> lock(state_->mutex);
    return state_->counters;
}

void ImpairRelay::run()
{
    State& st = *state_;
    const ImpairSettings& set = settings_;
    std::vector<pollfd> fds;
    std::vector<unsigned char> buf(65536);

    // Impairs one datagram received now on `flow` and queues what survives.
    auto impair = [&](const unsigned char* data, std::size_t size, int fd, const sockaddr_in& to,
                      std::size_t flow, double now)
    {
        if (flow >= st.next_seq.size())
        {
            st.next_seq.resize(flow + 1, 0);
            st.max_sent.resize(flow + 1, 0);
        }
        const std::uint64_t seq = st.next_seq[flow]++;
        const std::lock_guard<std::mutex> lock(st.mutex);
        ++st.counters.received;
        if (st.uniform(st.rng) < set.loss)
        {
            ++st.counters.dropped;
            return;
        }
        const int copies = st.uniform(st.rng) < set.duplicate ? 2 : 1;
        if (copies == 2)
            ++st.counters.duplicated;
        for (int c = 0; c < copies; ++c)
        {
            if (st.queue.size() >= set.max_queued)
            {
                ++st.counters.overflow;
                continue;
            }
            double delay = set.delay_s + set.jitter_s * st.uniform(st.rng);
            if (st.uniform(st.rng) < set.reorder)
            {
                delay += set.reorder_hold_s;
                ++st.counters.held;
            }
            State::Pending p;
            p.due = now + delay;
            p.order = st.order++;
            p.fd = fd;
            p.to = to;
            p.flow = flow;
            p.seq = seq;
            p.delay = delay;
            p.data.assign(data, data + size);
            st.queue.push(std::move(p));
        }
    };

    auto send_due = [&](double now)
    {
        // Bounded per round so that reading keeps up under a burst.
        for (int k = 0; k < 4096 && !st.queue.empty() && st.queue.top().due <= now; ++k)
        {
            const State::Pending& p = st.queue.top();
            const ssize_t n = ::sendto(p.fd, p.data.data(), p.data.size(), 0,
                                       reinterpret_cast<const sockaddr*>(&p.to), sizeof p.to);
            {
                const std::lock_guard<std::mutex> lock(st.mutex);
                if (n < 0)
                    ++st.counters.send_errors;
                else
                {
                    ++st.counters.sent;
                    st.counters.delay_sum_s += p.delay;
                    st.counters.max_delay_s = std::max(st.counters.max_delay_s, p.delay);
                    if (p.seq + 1 < st.max_sent[p.flow])
                        ++st.counters.inversions;
                }
            }
            st.max_sent[p.flow] = std::max(st.max_sent[p.flow], p.seq + 1);
            st.queue.pop();
        }
    };

    auto upstream_for = [&](std::size_t listener, const sockaddr_in& client) -> std::ptrdiff_t
    {
        const auto key = std::make_pair(listener, key_of(client));
        const auto it = st.upstream_of.find(key);
        if (it != st.upstream_of.end())
            return static_cast<std::ptrdiff_t>(it->second);
        std::string error;
        const int fd = open_socket(&error);
        if (fd < 0)
            return -1;
        st.upstreams.push_back({fd, listener, client});
        st.upstream_of[key] = st.upstreams.size() - 1;
        {
            const std::lock_guard<std::mutex> lock(st.mutex);
            ++st.counters.clients;
        }
        return static_cast<std::ptrdiff_t>(st.upstreams.size() - 1);
    };

    while (!stop_.load(std::memory_order_relaxed))
    {
        double now = now_s();
        send_due(now);
        fds.clear();
        for (const auto& l : st.listeners)
            fds.push_back({l.fd, POLLIN, 0});
        for (const auto& u : st.upstreams)
            fds.push_back({u.fd, POLLIN, 0});
        int timeout_ms = 2;
        if (!st.queue.empty())
        {
            const double wait = st.queue.top().due - now;
            timeout_ms = std::clamp(static_cast<int>(std::ceil(wait * 1000.0)), 0, 2);
        }
        if (::poll(fds.data(), fds.size(), timeout_ms) <= 0)
            continue;
        now = now_s();
        const std::size_t nl = st.listeners.size();
        for (std::size_t i = 0; i < fds.size(); ++i)
        {
            if ((fds[i].revents & POLLIN) == 0)
                continue;
            for (int k = 0; k < 256; ++k)
            {
                sockaddr_in from{};
                socklen_t len = sizeof from;
                const ssize_t n = ::recvfrom(fds[i].fd, buf.data(), buf.size(), MSG_DONTWAIT,
                                             reinterpret_cast<sockaddr*>(&from), &len);
                if (n < 0)
                    break;
                const auto size = static_cast<std::size_t>(n);
                if (i < nl)
                {
                    // From a client to listener i: out through the client's upstream socket.
                    const std::ptrdiff_t u = upstream_for(i, from);
                    if (u < 0)
                        continue;
                    const auto uu = static_cast<std::size_t>(u);
                    impair(buf.data(), size, st.upstreams[uu].fd, st.listeners[i].target, 2 * uu,
                           now);
                }
                else
                {
                    // From the target to an upstream socket: back to its client from the listener.
                    const std::size_t uu = i - nl;
                    const State::Upstream& up = st.upstreams[uu];
                    if (key_of(from) != key_of(st.listeners[up.listener].target))
                    {
                        const std::lock_guard<std::mutex> lock(st.mutex);
                        ++st.counters.unknown_source;
                        continue;
                    }
                    impair(buf.data(), size, st.listeners[up.listener].fd, up.client, 2 * uu + 1,
                           now);
                }
            }
        }
    }
}

}  // namespace pliant::test
