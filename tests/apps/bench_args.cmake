# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# The benchmark programs' own arguments (bench/common/bench_report.h's Usage): --help prints the
# usage to stdout and exits 0, an unknown option or a level out of range exits 2 naming the
# argument, both before anything is measured. Only where the programs are built (not under the
# sanitizers: PLIANT_BUILD_BENCH is OFF there; bench/ is configured after tests/, so the option
# and the folders are checked, and $<TARGET_FILE> resolves once every target exists).
if(PLIANT_BUILD_BENCH AND EXISTS ${PROJECT_SOURCE_DIR}/bench/CMakeLists.txt)
    # pliant_bench_args(NAME PROGRAM EXIT STDOUT|STDERR REGEX ARGS...)
    function(pliant_bench_args name program exit stream regex)
        list(JOIN ARGN ";" args)
        add_test(NAME ${name}
                 COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:${program}>;${args}"
                         -DEXIT=${exit} "-D${stream}_REGEX=${regex}"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(${name} PROPERTIES TIMEOUT 30 LABELS bench_args)
    endfunction()

    if(EXISTS ${PROJECT_SOURCE_DIR}/bench/session/CMakeLists.txt)
        pliant_bench_args(bench_args_session_help pliant_bench_session 0 STDOUT
                          "^usage: pliant_bench_session .*--steps \\[levels\\.\\.\\.\\]" --help)
        pliant_bench_args(bench_args_session_steps_level_out_of_range pliant_bench_session 2
                          STDERR "^pliant_bench_session: --steps level '99' is out of range \\(expected 1\\.\\.10\\)\nusage: "
                          --steps 99)
        pliant_bench_args(bench_args_session_unknown_option pliant_bench_session 2 STDERR
                          "^pliant_bench_session: unknown option '--bogus'\nusage: " --bogus)
        pliant_bench_args(bench_args_session_level_not_a_number pliant_bench_session 2 STDERR
                          "^pliant_bench_session: level 'five' is not a whole number \\(expected 1\\.\\.10\\)"
                          5 five)
        # The grab-latency run at level 4 (under a second): every grab shows on every peer
        # within its run (the program exits 1 otherwise) and the table has its last row.
        pliant_bench_args(bench_session_latency_level_4 pliant_bench_session 0 STDOUT
                          "\n +5\\.0 +4 +4 +fast \\| +[0-9.]+ / +[0-9.]+ \\|" --latency 4)
        # The same over ENet on 127.0.0.1 in real time (a thread per peer; about 10 s): every
        # grab shows on every peer within 2 s of wall time.
        pliant_bench_args(bench_session_latency_enet_level_4 pliant_bench_session 0 STDOUT
                          "\n +0\\.0 +4 +4 +fast \\| +[0-9.]+ / +[0-9.]+ \\|" --latency 4
                          --enet)
        set_tests_properties(bench_session_latency_enet_level_4 PROPERTIES TIMEOUT 120)
        # Joins through the impairing relay at level 4 without loss (about 3 s): every
        # configuration's run reaches its full mesh (the program exits 1 otherwise), the last
        # row closes the table.
        pliant_bench_args(bench_session_join_level_4 pliant_bench_session 0 STDOUT
                          "\n +4 fast retransmit \\+ 256 KiB window +\\| +[0-9.]+ / +[0-9.]+ \\|.* 0 \\| +[0-9]+\n$"
                          --join 4 --loss 0 --runs 1)
        set_tests_properties(bench_session_join_level_4 PROPERTIES TIMEOUT 120)
        pliant_bench_args(bench_args_session_loss_without_join pliant_bench_session 2
                          STDERR "^pliant_bench_session: --loss applies to --join only\nusage: "
                          --latency 4 --loss 0.1)
        pliant_bench_args(bench_args_session_loss_out_of_range pliant_bench_session 2
                          STDERR "^pliant_bench_session: --loss '0\\.9' is not a number >= 0 and <= 0\\.5"
                          --join 4 --loss 0.9)
        pliant_bench_args(bench_args_session_copy_accept_without_steps pliant_bench_session 2
                          STDERR "^pliant_bench_session: --copy-accept applies to --steps only\nusage: "
                          --latency 4 --copy-accept)
        pliant_bench_args(bench_args_session_random_points_without_steps pliant_bench_session 2
                          STDERR "^pliant_bench_session: --random-points applies to --steps only\nusage: "
                          --latency 4 --random-points 3)
        pliant_bench_args(bench_args_session_random_points_out_of_range pliant_bench_session 2
                          STDERR "^pliant_bench_session: --random-points '0' is out of range \\(expected 1\\.\\.1000\\)"
                          --steps 4 --random-points 0)
        # Random point layouts at level 4 (a few seconds): the 4-peer row closes the table, with
        # a median, a worst, the count within the target and the partitions' kinds per column.
        pliant_bench_args(bench_session_steps_random_points_level_4 pliant_bench_session 0 STDOUT
                          "\n +4 +4 \\| [0-9.]+ [0-9.]+ +[0-9]+ [0-9gsrtwb]+ \\| [0-9.]+ [0-9.]+ +[0-9]+ [0-9gsrtwb]+ \\| [0-9.]+ [0-9.]+ +[0-9]+ [0-9gsrtwb]+\n"
                          --steps 4 --random-points 1)
        # Each peer's whole work at level 4 (under a second): every row reaches its steady
        # state, the 4-peer fast row closes the table.
        pliant_bench_args(bench_session_cpu_level_4 pliant_bench_session 0 STDOUT
                          "\n +4 fast +4 \\| +[0-9.]+ +[0-9.]+ \\| +[0-9.]+ +[0-9.]+ \\| +[0-9.]+ \\| +[0-9.]+\n$"
                          --cpu 4)
        pliant_bench_args(bench_args_session_coarse_level_too_low pliant_bench_session 2 STDERR
                          "^pliant_bench_session: --coarse level '2' is out of range \\(expected 3\\.\\.10\\)"
                          --coarse 2)
    endif()
    if(EXISTS ${PROJECT_SOURCE_DIR}/bench/sim/CMakeLists.txt)
        pliant_bench_args(bench_args_sim_help pliant_bench_sim 0 STDOUT
                          "^usage: pliant_bench_sim \\[max_level\\].*max_level +finest grid level, 1\\.\\.10"
                          --help)
        pliant_bench_args(bench_args_sim_level_out_of_range pliant_bench_sim 2 STDERR
                          "^pliant_bench_sim: max_level '99' is out of range \\(expected 1\\.\\.10\\)\nusage: "
                          99)
        pliant_bench_args(bench_args_sim_min_above_max pliant_bench_sim 2 STDERR
                          "^pliant_bench_sim: min_level '9' is out of range \\(expected 1\\.\\.8\\)"
                          8 1 9)
        pliant_bench_args(bench_args_sim_unknown_option pliant_bench_sim 2 STDERR
                          "^pliant_bench_sim: unknown option '--levels'" --levels 8)
        # `mixed` runs the steps in mixed precision and says so (levels 3..3, timing only).
        pliant_bench_args(bench_args_sim_mixed pliant_bench_sim 0 STDOUT
                          "precision of full steps: mixed.*step,3,1," 3 0 3 mixed kernel)
    endif()
    if(EXISTS ${PROJECT_SOURCE_DIR}/bench/net/CMakeLists.txt)
        pliant_bench_args(bench_args_net_help bench_net 0 STDOUT
                          "^usage: bench_net .*--stream-rate HZ" --help)
        pliant_bench_args(bench_args_net_unknown_option bench_net 2 STDERR
                          "^bench_net: unknown option '--bogus'\nusage: " --bogus)
        pliant_bench_args(bench_args_net_bad_stream_rate bench_net 2 STDERR
                          "^bench_net: --stream-rate '0' is not a number > 0" --stream-rate 0)
    endif()
endif()
