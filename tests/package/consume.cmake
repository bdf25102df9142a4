# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Installs the library from BUILD_DIR into WORK/prefix (the `development` component: headers,
# static libraries, the CMake package) and checks, as a user of the library would meet them:
#   1. the installed tree: every public header, each module's library, the package files, and
#      nothing from src/;
#   2. examples/pull configured, built and run against it (find_package with components
#      mesh remesh subdiv sim): a remeshed, pulled and refined spot of the expected size;
#   3. a program linking pliant::session alone (its modules come with it: sim, subdiv, net,
#      whose ENet, libsodium and zstd the package finds again; mesh, remesh and render do not);
#   3b. examples/two_peers built and run against it: a session of two peers in one process;
#   4. refusals: a component that does not exist and a version the package does not satisfy,
#      each with the package's message.
set(prefix "${WORK}/prefix")
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

function(run what)
    execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                    TIMEOUT 300)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "${what} failed (${rc}):\n${out}${err}")
    endif()
    set(run_out "${out}${err}" PARENT_SCOPE)
endfunction()

# Configures (and, with BUILD, builds) project SRC in WORK/NAME against the installed package.
function(consumer name src)
    cmake_parse_arguments(A "BUILD;FAIL" "" "DEFS" ${ARGN})
    set(bin "${WORK}/${name}")
    execute_process(COMMAND ${CMAKE_COMMAND} -S "${src}" -B "${bin}" -G "${GENERATOR}"
                            "-DCMAKE_CXX_COMPILER=${CXX}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
                            "-DCMAKE_PREFIX_PATH=${prefix}" ${A_DEFS}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
    set(consumer_out "${out}${err}" PARENT_SCOPE)
    if(A_FAIL)
        if(rc EQUAL 0)
            message(FATAL_ERROR "configuring ${name} should have failed:\n${out}${err}")
        endif()
        return()
    endif()
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "configuring ${name} failed (${rc}):\n${out}${err}")
    endif()
    if(A_BUILD)
        run("building ${name}" ${CMAKE_COMMAND} --build "${bin}")
    endif()
endfunction()

# 1. Install and look at the tree.
run("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}"
    --component development)
get_filename_component(source_dir "${EXAMPLE}/../.." ABSOLUTE)
file(GLOB_RECURSE public RELATIVE "${source_dir}/include" "${source_dir}/include/*.h")
file(GLOB_RECURSE installed RELATIVE "${prefix}/include" "${prefix}/include/*")
list(SORT public)
list(SORT installed)
if(NOT public STREQUAL installed)
    message(FATAL_ERROR "installed headers differ from include/:\n${installed}\nagainst\n${public}")
endif()
foreach(module core mesh remesh subdiv sim net session render)
    if(NOT EXISTS "${prefix}/lib/libpliant_${module}.a")
        message(FATAL_ERROR "lib/libpliant_${module}.a was not installed")
    endif()
endforeach()
foreach(f pliantConfig.cmake pliantConfigVersion.cmake pliant-core-targets.cmake
          pliant-session-targets.cmake pliant-render-targets.cmake)
    if(NOT EXISTS "${prefix}/lib/cmake/pliant/${f}")
        message(FATAL_ERROR "lib/cmake/pliant/${f} was not installed")
    endif()
endforeach()
file(GLOB_RECURSE stray "${prefix}/*.cpp" "${prefix}/*.glsl")
if(stray)
    message(FATAL_ERROR "sources were installed: ${stray}")
endif()

# 2. The example: remesh spot at level 4, pull it, refine to level 5 (2 * 32^2 + 2 vertices).
consumer(pull "${EXAMPLE}" BUILD)
run("pull" "${WORK}/pull/pull" "${MESH}" "${WORK}/pulled.obj" 4)
foreach(expected "-> level 4, 514 vertices" "largest displacement [0-9]"
                 "pulled.obj: 2050 vertices, 4096 faces \\(level 5\\)")
    if(NOT run_out MATCHES "${expected}")
        message(FATAL_ERROR "pull's output lacks '${expected}':\n${run_out}")
    endif()
endforeach()
if(run_out MATCHES "largest displacement 0 m")
    message(FATAL_ERROR "the pull moved nothing:\n${run_out}")
endif()
file(STRINGS "${WORK}/pulled.obj" header LIMIT_COUNT 1)
if(NOT header STREQUAL "# pliant: 2050 vertices, 4096 faces")
    message(FATAL_ERROR "pulled.obj begins '${header}'")
endif()

# 3. pliant::session alone.
consumer(session_link "${TESTS}/session_link" BUILD)
run("session_link" "${WORK}/session_link/session_link")
if(NOT run_out MATCHES "session, sim, subdiv and net linked")
    message(FATAL_ERROR "session_link printed:\n${run_out}")
endif()

# 3b. examples/two_peers (find_package with COMPONENTS session): two peers over the simulated
# network end with equal displays, equal to the replay of the master's recording.
consumer(two_peers "${EXAMPLE}/../two_peers" BUILD)
run("two_peers" "${WORK}/two_peers/two_peers" 3)
if(NOT run_out MATCHES "the peers' displays differ by 0, the replay of the master's recording by 0\n")
    message(FATAL_ERROR "two_peers printed:\n${run_out}")
endif()

# 4. Refusals.
consumer(bad_component "${TESTS}/bad_component" FAIL DEFS -DWANT=COMPONENTS -DWHAT=physics)
# (CMake wraps the package's message at about 80 columns.)
if(NOT consumer_out MATCHES "pliant has no component 'physics'. its components are its modules:[ \n]+core[ \n]+mesh[ \n]+remesh")
    message(FATAL_ERROR "a bad component's message:\n${consumer_out}")
endif()
string(REGEX MATCH "^([0-9]+)\\.([0-9]+)" _ "${VERSION}")
math(EXPR next_minor "${CMAKE_MATCH_2} + 1")
set(newer "${CMAKE_MATCH_1}.${next_minor}")
consumer(bad_version "${TESTS}/bad_component" FAIL DEFS "-DWANT=${newer}" -DWHAT=core)
if(NOT consumer_out MATCHES "compatible[ \n]+with requested version \"${newer}\"")
    message(FATAL_ERROR "a newer version's message:\n${consumer_out}")
endif()
message(STATUS "package: installed, examples built and run, session linked, refusals checked")
