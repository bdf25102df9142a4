# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant refine` end to end, and the exit codes every command shares (docs/troubleshooting.md):
# 0 done, 1 bad input (the message names the file and the rule), 2 usage error (CLI11: an
# unknown option, a value out of range, a missing argument, an option without the one it needs).
if(TARGET pliant)
    set(cli_dir ${CMAKE_CURRENT_BINARY_DIR}/cli-refine)
    file(MAKE_DIRECTORY ${cli_dir})
    # A level-3 grid of the bundled cow, shared by the refine tests.
    pliant_cli_expect(cli_refine_setup 0 STDOUT "level 3: 130 vertices"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${cli_dir}/spot3.pgrid)
    set_tests_properties(cli_refine_setup PROPERTIES FIXTURES_SETUP cli_refine)
    # Two levels to OBJ: level 5 has 2,050 surface vertices and 4,096 faces; --verbose times
    # each level.
    pliant_cli_expect(cli_refine_obj_verbose 0 STDERR
                      "level 3 -> 4: [0-9.]+ ms.*level 4 -> 5: [0-9.]+ ms.*2 levels in"
                      refine ${cli_dir}/spot3.pgrid --levels 2 -o ${cli_dir}/spot5.obj -v)
    pliant_cli_expect(cli_refine_obj_counts 0 STDOUT
                      "level 3 -> 5, 2050 vertices, 4096 faces, 3 channel\\(s\\)"
                      refine ${cli_dir}/spot3.pgrid --levels 2 -o ${cli_dir}/spot5b.obj)
    pliant_cli_expect(cli_refine_native 0 STDOUT "level 3 -> 4"
                      refine ${cli_dir}/spot3.pgrid --levels 1 -o ${cli_dir}/spot4.pgrid)
    pliant_cli_expect(cli_refine_bad_extension 1 STDERR "must end in \\.pgrid"
                      refine ${cli_dir}/spot3.pgrid --levels 1 -o ${cli_dir}/spot4.xyz)
    pliant_cli_expect(cli_refine_directory 1 STDERR "cli-refine: not a regular file"
                      refine ${cli_dir} --levels 1 -o ${cli_dir}/x.obj)
    pliant_cli_expect(cli_refine_not_a_grid 1 STDERR "spot.obj: .*not a pliant grid file"
                      refine ${PROJECT_SOURCE_DIR}/data/spot.obj --levels 1
                      -o ${cli_dir}/x.obj)
    pliant_cli_expect(cli_refine_too_fine 1 STDERR "level 3 \\+ 8 = 11 exceeds the finest level 10 \\(use --levels 7 or fewer\\)"
                      refine ${cli_dir}/spot3.pgrid --levels 8 -o ${cli_dir}/x.obj)
    # -o naming the input is refused before anything is read (it replaced the input).
    pliant_cli_expect(cli_refine_output_is_the_input 2 STDERR
                      "refine: -o .*spot3.pgrid would replace the input GRID"
                      refine ${cli_dir}/spot3.pgrid --levels 1 -o ${cli_dir}/../cli-refine/spot3.pgrid)
    pliant_cli_expect(cli_remesh_output_is_the_input 2 STDERR
                      "remesh: .*in.obj would replace the input mesh"
                      remesh ${cli_dir}/in.obj --level 3 -o ${cli_dir}/in.obj)
    file(COPY_FILE ${PROJECT_SOURCE_DIR}/data/spot.obj ${cli_dir}/in.obj)
    # A map that folds under the method the user chose names the file and the way out.
    pliant_cli_expect(cli_remesh_spring_fold_names_the_file_and_auto 1 STDERR
                      "spot.obj: map_to_sphere: the spring embedder left [0-9]+ of [0-9]+ spherical triangles inverted. --method auto"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --method spring --level 3
                      -o ${cli_dir}/spring.obj)
    # A .gltf whose name a URI would have to escape (its buffer is named in one) is refused
    # before the work: Assimp's reader does not decode %-escapes.
    pliant_cli_expect(cli_remesh_gltf_name_needing_escapes 1 STDERR
                      "my model.gltf: the .gltf names its buffer my model.bin in a URI"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3 -o "${cli_dir}/my model.gltf")
    # Ctrl-C while the level-10 OBJ is formatted (seconds): exit 130, nothing written (it went
    # on, wrote all 236 MB and exited 0).
    pliant_add_interrupt_test(cli_refine_interrupted LOG "refine: level 9 -> 10"
        STDERR_REGEX "refine: interrupted; .*big.obj not written"
        ABSENT ${cli_dir}/big.obj TIMEOUT 300 FIXTURES_REQUIRED cli_refine
        ARGS -v refine ${cli_dir}/spot3.pgrid --levels 7 -o ${cli_dir}/big.obj)
    set_tests_properties(cli_refine_output_is_the_input
                         PROPERTIES FIXTURES_REQUIRED cli_refine)
    set_tests_properties(cli_refine_obj_verbose cli_refine_obj_counts cli_refine_native
                         cli_refine_directory
                         cli_refine_bad_extension cli_refine_not_a_grid cli_refine_too_fine
                         PROPERTIES FIXTURES_REQUIRED cli_refine)

    # remesh: -o and --report are checked before any work; --no-measure is honoured with
    # --report (no distance line, and no distance keys in the JSON); the report counts folds and
    # self-intersections of the output and of the input.
    pliant_cli_expect(cli_remesh_unwritable_output 1 STDERR "remesh: -o: cannot write"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${cli_dir}/no-such-dir/x.obj)
    pliant_cli_expect(cli_remesh_unwritable_report 1 STDERR "remesh: --report: cannot write"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                      -o ${cli_dir}/x3.obj --report ${cli_dir}/no-such-dir/x.json)
    pliant_cli_expect(cli_remesh_no_measure_report 0 STDOUT
                      "0 folded triangles, 0 intersecting triangle pairs.*input: 0 intersecting pairs\ntriangle areas"
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4 --no-measure
                      -o ${cli_dir}/spot4.obj --report ${cli_dir}/spot4.json)

    # Usage errors: status 2 from every command, with CLI11's message.
    pliant_cli_expect(cli_usage_levels_out_of_range 2 STDERR "--levels: 0 is not in 1 to 9"
                      refine x.pgrid --levels 0 -o x.obj)
    pliant_cli_expect(cli_usage_unknown_option 2 STDERR "pliant host: unknown option .--bogus."
                      host --bogus)
    pliant_cli_expect(cli_usage_bad_choice 2 STDERR "--mode: bogus not in \\{exact,fast\\}"
                      host --mode bogus)
    pliant_cli_expect(cli_usage_missing_argument 2 STDERR "MASTER is required" join)
    # A file option's missing, folder or unreadable file is bad input (status 1), said as the
    # GRID and MESH arguments' are, while the command line is parsed (existing_input_file).
    pliant_cli_expect(cli_input_file_missing 1
                      STDERR "error: --script: .*no-such/plan\\.txt: no such file \\[io-error\\]"
                      join 127.0.0.1:7 --script ${cli_dir}/no-such/plan.txt --duration 1)
    pliant_cli_expect(cli_input_file_is_a_folder 1 STDERR "error: --key-file: .*: is a folder, not a file"
                      host --key-file ${CMAKE_CURRENT_SOURCE_DIR} --duration 1)
    pliant_cli_expect(cli_input_recording_missing 1 STDERR "error: RECORDING: .*none\\.prec: no such file"
                      replay ${cli_dir}/none.prec -o ${cli_dir}/none.pgrid)
    pliant_cli_expect(cli_input_grid_missing 1 STDERR "error: .*none\\.pgrid: no such file"
                      host ${cli_dir}/none.pgrid --duration 1)
    # Numbers: the rule broken in words, no bound printed as DBL_MAX; and every FLOAT option of
    # every command refuses nan and the infinities, every UINT option a minus sign.
    pliant_cli_expect(cli_usage_negative 2 STDERR "--max-force: -2 is negative; give a number >= 0\n"
                      host --max-force -2)
    pliant_cli_expect(cli_usage_not_positive 2 STDERR "--tension: 0 is not positive; give a number > 0\n"
                      host --tension 0)
    # The shader takes --color-range as a float: 1e-50 became 0 and the largest |u| was used,
    # the summary naming 1e-50.
    pliant_cli_expect(cli_usage_color_range_below_a_float 2 STDERR
                      "--color-range: 1e-50 is outside \\[1e-30, 1e\\+30\\]"
                      render --color-range 1e-50)
    pliant_cli_expect(cli_usage_outside 2 STDERR "--fps: 200 is outside \\[1, 60\\]; give a number in it"
                      demo --fps 200)
    pliant_cli_expect(cli_usage_unsigned_too_large 2 STDERR
                      "--ticks: 99999999999999999999 is too large. give a whole number below 2.64"
                      host --ticks 99999999999999999999)
    add_test(NAME cli_usage_numbers_are_finite
             COMMAND ${CMAKE_COMMAND} -DPLIANT=$<TARGET_FILE:pliant>
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/number_options.cmake)
    # A port out of range says so (CLI11 alone: "Could not convert: --port = 70000").
    pliant_cli_expect(cli_usage_port_out_of_range 2 STDERR
                      "--port: 70000 is not a UDP port. give a whole number from 1 to 65535"
                      host --port 70000)
    pliant_cli_expect(cli_usage_join_port_out_of_range 2 STDERR
                      "--port: 65536 is not a UDP port. give a whole number from 0 to 65535 \\(0: any free port\\)"
                      join 127.0.0.1:7777 --port 65536)
    pliant_cli_expect(cli_usage_needs 2 STDERR "--cap requires --compress" join 127.0.0.1:7777 --cap 1)
    pliant_cli_expect(cli_usage_no_command 2 STDERR "A subcommand is required")
    # An unknown option is named before CLI11's other complaints ("A subcommand is required",
    # "--output is required"), which it would otherwise hide; a negative value is no option.
    pliant_cli_expect(cli_usage_unknown_option_alone 2 STDERR "pliant: unknown option '--bogus'"
                      --bogus)
    pliant_cli_expect(cli_usage_unknown_option_of_a_command 2 STDERR
                      "pliant remesh: unknown option '--bogus'" remesh --bogus x.obj)
    pliant_cli_expect(cli_usage_negative_value_is_no_option 2 STDERR
                      "--radius: -1 is outside" simulate --radius -1 -o y.pgrid)
    pliant_cli_expect(cli_usage_unknown_command 2 STDERR
                      "unknown command 'nosuch'; the commands are: demo, info, remesh" nosuch)
    pliant_cli_expect(cli_usage_verbose_and_quiet 2 STDERR "--verbose excludes --quiet"
                      -v -q info ${PROJECT_SOURCE_DIR}/data/spot.obj)
    # An empty argument is a usage error, whatever it stands for: CLI11 read it as "not given"
    # (`remesh "$MESH"` with MESH unset remeshed the bundled mesh; `--report ""` wrote no
    # report; `replay -o ""` wrote nothing; each exited 0).
    add_test(NAME cli_usage_empty_positional
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=sh;-c;'$<TARGET_FILE:pliant>' remesh '' --level 2 -o '${cli_dir}/empty.pgrid'"
                     -DEXIT=2 "-DSTDERR_REGEX=argument 2 is empty .a positional argument."
                     "-DABSENT=${cli_dir}/empty.pgrid"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    pliant_cli_expect(cli_usage_empty_option_value 2 STDERR
                      "argument 5 is empty .the value of --report."
                      remesh ${PROJECT_SOURCE_DIR}/data/spot.obj -o ${cli_dir}/x.pgrid --report=)
    # info --json carries every statistic: the edges of an orientation failure among them (it
    # gave the error but not the count).
    file(WRITE ${cli_dir}/flipped.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 4 3\n")
    pliant_cli_expect(cli_info_json_counts_inconsistent_edges 1 STDOUT
                      "\"raw_faces\": 4,.*\"inconsistent_edges\": 3,"
                      info ${cli_dir}/flipped.obj --json)
    # An empty secret would open the session to anyone (`--passphrase "$SECRET"`, SECRET unset).
    add_test(NAME cli_usage_empty_passphrase
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=sh;-c;'$<TARGET_FILE:pliant>' join 127.0.0.1:7777 --passphrase ''"
                     -DEXIT=2 "-DSTDERR_REGEX=an empty passphrase would leave the session open"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    add_test(NAME cli_empty_passphrase_variable
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=env;PLIANT_PASSPHRASE=;$<TARGET_FILE:pliant>;join;127.0.0.1:7777"
                     -DEXIT=1 "-DSTDERR_REGEX=PLIANT_PASSPHRASE is set but empty"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    pliant_cli_expect(cli_help_exits_0 0 STDOUT "Subcommands:" --help)
endif()
