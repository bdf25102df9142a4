# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant bench`: argument errors (every build), and one cheap suite end to end where the
# benchmark programs are built (not under the sanitizers: PLIANT_BUILD_BENCH is OFF there; the
# bench/ folder is configured after tests/, so the option, not the target, is checked). Never
# asserts on timings.
if(TARGET pliant)
    pliant_cli_expect(cli_bench_unknown_suite 2 STDERR
                      "unknown suite 'nosuch' \\(suites: subdiv net sim mixed session"
                      bench subdiv nosuch --out ${CMAKE_CURRENT_BINARY_DIR}/bench-unknown)
    pliant_cli_expect(cli_bench_missing_program 1 STDERR
                      "bench_net is missing: build the benchmark programs with the release preset"
                      bench net --bench-dir ${CMAKE_CURRENT_BINARY_DIR}/no-such-bench-dir
                      --out ${CMAKE_CURRENT_BINARY_DIR}/bench-missing)
    if(PLIANT_BUILD_BENCH)
        # From empty folders, so that the checks never see an earlier run's files.
        set(_quick ${CMAKE_CURRENT_BINARY_DIR}/bench-quick)
        add_test(NAME cli_bench_net_quick
                 COMMAND sh -c "rm -rf '${_quick}' && exec '$<TARGET_FILE:pliant>' bench net --quick --out '${_quick}'")
        set_tests_properties(cli_bench_net_quick PROPERTIES TIMEOUT 120)
        add_test(NAME cli_bench_net_quick_outputs
                 COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}/bench-quick -DSUITE=net
                         -P ${PROJECT_SOURCE_DIR}/apps/pliant-cli/bench/check_bench_outputs.cmake)
        set_property(TEST cli_bench_net_quick APPEND PROPERTY
                     FIXTURES_SETUP cli_bench_net_quick_done)
        set_tests_properties(cli_bench_net_quick_outputs PROPERTIES
                             FIXTURES_REQUIRED cli_bench_net_quick_done)
        # A suite that is a mode of a program (pliant_bench_session --latency, level 6).
        set(_latency ${CMAKE_CURRENT_BINARY_DIR}/bench-latency)
        add_test(NAME cli_bench_latency_quick
                 COMMAND sh -c "rm -rf '${_latency}' && exec '$<TARGET_FILE:pliant>' bench latency --quick --no-plots --out '${_latency}'")
        set_tests_properties(cli_bench_latency_quick PROPERTIES TIMEOUT 120)
        add_test(NAME cli_bench_latency_quick_outputs
                 COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}/bench-latency
                         -DSUITE=latency
                         -P ${PROJECT_SOURCE_DIR}/apps/pliant-cli/bench/check_bench_outputs.cmake)
        set_property(TEST cli_bench_latency_quick APPEND PROPERTY
                     FIXTURES_SETUP cli_bench_latency_quick_done)
        set_tests_properties(cli_bench_latency_quick_outputs PROPERTIES
                             FIXTURES_REQUIRED cli_bench_latency_quick_done)
        # Ctrl-C once the second suite has started (its log file is created when it is
        # spawned): it is stopped, and results.json is written with the first, which completed;
        # the stopped suite's earlier results (KEEP: sim.csv) stay as they were.
        set(_bench_int ${CMAKE_CURRENT_BINARY_DIR}/bench-interrupted)
        pliant_add_interrupt_test(cli_bench_interrupted FILE ${_bench_int}/.sim.log.part
            FRESH_DIR ${_bench_int} KEEP ${_bench_int}/sim.csv
            STDERR_REGEX "bench: interrupted during sim. .*results.json holds the 1 suite that completed \\(net\\)"
            TIMEOUT 170 FIXTURES_SETUP bench_interrupted
            ARGS bench net sim --quick --no-plots --out ${_bench_int})
        add_test(NAME cli_bench_interrupted_outputs
                 COMMAND ${CMAKE_COMMAND} -DDIR=${_bench_int} -DSUITE=net
                         -P ${PROJECT_SOURCE_DIR}/apps/pliant-cli/bench/check_bench_outputs.cmake)
        set_tests_properties(cli_bench_interrupted_outputs PROPERTIES
            FIXTURES_REQUIRED bench_interrupted)
        # Ctrl-C while the plots are drawn: the data are written, bench forwards the signal to
        # gnuplot and exits 130 saying so (it waited for gnuplot and exited 0). A stand-in
        # gnuplot on PATH marks that it started and waits; the plot script is an empty file.
        set(_bench_plot ${CMAKE_CURRENT_BINARY_DIR}/bench-plot-interrupted)
        set(_fake_gnuplot_dir ${CMAKE_CURRENT_BINARY_DIR}/fake-gnuplot)
        file(MAKE_DIRECTORY ${_fake_gnuplot_dir}/plots)
        file(WRITE ${_fake_gnuplot_dir}/plots/bandwidth.gp "")
        file(WRITE ${_fake_gnuplot_dir}/gnuplot
             "#!/bin/sh\ntouch '${_bench_plot}/gnuplot-started'\nexec sleep 60\n")
        file(CHMOD ${_fake_gnuplot_dir}/gnuplot PERMISSIONS OWNER_READ OWNER_WRITE
             OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
        pliant_add_interrupt_test(cli_bench_interrupted_while_plotting
            FILE ${_bench_plot}/gnuplot-started FRESH_DIR ${_bench_plot}
            STDERR_REGEX "bench: interrupted while plotting. .*results.json holds every suite's results"
            TIMEOUT 170
            ENVIRONMENT "PATH=${_fake_gnuplot_dir}:$ENV{PATH}"
            ARGS bench net --quick --plots-dir ${_fake_gnuplot_dir}/plots --out ${_bench_plot})
        # Two SIGTERMs in quick succession (a second Ctrl-C): bench ends its running suite
        # program (SIGKILL) and winds down with exit 130; the second signal ended pliant and
        # left the program running, orphaned.
        add_test(NAME cli_bench_second_signal_ends_the_suite_program
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=sh;${CMAKE_CURRENT_SOURCE_DIR}/double_signal.sh;$<TARGET_FILE:pliant>;bench;sim;--no-plots;--out;${CMAKE_CURRENT_BINARY_DIR}/bench-double"
                         -DEXIT=130 "-DSTDERR_REGEX=bench: interrupted during sim"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(cli_bench_second_signal_ends_the_suite_program PROPERTIES
            TIMEOUT 240)
    endif()
endif()
