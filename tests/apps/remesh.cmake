# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant remesh --gpu` end to end, on an offscreen OpenGL context (Mesa's llvmpipe here): on the
# default equal-area domain map the GPU locates and the CPU interpolates ("gpu-located"); on the
# gnomonic map it is the paper's colour look-up ("gpu"). The report printed names the sampler.
# That the samples equal the CPU sampler's is tested in tests/render/gpu_sampler_test.cpp.
if(TARGET pliant)
    foreach(map equal-area gnomonic)
        if(map STREQUAL "gnomonic")
            set(sampler "gpu")
        else()
            set(sampler "gpu-located")
        endif()
        add_test(NAME cli_remesh_gpu_${map}
                 COMMAND ${CMAKE_COMMAND}
                         "-DCOMMAND=$<TARGET_FILE:pliant>;remesh;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;4;-o;${CMAKE_CURRENT_BINARY_DIR}/remesh-gpu-${map}.pgrid;--gpu;--domain-map;${map}"
                         -DEXIT=0
                         "-DSTDOUT_REGEX=sampler: ${sampler}\n"
                         -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
        # Mesa keeps allocations alive until exit, which LeakSanitizer would report.
        set_tests_properties(cli_remesh_gpu_${map} PROPERTIES
            TIMEOUT 120
            ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0")
    endforeach()
endif()
# Ctrl-C during a long untangling (fox at level 7 untangles for many seconds): `remesh` stops
# within its next progress report, says where, exits with status 130 and writes nothing; an
# earlier file at the output path is left as it was.
if(TARGET pliant)
    set(_int_pgrid ${CMAKE_CURRENT_BINARY_DIR}/remesh-interrupted/fox7.pgrid)
    pliant_add_interrupt_test(cli_remesh_interrupted LOG "^untangle: "
        STDERR_REGEX "remesh: cancelled during untangle. nothing written"
        KEEP ${_int_pgrid} ENVIRONMENT "OMP_NUM_THREADS=1"
        ARGS remesh ${PROJECT_SOURCE_DIR}/tests/data/meshes/fox.ply --level 7 -o ${_int_pgrid})
endif()
