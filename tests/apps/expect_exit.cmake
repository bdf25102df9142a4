# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs COMMAND (a ;-list) and passes only if it exits with status EXIT and its output matches:
# STDOUT_REGEX against stdout, STDERR_REGEX against stderr (each optional). A program's --help
# (usage on stdout, exit 0) and its argument errors (message on stderr, exit 2) both.
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT "${rc}" STREQUAL "${EXIT}")
    message(FATAL_ERROR "expected exit ${EXIT}, got ${rc}:\n${out}${err}")
endif()
if(DEFINED STDOUT_REGEX AND NOT "${out}" MATCHES "${STDOUT_REGEX}")
    message(FATAL_ERROR "stdout does not match '${STDOUT_REGEX}':\n${out}\nstderr:\n${err}")
endif()
if(DEFINED STDERR_REGEX AND NOT "${err}" MATCHES "${STDERR_REGEX}")
    message(FATAL_ERROR "stderr does not match '${STDERR_REGEX}':\n${err}\nstdout:\n${out}")
endif()
