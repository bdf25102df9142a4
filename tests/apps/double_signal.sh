#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Two SIGTERMs 10 ms apart to a command once it has started a child program (`pliant bench`
# and its suite program): the command must end the child, not leave it running orphaned, and
# exit with its own status, which this script passes on (stderr after it ends).
#   double_signal.sh COMMAND...
# Bounded: 120 s for the child to appear (exit 97), 60 s for both to end (killed, exit 95).
set -u
dir=$(mktemp -d "${TMPDIR:-/tmp}/pliant-double.XXXXXX") || exit 94
"$@" 2>"$dir/stderr" &
pid=$!
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
    kill -0 "$pid" 2>/dev/null || { cat "$dir/stderr" >&2; rm -rf "$dir"; exit 96; }
    child=$(child_of "$pid")
    tries=$((tries + 1))
    [ "$tries" -gt 1200 ] && { kill -KILL "$pid"; cat "$dir/stderr" >&2; rm -rf "$dir"; exit 97; }
    [ -z "$child" ] && sleep 0.1
done
sleep 0.5
kill -TERM "$pid"
sleep 0.01
kill -TERM "$pid"
tries=0
while kill -0 "$pid" 2>/dev/null || kill -0 "$child" 2>/dev/null; do
    tries=$((tries + 1))
    if [ "$tries" -gt 600 ]; then
        echo "double_signal.sh: the command or its child ($child) still runs 60 s after" >&2
        kill -KILL "$pid" "$child" 2>/dev/null
        cat "$dir/stderr" >&2
        rm -rf "$dir"
        exit 95
    fi
    sleep 0.1
done
wait "$pid"
status=$?
cat "$dir/stderr" >&2
rm -rf "$dir"
exit "$status"
