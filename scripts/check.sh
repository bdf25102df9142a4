#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
#
# Builds pliant and runs every check CI runs: the README's test command.
#   1. installs missing Debian packages (scripts/install-deps.sh)
#   2. clang-format --dry-run -Werror on every C++ file
#   3. the module include rules (scripts/check_includes.py)
#   4. release build + the whole test suite (ctest)
#   5. ASan+UBSan build + the whole test suite
#   6. a short smoke run of each fuzz target's corpus replayer (when fuzz/ exists)
# Environment: PLIANT_CHECK_LEGS="format includes release asan fuzz" to choose legs;
# PLIANT_JOBS (default: number of cores). Under CI (CI=true) warnings are errors; elsewhere they
# are printed only, so that another compiler's new warning cannot stop a user's build.
set -euo pipefail
cd "$(dirname "$0")/.."

legs=${PLIANT_CHECK_LEGS:-"format includes release asan fuzz"}
jobs=${PLIANT_JOBS:-$(nproc)}
has_leg() { [[ " $legs " == *" $1 "* ]]; }
start=$(date +%s)
banner() { printf '\n==== %s (at %d s) ====\n' "$*" "$(( $(date +%s) - start ))"; }

banner "dependencies"
bash scripts/install-deps.sh

if has_leg format; then
    banner "format (clang-format --dry-run -Werror)"
    git ls-files '*.h' '*.cpp' | xargs -r clang-format --dry-run -Werror
    echo "format: $(git ls-files '*.h' '*.cpp' | wc -l) files clean"
fi

if has_leg includes; then
    banner "include rules (docs/style.md §2, scripts/check_includes.py)"
    python3 scripts/check_includes.py
fi

run_preset() {
    local preset=$1
    banner "$preset build"
    local werror=()
    if [ "${CI:-}" = "true" ]; then werror=(-DCMAKE_COMPILE_WARNING_AS_ERROR=ON); fi
    cmake --preset "$preset" "${werror[@]}" >/dev/null
    cmake --build --preset "$preset" -j "$jobs"
    banner "$preset tests"
    ctest --preset "$preset" -j "$jobs"
}

if has_leg release; then run_preset release; fi
if has_leg asan; then run_preset asan; fi

if has_leg fuzz && [ -x scripts/fuzz-smoke.sh ]; then
    banner "fuzz smoke"
    bash scripts/fuzz-smoke.sh build/asan
fi

banner "all checks passed in $(( $(date +%s) - start )) s"
