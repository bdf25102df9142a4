# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Shared by the scripts that signal a running command (interrupt.sh, fifo_interrupt.sh,
# double_signal.sh): sourced, not run. Each sets `script` (its name, for messages) and may define
# `cleanup_extra` (called before exiting) before calling these.

# Runs the command "$@" in the background with its stderr kept in a fresh folder: sets `pid` and
# `dir` (exit 94 if no folder can be made).
start_command() {
    dir=$(mktemp -d "${TMPDIR:-/tmp}/pliant-$script.XXXXXX") || exit 94
    "$@" 2>"$dir/stderr" &
    pid=$!
}

# Removes the folder (and what cleanup_extra removes).
finish() {
    if command -v cleanup_extra >/dev/null 2>&1; then
        cleanup_extra
    fi
    rm -rf "$dir"
}

# Kills the command (and the processes named in $3...), shows its stderr and exits with status
# $1 after saying $2.
give_up() {
    code=$1
    message=$2
    shift 2
    kill -KILL "$pid" "$@" 2>/dev/null
    wait "$pid" 2>/dev/null
    echo "$script: $message" >&2
    cat "$dir/stderr" >&2
    finish
    exit "$code"
}

# Waits, in tenths of a second up to $1, for the command (and the processes named in $3...) to
# end; gives up with status 95 and message $2 if one still runs.
await_end() {
    limit=$1
    message=$2
    shift 2
    tries=0
    while kill -0 "$pid" 2>/dev/null || { [ $# -gt 0 ] && kill -0 "$@" 2>/dev/null; }; do
        tries=$((tries + 1))
        [ "$tries" -gt "$limit" ] && give_up 95 "$message" "$@"
        sleep 0.1
    done
}

# Exits with the command's status, its stderr passed on.
exit_with_status() {
    wait "$pid"
    status=$?
    cat "$dir/stderr" >&2
    finish
    exit "$status"
}
