#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
#
# Smoke fuzz (seconds, bounded): runs every fuzz target found in BUILD_DIR/fuzz/ over its
# committed corpus fuzz/corpus/<name without the fuzz_ prefix>/.
#   - a corpus replayer (gcc builds): each input once;
#   - a libFuzzer binary (the `fuzz` preset): the corpus plus mutations for PLIANT_FUZZ_SECONDS
#     (default 20) per target.
# Exits non-zero when a target crashes, hangs (PLIANT_FUZZ_TIMEOUT, default 300 s per target) or a
# sanitizer reports. Usage: bash scripts/fuzz-smoke.sh [BUILD_DIR]   (default build/asan)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/asan}
seconds=${PLIANT_FUZZ_SECONDS:-20}
limit=${PLIANT_FUZZ_TIMEOUT:-300}

if [ ! -d "$build/fuzz" ]; then
    echo "fuzz-smoke: no $build/fuzz folder (build the tree first)" >&2
    exit 1
fi
found=0
failed=0
for exe in "$build"/fuzz/fuzz_*; do
    [ -f "$exe" ] && [ -x "$exe" ] || continue
    name=$(basename "$exe")
    corpus=fuzz/corpus/${name#fuzz_}
    if [ ! -d "$corpus" ]; then
        echo "fuzz-smoke: $name has no corpus folder $corpus" >&2
        failed=1
        continue
    fi
    found=$((found + 1))
    if "$exe" -help=1 2>&1 | grep -q "max_total_time"; then
        # libFuzzer: mutate into a scratch copy so the committed corpus stays as it is.
        work=$(mktemp -d)
        cp "$corpus"/* "$work"/ 2>/dev/null || true
        echo "fuzz-smoke: $name (libFuzzer, ${seconds} s)"
        if ! timeout "$limit" "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
            "$work"; then
            echo "fuzz-smoke: $name FAILED" >&2
            failed=1
        fi
        rm -rf "$work"
    else
        echo "fuzz-smoke: $name (replayer) over $corpus"
        if ! timeout "$limit" "$exe" "$corpus"; then
            echo "fuzz-smoke: $name FAILED" >&2
            failed=1
        fi
    fi
done
if [ "$found" -eq 0 ]; then
    echo "fuzz-smoke: no fuzz_* executables in $build/fuzz" >&2
    exit 1
fi
exit "$failed"
