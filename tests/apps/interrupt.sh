#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs a command, sends it SIGINT (Ctrl-C) once it is well into its work, and exits with the
# command's own status; its stdout and stderr are passed on (stderr after it ends).
#   interrupt.sh file PATH    COMMAND...   interrupt once PATH exists
#   interrupt.sh log PATTERN  COMMAND...   interrupt once the command's stderr has a line
#                                          matching PATTERN (grep -E)
# Bounded: 300 s for the condition (exit 97 if it never holds, 96 if the command ended first),
# then 120 s for the command to end after the signal (killed, exit 95, if it does not).
set -u
script=interrupt.sh
. "$(dirname "$0")/signal_common.sh"
kind=$1
what=$2
shift 2
start_command "$@"
ready() {
    if [ "$kind" = file ]; then
        [ -e "$what" ]
    else
        grep -Eq -- "$what" "$dir/stderr"
    fi
}
tries=0
while ! ready; do
    if ! kill -0 "$pid" 2>/dev/null; then
        wait "$pid"
        echo "$script: the command ended (status $?) before the condition held" >&2
        cat "$dir/stderr" >&2
        finish
        exit 96
    fi
    tries=$((tries + 1))
    if [ "$tries" -gt 3000 ]; then
        give_up 97 "the condition ($kind $what) did not hold within 300 s"
    fi
    sleep 0.1
done
kill -INT "$pid"
await_end 1200 "the command did not end within 120 s of SIGINT"
exit_with_status
