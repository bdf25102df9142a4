#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Ctrl-C while a command waits to open an output that is a FIFO nobody reads: the first SIGINT
# must end the wait (the handler does not restart system calls) and the command its run.
#   fifo_interrupt.sh FIFO COMMAND...
# Makes FIFO (replacing what is there), runs COMMAND, waits until it is blocked opening the FIFO
# (/proc/PID/syscall: openat; or /proc/PID/wchan: wait_for_partner; where neither can be read,
# 5 s), sends one SIGINT and exits with the command's status, its stderr passed on.
# Bounded: 120 s for the command to block (exit 97), 30 s to end after the signal (killed, 95).
set -u
fifo=$1
shift
rm -f "$fifo"
mkfifo "$fifo" || exit 94
dir=$(mktemp -d "${TMPDIR:-/tmp}/pliant-fifo.XXXXXX") || exit 94
"$@" 2>"$dir/stderr" &
pid=$!
give_up() {
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    echo "fifo_interrupt.sh: $2" >&2
    cat "$dir/stderr" >&2
    rm -rf "$dir" "$fifo"
    exit "$1"
}
blocked() {
    if [ -r "/proc/$pid/syscall" ] && [ -r "/proc/$pid/wchan" ]; then
        case "$(cat "/proc/$pid/syscall" 2>/dev/null)" in "257 "*) return 0 ;; esac
        [ "$(cat "/proc/$pid/wchan" 2>/dev/null)" = wait_for_partner ]
        return
    fi
    [ "$tries" -ge 50 ]
}
tries=0
while ! blocked; do
    kill -0 "$pid" 2>/dev/null || give_up 96 "the command ended before it opened $fifo"
    tries=$((tries + 1))
    [ "$tries" -gt 1200 ] && give_up 97 "the command did not block on $fifo within 120 s"
    sleep 0.1
done
sleep 0.2
kill -INT "$pid"
tries=0
while kill -0 "$pid" 2>/dev/null; do
    tries=$((tries + 1))
    [ "$tries" -gt 300 ] && give_up 95 "one SIGINT did not end the command within 30 s"
    sleep 0.1
done
wait "$pid"
status=$?
cat "$dir/stderr" >&2
rm -rf "$dir" "$fifo"
exit "$status"
