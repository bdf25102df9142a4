# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant simulate` end to end (docs/physics.md §7): the sample scenario on the built-in sphere
# writes every frame and the energy table, and its finger slides over the surface (no vertex is
# ever out of its reach: the chord it used to follow passed 0.29 m below the surface); a point
# force out of every vertex's reach is warned about, naming the file, line and distance; a
# misspelt key, an unknown force hold or precision is refused, naming the file, line and key;
# --precision mixed reaches the run. The audit of
# simulate (fixed steps, divergence, messages): a fixed step that does not divide the frame
# interval runs to the end (it hung); an unstable fixed_dt or dt_min is warned about and the steps
# at dt_min are counted; a run that becomes non-finite stops with exit 3; a face index beyond the
# grid, too many frames, a zero duration with forces and a point force without radius are refused
# with the key and its line; the default dt_initial is clamped under a small dt_max; keys the run
# ignores are warned about; -j 0 means OpenMP's default; --help lists every integrator key; the
# documented spot example runs without warnings. The audit of its outputs and timing: a run
# clears -o of an earlier run's frames (and nothing else), and refuses a --resume among them; a
# duration that is not a whole number of frame intervals is simulated to its end; a force that
# starts at or after the end is warned about; a frame or energy.csv that cannot be written ends
# the run with exit 1 and run.json says "failed" and why; a scenario that sets no key is warned
# about and --help states the defaults.
if(TARGET pliant)
    set(sim_out ${CMAKE_CURRENT_BINARY_DIR}/simulate-pull)
    # From an empty folder, so that the checks below never see an earlier run's files.
    add_test(NAME cli_simulate_pull
             COMMAND sh -c "rm -rf '${sim_out}' && exec '$<TARGET_FILE:pliant>' simulate --scenario '${PROJECT_SOURCE_DIR}/scenes/pull.toml' -o '${sim_out}' --level 4 -j 1")
    set_tests_properties(cli_simulate_pull PROPERTIES
        FIXTURES_SETUP simulate_pull_frames
        TIMEOUT 120
        PASS_REGULAR_EXPRESSION "101 frames, 4.000 s simulated"
        FAIL_REGULAR_EXPRESSION "beyond its radius;error")
    add_test(NAME cli_simulate_pull_outputs
             COMMAND ${CMAKE_COMMAND} -DDIR=${sim_out}
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_simulate_outputs.cmake)
    set_tests_properties(cli_simulate_pull_outputs PROPERTIES
                         FIXTURES_REQUIRED simulate_pull_frames)
    add_test(NAME cli_simulate_pull_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${sim_out} -DSTATUS=complete -DFRAMES=101 -DLEVEL=4
                     -DPRECISION=double -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_tests_properties(cli_simulate_pull_run_json PROPERTIES
                         FIXTURES_REQUIRED simulate_pull_frames)

    # Ctrl-C once frame 3 is written (level 8: 101 frames take seconds): the run stops before
    # its next step with exit status 130, says where it stopped, and run.json says
    # "interrupted" with as many frames as the folder and energy.csv hold.
    set(_int_out ${CMAKE_CURRENT_BINARY_DIR}/simulate-interrupted)
    pliant_add_interrupt_test(cli_simulate_interrupted FILE ${_int_out}/frame_00003.pgrid
        FRESH_DIR ${_int_out}
        STDERR_REGEX "pull.toml: interrupted at t = [0-9.]+ s. frames 0 to [0-9]+ of 0 to 100 are in"
        FIXTURES_SETUP simulate_interrupted
        ARGS simulate --scenario ${PROJECT_SOURCE_DIR}/scenes/pull.toml -o ${_int_out} --level 8
             -j 1)
    # Progress within a frame: a log line of 10 % comes before the only frame is written.
    set(_long ${CMAKE_CURRENT_BINARY_DIR}/simulate-one-long-frame)
    pliant_add_interrupt_test(cli_simulate_progress_within_a_frame
        LOG "simulate: [1-9]0% "
        FRESH_DIR ${_long}
        STDERR_REGEX "simulate: [1-9]0% .*one_long_frame.toml: interrupted at t = [0-9.]+ s. frames 0 to 0 of 0 to 1 are in"
        TIMEOUT 200
        ARGS simulate --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/one_long_frame.toml
             -o ${_long} --level 6 -j 1)
    # A run whose frames would outgrow the disk (a million level-7 frames, about 1.3 TB) is
    # warned about after frame 0, with the sizes; Ctrl-C then ends it.
    set(_many ${CMAKE_CURRENT_BINARY_DIR}/simulate-many-frames)
    pliant_add_interrupt_test(cli_simulate_warns_frames_outgrowing_the_disk
        LOG "the run will stop when the disk is full"
        FRESH_DIR ${_many}
        STDERR_REGEX "the 1000000 frames to come need about [0-9.]+ TB .[0-9.]+ MB each, as frame 0., but [0-9.]+ [kMGT]?B is free there"
        TIMEOUT 120
        ARGS simulate --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/many_frames.toml
             -o ${_many} --level 7 -j 1)
    add_test(NAME cli_simulate_interrupted_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${_int_out} -DSTATUS=interrupted -DLEVEL=8
                     -DPRECISION=double -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_tests_properties(cli_simulate_interrupted_run_json PROPERTIES
                         FIXTURES_REQUIRED simulate_interrupted)

    add_test(NAME cli_simulate_warns_unreachable_point
             COMMAND pliant simulate
                     --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/off_surface.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-off --level 3)
    set_tests_properties(cli_simulate_warns_unreachable_point PROPERTIES
        TIMEOUT 60
        PASS_REGULAR_EXPRESSION
        "off_surface.toml:12: force\\[0\\]'s point comes 0.5 m from the nearest vertex, beyond its radius 0.1 m")

    add_test(NAME cli_simulate_refuses_unknown_key
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${PROJECT_SOURCE_DIR}/tests/data/scenarios/bad_key.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-bad;--level;3"
                     "-DREGEX=bad_key.toml:8: 'material.tension' is not a known key"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
    set_tests_properties(cli_simulate_refuses_unknown_key PROPERTIES TIMEOUT 60)

    add_test(NAME cli_simulate_refuses_unknown_force_hold
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${PROJECT_SOURCE_DIR}/tests/data/scenarios/bad_hold.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-bad-hold;--level;3"
                     "-DREGEX=bad_hold.toml:8: 'integrator.force_hold' must be one of: linear, step"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
    set_tests_properties(cli_simulate_refuses_unknown_force_hold PROPERTIES TIMEOUT 60)
    add_test(NAME cli_simulate_refuses_unknown_precision
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${PROJECT_SOURCE_DIR}/tests/data/scenarios/bad_precision.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-bad-precision;--level;3"
                     "-DREGEX=bad_precision.toml:8: 'integrator.precision' must be one of: double, mixed"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
    set_tests_properties(cli_simulate_refuses_unknown_precision PROPERTIES TIMEOUT 60)
    # Mixed precision's float range: an atol below it is refused naming the key, its line and the
    # way out; with fixed steps atol and dt_min are not used, so the run only warns that they have
    # no effect; a tolerance tight enough for the slopes' float rounding to steer the steps is
    # warned about (docs/physics.md §9).
    add_test(NAME cli_simulate_refuses_mixed_atol_below_float
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${PROJECT_SOURCE_DIR}/tests/data/scenarios/mixed_atol.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-mixed-atol;--level;3"
                     "-DREGEX=mixed_atol.toml:8: 'integrator.atol' = 1e-35 is below 1e-30, the least precision = \"mixed\" allows .*use precision = \"double\""
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
    set_tests_properties(cli_simulate_refuses_mixed_atol_below_float PROPERTIES TIMEOUT 60)
    pliant_cli_expect(cli_simulate_mixed_fixed_steps_ignore_atol 0 STDERR
                      "mixed_fixed_ignores_atol.toml:10: 'integrator.atol' has no effect with 'fixed_step = true'"
                      simulate --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/mixed_fixed_ignores_atol.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-mixed-fixed --level 3 -j 1)
    pliant_cli_expect(cli_simulate_mixed_warns_tight_rtol 0 STDERR
                      "mixed_tight.toml:8: 'integrator.rtol' = 1e-10 with precision = \"mixed\": the error estimate comes from float slopes"
                      simulate --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/mixed_tight.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-mixed-tight --level 3 -j 1)
    # --precision mixed reaches the integrator (the summary names the precision the run used).
    add_test(NAME cli_simulate_pull_mixed
             COMMAND pliant simulate --scenario ${PROJECT_SOURCE_DIR}/scenes/pull.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-pull-mixed --level 4 -j 1
                     --precision mixed)
    set_tests_properties(cli_simulate_pull_mixed PROPERTIES
        TIMEOUT 120
        PASS_REGULAR_EXPRESSION "101 frames, 4.000 s simulated.* mixed precision"
        FAIL_REGULAR_EXPRESSION "beyond its radius;error")
    add_test(NAME cli_simulate_pull_mixed_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}/simulate-pull-mixed
                     -DSTATUS=complete -DFRAMES=101 -DLEVEL=4 -DPRECISION=mixed
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_property(TEST cli_simulate_pull_mixed APPEND PROPERTY
                 FIXTURES_SETUP cli_simulate_pull_mixed_done)
    set_tests_properties(cli_simulate_pull_mixed_run_json PROPERTIES
                         FIXTURES_REQUIRED cli_simulate_pull_mixed_done)
    set(scenarios ${PROJECT_SOURCE_DIR}/tests/data/scenarios)
    # 166 whole steps of 3 ms in 0.5 s, frames at the last step before each 100 ms.
    add_test(NAME cli_simulate_fixed_step_remainder
             COMMAND pliant simulate --scenario ${scenarios}/fixed_remainder.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-fixed-remainder --level 3 -j 1)
    set_tests_properties(cli_simulate_fixed_step_remainder PROPERTIES
        TIMEOUT 60
        PASS_REGULAR_EXPRESSION "6 frames, 0.498 s simulated.* 166 steps"
        FAIL_REGULAR_EXPRESSION "warning|error")

    pliant_cli_expect(cli_simulate_warns_unstable_fixed_step 0 STDERR
                      "unstable_fixed.toml:9: 'integrator.fixed_dt' = 0.05 s is [0-9.]+ times the stable step [0-9.e-]+ s of this grid and material .* the run will likely diverge; use fixed_dt <= "
                      simulate --scenario ${scenarios}/unstable_fixed.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-unstable --level 4 -j 1)

    pliant_cli_expect(cli_simulate_counts_steps_at_dt_min 0 STDERR
                      "dt_min_too_large.toml:12: 'integrator.dt_min' = 0.05 s is [0-9.]+ times the stable step .*will likely diverge.*dt_min_too_large.toml:12: 'integrator.dt_min' = 0.05 s: 10 of 10 steps were taken at dt_min with the error above the tolerance"
                      simulate --scenario ${scenarios}/dt_min_too_large.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-dt-min --level 5 -j 1)

    # Steps the run could never take, or that fit nowhere: refused before anything is written
    # (a fixed step of 1e-300 s ran for ever at t = 0; one longer than the run simulated
    # nothing and exited 0); a step longer than the frame interval is said.
    pliant_cli_expect(cli_simulate_refuses_endless_fixed_steps 1 STDERR
                      "tiny_fixed_step.toml:8: 'integrator.fixed_dt' = 1e-300 s would take over 1e\\+12 steps to cover 'duration' = 0.1 s. use fixed_dt >= 1e-13 s"
                      simulate --scenario ${scenarios}/tiny_fixed_step.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-tiny-step --level 3)
    pliant_cli_expect(cli_simulate_refuses_endless_adaptive_steps 1 STDERR
                      "tiny_adaptive_steps.toml:7: 'integrator.dt_max' = 1e-299 s would take over 1e\\+12 steps"
                      simulate --scenario ${scenarios}/tiny_adaptive_steps.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-tiny-adaptive --level 3)
    # A frame needing more steps than one advance call takes goes on to its time (run.json's
    # simulated_s 0.0012 s, not the 0.001 s where the first call stopped).
    find_program(PLIANT_PYTHON3 python3)
    if(PLIANT_PYTHON3)
        set(_many_steps ${CMAKE_CURRENT_BINARY_DIR}/simulate-frame-of-many-steps)
        add_test(NAME cli_simulate_frame_of_many_steps_reaches_its_time
                 COMMAND sh -c "'$<TARGET_FILE:pliant>' -q simulate --scenario '${scenarios}/frame_of_many_steps.toml' -o '${_many_steps}' --level 1 -j 1 && '${PLIANT_PYTHON3}' -c \"import json,sys; r=json.load(open('${_many_steps}/run.json'))['result']; print(r); sys.exit(0 if r['status']=='complete' and abs(r['simulated_s']-0.0012)<1e-9 else 1)\"")
        set_tests_properties(cli_simulate_frame_of_many_steps_reaches_its_time PROPERTIES
                             TIMEOUT 300)
    endif()
    # With fixed steps a force's start is a step boundary away from the frames: the linear hold
    # ramps it over the step that contains its start, so frames at 20 or 25 per second give
    # the same last state (the ramp began at the previous frame: 0.0214 J against 0.0204 J).
    if(PLIANT_PYTHON3)
        set(_hold ${CMAKE_CURRENT_BINARY_DIR}/simulate-linear-hold)
        add_test(NAME cli_simulate_linear_hold_ramps_over_the_start_step
                 COMMAND sh -c "for r in 20 25; do '$<TARGET_FILE:pliant>' -q simulate --scenario '${scenarios}/linear_hold_fps'$r'.toml' -o '${_hold}'$r --level 3 -j 1 || exit 1; done && '${PLIANT_PYTHON3}' -c \"import sys; last=lambda d: open(d+'/energy.csv').read().split()[-1].split(',')[1:6]; a,b=last('${_hold}20'),last('${_hold}25'); print(a, b); sys.exit(0 if a==b else 1)\"")
        set_tests_properties(cli_simulate_linear_hold_ramps_over_the_start_step PROPERTIES
                             TIMEOUT 300)
    endif()
    pliant_cli_expect(cli_simulate_huge_integer_is_out_of_range 1 STDERR
                      "huge_integer.toml:3: 'duration' = 9.22337e.18 is outside .0, 1e.06."
                      simulate --scenario ${scenarios}/huge_integer.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-huge-integer --level 2)
    pliant_cli_expect(cli_simulate_refuses_a_step_beyond_the_run 1 STDERR
                      "step_beyond_duration.toml:7: 'integrator.fixed_dt' = 100 s is longer than 'duration' = 0.1 s: no step fits"
                      simulate --scenario ${scenarios}/step_beyond_duration.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-step-beyond --level 3)
    pliant_cli_expect(cli_simulate_warns_a_step_beyond_the_frame_interval 0 STDERR
                      "step_beyond_frame.toml:11: 'integrator.fixed_dt' = 0.25 s is longer than the frame interval 0.1 s .'frame_rate' = 10.: frames without a step between them repeat"
                      simulate --scenario ${scenarios}/step_beyond_frame.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-step-beyond-frame --level 2 -j 1)
    pliant_cli_expect(cli_simulate_stops_when_non_finite 3 STDERR
                      "diverges.toml: the state became non-finite at t = [0-9.]+ s: the run diverged and stops \\(frames 0 to 0 are in "
                      simulate --scenario ${scenarios}/diverges.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-diverges --level 3 -j 1)
    add_test(NAME cli_simulate_diverged_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}/simulate-diverges
                     -DSTATUS=diverged -DFRAMES=1 -DLEVEL=3 -DPRECISION=double
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_tests_properties(cli_simulate_stops_when_non_finite PROPERTIES
                         FIXTURES_SETUP simulate_diverges)
    set_tests_properties(cli_simulate_diverged_run_json PROPERTIES
                         FIXTURES_REQUIRED simulate_diverges)

    set(refusals
        bad_face "bad_face.toml:7: 'force\\[0\\].face' = 999999 is not below the grid's 256 faces \\(level 3\\)"
        too_many_frames "too_many_frames.toml:4: 'frame_rate' = 10000 with 'duration' = 1e\\+06 s makes 1e\\+10 frames. a run writes at most 1000000"
        zero_duration "zero_duration.toml:3: 'duration' = 0 s: a scenario with forces needs a duration > 0"
        no_radius "no_radius.toml:5: 'force\\[0\\].radius' is missing: a point force spreads")
    list(LENGTH refusals n)
    math(EXPR last "${n} - 1")
    foreach(i RANGE 0 ${last} 2)
        math(EXPR j "${i} + 1")
        list(GET refusals ${i} name)
        list(GET refusals ${j} regex)
        add_test(NAME cli_simulate_refuses_${name}
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/${name}.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-${name};--level;3"
                         "-DREGEX=${regex}"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
        set_tests_properties(cli_simulate_refuses_${name} PROPERTIES TIMEOUT 60)
    endforeach()

    add_test(NAME cli_simulate_clamps_default_dt_initial
             COMMAND pliant simulate --scenario ${scenarios}/default_dt_initial.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-dt-initial --level 3 -j 1)
    set_tests_properties(cli_simulate_clamps_default_dt_initial PROPERTIES
        TIMEOUT 60
        PASS_REGULAR_EXPRESSION "3 frames, 0.020 s simulated"
        FAIL_REGULAR_EXPRESSION "warning|error")

    pliant_cli_expect(cli_simulate_warns_ignored_keys 0 STDERR
                      "ignored_keys.toml:7: 'integrator.fixed_dt' has no effect without 'fixed_step = true'.*ignored_keys.toml:12: 'force\\[0\\].radius' has no effect on a face force"
                      simulate --scenario ${scenarios}/ignored_keys.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-ignored --level 3)

    # -j 0 overrides the scenario's threads = 1 with OpenMP's default (here OMP_NUM_THREADS).
    pliant_cli_expect(cli_simulate_threads_zero_is_openmp_default 0 STDOUT
                      ", 3 thread\\(s\\), double precision -> "
                      simulate --scenario ${scenarios}/ignored_keys.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-j0 --level 3 -j 0)
    set_tests_properties(cli_simulate_threads_zero_is_openmp_default PROPERTIES ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;OMP_NUM_THREADS=3")

    pliant_cli_expect(cli_simulate_help_lists_integrator_keys 0 STDOUT
                      "rtol, atol, dt_min, dt_max, dt_initial \\[s\\], safety, max_growth,.*min_shrink.*fixed_dt"
                      simulate --help)

    # The help's second example on a remeshed spot (level 4 here): every point force reaches
    # vertices of the surface, so nothing is warned about.
    set(spot_grid ${CMAKE_CURRENT_BINARY_DIR}/simulate-spot.pgrid)
    add_test(NAME cli_simulate_spot_remesh
             COMMAND pliant remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4 -o ${spot_grid})
    set_tests_properties(cli_simulate_spot_remesh PROPERTIES
        TIMEOUT 300
        FIXTURES_SETUP simulate_spot)
    add_test(NAME cli_simulate_spot_example
             COMMAND pliant simulate ${spot_grid} --scenario ${PROJECT_SOURCE_DIR}/scenes/spot.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-spot --format ply -j 1)
    set_tests_properties(cli_simulate_spot_example PROPERTIES
        TIMEOUT 120
        FIXTURES_REQUIRED simulate_spot
        PASS_REGULAR_EXPRESSION " frames, "
        FAIL_REGULAR_EXPRESSION "warning|error")
    # The sphere's options given with a GRID are said to be ignored, not silently dropped.
    pliant_cli_expect(cli_simulate_sphere_options_with_a_grid 0 STDERR
                      "--level shapes the sphere used when GRID is omitted.*--radius shapes the sphere"
                      simulate ${spot_grid} --scenario ${scenarios}/partial_interval.toml
                      -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-sphere-options --level 5 --radius 2
                      -j 1)
    set_tests_properties(cli_simulate_sphere_options_with_a_grid PROPERTIES
        FIXTURES_REQUIRED simulate_spot)
    # An earlier run's frames in -o (those this run rewrites, those beyond its last, another
    # format's, a .gltf's buffer) are removed before the run, saying how many; files and folders
    # that do not match frame_NNNNN.EXT stay. run.json's frames are then those in the folder.
    set(_rerun ${CMAKE_CURRENT_BINARY_DIR}/simulate-rerun)
    set(_stale)
    foreach(i RANGE 0 25)
        list(APPEND _stale ${_rerun}/frame_0000${i}.pgrid)
    endforeach()
    string(REGEX REPLACE "frame_0000([0-9][0-9])" "frame_000\\1" _stale "${_stale}")
    list(APPEND _stale ${_rerun}/frame_00000.ply ${_rerun}/frame_00007.gltf
                       ${_rerun}/frame_00007.bin ${_rerun}/frame_123456.glb)
    set(_kept ${_rerun}/frame_notes.txt ${_rerun}/frame_1.pgrid ${_rerun}/frame_00001.pgrid.bak
              ${_rerun}/Frame_00002.pgrid ${_rerun}/frame_00099.pgrid/keep.txt)
    add_test(NAME cli_simulate_clears_earlier_frames
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/partial_interval.toml;-o;${_rerun};--level;3;-j;1"
                     -DEXIT=0 "-DSTDERR_REGEX=simulate: removed 29 frames of an earlier run from .*simulate-rerun"
                     "-DSTALE=${_stale}" "-DKEEP=${_kept}"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_clears_earlier_frames PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    add_test(NAME cli_simulate_clears_earlier_frames_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${_rerun} -DSTATUS=complete -DFRAMES=4 -DLEVEL=3
                     -DPRECISION=double -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_property(TEST cli_simulate_clears_earlier_frames APPEND PROPERTY
                 FIXTURES_SETUP cli_simulate_clears_earlier_frames_done)
    set_tests_properties(cli_simulate_clears_earlier_frames_run_json PROPERTIES
                         FIXTURES_REQUIRED cli_simulate_clears_earlier_frames_done)
    # An empty -o is a usage error, as every empty argument is (it was "cannot create :
    # Invalid argument", exit 1).
    # (through sh: a CMake list cannot carry an empty argument)
    add_test(NAME cli_simulate_empty_output
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=sh;-c;'$<TARGET_FILE:pliant>' simulate --scenario '${scenarios}/partial_interval.toml' -o '' --level 3"
                     -DEXIT=2 "-DSTDERR_REGEX=argument 5 is empty .after -o."
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_empty_output PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # A mesh given to --resume (a frame written with --format ply) says a state comes from a
    # .pgrid frame (it said "not a pliant grid file (bad magic)").
    pliant_cli_expect(cli_simulate_resume_from_a_mesh 1 STDERR
                      "--resume .*spot.obj: a state is resumed from a .pgrid frame"
                      simulate --scenario ${scenarios}/partial_interval.toml
                      -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-resume-mesh --level 3
                      --resume ${PROJECT_SOURCE_DIR}/data/spot.obj)
    # A --resume frame among those the run would clear is refused (usage) and left as it was.
    set(_here ${CMAKE_CURRENT_BINARY_DIR}/simulate-resume-here)
    add_test(NAME cli_simulate_refuses_resume_from_its_folder
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/partial_interval.toml;-o;${_here};--level;3;--resume;${_here}/frame_00002.pgrid"
                     -DEXIT=2 "-DSTDERR_REGEX=--resume .*frame_00002.pgrid is a frame of an earlier run in -o's folder .*give another -o"
                     "-DKEEP=${_here}/frame_00002.pgrid;${_here}/frame_00003.pgrid"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_refuses_resume_from_its_folder PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # The scenario too: a TOML named like a frame in -o was removed as "1 frame of an earlier
    # run" before the run read it.
    add_test(NAME cli_simulate_refuses_scenario_from_its_folder
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${_here}/frame_00009.obj;-o;${_here};--level;3"
                     -DEXIT=2 "-DSTDERR_REGEX=--scenario .*frame_00009.obj is a frame of an earlier run in -o's folder"
                     "-DKEEP=${_here}/frame_00009.obj"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_refuses_scenario_from_its_folder PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")

    # A duration that is not a whole number of frame intervals: the last frame comes after a
    # shorter interval, at the duration (0.25 s at 10 frames per second: frame 3 at 0.25 s; 0.5 s
    # at one frame per second: frame 1 at 0.5 s), and forces late in the run act. A force that
    # starts at the end is warned about, naming the file, its line and the key.
    add_test(NAME cli_simulate_partial_last_interval
             COMMAND pliant simulate --scenario ${scenarios}/partial_interval.toml
                     -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-partial --level 3 -j 1)
    set_tests_properties(cli_simulate_partial_last_interval PROPERTIES
        TIMEOUT 60
        PASS_REGULAR_EXPRESSION "4 frames, 0.250 s simulated"
        FAIL_REGULAR_EXPRESSION "warning|error")
    add_test(NAME cli_simulate_partial_last_interval_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}/simulate-partial
                     -DSTATUS=complete -DFRAMES=4 -DLEVEL=3 -DPRECISION=double
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_property(TEST cli_simulate_partial_last_interval APPEND PROPERTY
                 FIXTURES_SETUP cli_simulate_partial_last_interval_done)
    set_tests_properties(cli_simulate_partial_last_interval_run_json PROPERTIES
                         FIXTURES_REQUIRED cli_simulate_partial_last_interval_done)
    add_test(NAME cli_simulate_warns_force_after_end
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/force_after_end.toml;-o;${CMAKE_CURRENT_BINARY_DIR}/simulate-after-end;--level;3;-j;1"
                     -DEXIT=0 "-DSTDOUT_REGEX=^2 frames, 0.500 s simulated"
                     "-DSTDERR_REGEX=force_after_end.toml:13: 'force\\[1\\].start' = 0.5 s is not before 'duration' = 0.5 s: the force never acts.*force_after_end.toml:19: 'force\\[2\\].start' = 0.5 s is not before 'duration' = 0.5 s: the force never acts"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_warns_force_after_end PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")

    # An output that cannot be written mid-run (frame 1's path is a folder): exit 1 with the
    # system's reason, and run.json says "failed", why, and the one frame written; no temporary
    # file is left and the folder stays.
    set(_fail ${CMAKE_CURRENT_BINARY_DIR}/simulate-frame-fails)
    add_test(NAME cli_simulate_frame_write_fails
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/partial_interval.toml;-o;${_fail};--level;3;-j;1"
                     -DEXIT=1 "-DSTDERR_REGEX=error: /[^ ]*/frame_00001.pgrid: cannot open for writing: Is a directory"
                     "-DKEEP=${_fail}/frame_00001.pgrid/keep.txt"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_simulate_frame_write_fails PROPERTIES TIMEOUT 60
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    add_test(NAME cli_simulate_frame_write_fails_run_json
             COMMAND ${CMAKE_COMMAND} -DDIR=${_fail} -DSTATUS=failed -DFRAMES=1 -DLEVEL=3
                     -DPRECISION=double "-DREASON=frame_00001.pgrid: cannot open for writing: Is a directory"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
    set_property(TEST cli_simulate_frame_write_fails APPEND PROPERTY
                 FIXTURES_SETUP cli_simulate_frame_write_fails_done)
    set_tests_properties(cli_simulate_frame_write_fails_run_json PROPERTIES
                         FIXTURES_REQUIRED cli_simulate_frame_write_fails_done)
    # energy.csv on a full disk (a link to /dev/full): its write is checked, exit 1 with the
    # reason, and run.json says "failed" and why.
    if(EXISTS /dev/full)
        set(_full ${CMAKE_CURRENT_BINARY_DIR}/simulate-energy-full)
        add_test(NAME cli_simulate_energy_csv_write_fails
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=$<TARGET_FILE:pliant>;simulate;--scenario;${scenarios}/partial_interval.toml;-o;${_full};--level;3;-j;1"
                         -DEXIT=1 "-DSTDERR_REGEX=energy.csv: write failed: No space left on device"
                         "-DLINKS=${_full}/energy.csv=/dev/full"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(cli_simulate_energy_csv_write_fails PROPERTIES TIMEOUT 60
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
        add_test(NAME cli_simulate_energy_csv_write_fails_run_json
                 COMMAND ${CMAKE_COMMAND} -DDIR=${_full} -DSTATUS=failed -DFRAMES=0 -DLEVEL=3
                         -DPRECISION=double
                         "-DREASON=energy.csv: write failed: No space left on device"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
        set_property(TEST cli_simulate_energy_csv_write_fails APPEND PROPERTY
                     FIXTURES_SETUP cli_simulate_energy_csv_write_fails_done)
        set_tests_properties(cli_simulate_energy_csv_write_fails_run_json PROPERTIES
                             FIXTURES_REQUIRED cli_simulate_energy_csv_write_fails_done)
    endif()

    # A scenario that sets no key runs on the defaults and says which; --help states them.
    pliant_cli_expect(cli_simulate_warns_no_key 0 STDERR
                      "no_key.toml sets no key: using the defaults \\(duration = 1 s, frame_rate = 25 frames/s, no force"
                      simulate --scenario ${scenarios}/no_key.toml -o ${CMAKE_CURRENT_BINARY_DIR}/simulate-no-key --level 3 -j 1)
    pliant_cli_expect(cli_simulate_help_states_defaults 0 STDOUT
                      "duration \\[s\\] \\(default 1\\),.frame_rate \\[1/s\\] \\(default 25\\)"
                      simulate --help)
    # A scenario from a pipe (`-s <(...)`, here /dev/stdin): toml++'s own reader could not open
    # it ("File could not be opened for reading").
    add_test(NAME cli_simulate_scenario_from_a_pipe
             COMMAND sh -c "cat '${PROJECT_SOURCE_DIR}/scenes/pull.toml' | '$<TARGET_FILE:pliant>' simulate -s /dev/stdin --level 3 -j 1 -o '${CMAKE_CURRENT_BINARY_DIR}/simulate-pipe'")
    set_tests_properties(cli_simulate_scenario_from_a_pipe PROPERTIES TIMEOUT 120
        FIXTURES_SETUP simulate_pipe PASS_REGULAR_EXPRESSION "101 frames, 4.000 s simulated")
    # A scenario whose name is not UTF-8 (Latin-1 "sz\xe9n.toml"): run.json holds it with
    # U+FFFD; the JSON writer threw and the process aborted (status 134).
    add_test(NAME cli_simulate_non_utf8_path
             COMMAND sh -c "d='${CMAKE_CURRENT_BINARY_DIR}/simulate-latin1' && rm -rf \"$d\" && mkdir -p \"$d\" && f=\"$d/$(printf 'sz\\351n.toml')\" && cp '${PROJECT_SOURCE_DIR}/scenes/pull.toml' \"$f\" && '$<TARGET_FILE:pliant>' -q simulate -s \"$f\" --level 3 -j 1 -o \"$d/out\" && grep -q '\"status\": \"complete\"' \"$d/out/run.json\"")
    set_tests_properties(cli_simulate_non_utf8_path PROPERTIES TIMEOUT 120)
    # Two runs into one folder: the second is refused while the first runs (they spliced
    # their frames and energy.csv, both exiting 0), and the first completes untouched.
    add_test(NAME cli_simulate_one_run_per_folder
             COMMAND sh -c "d='${CMAKE_CURRENT_BINARY_DIR}/simulate-locked' && rm -rf \"$d\" && P='$<TARGET_FILE:pliant>' && S='${PROJECT_SOURCE_DIR}/scenes/pull.toml' && { \"$P\" -q simulate -s \"$S\" --level 7 -j 1 -o \"$d\" & } && i=0 && while [ ! -e \"$d/run.json\" ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done && ! \"$P\" simulate -s \"$S\" --level 4 -j 1 -o \"$d\" 2> \"$d.second\" && grep -q 'another run is writing to .*simulate-locked' \"$d.second\" && wait && grep -q '\"level\": 7' \"$d/run.json\" && grep -q '\"status\": \"complete\"' \"$d/run.json\"")
    # The exit status decides (a PASS_REGULAR_EXPRESSION would ignore it, and with it the
    # first run's outcome).
    set_tests_properties(cli_simulate_one_run_per_folder PROPERTIES TIMEOUT 300)
    # A state resumed from a pipe (`--resume <(...)`, here /dev/stdin): a name without an
    # extension is read and its header decides; it was refused as "not from a mesh".
    # The run starts from the piped state itself: its frame 0 is that frame, byte for byte.
    set(_piped ${CMAKE_CURRENT_BINARY_DIR}/simulate-pipe/frame_00050.pgrid)
    set(_resumed ${CMAKE_CURRENT_BINARY_DIR}/simulate-pipe-resumed)
    add_test(NAME cli_simulate_resume_from_a_pipe
             COMMAND sh -c "rm -rf '${_resumed}' && cat '${_piped}' | '$<TARGET_FILE:pliant>' simulate -s '${PROJECT_SOURCE_DIR}/scenes/pull.toml' --level 3 -j 1 --resume /dev/stdin -o '${_resumed}' > '${_resumed}.log' 2>&1 && grep -q '101 frames, 4.000 s simulated' '${_resumed}.log' && cmp '${_piped}' '${_resumed}/frame_00000.pgrid'")
    set_tests_properties(cli_simulate_resume_from_a_pipe PROPERTIES TIMEOUT 120
        FIXTURES_REQUIRED simulate_pipe)
endif()
