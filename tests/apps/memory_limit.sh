#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs a command with its address space limited to KB kibibytes (ulimit -v), as a small machine
# or a container's limit would: an allocation past it fails (std::bad_alloc) instead of the
# machine running out of memory.
#   memory_limit.sh KB COMMAND...
set -u
ulimit -v "$1" || exit 94
shift
exec "$@"
