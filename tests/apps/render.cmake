# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant render` end to end (docs/rendering.md) under Mesa's software OpenGL (EGL surfaceless
# or OSMesa: no display needed). Each render runs through render_and_check.cmake: it must exit 0
# and print what it drew, and pliant_png_check (png_check.cpp) must find a PNG of the asked size
# with the object covering a plausible share of it and the colours asked for. Inputs: a level-4
# remesh of the bundled cow, the first half second of the pull scenario at level 4 (6 frames,
# tests/data/scenarios/pull_short.toml), and the final state of `pliant demo --quick`.
if(TARGET pliant AND TARGET pliant_png_check)
    set(_r ${CMAKE_CURRENT_BINARY_DIR}/render)
    set(_check $<TARGET_FILE:pliant_png_check>)
    set(_env "ASAN_OPTIONS=detect_leaks=0;OMP_NUM_THREADS=1")
    add_test(NAME cli_render_clean
             COMMAND ${CMAKE_COMMAND} -DDIR=${_r} -P ${CMAKE_CURRENT_SOURCE_DIR}/fresh_dir.cmake)
    set_tests_properties(cli_render_clean PROPERTIES FIXTURES_SETUP render_clean)
    add_test(NAME cli_render_setup_remesh
             COMMAND pliant remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4
                     -o ${_r}/spot4.pgrid)
    set_tests_properties(cli_render_setup_remesh PROPERTIES TIMEOUT 120
        FIXTURES_REQUIRED render_clean FIXTURES_SETUP render_grid)
    add_test(NAME cli_render_setup_simulate
             COMMAND pliant simulate
                     --scenario ${PROJECT_SOURCE_DIR}/tests/data/scenarios/pull_short.toml
                     -o ${_r}/frames --level 4 -j 1)
    set_tests_properties(cli_render_setup_simulate PROPERTIES TIMEOUT 120
        FIXTURES_REQUIRED render_clean FIXTURES_SETUP render_frames
        PASS_REGULAR_EXPRESSION "6 frames, 0.500 s simulated")

    # pliant_add_render_test(NAME FIXTURE REGEX ARGS CHECK...): `pliant render ARGS` (a ;-list)
    # with stdout matching REGEX, then pliant_png_check with each CHECK's arguments (a
    # ,-separated list).
    function(pliant_add_render_test name fixture regex args)
        set(checks)
        set(n 0)
        foreach(check IN LISTS ARGN)
            math(EXPR n "${n} + 1")
            list(APPEND checks "-DCHECK${n}=${check}")
        endforeach()
        add_test(NAME ${name}
                 COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:pliant>;render;${args}"
                         "-DSTDOUT_REGEX=${regex}" -DPNG_CHECK=${_check} ${checks} -DTIMEOUT=110
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/render_and_check.cmake)
        set_tests_properties(${name} PROPERTIES TIMEOUT 120 FIXTURES_REQUIRED "${fixture}"
                             ENVIRONMENT "${_env}")
    endfunction()

    # A mesh (vertex-buffer path) and a remeshed grid refined one level for display (texture
    # path): PNGs of the asked size with the cow on 5-80 % of the picture (measured 16 %).
    pliant_add_render_test(cli_render_mesh render_clean
        "320x240, mesh, 5856 triangles"
        "${PROJECT_SOURCE_DIR}/data/spot.obj;-o;${_r}/mesh.png;--size;320x240"
        "${_r}/mesh.png,--size,320x240,--cover,0.05,0.8")
    pliant_add_render_test(cli_render_grid render_grid
        "320x240, level 5 grid, 4096 triangles"
        "${_r}/spot4.pgrid;-o;${_r}/grid.png;--size;320x240;--level-up;1;--camera;40,25"
        "${_r}/grid.png,--size,320x240,--cover,0.05,0.8,--saturated,0,0.05")
    # Owners without an "owner" channel: the stand-in leaves, in at least 3 palette colours
    # from one side, and the summary line says they are stand-ins.
    pliant_add_render_test(cli_render_grid_owner render_grid
        "owners from no channel \"owner\": the 8 quad-tree leaves at depth 1 stand in for peers"
        "${_r}/spot4.pgrid;-o;${_r}/owner.png;--size;320x240;--color;owner;--wireframe"
        "${_r}/owner.png,--size,320x240,--cover,0.05,0.8,--min-owner-colours,3")
    # The demo's final state carries the session's partition: its 3 peers in their colours.
    pliant_add_render_test(cli_render_demo_owners demo_quick
        "owners from the channel \"owner\": 3 peers"
        "${CMAKE_CURRENT_BINARY_DIR}/demo-quick/final.pgrid;-o;${_r}/demo-owners.png;--size;320x240;--color;owner"
        "${_r}/demo-owners.png,--size,320x240,--cover,0.05,0.8,--min-owner-colours,3")
    # A simulated sequence in displacement colours, one range for all frames (the largest |u|
    # of any): the rest state (frame 0) is grey, the first frame's small bump leaves most of
    # the surface grey too, and the last frame's bump is saturated somewhere. With the first
    # frame's range (|u| = 0, floored at 1e-12) every later frame was wholly saturated.
    pliant_add_render_test(cli_render_frames_displacement render_frames
        "6 frames from .*; displacement colours full at \\|u\\| = [0-9.]+e-0[1-3] m \\(the largest \\|u\\| over the 6 frames\\)"
        "--frames;${_r}/frames;-o;${_r}/seq/f.png;--size;240x180;--color;displacement;--camera;0,30"
        "${_r}/seq/f_0000.png,--size,240x180,--cover,0.05,0.9,--saturated,0,0.01"
        "${_r}/seq/f_0001.png,--size,240x180,--cover,0.05,0.9,--saturated,0,0.2"
        "${_r}/seq/f_0005.png,--size,240x180,--cover,0.05,0.9,--saturated,0.01,0.6")
    # --color-range sets the range by hand: 1 mm saturates the bump of frame 5 over more of the
    # surface than the automatic range does.
    pliant_add_render_test(cli_render_frames_color_range render_frames
        "6 frames from .*; displacement colours full at \\|u\\| = 1\\.000e-03 m \\(--color-range\\)"
        "--frames;${_r}/frames;-o;${_r}/seq-range/f.png;--size;240x180;--color;displacement;--camera;0,30;--color-range;1e-3"
        "${_r}/seq-range/f_0000.png,--size,240x180,--cover,0.05,0.9,--saturated,0,0.01"
        "${_r}/seq-range/f_0005.png,--size,240x180,--cover,0.05,0.9,--saturated,0.3,1")

    # An earlier, longer sequence under the same name: its frames go before the new ones are
    # written (f_0007.png of an earlier run was left beside the 6 new frames).
    add_test(NAME cli_render_frames_clear_an_earlier_run
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;render;--frames;${_r}/frames;-o;${_r}/seq-stale/f.png;--size;64x48"
                     -DEXIT=0 "-DSTDERR_REGEX=removed 1 frame.s. f_NNNN.png of an earlier run"
                     "-DSTALE=${_r}/seq-stale/f_0007.png"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_render_frames_clear_an_earlier_run PROPERTIES TIMEOUT 120
                         FIXTURES_REQUIRED render_frames ENVIRONMENT "${_env}")
    # Every frame's file is checked before an earlier sequence goes: a folder named f_0002.png
    # is refused with the earlier f_0000.png still there (it was removed, frames 0 and 1
    # drawn, and the run stopped at frame 2 with a message not naming render or -o).
    set(_blocked ${_r}/seq-blocked)
    add_test(NAME cli_render_frames_blocked_output_keeps_the_earlier_sequence
             COMMAND sh -c "mkdir -p '${_blocked}/f_0002.png' && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;render;--frames;${_r}/frames;-o;${_blocked}/f.png;--size;64x48' -DEXIT=1 '-DSTDERR_REGEX=render: -o: cannot write .*f_0002.png' '-DKEEP=${_blocked}/f_0000.png' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
    set_tests_properties(cli_render_frames_blocked_output_keeps_the_earlier_sequence PROPERTIES
                         TIMEOUT 60 FIXTURES_REQUIRED render_frames ENVIRONMENT "${_env}")
    # Grids the reader accepts but no picture can show (written by make_bad_grid.py from the
    # format's rules): refused, where an all-white picture was written with exit 0.
    find_program(PLIANT_PYTHON3 python3)
    if(PLIANT_PYTHON3)
        foreach(kind point far)
            set(_bad ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/${kind}.pgrid)
            if(kind STREQUAL "point")
                set(_why "every node lies at one point: there is no surface to draw")
            else()
                set(_why "node \\(8, 4\\) lies at \\(1e\\+300, 0, 0\\), which cannot be drawn")
            endif()
            add_test(NAME cli_render_refuses_an_undrawable_${kind}
                     COMMAND sh -c "'${PLIANT_PYTHON3}' '${CMAKE_CURRENT_SOURCE_DIR}/make_bad_grid.py' ${kind} '${_bad}' && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;render;${_bad};-o;${_r}/undrawable-${kind}.png' -DEXIT=1 '-DSTDERR_REGEX=${_why}' '-DABSENT=${_r}/undrawable-${kind}.png' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
            set_tests_properties(cli_render_refuses_an_undrawable_${kind} PROPERTIES TIMEOUT 60
                                 ENVIRONMENT "${_env}")
        endforeach()
        # --frames: a frame the drawing pass would refuse (no surface) is found in the first
        # pass, before an earlier sequence goes (it removed the earlier frames, then stopped at
        # the bad one); an -o whose folder is missing is refused before the frames are read
        # (it was made, and the frames written there).
        set(_undrawable ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/frames-undrawable)
        add_test(NAME cli_render_frames_undrawable_keeps_the_earlier_sequence
                 COMMAND sh -c "mkdir -p '${_undrawable}' && cp '${_r}/frames/frame_00000.pgrid' '${_undrawable}/a.pgrid' && '${PLIANT_PYTHON3}' '${CMAKE_CURRENT_SOURCE_DIR}/make_bad_grid.py' point '${_undrawable}/b.pgrid' && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;render;--frames;${_undrawable};-o;${_r}/seq-kept/f.png;--size;64x48' -DEXIT=1 '-DSTDERR_REGEX=b.pgrid: every node lies at one point' '-DKEEP=${_r}/seq-kept/f_0000.png;${_r}/seq-kept/f_0001.png' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
        set_tests_properties(cli_render_frames_undrawable_keeps_the_earlier_sequence PROPERTIES
                             TIMEOUT 60 FIXTURES_REQUIRED render_frames ENVIRONMENT "${_env}")
        # `info` says when owner values are not peer ids (whole numbers from -1 to 65535),
        # counting only the ids.
        set(_bad ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/owner.pgrid)
        add_test(NAME cli_info_names_fractional_owners
                 COMMAND sh -c "'${PLIANT_PYTHON3}' '${CMAKE_CURRENT_SOURCE_DIR}/make_bad_grid.py' owner '${_bad}' && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;info;${_bad}' -DEXIT=1 '-DSTDOUT_REGEX=owner .vertices. +peer 0: 129  .1 vertex holds no peer id, e.g. 0.5 at node .8, 4..' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
        set_tests_properties(cli_info_names_fractional_owners PROPERTIES TIMEOUT 60)
        # The demo's final.pgrid with an owner of 1e300 at node (8, 4): `render --color owner`
        # refuses it naming the node (it drew the node as no one's), `info` says it is invalid
        # (it printed "peer -9223372036854775808").
        set(_bad ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/owner-far.pgrid)
        add_test(NAME cli_render_refuses_an_owner_that_is_no_peer_id
                 COMMAND sh -c "'${PLIANT_PYTHON3}' '${CMAKE_CURRENT_SOURCE_DIR}/make_bad_grid.py' set-owner '${CMAKE_CURRENT_BINARY_DIR}/demo-quick/final.pgrid' '${_bad}' 1e300 && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;render;${_bad};-o;${_r}/owner-far.png;--color;owner' -DEXIT=1 '-DSTDERR_REGEX=channel owner: node .8, 4. holds 1e.300, which is not a peer id' '-DABSENT=${_r}/owner-far.png' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake' && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;info;${_bad}' -DEXIT=1 '-DSTDOUT_REGEX=1 vertex holds no peer id, e.g. 1e.300 at node .8, 4.' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
        set_tests_properties(cli_render_refuses_an_owner_that_is_no_peer_id PROPERTIES TIMEOUT 60
                             FIXTURES_REQUIRED demo_quick ENVIRONMENT "${_env}")
        # -1 (and 65535) is no owner: `info` counts it as such after the peers (it printed
        # "peer -1: 1").
        set(_unowned ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/owner-none.pgrid)
        add_test(NAME cli_info_counts_nodes_without_owner
                 COMMAND sh -c "'${PLIANT_PYTHON3}' '${CMAKE_CURRENT_SOURCE_DIR}/make_bad_grid.py' set-owner '${CMAKE_CURRENT_BINARY_DIR}/demo-quick/final.pgrid' '${_unowned}' -1 && '${CMAKE_COMMAND}' '-DCOMMAND=$<TARGET_FILE:pliant>;info;${_unowned}' -DEXIT=0 '-DSTDOUT_REGEX=owner .vertices. +peer 0: [0-9]+, peer 1: [0-9]+, peer 2: [0-9]+, no owner: 1\n' -P '${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake'")
        set_tests_properties(cli_info_counts_nodes_without_owner PROPERTIES TIMEOUT 60
                             FIXTURES_REQUIRED demo_quick ENVIRONMENT "${_env}")
    endif()

    # Ctrl-C during a sequence (the 101 frames of cli_simulate_pull), once f_0003.png is
    # written: the render stops after the frame being written, says how many, exits 130.
    pliant_add_interrupt_test(cli_render_frames_interrupted FILE ${_r}/interrupted/f_0003.png
        STDERR_REGEX "render: interrupted after [0-9]+ of 101 frames \\(.*f_0000\\.png to .*f_[0-9]+\\.png\\)"
        FIXTURES_REQUIRED render_clean simulate_pull_frames ENVIRONMENT ${_env}
        ARGS render --frames ${sim_out} -o ${_r}/interrupted/f.png --size 320x240)

    # Bad input: each refusal exits non-zero and says why.
    file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/empty)
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/render-inputs/corrupt.pgrid "not a grid file\n")
    # Each case: NAME|ARGUMENTS (comma-separated)|REGEX.
    set(_inputs ${CMAKE_CURRENT_BINARY_DIR}/render-inputs)
    set(_bad_cases
        "missing_file|${_r}/none.pgrid,-o,${_r}/x.png|none\\.pgrid: no such file"
        "no_input|-o,${_r}/x.png|give GRID or MESH"
        "bad_size|${_r}/spot4.pgrid,-o,${_r}/x.png,--size,8x8|--size 8x8 is not WxH"
        "not_png|${_r}/spot4.pgrid,-o,${_r}/x.jpg|must end in \\.png"
        "bad_camera|${_r}/spot4.pgrid,-o,${_r}/x.png,--camera,north|--camera north is not AZIMUTH"
        "bad_color_range|${_r}/spot4.pgrid,-o,${_r}/x.png,--color-range,-1|--color-range"
        "corrupt_grid|${_inputs}/corrupt.pgrid,-o,${_r}/x.png|corrupt\\.pgrid"
        "empty_frames|--frames,${_inputs}/empty,-o,${_r}/x.png|no \\.pgrid files in"
        "frames_not_a_folder|--frames,${_r}/none,-o,${_r}/x.png|--frames .*none is not a folder")
    foreach(case IN LISTS _bad_cases)
        string(REPLACE "|" ";" parts "${case}")
        list(GET parts 0 what)
        list(GET parts 1 args)
        list(GET parts 2 regex)
        string(REPLACE "," ";" args "${args}")
        add_test(NAME cli_render_refuses_${what}
                 COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:pliant>;render;${args}"
                         "-DREGEX=${regex}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
        set_tests_properties(cli_render_refuses_${what} PROPERTIES TIMEOUT 60
                             FIXTURES_REQUIRED render_grid ENVIRONMENT "${_env}")
    endforeach()
endif()
