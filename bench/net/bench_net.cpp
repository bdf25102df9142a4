// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Codec throughput (bytes/s and datagrams/s for the state messages that dominate traffic, and the
// large control messages) and the round trip of a Ping/Pong over ENet on 127.0.0.1 through the
// Messenger (encode, ENet, decode, both ways). Timing is noisy on shared machines: compare
// medians of --benchmark_repetitions runs.
//
// Before the timed part, the state-streaming bandwidth per peer for levels 4..8 (no timing: it
// follows from the protocol): every leaf of the partition depth is encoded as the LeafState
// datagram the session streams (f64 and f32 values), and the bytes of one full-object broadcast
// give, at the stream rate R, P peers each owning 1/P of the leaves and sending them to the P - 1
// others: bytes/s out per peer = total * (P - 1) / P * R. Payload bytes (as SessionStats counts
// them) and, on the wire, + 28 B of UDP/IPv4 and ~10 B of ENet headers per datagram.
//
//   bench_net [--quick] [--json FILE] [--csv FILE] [--stream-rate HZ] [Google Benchmark flags]
//
// --help prints the usage (k_usage); an unknown argument or a bad rate exits 2 before anything
// runs.

#include <pliant/net/codec.h>
#include <pliant/net/enet_transport.h>
#include <pliant/net/messenger.h>
#include <pliant/session/partition.h>

#include <benchmark/benchmark.h>

#include "gbench_report.h"
#include "net/sample_messages.h"

#include <chrono>
#include <cstdio>
#include <limits>
#include <string_view>

namespace
{

using namespace pliant::net;

Message sample(MessageType type, std::size_t nth = 0)
{
    for (const Message& m : samples::all())
        if (m.type() == type && nth-- == 0)
            return m;
    return samples::all().front();
}

// args: 0 LeafState f64 x 73, 1 LeafState f32 x 147, 2 Halo f64 u+v, 3 Welcome, 4 Partition d=2,
// 5 LeafBatch of 5 leaves x 72 nodes (zstd-packed quantised residuals)
Message case_message(std::int64_t which)
{
    switch (which)
    {
    case 0: return sample(MessageType::LeafState, 0);
    case 1: return sample(MessageType::LeafState, 1);
    case 2: return sample(MessageType::Halo, 1);
    case 3: return sample(MessageType::Welcome);
    case 5: return sample(MessageType::LeafBatch, 1);
    default: return sample(MessageType::Partition);
    }
}

void label(benchmark::State& state, const Message& m, std::size_t bytes)
{
    state.SetLabel(std::string(to_string(m.type())) + " " + std::to_string(bytes) + " B");
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_Encode(benchmark::State& state)
{
    const Message m = case_message(state.range(0));
    std::vector<std::byte> buf(k_max_datagram_size);
    std::size_t bytes = 0;
    for (auto _ : state)
    {
        auto r = encode(m, buf);
        bytes = *r;
        benchmark::DoNotOptimize(buf.data());
    }
    label(state, m, bytes);
}
BENCHMARK(BM_Encode)->DenseRange(0, 5);

void BM_Decode(benchmark::State& state)
{
    const Message m = case_message(state.range(0));
    std::vector<std::byte> buf(encoded_size(m));
    (void)encode(m, buf);
    for (auto _ : state)
    {
        auto r = decode(buf);
        benchmark::DoNotOptimize(r);
    }
    label(state, m, buf.size());
}
BENCHMARK(BM_Decode)->DenseRange(0, 5);

// decode_into() into one reused message, as Messenger::next() does: no allocation once the
// message's vectors have grown.
void BM_DecodeInto(benchmark::State& state)
{
    const Message m = case_message(state.range(0));
    std::vector<std::byte> buf(encoded_size(m));
    (void)encode(m, buf);
    Message out;
    for (auto _ : state)
    {
        auto err = decode_into(buf, out);
        benchmark::DoNotOptimize(err);
        benchmark::DoNotOptimize(out);
    }
    label(state, m, buf.size());
}
BENCHMARK(BM_DecodeInto)->DenseRange(0, 5);

// One Ping from a to b and the Pong back, over ENet on loopback, both hosts serviced by this
// thread. Skips (with an error) if no socket binds.
void BM_EnetLoopbackRoundTrip(benchmark::State& state)
{
    auto ta = make_enet_transport();
    auto tb = make_enet_transport();
    auto ra = ta->open(Address{{127, 0, 0, 1}, 0});
    auto rb = tb->open(Address{{127, 0, 0, 1}, 0});
    if (!ra || !rb)
    {
        state.SkipWithError("cannot bind UDP on 127.0.0.1");
        return;
    }
    Messenger a(*ta);
    Messenger b(*tb);
    const PeerHandle a_to_b = ta->connect(*rb).value();
    PeerHandle b_to_a;
    bool a_up = false;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while ((!a_up || b_to_a.value == 0) && std::chrono::steady_clock::now() < deadline)
    {
        if (auto ev = a.poll(1))
            a_up = a_up || ev->kind == MessengerEvent::Kind::Connected;
        if (auto ev = b.poll(1); ev && ev->kind == MessengerEvent::Kind::Connected)
            b_to_a = ev->peer;
    }
    if (!a_up || b_to_a.value == 0)
    {
        state.SkipWithError("ENet loopback connect failed");
        return;
    }
    const Message ping = sample(MessageType::Ping);
    const Message pong = sample(MessageType::Pong);
    const Message leaf = case_message(0);
    const Message& payload = state.range(0) == 0 ? ping : leaf;
    for (auto _ : state)
    {
        (void)a.send(a_to_b, payload);
        bool answered = false;
        for (int spin = 0; spin < 1000000 && !answered; ++spin)
        {
            if (auto ev = b.poll(0); ev && ev->kind == MessengerEvent::Kind::Received)
                (void)b.send(b_to_a, pong);
            if (auto ev = a.poll(0); ev && ev->kind == MessengerEvent::Kind::Received)
                answered = true;
        }
        if (!answered)
        {
            state.SkipWithError("a round trip was lost");
            return;
        }
    }
    state.SetLabel(state.range(0) == 0 ? "ping/pong (40 B each way)"
                                       : "leaf-state 1,224 B / pong 40 B (unreliable)");
}
BENCHMARK(BM_EnetLoopbackRoundTrip)->Arg(0)->Arg(1)->UseRealTime();

// Per-datagram overhead below the payload: UDP + IPv4 headers, and ENet's protocol header plus
// an unreliable-sequenced command header (about 10 B).
constexpr double k_udp_ip_bytes = 28.0;
constexpr double k_enet_bytes = 10.0;

constexpr const char* k_usage =
    "usage: bench_net [--quick] [--json FILE] [--csv FILE] [--stream-rate HZ]\n"
    "                 [Google Benchmark flags]\n"
    "The state-streaming bandwidth per peer for levels 4..8 (from the encoded LeafState\n"
    "datagrams, no timing), then codec encode/decode throughput per message type and the "
    "Ping/Pong\n"
    "round trip over ENet on 127.0.0.1 (Google Benchmark; compare medians of repetitions).\n"
    "  --stream-rate HZ  stream rate of the bandwidth table, > 0 (default 60)\n"
    "  --quick           0.05 s per benchmark\n"
    "  --json FILE, --csv FILE\n"
    "                    also write the figures as rows (bench/common/bench_report.h)\n"
    "  --benchmark_filter=REGEX, --benchmark_repetitions=N, ...\n"
    "                    passed to Google Benchmark (--benchmark_list_tests=true lists the cases)\n"
    "  -h, --help        print this and exit\n";

/// Payload bytes and datagrams of one broadcast of every leaf's state at `level`.
std::pair<double, double> broadcast_bytes(int level, ValueEncoding encoding)
{
    const auto grid = pliant::core::TetraGrid::create(level).value();
    const pliant::session::LeafGraph graph(grid, pliant::session::leaf_depth_for(grid, encoding));
    double bytes = 0.0;
    double datagrams = 0.0;
    for (std::size_t l = 0; l < graph.size(); ++l)
    {
        const auto id = graph.leaves()[l];
        LeafState st;
        st.epoch = 1;
        st.leaf = WireLeafId{id.square, id.depth, id.ix, id.iy};
        st.encoding = encoding;
        st.u.assign(graph.node_count(l), 0.0);
        st.v.assign(graph.node_count(l), 0.0);
        Message m{Header{1, PeerId{1}, 0, 0}, st};
        bytes += static_cast<double>(encoded_size(m));
        datagrams += 1.0;
    }
    return {bytes, datagrams};
}

void streaming_bandwidth(pliant::bench::Report& report, double rate_hz)
{
    std::printf(
        "state streaming at %.0f Hz: bytes/s out per peer (payload; wire adds %.0f B per "
        "datagram)\n",
        rate_hz, k_udp_ip_bytes + k_enet_bytes);
    std::printf("%5s %9s %5s %10s %12s %12s %12s\n", "level", "vertices", "enc", "datagrams",
                "2 peers MB/s", "2 peers Mbit", "4 peers MB/s");
    for (int level = 4; level <= 8; ++level)
    {
        const auto grid = pliant::core::TetraGrid::create(level).value();
        const double vertices = static_cast<double>(grid.unique_count());
        for (const ValueEncoding enc : {ValueEncoding::F64, ValueEncoding::F32})
        {
            const auto [bytes, datagrams] = broadcast_bytes(level, enc);
            const std::string name = enc == ValueEncoding::F64 ? "f64" : "f32";
            const double wire = bytes + datagrams * (k_udp_ip_bytes + k_enet_bytes);
            for (const int peers : {2, 3, 4})
            {
                const double share = static_cast<double>(peers - 1) / peers * rate_hz;
                const std::string c = name + " " + std::to_string(peers) + " peers";
                report.add(c, level, vertices, "vertices", "stream_bytes_per_s_per_peer",
                           bytes * share, "B/s");
                report.add(c, level, vertices, "vertices", "stream_wire_bits_per_s_per_peer",
                           wire * share * 8.0, "bit/s");
            }
            report.add(name, level, vertices, "vertices", "datagrams_per_broadcast", datagrams,
                       "1");
            std::printf("%5d %9.0f %5s %10.0f %12.2f %12.2f %12.2f\n", level, vertices,
                        name.c_str(), datagrams, bytes * 0.5 * rate_hz / 1e6,
                        wire * 0.5 * rate_hz * 8.0 / 1e6, bytes * 0.75 * rate_hz / 1e6);
        }
    }
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv)
{
    pliant::bench::Report report("net");
    const pliant::bench::Usage usage(argv[0], k_usage);
    // --help and argument errors before anything runs; run_with_report parses again and finds
    // the report options already taken out (it keeps --quick and the file names).
    if (const auto status = report.parse_args(argc, argv, usage))
        return *status;
    double rate_hz = 60.0;
    // --stream-rate is ours; Google Benchmark's flags (--benchmark_*, --v=N) go on to it, and
    // anything else is refused here rather than after the streaming table.
    int out = 1;
    for (int i = 1; i < argc; ++i)
    {
        const std::string_view a = argv[i];
        if (a == "--stream-rate")
        {
            if (i + 1 >= argc)
                return usage.error("--stream-rate needs a rate in Hz");
            const auto rate = usage.number_in("--stream-rate", argv[++i], 0.0,
                                              std::numeric_limits<double>::infinity(),
                                              /*lo_open=*/true);
            if (!rate)
                return 2;
            rate_hz = *rate;
        }
        else if (a.starts_with("--benchmark_") || a.starts_with("--v="))
            argv[out++] = argv[i];
        else
            return usage.unexpected(a);
    }
    argc = out;
    argv[argc] = nullptr;
    report.meta("stream_rate_hz", std::to_string(rate_hz));
    streaming_bandwidth(report, rate_hz);  // cheap: the same in quick and full runs
    return pliant::bench::run_with_report(
        report, argc, argv,
        [&report](const benchmark::BenchmarkReporter::Run& r)
        {
            const double s = pliant::bench::real_seconds(r);
            const std::string name = r.benchmark_name();
            if (name.rfind("BM_EnetLoopbackRoundTrip", 0) == 0)
                report.add(r.report_label, -1, 0.0, "", "round_trip_us", s * 1e6, "us");
            else
            {
                const double items = pliant::bench::counter(r, "items_per_second");
                const double bytes = pliant::bench::counter(r, "bytes_per_second");
                const std::string op = name.rfind("BM_Encode", 0) == 0       ? "encode "
                                       : name.rfind("BM_DecodeInto", 0) == 0 ? "decode_into "
                                                                             : "decode ";
                report.add(op + r.report_label, -1, 0.0, "", "messages_per_s", items, "1/s");
                report.add(op + r.report_label, -1, 0.0, "", "bytes_per_s", bytes, "B/s");
            }
        });
}
