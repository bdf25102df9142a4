#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs a command with a small file-size limit, as a full disk would stop it: a write past
# BLOCKS blocks (ulimit -f) fails with EFBIG ("File too large") instead of killing the command.
#   file_size_limit.sh BLOCKS COMMAND...
set -u
ulimit -f "$1" || exit 94
trap '' XFSZ
shift
exec "$@"
