# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DPLIANT=exe -DFILE=surface -DFACES=N -P viewer_check_export.cmake: a surface the viewer
# exported exists, re-imports with `pliant info --json` as a valid closed genus-0 mesh (exit 0)
# and has N faces.
if(NOT EXISTS "${FILE}")
    message(FATAL_ERROR "no exported surface at ${FILE}")
endif()
execute_process(COMMAND "${PLIANT}" info "${FILE}" --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pliant info ${FILE} exited ${rc}:\n${out}\n${err}")
endif()
string(JSON faces GET "${out}" faces)
string(JSON genus GET "${out}" genus)
if(NOT faces EQUAL FACES OR NOT genus EQUAL 0)
    message(FATAL_ERROR "${FILE}: ${faces} faces (expected ${FACES}), genus ${genus}")
endif()
message(STATUS "${FILE}: ${faces} faces, genus ${genus}")
