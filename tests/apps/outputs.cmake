# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Outputs are written whole or not at all (core::write_files): a write that fails (a file-size
# limit stands in for a full disk) exits 1 naming the reason, and the files that were at the
# outputs before stay as they were; outputs are checked before the work and nothing is created
# by the check; the file-reading commands' messages and exit codes (docs/troubleshooting.md).
if(TARGET pliant)
    set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/cli-outputs)
    file(MAKE_DIRECTORY ${out_dir} ${out_dir}/frames)
    set(limit sh ${CMAKE_CURRENT_SOURCE_DIR}/file_size_limit.sh 2)
    pliant_cli_expect(cli_outputs_setup 0 STDOUT "level 3: 130 vertices"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${out_dir}/spot3.pgrid)
    set_tests_properties(cli_outputs_setup PROPERTIES FIXTURES_SETUP cli_outputs)
    # pliant_full_disk(NAME KEEP COMMAND...): COMMAND under the limit exits 1 with "File too
    # large" and leaves the ;-list of paths KEEP (written before it runs) unchanged.
    function(pliant_full_disk name keep)
        list(JOIN ARGN ";" args)
        add_test(NAME ${name}
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=${limit};$<TARGET_FILE:pliant>;${args}" -DEXIT=1
                         "-DSTDERR_REGEX=File too large" "-DKEEP=${keep}"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(${name} PROPERTIES TIMEOUT 120 FIXTURES_REQUIRED cli_outputs
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endfunction()
    foreach(ext pgrid obj ply glb pfm)
        pliant_full_disk(cli_full_disk_remesh_${ext} ${out_dir}/full.${ext}
                         remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4 --no-measure
                         -o ${out_dir}/full.${ext})
    endforeach()
    # A .gltf and its buffer: both kept (neither replaced without the other).
    pliant_full_disk(cli_full_disk_remesh_gltf "${out_dir}/full.gltf;${out_dir}/full.bin"
                     remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4 --no-measure
                     -o ${out_dir}/full.gltf)
    pliant_full_disk(cli_full_disk_refine ${out_dir}/refined.pgrid
                     refine ${out_dir}/spot3.pgrid --levels 2 -o ${out_dir}/refined.pgrid)
    pliant_full_disk(cli_full_disk_render ${out_dir}/shot.png
                     render ${out_dir}/spot3.pgrid -o ${out_dir}/shot.png --size 320x240)
    # A new output that cannot be written whole is not left in part.
    add_test(NAME cli_full_disk_leaves_no_part
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${limit};$<TARGET_FILE:pliant>;refine;${out_dir}/spot3.pgrid;--levels;2;-o;${out_dir}/never.obj"
                     -DEXIT=1 "-DSTDERR_REGEX=File too large" -DABSENT=${out_dir}/never.obj
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_full_disk_leaves_no_part PROPERTIES FIXTURES_REQUIRED cli_outputs
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # A file-size limit set in a shell (`ulimit -f`) leaves SIGXFSZ at its default, which
    # killed pliant (status 153) with its new file left beside the output: pliant ignores the
    # signal, says "File too large", exits 1 and leaves nothing (the folder is listed after).
    file(MAKE_DIRECTORY ${out_dir}/xfsz)
    add_test(NAME cli_file_size_limit_set_in_a_shell
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=sh;${CMAKE_CURRENT_SOURCE_DIR}/file_size_limit.sh;--as-set;2;$<TARGET_FILE:pliant>;refine;${out_dir}/spot3.pgrid;--levels;2;-o;${out_dir}/xfsz/big.obj"
                     -DEXIT=1 "-DSTDERR_REGEX=big.obj: write failed: File too large"
                     -DEMPTY_DIR=${out_dir}/xfsz
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_file_size_limit_set_in_a_shell PROPERTIES
                         FIXTURES_REQUIRED cli_outputs ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # A closed standard stream (`2>&-`) is opened on /dev/null: the energy.csv that simulate
    # opened next took its number and got the progress lines (`simulate: 50% (1.0s)`).
    add_test(NAME cli_closed_stderr_takes_no_output_file
             COMMAND sh -c "'$<TARGET_FILE:pliant>' simulate -s '${PROJECT_SOURCE_DIR}/scenes/pull.toml' --level 3 -o '${out_dir}/closed-stderr' 2>&- && test -s '${out_dir}/closed-stderr/energy.csv' && ! grep -rn 'simulate:' '${out_dir}/closed-stderr'")
    set_tests_properties(cli_closed_stderr_takes_no_output_file PROPERTIES
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # Out of memory (an address space of 300 MiB; refining level 3 to 10 needs about 350 MB): an
    # error and exit status 3, nothing written, where std::bad_alloc aborted (status 134). Not
    # under the sanitizers, whose shadow memory needs far more address space than any limit.
    if(NOT PLIANT_SANITIZE)
        add_test(NAME cli_out_of_memory_is_an_error
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=sh;${CMAKE_CURRENT_SOURCE_DIR}/memory_limit.sh;307200;$<TARGET_FILE:pliant>;refine;${out_dir}/spot3.pgrid;--levels;7;-j;1;-o;${out_dir}/oom.pgrid"
                         -DEXIT=3 "-DSTDERR_REGEX=error: out of memory: .*\\[out-of-memory\\]"
                         -DABSENT=${out_dir}/oom.pgrid
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(cli_out_of_memory_is_an_error PROPERTIES
                             FIXTURES_REQUIRED cli_outputs TIMEOUT 120)
        # simulate records in run.json that it failed, out of memory (level 9 needs about
        # 500 MB; under 350 MiB the model is built, run.json written, and the workspace's
        # allocation fails), where run.json said "running" after the process had ended.
        set(oom_dir ${out_dir}/simulate-oom)
        add_test(NAME cli_simulate_out_of_memory
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=sh;${CMAKE_CURRENT_SOURCE_DIR}/memory_limit.sh;358400;$<TARGET_FILE:pliant>;simulate;-s;${PROJECT_SOURCE_DIR}/scenes/pull.toml;--level;9;-j;1;-o;${oom_dir}"
                         -DEXIT=3 "-DSTDERR_REGEX=error: out of memory: .*\\[out-of-memory\\]"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(cli_simulate_out_of_memory PROPERTIES TIMEOUT 120
                             FIXTURES_SETUP cli_simulate_oom)
        add_test(NAME cli_simulate_out_of_memory_run_json
                 COMMAND ${CMAKE_COMMAND} -DDIR=${oom_dir} -DSTATUS=failed -DFRAMES=0 -DLEVEL=9
                         -DPRECISION=double "-DREASON=^out of memory$"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_json.cmake)
        set_tests_properties(cli_simulate_out_of_memory_run_json PROPERTIES
                             FIXTURES_REQUIRED cli_simulate_oom)
    endif()

    # An output that is a FIFO: with no reader the command waits in open(), with a reader that
    # never reads in write() once the pipe is full (refine to level 6: a 790 KB OBJ); one
    # Ctrl-C ends the wait and the run (exit 130). The handler was installed with std::signal,
    # which restarts the call, so the first Ctrl-C did nothing; and a write larger than the
    # pipe returned the part sent and blocked again.
    foreach(case "refine;no-reader;obj;fifo-1.obj: cannot open for writing: interrupted by a signal while waiting for a reader"
                 "remesh;no-reader;pgrid;fifo-2.pgrid: cannot open for writing: interrupted by a signal while waiting for a reader"
                 "refine;stalled-reader;obj;fifo-3.obj: write failed: interrupted by a signal while waiting for a reader")
        list(GET case 0 cmd)
        list(GET case 1 mode)
        list(GET case 2 ext)
        list(GET case 3 regex)
        string(REGEX MATCH "fifo-[0-9]" stem "${regex}")
        if(cmd STREQUAL "refine")
            set(args refine;${out_dir}/spot3.pgrid;--levels;3)
        else()
            set(args remesh;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;3;--no-measure)
        endif()
        set(name cli_${cmd}_interrupted_waiting_for_a_fifo_${mode})
        add_test(NAME ${name}
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=sh;${CMAKE_CURRENT_SOURCE_DIR}/fifo_interrupt.sh;${mode};${out_dir}/${stem}.${ext};$<TARGET_FILE:pliant>;${args};-o;${out_dir}/${stem}.${ext}"
                         -DEXIT=130 "-DSTDERR_REGEX=${regex}"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(${name} PROPERTIES FIXTURES_REQUIRED cli_outputs TIMEOUT 200
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endforeach()

    # More threads than cores: the same result, said to be slower (-j 1024 on 2 cores was 22x
    # slower than -j 2, without a word). 256, the most -j takes, is above this machine's cores.
    pliant_cli_expect(cli_threads_above_the_cores_are_warned_about 0 STDERR
                      "warning: -j 256 is above the [0-9]+ logical cores of this machine: the result is the same"
                      refine ${out_dir}/spot3.pgrid --levels 1 -j 256 -o ${out_dir}/threads.pgrid)
    set_tests_properties(cli_threads_above_the_cores_are_warned_about PROPERTIES
                         FIXTURES_REQUIRED cli_outputs)
    # Outputs checked before the work: a missing folder is refused with the reason, nothing
    # created; --report naming -o's own file is a usage error.
    pliant_cli_expect(cli_refine_output_checked_first 1 STDERR
                      "refine: -o: cannot write '.*no-such-dir/x.obj': its folder .* does not exist"
                      refine ${out_dir}/spot3.pgrid --levels 1 -o ${out_dir}/no-such-dir/x.obj)
    # A .gltf's buffer (<stem>.bin) is checked with it (check_writable, for every command).
    file(MAKE_DIRECTORY ${out_dir}/g.bin)
    pliant_cli_expect(cli_refine_gltf_buffer_checked_first 1 STDERR
                      "refine: -o \\(the .gltf's buffer\\): cannot write '.*g.bin': Is a directory"
                      refine ${out_dir}/spot3.pgrid --levels 1 -o ${out_dir}/g.gltf)
    set_tests_properties(cli_refine_gltf_buffer_checked_first PROPERTIES
                         FIXTURES_REQUIRED cli_outputs)
    pliant_cli_expect(cli_remesh_report_is_the_output 2 STDERR
                      "-o .*same.obj and --report .*same.obj are one file"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${out_dir}/same.obj --report ${out_dir}/same.obj)
    pliant_cli_expect(cli_remesh_report_is_the_buffer 2 STDERR
                      "same.bin .the buffer of -o's .gltf. and --report .*same.bin are one file"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${out_dir}/same.gltf --report ${out_dir}/same.bin)
    # No output replaces an input, a .gltf's buffer (<stem>.bin) included, nor another output
    # (file_clash): usage errors (exit 2) before any work, the input left as it was. Inputs are
    # read by content, not by name, so a grid or recording may be called X.bin.
    # pliant_refuses_clash(NAME REGEX KEEP ARGS...): exit 2, stderr matching REGEX, KEEP unchanged.
    function(pliant_refuses_clash name regex keep)
        list(JOIN ARGN ";" args)
        add_test(NAME ${name}
                 COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:pliant>;${args}" -DEXIT=2
                         "-DSTDERR_REGEX=${regex}" "-DKEEP=${keep}"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(${name} PROPERTIES TIMEOUT 120 FIXTURES_REQUIRED cli_outputs
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endfunction()
    pliant_refuses_clash(cli_refine_gltf_buffer_is_the_input
                         "refine: .*clash/in.bin .the buffer of -o's .gltf. would replace the input GRID"
                         ${out_dir}/clash/in.bin
                         refine ${out_dir}/clash/in.bin --levels 1 -o ${out_dir}/clash/in.gltf)
    pliant_refuses_clash(cli_replay_output_is_the_recording
                         "replay: -o .*clash/rec.ply would replace the input RECORDING"
                         ${out_dir}/clash/rec.ply
                         replay ${out_dir}/clash/rec.ply -o ${out_dir}/clash/rec.ply)
    pliant_refuses_clash(cli_replay_gltf_buffer_is_the_recording
                         "replay: .*clash/r.bin .the buffer of -o's .gltf. would replace the input RECORDING"
                         ${out_dir}/clash/r.bin
                         replay ${out_dir}/clash/r.bin -o ${out_dir}/clash/r.gltf)
    pliant_refuses_clash(cli_host_save_is_the_grid
                         "host: --save .*spot3.pgrid would replace the input GRID" ""
                         host ${out_dir}/spot3.pgrid --port 47999 --duration 1
                         --save ${out_dir}/spot3.pgrid)
    pliant_refuses_clash(cli_host_outputs_are_one_file
                         "host: --stats .*one.csv and --record .*one.csv are one file"
                         ${out_dir}/clash/one.csv
                         host ${out_dir}/spot3.pgrid --port 47999 --duration 1
                         --stats ${out_dir}/clash/one.csv --record ${out_dir}/clash/one.csv)
    pliant_refuses_clash(cli_join_outputs_are_one_file
                         "join: --stats .*both.pgrid and --save .*both.pgrid are one file" ""
                         join 127.0.0.1:9 --duration 1 --stats ${out_dir}/both.pgrid
                         --save ${out_dir}/both.pgrid)
    # --save holds the state (u, v, owners): another extension than .pgrid is bad input.
    pliant_cli_expect(cli_host_save_must_be_a_grid 1 STDERR
                      "host: --save .*state.obj must end in .pgrid"
                      host ${out_dir}/spot3.pgrid --port 47999 --duration 1
                      --save ${out_dir}/state.obj)
    set_tests_properties(cli_host_save_must_be_a_grid PROPERTIES FIXTURES_REQUIRED cli_outputs)
    # An input that does not exist is "no such file", not an output that would replace it.
    pliant_cli_expect(cli_remesh_missing_input_named_as_output 1 STDERR
                      "missing.obj: cannot open: no such file"
                      remesh ${out_dir}/missing.obj --level 3 -o ${out_dir}/missing.obj)

    # render: usage errors exit 2 (an output that is not .png: 1, as remesh's); a folder is not "no such file"; --level-up past level 10
    # says so; extensions in any case.
    pliant_cli_expect(cli_render_size_with_junk 2 STDERR "--size 64x64junk is not WxH"
                      render ${out_dir}/spot3.pgrid -o ${out_dir}/x.png --size 64x64junk)
    pliant_cli_expect(cli_render_camera_with_junk 2 STDERR "--camera 10,20x is not AZIMUTH"
                      render ${out_dir}/spot3.pgrid -o ${out_dir}/x.png --camera 10,20x)
    # The elevation was clamped to ±90 without a word (100 and 1e9 drew the view from above).
    pliant_cli_expect(cli_render_camera_above_the_pole 2 STDERR
                      "--camera 30,100: the elevation must lie in -90..90"
                      render ${out_dir}/spot3.pgrid -o ${out_dir}/x.png --camera 30,100)
    pliant_cli_expect(cli_render_not_png 1 STDERR "output .*x.jpg must end in .png"
                      render ${out_dir}/spot3.pgrid -o ${out_dir}/x.jpg)
    pliant_cli_expect(cli_render_folder_input 1 STDERR "cli-outputs: not a regular file \\(a folder\\)"
                      render ${out_dir} -o ${out_dir}/x.png)
    pliant_cli_expect(cli_render_level_up_too_far 1 STDERR
                      "spot3.pgrid is level 3. level 3 \\+ --level-up 8 = 11 exceeds the finest level 10 \\(use --level-up 7 or fewer\\)"
                      render ${out_dir}/spot3.pgrid -o ${out_dir}/x.png --size 64x64 --level-up 8)
    pliant_cli_expect(cli_remesh_upper_case_extension 0 STDOUT "level 3"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3 -o ${out_dir}/UP.PGRID)
    set_tests_properties(cli_remesh_upper_case_extension PROPERTIES FIXTURES_SETUP cli_upper)
    pliant_cli_expect(cli_render_upper_case_extensions 0 STDOUT "level 3 grid"
                      render ${out_dir}/UP.PGRID -o ${out_dir}/UP.PNG --size 64x64)
    set_tests_properties(cli_render_upper_case_extensions PROPERTIES FIXTURES_REQUIRED cli_upper)
    # --frames: every frame is read before any picture is written, so a bad frame stops the run
    # with the earlier sequence untouched (KEEP writes the bad frame b.pgrid, and f_0000.png).
    add_test(NAME cli_render_frames_setup
             COMMAND ${CMAKE_COMMAND} -E copy ${out_dir}/spot3.pgrid ${out_dir}/frames/a.pgrid)
    set_tests_properties(cli_render_frames_setup PROPERTIES FIXTURES_REQUIRED cli_outputs
                         FIXTURES_SETUP cli_frames)
    add_test(NAME cli_render_frames_bad_frame_writes_nothing
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;render;--frames;${out_dir}/frames;-o;${out_dir}/seq/f.png;--size;64x64"
                     -DEXIT=1 "-DSTDERR_REGEX=frames/b.pgrid: too short for a pliant grid file"
                     "-DKEEP=${out_dir}/frames/b.pgrid;${out_dir}/seq/f_0000.png"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_render_frames_bad_frame_writes_nothing PROPERTIES
                         FIXTURES_REQUIRED cli_frames ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # Standard output that cannot be written is an error (exit 1), not an answer lost with exit
    # 0; a reader that went away does not kill the run (SIGPIPE ignored): the work ends, its
    # file is written, and the lost output is reported (it was killed at the next progress
    # line, status 141, nothing written).
    add_test(NAME cli_stdout_full_is_an_error
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=sh;-c;'$<TARGET_FILE:pliant>' info '${PROJECT_SOURCE_DIR}/data/spot.obj' --json > /dev/full"
                     -DEXIT=1 "-DSTDERR_REGEX=cannot write to standard output: No space left on device"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    find_program(PLIANT_PYTHON3 python3)
    if(PLIANT_PYTHON3)
        add_test(NAME cli_closed_pipe_does_not_kill_the_run
                 COMMAND ${PLIANT_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/closed_pipe.py 1
                         ${out_dir}/piped.pgrid $<TARGET_FILE:pliant> remesh
                         ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3 -o ${out_dir}/piped.pgrid)
        set_tests_properties(cli_closed_pipe_does_not_kill_the_run PROPERTIES TIMEOUT 300
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endif()
    # -q: only errors. info's answer is then its exit status.
    pliant_cli_expect(cli_quiet_info 0 STDOUT "^$" -q info ${PROJECT_SOURCE_DIR}/data/spot.obj)
    pliant_cli_expect(cli_quiet_render 0 STDOUT "^$"
                      -q render ${out_dir}/spot3.pgrid -o ${out_dir}/q.png --size 64x64)
    pliant_cli_expect(cli_quiet_refine 0 STDOUT "^$"
                      -q refine ${out_dir}/spot3.pgrid --levels 1 -o ${out_dir}/q.obj)
    # join: --duration ending before any answer says "never answered"; key files that are empty
    # or readable by others are told as that (nobody listens on 127.0.0.1:9).
    # Addresses that cannot be a master: 0.0.0.0 (a listening address: "never answered") and
    # this peer's own --port ("refused ... may need a --passphrase").
    pliant_cli_expect(cli_join_any_address_is_refused 2 STDERR
                      "join: 0.0.0.0:47998 is the 'any' address" join 0.0.0.0:47998 --duration 1)
    pliant_cli_expect(cli_join_own_port_is_refused 2 STDERR
                      "join: 127.0.0.1:47998 is this peer's own --port 47998"
                      join 127.0.0.1:47998 --port 47998 --duration 1)
    # A malformed MASTER is a usage error (2); a host name that does not resolve (RFC 6761:
    # nothing under .invalid does) is the network's failure (3), as is a master that never
    # answers.
    pliant_cli_expect(cli_join_malformed_address_is_a_usage_error 2 STDERR
                      "address '127.0.0.1:99999' has a bad port" join 127.0.0.1:99999 --duration 1)
    pliant_cli_expect(cli_join_unknown_host_is_a_network_failure 3 STDERR
                      "cannot find an IPv4 address for host 'no-such-host.invalid'"
                      join no-such-host.invalid:7777 --duration 1)
    # A file name holding an escape sequence (ESC [31m) is printed with the control byte as \x1b,
    # in info's heading and in an error: it recoloured the terminal.
    add_test(NAME cli_control_bytes_in_names_are_escaped
             COMMAND sh -c "d='${out_dir}/escape' && rm -rf \"$d\" && mkdir -p \"$d\" && f=\"$d/a$(printf '\\033')[31m.obj\" && cp '${PROJECT_SOURCE_DIR}/data/spot.obj' \"$f\" && '$<TARGET_FILE:pliant>' info \"$f\" | grep -F 'a\\x1b[31m.obj (obj)' && '$<TARGET_FILE:pliant>' info \"$d/b$(printf '\\033').obj\" 2>&1 | grep -F 'b\\x1b.obj: cannot open: no such file'")
    set_tests_properties(cli_control_bytes_in_names_are_escaped PROPERTIES
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    # The same for `view HOST:PORT`, before any window opens (it waited for an answer).
    pliant_cli_expect(cli_view_any_address_is_refused 2 STDERR
                      "view: 0.0.0.0:47998 is the 'any' address" view 0.0.0.0:47998 --exit-after 1)
    pliant_cli_expect(cli_view_own_port_is_refused 2 STDERR
                      "view: 127.0.0.1:47998 is this peer's own --port 47998"
                      view 127.0.0.1:47998 --port 47998 --exit-after 1)
    pliant_cli_expect(cli_join_never_answers_within_duration 3 STDERR
                      "127.0.0.1:9 never answered within --duration 1 s: check the address and port"
                      join 127.0.0.1:9 --duration 1)
    file(WRITE ${out_dir}/empty.key "")
    pliant_cli_expect(cli_key_file_empty 1 STDERR "key file .*empty.key is empty"
                      join 127.0.0.1:9 --duration 1 --key-file ${out_dir}/empty.key)
    file(WRITE ${out_dir}/open.key "0123456789abcdef0123456789abcdef")
    file(CHMOD ${out_dir}/open.key PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
    pliant_cli_expect(cli_key_file_readable_by_all 3 STDERR
                      "open.key: the key file can be read by every user \\(mode 0644\\).*chmod 600"
                      join 127.0.0.1:9 --duration 1 --key-file ${out_dir}/open.key)
    # demo: level 3 has two quad-tree leaves, too few for its three simulating peers (it spun
    # until --wall-limit); --screenshot without --view is a usage error. bench: an unknown suite.
    # An --out that exists but cannot be written fails before the remeshing (it failed after).
    pliant_cli_expect(cli_demo_unwritable_out_fails_first 1 STDERR
                      "demo: --out: cannot write '/proc/self/summary.md'"
                      demo --quick --out /proc/self)
    pliant_cli_expect(cli_demo_level_3_is_refused 2 STDERR "--level: 3 is not in 4 to 8"
                      demo --quick --level 3 --out ${out_dir}/demo-l3)
    pliant_cli_expect(cli_demo_screenshot_needs_view 2 STDERR
                      "--screenshot and --exit-after go with --view"
                      demo --quick --screenshot ${out_dir}/d.png --out ${out_dir}/demo-s)
    pliant_cli_expect(cli_bench_unknown_suite_is_a_usage_error 2 STDERR "unknown suite 'nosuch'"
                      bench nosuch --out ${out_dir}/bench-nosuch)
    set_tests_properties(cli_render_size_with_junk cli_render_camera_with_junk cli_render_camera_above_the_pole cli_render_not_png
                         cli_render_level_up_too_far cli_quiet_render cli_quiet_refine
                         cli_refine_output_checked_first PROPERTIES FIXTURES_REQUIRED cli_outputs)
endif()
