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
#   7. (only when asked: PLIANT_CHECK_LEGS="tsan") ThreadSanitizer over the code that runs on
#      several threads: the net and session tests (peers as threads, the transports), the
#      viewer's background loader, and `demo --view` (session thread + window) under xvfb-run
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

# CI installs Mesa (EGL, OSMesa): an offscreen OpenGL context that cannot be made is a failure
# there, not a skip (tests/render/gl_fixture.h), so that a broken driver cannot turn the
# rendering tests green.
if [ "${CI:-}" = "true" ]; then export PLIANT_REQUIRE_GL=1; fi

if has_leg release; then run_preset release; fi
if has_leg asan; then run_preset asan; fi

if has_leg fuzz && [ -x scripts/fuzz-smoke.sh ]; then
    banner "fuzz smoke"
    bash scripts/fuzz-smoke.sh build/asan
fi

if has_leg tsan; then
    # Not in CI's legs: about 15 minutes more on 2 cores. OpenMP stays on one thread: GCC's
    # libgomp is not built with ThreadSanitizer, whose reports through it would be false.
    banner "tsan build (net, session, the viewer's loader, pliant)"
    cmake --preset tsan >/dev/null
    targets=(pliant_net_tests pliant_session_tests pliant)
    if grep -q '^PLIANT_HAVE_VIEWER:INTERNAL=ON' build/tsan/CMakeCache.txt; then
        targets+=(viewer_load_test)
    fi
    cmake --build --preset tsan -j "$jobs" --target "${targets[@]}"
    banner "tsan tests"
    export TSAN_OPTIONS="halt_on_error=1 ignore_noninstrumented_modules=1 second_deadlock_stack=1"
    export OMP_NUM_THREADS=1
    build/tsan/tests/net/pliant_net_tests --gtest_brief=1
    # The long fast-coupling drags are left out as in the asan leg (minutes under a sanitizer).
    build/tsan/tests/session/pliant_session_tests --gtest_brief=1 --gtest_filter='-SessionFastDrag.*'
    if [ -x build/tsan/tests/apps/viewer_load_test ]; then
        build/tsan/tests/apps/viewer_load_test --gtest_brief=1
    fi
    if command -v xvfb-run >/dev/null && [ -x build/tsan/apps/pliant-cli/pliant ]; then
        tsan_out=$(mktemp -d)
        xvfb-run -a build/tsan/apps/pliant-cli/pliant -q demo --quick --view --exit-after 4 \
            --out "$tsan_out/demo"
        rm -rf "$tsan_out"
    fi
    echo "tsan: no data race reported"
fi

banner "all checks passed in $(( $(date +%s) - start )) s"
