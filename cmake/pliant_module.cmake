# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# pliant_add_module(NAME SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# One static library per module, aliased pliant::NAME; PUBLIC_DEPS lists exactly the modules
# docs/style.md §2 allows (scripts/check_includes.py checks the includes). Installed with the
# export set pliant-NAME-targets as pliant::NAME (docs/library.md; the package:
# cmake/pliantConfig.cmake.in loads the sets of the components asked for).
function(pliant_add_module name)
    cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
    add_library(pliant_${name} STATIC ${ARG_SOURCES})
    add_library(pliant::${name} ALIAS pliant_${name})
    target_include_directories(pliant_${name}
        PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
               $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
        PRIVATE ${PROJECT_SOURCE_DIR}/src)
    target_compile_features(pliant_${name} PUBLIC cxx_std_20)
    target_link_libraries(pliant_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    pliant_set_warnings(pliant_${name})
    # Reproducible floating point across builds and peers (docs/style.md §7): no FMA contraction,
    # never -ffast-math.
    target_compile_options(pliant_${name} PRIVATE -ffp-contract=off)
    # A library built with sanitizers needs their runtimes in whatever links it.
    if(PLIANT_SANITIZE)
        string(REPLACE "," "$<COMMA>" _sanitize "${PLIANT_SANITIZE}")
        target_link_options(pliant_${name} INTERFACE
            $<INSTALL_INTERFACE:-fsanitize=${_sanitize}>)
    endif()
    set_target_properties(pliant_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME pliant_${name})
    install(TARGETS pliant_${name} EXPORT pliant-${name}-targets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
endfunction()
