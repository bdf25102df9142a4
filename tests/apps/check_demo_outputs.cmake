# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Checks what `pliant demo --quick` left in DIR: the grid, 12 frames, the CSV, the recording
# and the summary.
foreach(f grid.pgrid summary.md timeline.csv session.prec remesh-report.json frame_0001.png frame_0012.png)
    if(NOT EXISTS ${DIR}/${f})
        message(FATAL_ERROR "pliant demo --quick did not write ${DIR}/${f}")
    endif()
endforeach()
file(GLOB frames ${DIR}/frame_*.png)
list(LENGTH frames n)
if(NOT n EQUAL 12)
    message(FATAL_ERROR "expected 12 frames in ${DIR}, found ${n}")
endif()
file(READ ${DIR}/timeline.csv csv)
string(REGEX MATCHALL "\n" lines "${csv}")
list(LENGTH lines rows)
if(NOT rows EQUAL 13)
    message(FATAL_ERROR "timeline.csv has ${rows} lines, expected a header and 12 rows")
endif()
