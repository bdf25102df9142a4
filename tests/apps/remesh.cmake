# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant remesh` options end to end: --gpu samples on the gnomonic domain map only, so asking for
# it together with --domain-map equal-area is refused before any OpenGL context is made.
if(TARGET pliant)
    add_test(NAME cli_remesh_gpu_refuses_equal_area
             COMMAND ${CMAKE_COMMAND}
                     "-DCOMMAND=$<TARGET_FILE:pliant>;remesh;${PROJECT_SOURCE_DIR}/data/spot.obj;--level;3;-o;${CMAKE_CURRENT_BINARY_DIR}/remesh-refused.pgrid;--gpu;--domain-map;equal-area"
                     "-DREGEX=--gpu samples on the gnomonic domain map only"
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_failure.cmake)
    set_tests_properties(cli_remesh_gpu_refuses_equal_area PROPERTIES TIMEOUT 60)
endif()
