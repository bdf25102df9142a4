# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Runs COMMAND (a ;-list) and passes only if it exits non-zero and its output (stdout and stderr)
# matches REGEX: a refusal must both fail and say why.
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
    message(FATAL_ERROR "expected a non-zero exit, got 0:\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "${REGEX}")
    message(FATAL_ERROR "exit ${rc}, but the output does not match '${REGEX}':\n${out}${err}")
endif()
