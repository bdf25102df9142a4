#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Ctrl-C while a command waits on an output that is a FIFO: the first SIGINT must end the wait
# (the handler does not restart system calls) and the command its run.
#   fifo_interrupt.sh MODE FIFO COMMAND...
#   MODE no-reader:      nothing opens FIFO: COMMAND waits in open() for a reader
#   MODE stalled-reader: a reader opens FIFO and never reads: COMMAND waits in write() once the
#                        pipe's buffer (64 KiB) is full
# Makes FIFO (replacing what is there), runs COMMAND, waits until it is blocked there
# (/proc/PID/wchan: wait_for_partner, or *pipe_write; where wchan says nothing, the x86-64
# system call in /proc/PID/syscall: openat or write; where neither can be read, 5 s), checks
# again 0.2 s later, sends one SIGINT and exits with the command's status, its stderr passed on.
# Bounded: 120 s for the command to block (exit 97), 30 s to end after the signal (killed, 95).
set -u
script=fifo_interrupt.sh
. "$(dirname "$0")/signal_common.sh"
mode=$1
fifo=$2
shift 2
rm -f "$fifo"
mkfifo "$fifo" || exit 94
reader=
if [ "$mode" = stalled-reader ]; then
    sleep 300 <"$fifo" &
    reader=$!
fi
cleanup_extra() {
    [ -n "$reader" ] && kill "$reader" 2>/dev/null
    rm -f "$fifo"
}
start_command "$@"
blocked() {
    wchan=$(cat "/proc/$pid/wchan" 2>/dev/null)
    case "$mode:$wchan" in
    no-reader:wait_for_partner | stalled-reader:*pipe_write) return 0 ;;
    *:0 | *:) ;;  # wchan hidden: the system call instead
    *) return 1 ;;
    esac
    if [ -r "/proc/$pid/syscall" ]; then
        case "$mode:$(cat "/proc/$pid/syscall" 2>/dev/null)" in
        "no-reader:257 "* | "stalled-reader:1 "*) return 0 ;;
        *) return 1 ;;
        esac
    fi
    [ "$tries" -ge 50 ]
}
tries=0
while :; do
    kill -0 "$pid" 2>/dev/null || give_up 96 "the command ended before it blocked on $fifo"
    tries=$((tries + 1))
    [ "$tries" -gt 1200 ] && give_up 97 "the command did not block on $fifo within 120 s"
    if blocked; then
        sleep 0.2
        blocked && break
    fi
    sleep 0.1
done
kill -INT "$pid"
await_end 300 "one SIGINT did not end the command within 30 s"
exit_with_status
