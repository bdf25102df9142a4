# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# What `pliant simulate` records in DIR/run.json (docs/physics.md §7, "Output"): the result's STATUS and
# FRAMES written, the level and the precision in effect, and no temporary file left beside it.
# Without FRAMES (an interrupted run), the frames written must be those in DIR (frame_*.pgrid)
# and the rows of energy.csv, at least one and fewer than the run's frames.
file(READ ${DIR}/run.json json)
string(JSON status GET "${json}" result status)
string(JSON frames GET "${json}" result frames_written)
string(JSON level GET "${json}" level)
string(JSON precision GET "${json}" integrator precision)
string(JSON program GET "${json}" program)
if(NOT program STREQUAL "pliant simulate")
    message(FATAL_ERROR "run.json: program '${program}'")
endif()
if(NOT status STREQUAL "${STATUS}")
    message(FATAL_ERROR "run.json: status '${status}', expected '${STATUS}'")
endif()
if(DEFINED FRAMES)
    if(NOT frames EQUAL FRAMES)
        message(FATAL_ERROR "run.json: ${frames} frames written, expected ${FRAMES}")
    endif()
else()
    string(JSON planned GET "${json}" frames)
    file(GLOB frame_files ${DIR}/frame_*.pgrid)
    list(LENGTH frame_files on_disk)
    file(STRINGS ${DIR}/energy.csv rows)
    list(LENGTH rows row_count)
    math(EXPR row_count "${row_count} - 1")  # the header
    if(frames LESS 1 OR NOT frames LESS planned OR NOT frames EQUAL on_disk
       OR NOT frames EQUAL row_count)
        message(FATAL_ERROR "run.json: ${frames} frames written of ${planned}; ${DIR} holds "
                            "${on_disk} frames and energy.csv ${row_count} rows")
    endif()
endif()
if(NOT level EQUAL LEVEL)
    message(FATAL_ERROR "run.json: level ${level}, expected ${LEVEL}")
endif()
if(NOT precision STREQUAL "${PRECISION}")
    message(FATAL_ERROR "run.json: precision '${precision}', expected '${PRECISION}'")
endif()
if(EXISTS ${DIR}/run.json.tmp)
    message(FATAL_ERROR "run.json.tmp left in ${DIR}")
endif()
