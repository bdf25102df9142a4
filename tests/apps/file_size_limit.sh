#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs a command with a small file-size limit, as a full disk would stop it: a write past
# BLOCKS blocks (ulimit -f) fails with EFBIG ("File too large") instead of killing the command.
#   file_size_limit.sh BLOCKS COMMAND...           SIGXFSZ ignored here, as a full disk is
#   file_size_limit.sh --as-set BLOCKS COMMAND...  SIGXFSZ left as a shell's `ulimit -f` leaves
#                                                  it (it kills): pliant must ignore it itself
set -u
trap_it=1
if [ "$1" = --as-set ]; then
    trap_it=0
    shift
fi
ulimit -f "$1" || exit 94
[ "$trap_it" = 1 ] && trap '' XFSZ
shift
exec "$@"
