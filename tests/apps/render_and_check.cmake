# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DCOMMAND=a;b;... [-DSTDOUT_REGEX=...] -DPNG_CHECK=path [-DCHECK1=c,d,...] ...
#       [-DCHECK4=...] -P this:
# runs COMMAND (a `pliant render`), which must exit 0 with stdout matching STDOUT_REGEX, then
# PNG_CHECK (pliant_png_check) with the arguments of each CHECKn given (comma-separated, a picture
# the render wrote first), which must exit 0 too. Every run is bounded by TIMEOUT seconds
# (default 120).
if(NOT DEFINED TIMEOUT)
    set(TIMEOUT 120)
endif()
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                TIMEOUT ${TIMEOUT})
if(NOT "${rc}" STREQUAL "0")
    message(FATAL_ERROR "expected exit 0, got ${rc}:\n${out}${err}")
endif()
if(DEFINED STDOUT_REGEX AND NOT "${out}" MATCHES "${STDOUT_REGEX}")
    message(FATAL_ERROR "stdout does not match '${STDOUT_REGEX}':\n${out}\nstderr:\n${err}")
endif()
message("${out}${err}")
foreach(n 1 2 3 4)
    if(DEFINED CHECK${n})
        string(REPLACE "," ";" check_args "${CHECK${n}}")
        execute_process(COMMAND ${PNG_CHECK} ${check_args} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                        ERROR_VARIABLE err TIMEOUT ${TIMEOUT})
        message("${out}${err}")
        if(NOT "${rc}" STREQUAL "0")
            message(FATAL_ERROR "check ${n} failed (exit ${rc})")
        endif()
    endif()
endforeach()
