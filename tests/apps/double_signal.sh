#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Two SIGTERMs 10 ms apart to a command once it has started a child program (`pliant bench`
# and its suite program): the command must end the child, not leave it running orphaned, and
# exit with its own status, which this script passes on (stderr after it ends).
#   double_signal.sh COMMAND...
# Bounded: 120 s for the child to appear (exit 97), 60 s for both to end (killed, exit 95).
set -u
script=double_signal.sh
. "$(dirname "$0")/signal_common.sh"
start_command "$@"
# The first child of `pid` (from /proc: pgrep may not be installed).
child_of() {
    for status in /proc/[0-9]*/status; do
        if grep -q "^PPid:[[:space:]]*$1\$" "$status" 2>/dev/null; then
            basename "$(dirname "$status")"
            return
        fi
    done
}
child=
tries=0
while [ -z "$child" ]; do
    kill -0 "$pid" 2>/dev/null || { cat "$dir/stderr" >&2; finish; exit 96; }
    child=$(child_of "$pid")
    tries=$((tries + 1))
    [ "$tries" -gt 1200 ] && give_up 97 "no child program appeared within 120 s"
    [ -z "$child" ] && sleep 0.1
done
sleep 0.5
kill -TERM "$pid"
sleep 0.01
kill -TERM "$pid"
await_end 600 "the command or its child ($child) still runs 60 s after" "$child"
exit_with_status
