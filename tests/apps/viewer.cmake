# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# End-to-end test of `pliant view` (docs/viewer.md) under Xvfb with Mesa's software OpenGL: the
# bundled mesh is remeshed at level 4 on the viewer's worker thread, a scripted drag pulls the
# surface, the surface is exported (glTF binary and OBJ) and re-imported, and a screenshot is
# written at exit. Only when the viewer was built and Xvfb exists (Debian's xvfb).
find_program(PLIANT_XVFB Xvfb)
if(TARGET pliant AND PLIANT_HAVE_VIEWER AND PLIANT_XVFB)
    set(_viewer_png ${CMAKE_CURRENT_BINARY_DIR}/viewer.png)
    # The script exports the surface after the drag (`export viewer_export.glb`, then key E:
    # pliant-view-0000.obj, the first free name) and takes two screenshots (P, F12) into the
    # test's working folder; stale files from an earlier run are removed first so the checks
    # below see this run's, and a stand-in earlier screenshot pliant-view-0000.png is written,
    # which the presses must not overwrite.
    set(_viewer_exports ${CMAKE_CURRENT_BINARY_DIR}/viewer_export.glb
                        ${CMAKE_CURRENT_BINARY_DIR}/pliant-view-0000.obj)
    add_test(NAME cli_view_export_clean
             COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}
                     "-DFILES=viewer_export.glb;pliant-view-0000.obj;pliant-view-0001.png;pliant-view-0002.png;pliant-view-0003.png"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer_prepare.cmake)
    set_tests_properties(cli_view_export_clean PROPERTIES FIXTURES_SETUP viewer_export_clean)
    # The viewer's runs go through expect_exit.cmake: the output must match and the exit status
    # must be 0 (it exits cleanly), which PASS_REGULAR_EXPRESSION alone would not check.
    # A private Xvfb per run (with_xvfb.sh says why not xvfb-run).
    set(_xvfb sh ${CMAKE_CURRENT_SOURCE_DIR}/with_xvfb.sh)
    # The drag must move the surface by at least 0.5 % of its radius (the pull gives several per
    # cent; an unpicked or ignored drag gives 0.000 %), and the object must cover at least 5 % of
    # the picture (a failed read-back or an empty view gives 0).
    set(_drag_regex
        "largest \\|u\\| reached [0-9.e+-]+ m = ([1-9][0-9]*|0\\.[5-9][0-9]*)\\.?[0-9]* % of the object radius.*covers ([5-9]|[1-9][0-9])\\.[0-9] % of the 3D view")
    add_test(NAME cli_view_scripted_drag
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;4;--size;640x480;--script;${CMAKE_CURRENT_SOURCE_DIR}/viewer_drag.txt;--screenshot;${_viewer_png};--exit-after;3"
                     -DEXIT=0 "-DSTDOUT_REGEX=${_drag_regex}" -DTIMEOUT=110
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_scripted_drag PROPERTIES
        TIMEOUT 120
        WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}
        FIXTURES_SETUP "viewer_png;viewer_export"
        FIXTURES_REQUIRED viewer_export_clean
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1;OMP_NUM_THREADS=1")
    # A surface loaded while a pull is held (`load` in the script, as the Load panel): the grab
    # lets go, and the new surface (a level-3 grid of another mesh) stays at rest, where the
    # grab went on pulling it through the old surface's face and rest point (a read past the
    # new surface's faces; the pull landed elsewhere, up to 1,200 % of the radius). The exit
    # summary speaks of the surface shown last.
    set(_load_dir ${CMAKE_CURRENT_BINARY_DIR}/viewer-load)
    add_test(NAME cli_view_load_grid
             COMMAND sh -c "rm -rf '${_load_dir}' && mkdir -p '${_load_dir}' && exec '$<TARGET_FILE:pliant>' -q remesh '${PROJECT_SOURCE_DIR}/tests/data/meshes/cube_minus_sphere.obj' --level 3 -o '${_load_dir}/viewer-load.pgrid'")
    set_tests_properties(cli_view_load_grid PROPERTIES TIMEOUT 120 FIXTURES_SETUP viewer_load_grid
                         ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    add_test(NAME cli_view_load_during_a_drag_lets_go
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;4;--size;640x480;--script;${CMAKE_CURRENT_SOURCE_DIR}/viewer_load_during_drag.txt;--exit-after;5"
                     -DEXIT=0 "-DSTDOUT_REGEX=largest \\|u\\| reached 0\\.0000e\\+00 m"
                     "-DSTDERR_REGEX=viewer-load\\.pgrid \\(level 3 grid\\)" -DTIMEOUT=110
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_load_during_a_drag_lets_go PROPERTIES
        TIMEOUT 120
        WORKING_DIRECTORY ${_load_dir}
        FIXTURES_REQUIRED viewer_load_grid
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1;OMP_NUM_THREADS=1")
    add_test(NAME cli_view_screenshot_png
             COMMAND ${CMAKE_COMMAND} -DPNG=${_viewer_png} -DMIN_BYTES=8000
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer_check_png.cmake)
    set_tests_properties(cli_view_screenshot_png PROPERTIES FIXTURES_REQUIRED viewer_png)
    add_test(NAME cli_view_screenshots_first_free
             COMMAND ${CMAKE_COMMAND} -DDIR=${CMAKE_CURRENT_BINARY_DIR}
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer_check_screenshots.cmake)
    set_tests_properties(cli_view_screenshots_first_free PROPERTIES
                         FIXTURES_REQUIRED viewer_export)
    # `pliant demo --view`: the demo's peers on a second thread in real time, the viewer joined
    # to the master over 127.0.0.1 for 4 s after the object shows. The viewer must show the
    # object (>= 5 % of the view) deformed by the scripted grabs it received (>= 0.5 % of the
    # radius), and the demo must end and write its summary and recording after the window
    # closes (the last line), and exit 0.
    set(_demo_view_png ${CMAKE_CURRENT_BINARY_DIR}/demo-view.png)
    add_test(NAME cli_demo_view
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;demo;--quick;--view;--out;${CMAKE_CURRENT_BINARY_DIR}/demo-view;--screenshot;${_demo_view_png};--exit-after;4"
                     -DEXIT=0 "-DSTDOUT_REGEX=${_drag_regex}.*wrote .*session\\.prec"
                     -DTIMEOUT=170 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_demo_view PROPERTIES
        TIMEOUT 180
        FIXTURES_SETUP demo_view_png
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1;OMP_NUM_THREADS=1")
    # Ctrl-C in the terminal (docs/viewer.md "Ctrl-C"): once the object shows, SIGINT closes the
    # viewer as its window's close button does (the --screenshot is still written) and the
    # status is 130. With `demo --view`, the demo then ends its session and writes every output.
    set(_int_png ${CMAKE_CURRENT_BINARY_DIR}/viewer-interrupted.png)
    set(_int_env ASAN_OPTIONS=detect_leaks=0 LIBGL_ALWAYS_SOFTWARE=1 OMP_NUM_THREADS=1)
    pliant_add_interrupt_test(cli_view_interrupted XVFB LOG "remeshed at level 4"
        STDOUT_REGEX "view: screenshot .*viewer-interrupted\\.png .*covers"
        STDERR_REGEX "view: interrupted. closing" TIMEOUT 170 ENVIRONMENT ${_int_env}
        ARGS view ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4 --size 320x240
             --screenshot ${_int_png})
    pliant_add_interrupt_test(cli_demo_view_interrupted XVFB LOG "view: joined "
        STDOUT_REGEX "wrote .*demo-view-interrupted .*session\\.prec"
        STDERR_REGEX "demo: interrupted. .*demo-view-interrupted holds what ran"
        TIMEOUT 170 ENVIRONMENT ${_int_env}
        ARGS demo --quick --view --out ${CMAKE_CURRENT_BINARY_DIR}/demo-view-interrupted)
    add_test(NAME cli_demo_view_png
             COMMAND ${CMAKE_COMMAND} -DPNG=${_demo_view_png} -DMIN_BYTES=8000
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer_check_png.cmake)
    set_tests_properties(cli_demo_view_png PROPERTIES FIXTURES_REQUIRED demo_view_png)
    # --resume (docs/viewer.md): a level-3 spot grid, simulated with the spot scenario; the viewer
    # started from frame 30 (spot.toml's first pull has just ended) shows a surface displaced by
    # more than 0.5 % of its radius from its first frame, where the same grid alone starts at
    # rest (0.000 %, the drag test's runs before their drag). Refused before any window opens:
    # the state given as INPUT (it would become the rest shape), a mesh as INPUT, a rest grid of
    # another level.
    set(_resume_dir ${CMAKE_CURRENT_BINARY_DIR}/view-resume)
    add_test(NAME cli_view_resume_prepare_grid
             COMMAND pliant remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 3
                     -o ${_resume_dir}-spot3.pgrid)
    set_tests_properties(cli_view_resume_prepare_grid PROPERTIES
        TIMEOUT 120 FIXTURES_SETUP view_resume_grid)
    add_test(NAME cli_view_resume_prepare_state
             COMMAND pliant simulate ${_resume_dir}-spot3.pgrid
                     --scenario ${PROJECT_SOURCE_DIR}/scenes/spot.toml -o ${_resume_dir}-sim -j 1)
    set_tests_properties(cli_view_resume_prepare_state PROPERTIES
        TIMEOUT 120 FIXTURES_REQUIRED view_resume_grid FIXTURES_SETUP view_resume_state)
    set(_resume_state ${_resume_dir}-sim/frame_00030.pgrid)
    add_test(NAME cli_view_resume_starts_from_the_state
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;${_resume_dir}-spot3.pgrid;--resume;${_resume_state};--size;320x240;--exit-after;0.5"
                     -DEXIT=0
                     "-DSTDOUT_REGEX=largest \\|u\\| reached [0-9.e+-]+ m = ([1-9][0-9]*|0\\.[5-9][0-9]*)\\.?[0-9]* % of the object radius"
                     "-DSTDERR_REGEX=spot3.pgrid \\(level 3 grid\\), resumed from frame_00030.pgrid"
                     -DTIMEOUT=110 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_resume_starts_from_the_state PROPERTIES
        TIMEOUT 120
        FIXTURES_REQUIRED view_resume_state
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1;OMP_NUM_THREADS=1")
    # A scripted export that fails ends the run with status 3 (it exited 0); a --screenshot
    # that cannot be written is refused before any window opens (it ran the whole session and
    # then said "screenshot ... covers" for a file it never wrote).
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/view-afile "a file, not a folder\n")
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/view-bad-export.txt
         "0.2 export ${CMAKE_CURRENT_BINARY_DIR}/view-afile/x.obj\n")
    add_test(NAME cli_view_failed_scripted_export_exits_3
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;${_resume_dir}-spot3.pgrid;--size;320x240;--exit-after;0.6;--script;${CMAKE_CURRENT_BINARY_DIR}/view-bad-export.txt"
                     -DEXIT=3 "-DSTDERR_REGEX=view-afile/x.obj.*a scripted export failed"
                     -DTIMEOUT=110 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_failed_scripted_export_exits_3 PROPERTIES
        TIMEOUT 120 FIXTURES_REQUIRED view_resume_grid
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1;OMP_NUM_THREADS=1")
    add_test(NAME cli_view_screenshot_checked_first
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;view;${_resume_dir}-spot3.pgrid;--exit-after;0.5;--screenshot;${CMAKE_CURRENT_BINARY_DIR}/view-afile/s.png"
                     -DEXIT=1 "-DSTDERR_REGEX=--screenshot: cannot write .*view-afile is not a folder"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_screenshot_checked_first PROPERTIES
        FIXTURES_REQUIRED view_resume_grid ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    pliant_cli_expect(cli_view_size_with_junk 2 STDERR "--size 640x480junk is not WxH"
                      view --size 640x480junk)
    set(_resume_refusals
        state_as_input "${_resume_dir}-sim/frame_00010.pgrid" "frame_00010.pgrid holds a simulated state \\(channels u and v\\).*your state to --resume \\(`pliant view REST.pgrid --resume [^`]*frame_00030.pgrid`\\)"
        mesh_as_input "${PROJECT_SOURCE_DIR}/data/spot.obj" "--resume needs INPUT to be the rest grid \\(.pgrid\\) the state was simulated on, not .*spot.obj"
        other_level "${_resume_dir}-spot4.pgrid" "a state of level 3, but the rest grid is of level 4")
    add_test(NAME cli_view_resume_prepare_other_level
             COMMAND pliant remesh ${PROJECT_SOURCE_DIR}/data/spot.obj --level 4
                     -o ${_resume_dir}-spot4.pgrid)
    set_tests_properties(cli_view_resume_prepare_other_level PROPERTIES
        TIMEOUT 120 FIXTURES_SETUP view_resume_other_level)
    list(LENGTH _resume_refusals _n)
    math(EXPR _last "${_n} - 1")
    foreach(_i RANGE 0 ${_last} 3)
        math(EXPR _j "${_i} + 1")
        math(EXPR _k "${_i} + 2")
        list(GET _resume_refusals ${_i} _name)
        list(GET _resume_refusals ${_j} _input)
        list(GET _resume_refusals ${_k} _regex)
        add_test(NAME cli_view_resume_refuses_${_name}
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=$<TARGET_FILE:pliant>;view;${_input};--resume;${_resume_state}"
                         -DEXIT=1 "-DSTDERR_REGEX=${_regex}" -DTIMEOUT=50
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        set_tests_properties(cli_view_resume_refuses_${_name} PROPERTIES
            TIMEOUT 60
            FIXTURES_REQUIRED "view_resume_state;view_resume_other_level"
            ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endforeach()
    # A join that cannot reach its master (UDP port 9 on this machine: nothing answers) must say
    # so and, in a scripted run, exit with status 1 within ENet's connection timeout (about 5 s),
    # not wait for --exit-after's 300 s grace.
    add_test(NAME cli_view_join_unreachable
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;127.0.0.1:9;--exit-after;1"
                     -DEXIT=1
                     "-DSTDERR_REGEX=could not reach the master at 127\\.0\\.0\\.1:9: no answer"
                     -DTIMEOUT=50 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_join_unreachable PROPERTIES TIMEOUT 60
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1")
    # A session with a secret: the viewer joins it with the same key file and, without one,
    # says what is missing (viewer_secure_join.sh; about 10 s).
    add_test(NAME cli_view_joins_a_secured_session
             COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/viewer_secure_join.sh $<TARGET_FILE:pliant>
                     ${CMAKE_CURRENT_SOURCE_DIR}/with_xvfb.sh
                     ${CMAKE_CURRENT_BINARY_DIR}/view-secure)
    set_tests_properties(cli_view_joins_a_secured_session PROPERTIES TIMEOUT 150
        SKIP_RETURN_CODE 77
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1")
    # `demo --view` checks its --screenshot path before the run, as `view` does (found at the
    # end, a bad one failed the whole run and left no outputs).
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/demo-view-not-a-folder "")
    add_test(NAME cli_demo_view_bad_screenshot_path
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;demo;--quick;--view;--out;${CMAKE_CURRENT_BINARY_DIR}/demo-view-bad-shot;--screenshot;${CMAKE_CURRENT_BINARY_DIR}/demo-view-not-a-folder/s.png;--exit-after;1"
                     -DEXIT=1
                     "-DSTDERR_REGEX=demo --view: --screenshot: cannot write .*demo-view-not-a-folder is not a folder"
                     -DTIMEOUT=50 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_demo_view_bad_screenshot_path PROPERTIES TIMEOUT 60
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1")
    # An input that is neither a file nor a HOST:PORT that resolves says both (RFC 6761: names
    # under .invalid never resolve), before any window: with no display at all (a missing file
    # was reported as "no display" first).
    add_test(NAME cli_view_bad_input
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;view;no-such-host.invalid:7777;--exit-after;1"
                     -DEXIT=1
                     "-DSTDERR_REGEX=no-such-host\\.invalid:7777 is neither an existing file nor a HOST:PORT to join"
                     -DTIMEOUT=50 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    add_test(NAME cli_view_missing_file
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;view;${CMAKE_CURRENT_BINARY_DIR}/no-such.pgrid;--exit-after;1"
                     -DEXIT=1
                     "-DSTDERR_REGEX=no-such\\.pgrid is neither an existing file nor a HOST:PORT to join"
                     -DTIMEOUT=50 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_bad_input cli_view_missing_file PROPERTIES TIMEOUT 60
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;DISPLAY=;WAYLAND_DISPLAY=")
    # A script pressing a key the viewer ignores is refused before the window opens, naming the
    # file and line.
    add_test(NAME cli_view_script_unknown_key
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=${_xvfb};$<TARGET_FILE:pliant>;view;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;3;--script;${CMAKE_CURRENT_SOURCE_DIR}/viewer_bad_key.txt;--exit-after;1"
                     -DEXIT=1 "-DSTDERR_REGEX=viewer_bad_key\\.txt:4: unknown key `q`"
                     -DTIMEOUT=50 -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
    set_tests_properties(cli_view_script_unknown_key PROPERTIES TIMEOUT 60
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;LIBGL_ALWAYS_SOFTWARE=1")
    # Each export re-imports as a closed genus-0 surface (`pliant info` exits 0) with the
    # simulation level's 4W^2 = 1024 faces (level 4).
    foreach(_export IN LISTS _viewer_exports)
        get_filename_component(_ext ${_export} LAST_EXT)
        string(SUBSTRING ${_ext} 1 -1 _ext)
        add_test(NAME cli_view_export_${_ext}
                 COMMAND ${CMAKE_COMMAND} -DPLIANT=$<TARGET_FILE:pliant> -DFILE=${_export}
                         -DFACES=1024 -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer_check_export.cmake)
        set_tests_properties(cli_view_export_${_ext} PROPERTIES FIXTURES_REQUIRED viewer_export
                             ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endforeach()
elseif(TARGET pliant AND "$ENV{CI}" STREQUAL "true")
    # CI installs GLFW, Dear ImGui and Xvfb (scripts/install-deps.sh): a missing one must not
    # leave the viewer untested with the run green.
    message(FATAL_ERROR "CI: the viewer's tests need the viewer (PLIANT_HAVE_VIEWER: "
                        "'${PLIANT_HAVE_VIEWER}') and Xvfb (found: '${PLIANT_XVFB}')")
elseif(TARGET pliant)
    message(STATUS "pliant view is not tested: it needs the viewer (GLFW, Dear ImGui) and Xvfb")
endif()
# The viewer's window-free parts (picking, input scripts, the grab's spring) as unit tests.
if(TARGET pliant_render AND TARGET pliant_test_support)
    pliant_add_test(viewer_picking_test
        SOURCES viewer_picking_test.cpp viewer_grab_test.cpp
                ${PROJECT_SOURCE_DIR}/apps/pliant-cli/viewer/picking.cpp
                ${PROJECT_SOURCE_DIR}/apps/pliant-cli/viewer/input_script.cpp
                ${PROJECT_SOURCE_DIR}/apps/pliant-cli/viewer/sim_scene.cpp
        LIBS pliant::render pliant::sim pliant::subdiv pliant::core)
endif()
# Its background load: cancelling a remeshing, and quitting during one.
if(TARGET pliant_remesh AND TARGET pliant_test_support)
    pliant_add_test(viewer_load_test
        SOURCES viewer_load_test.cpp ${PROJECT_SOURCE_DIR}/apps/pliant-cli/viewer/mesh_loader.cpp
        LIBS pliant::remesh pliant::mesh pliant::core)
endif()
