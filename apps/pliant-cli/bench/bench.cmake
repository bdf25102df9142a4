# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant bench` (cmd_bench.cpp): where the benchmark programs of this build tree are (the bench/
# folder is configured after the apps, so its targets cannot be asked for here; the command
# checks for each program when it runs) and where the gnuplot scripts are.
target_compile_definitions(pliant PRIVATE
    PLIANT_BENCH_DIR="${PROJECT_BINARY_DIR}/bench"
    PLIANT_PLOTS_DIR="${PROJECT_SOURCE_DIR}/scripts/plots")
