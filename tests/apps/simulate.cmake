# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant simulate` end to end (docs/physics.md §7): the sample scenario on the built-in sphere
# writes every frame and the energy table, and its finger slides over the surface (no vertex is
# ever out of its reach: the chord it used to follow passed 0.29 m below the surface); a point
# force out of every vertex's reach is warned about, naming the file, line and distance; a
# misspelt key or an unknown force hold is refused, naming the file, line and key.
if(TARGET pliant)
    set(sim_out ${CMAKE_CURRENT_BINARY_DIR}/simulate-pull)
    add_test(NAME cli_simulate_pull
             COMMAND pliant simulate --scenario ${PROJECT_SOURCE_DIR}/scenes/pull.toml
                     -o ${sim_out} --level 4 -j 1)
    set_tests_properties(cli_simulate_pull PROPERTIES
        TIMEOUT 120
        PASS_REGULAR_EXPRESSION "101 frames, 4.000 s simulated"
        FAIL_REGULAR_EXPRESSION "beyond its radius;error")
    add_test(NAME cli_simulate_pull_outputs
             COMMAND ${CMAKE_COMMAND} -DDIR=${sim_out}
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/check_simulate_outputs.cmake)
    set_tests_properties(cli_simulate_pull_outputs PROPERTIES DEPENDS cli_simulate_pull)

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
endif()
