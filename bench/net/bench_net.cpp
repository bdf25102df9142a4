// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Codec throughput (bytes/s and datagrams/s for the state messages that dominate traffic, and the
// large control messages) and the round trip of a Ping/Pong over ENet on 127.0.0.1 through the
// Messenger (encode, ENet, decode, both ways). Timing is noisy on shared machines: compare
// medians of --benchmark_repetitions runs.

#include <pliant/net/codec.h>
#include <pliant/net/enet_transport.h>
#include <pliant/net/messenger.h>

#include <benchmark/benchmark.h>

#include "net/sample_messages.h"

#include <chrono>

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

// args: 0 LeafState f64 x 73, 1 LeafState f32 x 147, 2 Halo f64 u+v, 3 Welcome, 4 Partition d=2
Message case_message(std::int64_t which)
{
    switch (which)
    {
    case 0: return sample(MessageType::LeafState, 0);
    case 1: return sample(MessageType::LeafState, 1);
    case 2: return sample(MessageType::Halo, 1);
    case 3: return sample(MessageType::Welcome);
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
BENCHMARK(BM_Encode)->DenseRange(0, 4);

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
BENCHMARK(BM_Decode)->DenseRange(0, 4);

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

}  // namespace

BENCHMARK_MAIN();
