# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DDIR=folder -P viewer_check_screenshots.cmake: after the scripted viewer run (P at
# 1.4 s, F12 at 2.0 s, viewer_drag.txt) the earlier pliant-view-0000.png is untouched and the two
# screenshots took the next free names, pliant-view-0001.png and pliant-view-0002.png.
file(READ "${DIR}/pliant-view-0000.png" earlier)
if(NOT earlier STREQUAL "an earlier screenshot\n")
    message(FATAL_ERROR "${DIR}/pliant-view-0000.png was overwritten")
endif()
foreach(n 0001 0002)
    set(png "${DIR}/pliant-view-${n}.png")
    if(NOT EXISTS "${png}")
        message(FATAL_ERROR "no screenshot ${png}")
    endif()
    file(READ "${png}" signature LIMIT 8 HEX)
    if(NOT signature STREQUAL "89504e470d0a1a0a")
        message(FATAL_ERROR "${png} is not a PNG (starts with ${signature})")
    endif()
endforeach()
if(EXISTS "${DIR}/pliant-view-0003.png")
    message(FATAL_ERROR "${DIR}/pliant-view-0003.png: more screenshots than key presses")
endif()
