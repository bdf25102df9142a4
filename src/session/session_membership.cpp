// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// Session::Impl (session/session_internal.h): connections, leaving, losses, pauses and master
// failover.
#include <spdlog/spdlog.h>

#include "session/session_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace pliant::session
{

void Session::Impl::finish_leave_soon()
{
    // The others disconnect us once past the hand-over; a timeout guards against a peer that
    // never does.
    if (last_now - leave_started > k_leave_timeout_s)
        close_all(net::DisconnectReason::Quit);
}

void Session::Impl::close_all(net::DisconnectReason reason)
{
    for (const net::PeerHandle h : transport.peers())
        transport.disconnect(h, reason);
    transport.flush();
    s.left_ = true;
}

void Session::Impl::disconnect_finished_leavers()
{
    const std::uint64_t t = s.state_.tick;
    for (auto& [id, p] : peers)
        if (p.leaving && !p.departed && p.handle && !member(partition_at(t), net::PeerId{id}) &&
            !member(t > 0 ? partition_at(t - 1) : nullptr, net::PeerId{id}))
        {
            transport.disconnect(*p.handle, net::DisconnectReason::Quit);
            p.departed = true;
        }
}

void Session::Impl::on_connected(net::PeerHandle h)
{
    if (master_handle && h == *master_handle && !welcomed)
    {
        master_connected = true;
        // Asking to be admitted: reliable only (a repeat would be a second joiner).
        net::Message m;
        m.header.sender = net::k_no_peer;
        m.body = make_hello();
        (void)messenger.send(h, m);
        return;
    }
    auto it = dialing.find(h);
    if (it == dialing.end())
    {
        // Someone dialled us: it has k_greeting_deadline_s to say who it is, counted from
        // the caller's next advance() if none has come yet (NaN until then).
        ungreeted[h] = advanced ? last_now : std::numeric_limits<double>::quiet_NaN();
        return;
    }
    (void)messenger.send(h, make(make_hello(), s.state_.tick));
    const std::uint16_t id = it->second;
    bind(h, id);
    dialing.erase(it);
    RemotePeer& p = peers[id];
    if (!p.heard)
        p.hello_repeat_until = last_now + k_greeting_repeat_s;
}

/// Closes the incoming connections that have not greeted within k_greeting_deadline_s of the
/// caller's clock (a bound connection has greeted: its entry is dropped).
void Session::Impl::close_ungreeted()
{
    for (auto it = ungreeted.begin(); it != ungreeted.end();)
    {
        if (std::isnan(it->second))
            it->second = last_now;
        if (handle_ids.contains(it->first))
            it = ungreeted.erase(it);
        else if (last_now - it->second > k_greeting_deadline_s)
        {
            const auto address = transport.remote_address(it->first);
            spdlog::warn("session: the connection from {} sent no Hello within {:g} s: closed",
                         address ? net::to_string(*address) : std::string("?"),
                         k_greeting_deadline_s);
            ++counters.ungreeted_closed;
            transport.disconnect(it->first, net::DisconnectReason::TimedOut);
            it = ungreeted.erase(it);
        }
        else
            ++it;
    }
}

void Session::Impl::on_disconnected(net::PeerHandle h, net::DisconnectReason reason)
{
    ungreeted.erase(h);
    auto ls = last_stats.find(h);
    if (ls != last_stats.end())
    {
        closed_stats.bytes_sent += ls->second.bytes_sent;
        closed_stats.bytes_received += ls->second.bytes_received;
        closed_stats.packets_sent += ls->second.packets_sent;
        closed_stats.packets_received += ls->second.packets_received;
        closed_stats.bad_datagrams += ls->second.bad_datagrams;
        last_stats.erase(ls);
    }
    lose_peer(h, reason);
}

/// The session's part of a disconnection (on_disconnected without the traffic counters):
/// the peer on `h` is gone; the master tells the others and re-partitions.
void Session::Impl::lose_peer(net::PeerHandle h, net::DisconnectReason reason)
{
    auto it = handle_ids.find(h);
    if (it == handle_ids.end())
    {
        if (master_handle && h == *master_handle && !welcomed)
        {
            // Refused or unreachable: keep why, a joiner's user has nothing else to go on.
            if (!join_lost)
                join_lost = reason;
            spdlog::debug("session: connection to the master ended before the Welcome ({})",
                          net::to_string(reason));
            s.left_ = true;
        }
        return;
    }
    const std::uint16_t id = it->second;
    handle_ids.erase(it);
    RemotePeer& p = peers[id];
    p.handle.reset();
    p.departed = true;
    // Its entry stays (ids are never reused; its forces end by the partitions), but not what
    // only a connected peer needs: partitions it sent aside, its acks (received and to send),
    // its stream budget and batch. Else every connection that ever claimed an id would hold
    // them for the session's life.
    foreign_partitions.erase(id);
    acked.erase(id);
    pending_acks.erase(id);
    priority.erase(id);
    budget.erase(id);
    batch.erase(id);
    spdlog::debug("session: peer {} disconnected ({})", id, net::to_string(reason));
    if (net::PeerId{id} == master_id && s.role_ != SessionRole::Master &&
        reason == net::DisconnectReason::Shutdown)
        close_all(net::DisconnectReason::Shutdown);  // the master ended the session
    else if (net::PeerId{id} == master_id && s.role_ != SessionRole::Master &&
             reason == net::DisconnectReason::Kicked)
    {
        // The master removed us (exact coupling: we held the lockstep past its
        // max_barrier_wait_s). The others drop us too; taking over as master would split
        // the session.
        refusal = fmt::format(
            "the master removed this peer from the session (in exact coupling, a peer that "
            "publishes no step for the session's max_barrier_wait_s, {:g} s here, is removed: "
            "was this process stopped or far too slow?)",
            settings.max_barrier_wait_s);
        close_all(net::DisconnectReason::Quit);
    }
    else
        lost_pending.emplace_back(id, reason);  // settle_losses(), once the clock is known
    if (leaving && handle_ids.empty())
        s.left_ = true;
}

/// Handles the departures lose_peer noticed: a participant or viewer whose master is gone
/// follows the successor (or becomes it); a master tells the others and re-partitions. Run
/// from advance(), after the pause check: a process resumed after a stop past its own
/// transport's longest timeout (ENet: 30 s) sees every peer time out in its first poll(),
/// before the advance() that shows the gap, and those departures are its own removal, not
/// the others' (pause_s).
void Session::Impl::settle_losses()
{
    if (lost_pending.empty())
        return;
    const auto lost = std::move(lost_pending);
    lost_pending.clear();
    if (s.left_ || dropped_after_pause(lost))
        return;
    follow_master();
    if (s.role_ != SessionRole::Master || s.left_)
        return;
    for (const auto& [id, reason] : lost)
    {
        net::PeerLeft msg;
        msg.peer = net::PeerId{id};
        msg.reason =
            reason == net::DisconnectReason::None ? net::DisconnectReason::TimedOut : reason;
        send_all(make(msg, s.state_.tick));
    }
    repartition_pending = true;
    if (s.coupling_ == Coupling::Fast)
        master_repartition(s.state_.tick);
}

/// Whether `lost` is this peer's own removal after a pause (SessionSettings::pause_s): the
/// others dropped it while it did not run and went on without it. Then it leaves, saying
/// so, instead of following a successor of its own choosing (a master: instead of going on
/// with what is left), which would split the session in two.
bool Session::Impl::dropped_after_pause(
    const std::vector<std::pair<std::uint16_t, net::DisconnectReason>>& lost)
{
    if (!pause_suspect)
        return false;
    // Only a loss by timeout tells: a peer that said goodbye (Quit, a leave or a diverged
    // step; Shutdown, handled in lose_peer) left on its own, and Kicked is this master's own
    // removal of a member (wait_at_barrier).
    bool ours = false;
    for (const auto& [id, reason] : lost)
    {
        const RemotePeer& p = peers.at(id);
        if ((reason != net::DisconnectReason::TimedOut && reason != net::DisconnectReason::None) ||
            p.leaving)
            continue;
        ours = ours || (s.role_ != SessionRole::Master ? net::PeerId{id} == master_id
                                                       : p.info.role == net::Role::Participant);
    }
    if (!ours)
        return false;
    leave_after_pause();
    return true;
}

/// The peers whose silence after a pause tells that this peer was dropped: its master, or
/// (the master) the participants.
bool Session::Impl::pause_witness(std::uint16_t id, const RemotePeer& p) const
{
    if (p.departed || p.leaving)
        return false;
    return s.role_ == SessionRole::Master ? p.info.role == net::Role::Participant
                                          : net::PeerId{id} == master_id;
}

/// While pause_suspect: a message from a witness (pause_witness) clears it; a silence of
/// every witness's link for k_pause_silence_s since the pause (the transport hears not even
/// an acknowledgement: the far end dropped this peer) means this peer was dropped.
void Session::Impl::check_pause()
{
    if (!pause_suspect || s.left_)
        return;
    const double since = last_now - pause_end;
    if (since > k_pause_suspect_s)
    {
        pause_suspect = false;
        return;
    }
    bool any = false;
    bool silent = true;
    for (const auto& [id, p] : peers)
    {
        if (!pause_witness(id, p))
            continue;
        if (p.heard_at > pause_end)
        {
            pause_suspect = false;  // it still sends to us: still a member
            return;
        }
        any = true;
        const auto st = p.handle ? transport.stats(*p.handle) : std::nullopt;
        silent = silent && st && st->silent_s >= k_pause_silence_s;
    }
    if (any && silent && since >= k_pause_silence_s)
        leave_after_pause();
}

void Session::Impl::leave_after_pause()
{
    pause_suspect = false;
    const char* who = s.role_ == SessionRole::Master   ? "master"
                      : s.role_ == SessionRole::Viewer ? "viewer"
                                                       : "participant";
    const char* then =
        s.role_ == SessionRole::Master
            ? "it left rather than run a second session beside theirs (their participant "
              "with the lowest id takes over as master): join their session through it, or "
              "host a new one"
        : s.role_ == SessionRole::Viewer
            ? "it left: join again (through the master's address: it may have changed)"
            : "it left rather than run a second session beside theirs: join again (through "
              "the master's address: it may have changed)";
    refusal = fmt::format(
        "this {} did not run for {:.1f} s (the process was stopped, suspended or starved), "
        "longer than the others wait for a silent peer: they dropped it and went on without "
        "it (or left while it was stopped, their goodbye lost); {}",
        who, pause_length, then);
    close_all(net::DisconnectReason::Quit);
}

/// Notes a pause (no advance() for SessionSettings::pause_s) ending at `now`, after `gap`.
void Session::Impl::note_pause(double now, double gap)
{
    pause_end = now;
    pause_length = gap;
    pause_suspect = true;
    ++counters.pauses;
    counters.longest_pause_s = std::max(counters.longest_pause_s, gap);
    // A wait at the barrier restarts: the time this peer did not run is nobody's fault.
    if (barrier_since >= 0.0)
        barrier_since = now;
    spdlog::warn(
        "session: this peer did not run for {:.1f} s (the process was stopped, suspended or "
        "starved); the others drop a peer silent for their transport's timeout (5-30 s)",
        gap);
}

/// The lowest id among the participants this peer knows to be alive and staying, itself
/// included: the same on every peer once each has noticed the same departures.
/// `without`: as if that peer were gone too.
std::optional<net::PeerId> Session::Impl::successor(std::optional<net::PeerId> without) const
{
    std::optional<net::PeerId> best;
    if (s.role_ != SessionRole::Viewer && !leaving)
        best = s.id_;
    for (const auto& [id, p] : peers)
        if (!p.departed && !p.leaving && p.info.role == net::Role::Participant &&
            (!without || id != without->value) && (!best || id < best->value))
            best = net::PeerId{id};
    return best;
}

/// If the master we follow is gone, follows its successor (or becomes it). Called on every
/// departure, so a successor that was itself lost is replaced in turn.
void Session::Impl::follow_master()
{
    // A leaver follows too (its hand-over needs the successor's partition), but never
    // becomes master itself (successor() leaves it out).
    if (s.role_ == SessionRole::Master || s.left_)
        return;
    auto it = peers.find(master_id.value);
    if (it != peers.end() && !it->second.departed)
        return;
    const auto next = successor();
    if (leaving && !next)
    {
        close_all(net::DisconnectReason::Quit);  // our leave is done: nobody left to hand to
        return;
    }
    if (!s.model_)
    {
        // Nothing to continue with: the model was still arriving. Said as the refusal, which
        // `pliant join` and the viewer report.
        refusal = "the master (peer " + std::to_string(master_id.value) +
                  ") was lost before this peer had the model; join the session again "
                  "through its new master, the participant with the lowest id";
        spdlog::warn("session: {}", refusal);
        close_all(net::DisconnectReason::Quit);
        return;
    }
    if (!next)
    {
        spdlog::warn("session: master {} lost and no successor; the session ends", master_id.value);
        close_all(net::DisconnectReason::Quit);
        return;
    }
    if (leaving)  // our own leave: nothing the user needs to hear about
        spdlog::debug("session: leaving; master {} gone, following peer {}", master_id.value,
                      next->value);
    else
        spdlog::info("session: master {} lost; peer {} takes over", master_id.value, next->value);
    master_id = *next;
    if (*next == s.id_)
    {
        promote();
        return;
    }
    // Partitions it sent before we noticed the loss.
    auto kept = foreign_partitions.find(next->value);
    if (kept != foreign_partitions.end())
    {
        auto list = std::move(kept->second);
        foreign_partitions.erase(kept);
        for (const auto& [tick, p] : list)
            apply_partition(tick, p);
    }
    foreign_partitions.clear();
}

/// This peer becomes master: it partitions from now on (epochs above any seen), admits
/// joiners (ids above any known) and reports departures. It records nothing: a recording
/// needs every input from the start.
void Session::Impl::promote()
{
    s.role_ = SessionRole::Master;
    ++counters.promotions;
    // Joiners from now on must dial this peer: say where (`pliant join` listens on a port
    // of the system's choosing unless given --port).
    if (settings.listen_port != 0)
        spdlog::info("session: this peer (id {}) is the master now; joiners dial it on port {}",
                     s.id_.value, settings.listen_port);
    else
        spdlog::info("session: this peer (id {}) is the master now", s.id_.value);
    foreign_partitions.clear();
    const PartitionEntry* cur = newest();
    if (cur != nullptr)
        next_epoch = std::max(next_epoch, cur->epoch + k_successor_epoch_gap);
    std::uint16_t top = s.id_.value;
    for (const auto& [id, p] : peers)
        top = std::max(top, id);
    next_peer_id = std::max<std::uint16_t>(
        next_peer_id, static_cast<std::uint16_t>(std::min<int>(top + k_successor_id_gap, 0xFFFE)));
    // Participants partitioned before are ready even if their points never reached us.
    for (auto& [id, p] : peers)
        if (member(cur, net::PeerId{id}) && p.info.role == net::Role::Participant)
            p.ready = true;
    points_dirty = false;
    repartition_pending = true;
    if (s.coupling_ == Coupling::Exact && !lockstep)
    {
        // Not partitioned yet: start the lockstep from what we show.
        lockstep = true;
        published = false;
        state_exact = true;
        exact_from = s.state_.tick;
        flush_display();
        const core::TetraGrid& g = s.model_->grid();
        for (int y = 0; y < g.ny(); ++y)
            for (int x = 0; x < g.nx(); ++x)
            {
                s.state_.u.at(x, y) = s.display_u_.at(x, y);
                s.state_.v.at(x, y) = s.display_v_.at(x, y);
            }
    }
    // Tell the others which departures we saw (they may not have noticed them yet).
    for (const auto& [id, p] : peers)
        if (p.departed && !p.leaving)
        {
            net::PeerLeft msg;
            msg.peer = net::PeerId{id};
            msg.reason = net::DisconnectReason::TimedOut;
            send_all(make(msg, s.state_.tick));
        }
}

}  // namespace pliant::session
