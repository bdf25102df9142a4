# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# PLIANT_SANITIZE=address,undefined (or thread) instruments everything built here.
if(PLIANT_SANITIZE)
    set(_flags -fsanitize=${PLIANT_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
    if(PLIANT_SANITIZE MATCHES "undefined")
        list(APPEND _flags -fsanitize=float-divide-by-zero)
    endif()
    add_compile_options(${_flags})
    add_link_options(${_flags})
    # GCC documents that -fsanitize=address makes -Wmaybe-uninitialized report false positives
    # (it fires inside OpenMesh's and libstdc++'s headers here); the release build keeps it.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
        add_compile_options(-Wno-maybe-uninitialized)
    endif()
    message(STATUS "pliant: sanitizers ${PLIANT_SANITIZE}")
endif()
if(PLIANT_NATIVE)
    add_compile_options(-march=native)
    add_compile_definitions(PLIANT_NATIVE_ISA=1)
    message(STATUS "pliant: compiling for this machine's instruction set (-march=native)")
endif()
if(PLIANT_PROFILE)
    add_compile_definitions(PLIANT_PROFILE=1)
endif()
