#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
#
# The README's main job: installs what is missing, builds pliant (release preset) and runs
# `pliant demo` on the bundled mesh. Extra arguments go to `pliant demo` (try --help).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --demo
cmake --preset release >/dev/null
cmake --build --preset release -j "${PLIANT_JOBS:-$(nproc)}" --target pliant
exec build/release/apps/pliant-cli/pliant demo "$@"
