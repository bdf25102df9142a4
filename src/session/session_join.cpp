// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): greetings, the Welcome and its blobs.
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

void Session::Impl::on_hello(net::PeerHandle h, const net::Message& m, const net::Hello& hello)
{
    if (s.role_ == SessionRole::Master && m.header.sender == net::k_no_peer)
    {
        // A Welcome lists every peer, itself and the joiner included, at most
        // k_max_welcome_peers: a joiner beyond that would get a Welcome that cannot be
        // encoded (it waited for ever for its model).
        std::size_t members = 2;  // this master and the joiner
        for (const auto& [oid, op] : peers)
            members += !op.departed && op.info_known ? 1 : 0;
        if (!s.model_ || next_peer_id >= 0xFFFE || members > net::k_max_welcome_peers)
        {
            if (members > net::k_max_welcome_peers && last_now - warned_full_at >= 10.0)
            {
                warned_full_at = last_now;
                spdlog::warn(
                    "session: a joiner was refused: the session holds {} peers, "
                    "the most it can",
                    net::k_max_welcome_peers);
            }
            transport.disconnect(h, net::DisconnectReason::SessionFull);
            return;
        }
        const std::uint16_t id = next_peer_id++;
        RemotePeer& p = peers[id];
        p.info.id = net::PeerId{id};
        p.info.role = hello.role;
        const auto addr = transport.remote_address(h);
        p.info.ipv4 = addr ? addr->ipv4 : std::array<std::uint8_t, 4>{127, 0, 0, 1};
        p.info.port = hello.listen_port != 0 ? hello.listen_port : (addr ? addr->port : 1);
        if (p.info.port == 0)
            p.info.port = 1;
        p.info.name = hello.name;
        p.info_known = true;
        bind(h, id);
        send_welcome(id);
        net::PeerJoined joined;
        joined.peer = p.info;
        for (auto& [oid, op] : peers)
            if (oid != id)
                send_to(oid, make(joined, s.state_.tick));
        return;
    }
    if (m.header.sender == net::k_no_peer)
    {
        // Only the master admits: a joiner that dialled another peer (say, one that knew an
        // old master's successor by the wrong address) is refused at once, not left waiting.
        if (handle_ids.count(h) == 0)
            transport.disconnect(h, net::DisconnectReason::Refused);
        return;
    }
    // A peer greeting us after its Welcome.
    if (handle_ids.count(h) != 0)
        return;
    // Each joiner dials each peer once and ids are never reused: a second connection for
    // an id already connected, or departed, is someone else's claim to that peer's place
    // (its forces, its leaves' halos), refused before it could take the first one's link.
    if (const auto known = peers.find(m.header.sender.value);
        known != peers.end() && (known->second.handle || known->second.departed))
    {
        if (count_reject(counters.peer_claim_rejects, h))
            warn_rejected(h, "a Hello claiming the id of peer " +
                                 std::to_string(m.header.sender.value) +
                                 ", already connected or departed");
        transport.disconnect(h, net::DisconnectReason::Refused);
        return;
    }
    bind(h, m.header.sender.value);
    RemotePeer& p = peers[m.header.sender.value];
    if (!p.info_known)
    {
        // Its PeerJoined may still be on its way; the master's word replaces this then.
        p.info.role = hello.role;
        p.info.name = hello.name;
    }
    greet_new_peer(m.header.sender.value);
}

/// Sends a newly known peer what it needs from us that it cannot have seen: that we can take
/// leaf states, our points of interest, our newest force.
void Session::Impl::greet_new_peer(std::uint16_t id)
{
    if (s.model_)
        send_ready(id);
    if (points_sent && s.role_ != SessionRole::Viewer && !leaving)
    {
        net::PointsOfInterest poi;
        poi.points = my_points;
        send_to(id, make(poi, s.state_.tick));
    }
    for (const ForceEntry& e : my_forces)
    {
        net::Force f;
        f.forces = e.forces;
        send_to(id, make(f, e.apply_tick));
    }
}

/// Sends the Welcome's blob chunks to the joiners being fed while their connections hold
/// less than k_feed_window_bytes; a finished feed lets the messages that waited behind it go.
void Session::Impl::feed_blobs()
{
    if (feeding == 0)
        return;
    for (auto& [id, p] : peers)
    {
        if (!p.feed)
            continue;
        if (!p.handle || p.departed)
        {
            p.feed.reset();
            p.after_feed.clear();
            --feeding;
            continue;
        }
        RemotePeer::BlobFeed& f = *p.feed;
        const std::size_t total = f.model->size() + f.state->size();
        // Bounded: one chunk per pass, at most the window's worth per call.
        for (int guard = 0; guard < 64 && f.next < total &&
                            transport.queued_bytes(*p.handle) < k_feed_window_bytes;
             ++guard)
        {
            const bool in_model = f.next < f.model->size();
            const std::vector<std::byte>& blob = in_model ? *f.model : *f.state;
            const std::size_t off = in_model ? f.next : f.next - f.model->size();
            net::Blob b;
            b.kind = in_model ? net::BlobKind::Model : net::BlobKind::State;
            b.total_size = static_cast<std::uint32_t>(blob.size());
            b.offset = static_cast<std::uint32_t>(off);
            const std::size_t len = std::min(net::k_max_blob_chunk, blob.size() - off);
            b.data.assign(blob.begin() + static_cast<std::ptrdiff_t>(off),
                          blob.begin() + static_cast<std::ptrdiff_t>(off + len));
            (void)messenger.send(*p.handle, make(b, f.tick));
            f.next += len;
        }
        if (f.next < total)
            continue;
        p.feed.reset();
        --feeding;
        auto waiting = std::move(p.after_feed);
        p.after_feed.clear();
        for (auto& [m, mode] : waiting)
            (void)messenger.send(*p.handle, m, mode);
    }
}

void Session::Impl::send_welcome(std::uint16_t id)
{
    const core::TetraGrid& g = s.model_->grid();
    if (!model_blob_shared)  // the model never changes: encoded once, shared by every feed
        model_blob_shared = std::make_shared<const std::vector<std::byte>>(
            encode_model(*s.model_, s.coupling_, s.clearance_, settings.max_barrier_wait_s));
    const std::vector<std::byte>& model = *model_blob_shared;
    flush_display();
    auto state = encode_state(g, s.display_u_, s.display_v_, s.state_.tick, s.state_.time);
    net::Welcome w;
    w.your_id = net::PeerId{id};
    w.master_id = s.id_;
    w.grid_level = static_cast<std::uint8_t>(g.level());
    w.leaf_depth = static_cast<std::uint8_t>(s.graph_->depth());
    w.epoch = newest() != nullptr ? newest()->epoch : 0;
    w.time = s.state_.time;
    w.model_size = static_cast<std::uint32_t>(model.size());
    w.model_hash = core::hash_bytes(model);
    w.state_size = static_cast<std::uint32_t>(state.size());
    w.state_hash = core::hash_bytes(state);
    net::PeerInfo me = my_info_known ? my_info : net::PeerInfo{};
    me.id = s.id_;
    me.role = net::Role::Participant;
    if (!my_info_known)
    {
        me.port = settings.listen_port != 0 ? settings.listen_port : 1;
        me.name = settings.name;
    }
    w.peers.push_back(me);
    for (const auto& [oid, op] : peers)
        if (!op.departed && op.info_known && w.peers.size() < net::k_max_welcome_peers)
            w.peers.push_back(op.info);
    send_to(id, make(w, s.state_.tick));
    // The blobs follow as the connection drains (feed_blobs); what is sent to the joiner
    // from here on waits behind them.
    RemotePeer& joiner = peers[id];
    joiner.feed = RemotePeer::BlobFeed{
        model_blob_shared, std::make_shared<const std::vector<std::byte>>(std::move(state)), 0,
        s.state_.tick};
    ++feeding;
    // The partitions the joiner needs to follow the lockstep, then our forces.
    for (const PartitionEntry& p : partitions)
    {
        net::Partition msg;
        msg.epoch = p.epoch;
        msg.leaf_depth = static_cast<std::uint8_t>(s.graph_->depth());
        msg.owners = p.owners;
        send_to(id, make(msg, p.apply_tick));
    }
    greet_new_peer(id);
    feed_blobs();
}

void Session::Impl::on_welcome(net::PeerHandle h, const net::Message& m, const net::Welcome& w)
{
    if (welcomed || !master_handle || h != *master_handle)
        return;
    welcomed = true;
    welcome = w;
    welcome_tick = m.header.tick;
    welcome_now = last_now;
    s.id_ = w.your_id;
    master_id = w.master_id;
    session_id = m.header.session;
    messenger.set_session(session_id);
    bind(h, master_id.value);
    model_blob.assign(w.model_size, std::byte{0});
    state_blob.assign(w.state_size, std::byte{0});
    for (const net::PeerInfo& info : w.peers)
    {
        if (info.id == s.id_)
        {
            my_info = info;
            my_info_known = true;
            continue;
        }
        RemotePeer& p = peers[info.id.value];
        p.info = info;
        p.info_known = true;
        if (info.id == master_id)
            continue;
        auto handle = transport.connect(net::Address{info.ipv4, info.port});
        if (handle)
            dialing[*handle] = info.id.value;
    }
}

void Session::Impl::on_blob(const net::Blob& b)
{
    if (!welcomed || s.model_ || s.left_)  // left: refused a chunk already
        return;
    std::vector<std::byte>& dst = b.kind == net::BlobKind::Model ? model_blob : state_blob;
    std::size_t& got = b.kind == net::BlobKind::Model ? model_got : state_got;
    // The master sends each blob's chunks in order on the reliable, ordered channel, so each
    // starts where the previous one ended; anything else (a gap, an overlap, another total)
    // is a faulty master, and the blob could complete with a hole or never: refused now.
    if (b.total_size != dst.size() || b.offset != got || b.data.size() > dst.size() - got)
    {
        const char* what = b.kind == net::BlobKind::Model ? "model" : "state";
        spdlog::error(
            "session: the master's {} blob chunk of {} bytes at byte {} of {}, "
            "where byte {} of {} was next",
            what, b.data.size(), b.offset, b.total_size, got, dst.size());
        refusal = std::string("the master sent a chunk of its ") + what + " blob at byte " +
                  std::to_string(b.offset) + " (" + std::to_string(b.data.size()) + " bytes of " +
                  std::to_string(b.total_size) + ") where byte " + std::to_string(got) + " of " +
                  std::to_string(dst.size()) +
                  " was next: chunks must follow each other in order (docs/protocol.md, Blob)";
        close_all(net::DisconnectReason::ProtocolMismatch);
        return;
    }
    std::copy(b.data.begin(), b.data.end(), dst.begin() + b.offset);
    got += b.data.size();
    if (model_got < model_blob.size() || state_got < state_blob.size())
        return;
    if (core::hash_bytes(model_blob) != welcome.model_hash ||
        core::hash_bytes(state_blob) != welcome.state_hash)
    {
        spdlog::error("session: model or state blob hash mismatch");
        refusal = "the master's model or state blob does not match its hash";
        close_all(net::DisconnectReason::ProtocolMismatch);
        return;
    }
    auto decoded = decode_model(model_blob);
    if (!decoded)
    {
        spdlog::error("session: {}", decoded.error().message);
        refusal = decoded.error().message;
        close_all(net::DisconnectReason::ProtocolMismatch);
        return;
    }
    std::optional<DecodedState> state;
    if (!state_blob.empty())
    {
        auto st = decode_state(decoded->model.grid(), state_blob);
        if (!st)
        {
            // The master's state cannot be taken: stepping on from rest would diverge.
            spdlog::error("session: {}", st.error().message);
            refusal = st.error().message;
            close_all(net::DisconnectReason::ProtocolMismatch);
            return;
        }
        state = std::move(*st);
    }
    s.coupling_ = decoded->coupling;
    s.clearance_ = decoded->clearance;
    // The session's limit, which this peer applies if it becomes the master (the joiner's
    // own setting is not used, as for the clearance).
    if (decoded->max_barrier_wait_s)
        settings.max_barrier_wait_s = *decoded->max_barrier_wait_s;
    install_model(std::move(decoded->model));
    const core::TetraGrid& g = s.model_->grid();
    if (s.role_ != SessionRole::Viewer)
        if (auto r = check_coarsen(settings, g, s.graph_->depth(), s.coupling_, "Session::join");
            !r)
        {
            // Known only now (the master chose the level and the coupling): leave at once.
            spdlog::error("session: {}", r.error().message);
            refusal = r.error().message;
            close_all(net::DisconnectReason::Quit);
            return;
        }
    if (state)
    {
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
            {
                s.display_u_.at(x, y) = state->u.at(x, y);
                s.display_v_.at(x, y) = state->v.at(x, y);
            }
        s.model_->sync(s.display_u_);
        s.model_->sync(s.display_v_);
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
            {
                s.state_.u.at(x, y) = s.display_u_.at(x, y);
                s.state_.v.at(x, y) = s.display_v_.at(x, y);
            }
    }
    s.state_.time = welcome.time;
    s.state_.tick = welcome_tick;  // fast mode: ticks line up with the master's
    std::fill(leaf_time.begin(), leaf_time.end(), welcome.time);
    std::fill(leaf_tick.begin(), leaf_tick.end(), welcome_tick);
    clock_offset = welcome.time - last_now;
    if (s.coupling_ == Coupling::Fast)
    {
        // Fast mode runs on the master's clock: the welcome's time was the master's half a
        // round trip before the Welcome arrived, and the blobs took a while since (seconds
        // over a lossy link); starting from welcome.time now would leave this peer that far
        // behind for the whole session, and age every state it sends (docs/session.md §4.3).
        // The state is not stepped over the gap: the leaves we get start from the newest
        // states streamed to us (fast_advance), the rest is held anyway.
        double half_rtt = 0.0;
        if (master_handle)
            if (const auto st = transport.stats(*master_handle))
                half_rtt = std::clamp(0.5 * st->rtt_s, 0.0, 0.25);
        clock_offset = welcome.time + half_rtt - welcome_now;
        s.state_.time = last_now + clock_offset;
    }
    clock_set = true;
    next_stream = last_now;
    next_frame = last_now;
    model_blob.clear();
    state_blob.clear();
    // Leaf states may come now: to the peers we are connected to, and to the others (queued
    // until their connection is up) right after our Hello.
    for (const auto& [pid, p] : peers)
        send_ready(pid);
    // Partitions that arrived with the blobs.
    for (auto& m : early)
        handle(m.first, m.second);
    early.clear();
    if (s.role_ == SessionRole::Participant)
    {
        points_dirty = true;
        send_points();
    }
}

}  // namespace pliant::session
