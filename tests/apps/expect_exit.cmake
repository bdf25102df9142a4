# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs COMMAND (a ;-list) and passes only if it exits with status EXIT and its output matches:
# STDOUT_REGEX against stdout, STDERR_REGEX against stderr (each optional). A program's --help
# (usage on stdout, exit 0), its argument errors (message on stderr, exit 2), and runs whose
# output and clean exit both matter (the viewer's tests: PASS_REGULAR_EXPRESSION alone ignores
# the exit status). TIMEOUT (s, optional) stops COMMAND itself, so a hung program fails here
# rather than being left behind when ctest stops this script. KEEP (a ;-list of paths,
# optional): files written before COMMAND runs that must be there, unchanged, after it (an
# earlier run's outputs that a refused run must not touch). ABSENT (a ;-list of paths,
# optional): files that must not exist after it (removed before it runs). STALE (a ;-list of
# paths, optional): files written before COMMAND runs, as KEEP's, that must not be there as they
# were after it (removed or replaced: an earlier run's outputs that a run clears). LINKS (a
# ;-list of LINK=TARGET, optional): symbolic links made before COMMAND runs, replacing what was
# at LINK (an output that is /dev/full). EMPTY_DIR (a folder, optional): emptied before
# COMMAND runs, and must hold nothing after it, hidden files included (no temporary left).
foreach(f IN LISTS KEEP STALE)
    get_filename_component(d "${f}" DIRECTORY)
    file(MAKE_DIRECTORY "${d}")
    file(WRITE "${f}" "an earlier run's file\n")
endforeach()
foreach(l IN LISTS LINKS)
    string(REPLACE "=" ";" l "${l}")
    list(GET l 0 link)
    list(GET l 1 target)
    get_filename_component(d "${link}" DIRECTORY)
    file(MAKE_DIRECTORY "${d}")
    file(REMOVE "${link}")
    file(CREATE_LINK "${target}" "${link}" SYMBOLIC)
endforeach()
foreach(f IN LISTS ABSENT)
    file(REMOVE "${f}")
endforeach()
if(DEFINED EMPTY_DIR)
    file(REMOVE_RECURSE "${EMPTY_DIR}")
    file(MAKE_DIRECTORY "${EMPTY_DIR}")
endif()
set(timeout_args)
if(DEFINED TIMEOUT)
    set(timeout_args TIMEOUT ${TIMEOUT})
endif()
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                ${timeout_args})
if(NOT "${rc}" STREQUAL "${EXIT}")
    message(FATAL_ERROR "expected exit ${EXIT}, got ${rc}:\n${out}${err}")
endif()
if(DEFINED STDOUT_REGEX AND NOT "${out}" MATCHES "${STDOUT_REGEX}")
    message(FATAL_ERROR "stdout does not match '${STDOUT_REGEX}':\n${out}\nstderr:\n${err}")
endif()
if(DEFINED STDERR_REGEX AND NOT "${err}" MATCHES "${STDERR_REGEX}")
    message(FATAL_ERROR "stderr does not match '${STDERR_REGEX}':\n${err}\nstdout:\n${out}")
endif()
foreach(f IN LISTS KEEP)
    if(NOT EXISTS "${f}")
        message(FATAL_ERROR "${f} was removed:\n${out}${err}")
    endif()
    file(READ "${f}" kept)
    if(NOT kept STREQUAL "an earlier run's file\n")
        message(FATAL_ERROR "${f} was overwritten:\n${out}${err}")
    endif()
endforeach()
foreach(f IN LISTS ABSENT)
    if(EXISTS "${f}")
        message(FATAL_ERROR "${f} was left behind:\n${out}${err}")
    endif()
endforeach()
foreach(f IN LISTS STALE)
    if(EXISTS "${f}")
        file(READ "${f}" kept)
        if(kept STREQUAL "an earlier run's file\n")
            message(FATAL_ERROR "${f} was left as it was:\n${out}${err}")
        endif()
    endif()
endforeach()
if(DEFINED EMPTY_DIR)
    file(GLOB left LIST_DIRECTORIES true "${EMPTY_DIR}/*" "${EMPTY_DIR}/.*")
    if(left)
        message(FATAL_ERROR "${EMPTY_DIR} holds ${left}:\n${out}${err}")
    endif()
endif()
message("${out}${err}")
