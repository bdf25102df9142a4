#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs "$@" on a private Xvfb display (1280x800x24, no TCP) and exits with the command's status.
# xvfb-run was used before; its exit trap fails now and then on this machine (status 5,
# "problem while cleaning up temporary directory") after the command itself exited 1, which
# turned a correct run into a failure. Xvfb picks a free display itself (-displayfd), waited
# for at most 20 s.
set -u
dir=$(mktemp -d "${TMPDIR:-/tmp}/pliant-xvfb.XXXXXX") || exit 97
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$dir/display" 2>"$dir/log" &
server=$!
tries=0
while [ ! -s "$dir/display" ]; do
    tries=$((tries + 1))
    if [ "$tries" -gt 200 ] || ! kill -0 "$server" 2>/dev/null; then
        echo "with_xvfb: Xvfb did not start:" >&2
        cat "$dir/log" >&2
        kill "$server" 2>/dev/null
        rm -rf "$dir"
        exit 98
    fi
    sleep 0.1
done
DISPLAY=":$(head -n 1 "$dir/display")" "$@"
status=$?
kill "$server" 2>/dev/null
wait "$server" 2>/dev/null
rm -rf "$dir"
exit "$status"
