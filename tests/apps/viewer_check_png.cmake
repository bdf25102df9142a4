# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DPNG=file.png -DMIN_BYTES=N -P viewer_check_png.cmake: the viewer's screenshot exists,
# is a PNG (signature) and is larger than MIN_BYTES (a blank or failed read-back compresses to
# a few hundred bytes).
if(NOT EXISTS "${PNG}")
    message(FATAL_ERROR "no screenshot at ${PNG}")
endif()
file(READ "${PNG}" signature LIMIT 8 HEX)
if(NOT signature STREQUAL "89504e470d0a1a0a")
    message(FATAL_ERROR "${PNG} is not a PNG (starts with ${signature})")
endif()
file(SIZE "${PNG}" bytes)
if(bytes LESS MIN_BYTES)
    message(FATAL_ERROR "${PNG} has ${bytes} bytes, expected at least ${MIN_BYTES}")
endif()
message(STATUS "${PNG}: ${bytes} bytes")
