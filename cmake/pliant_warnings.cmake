# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Warnings per target (STYLE.md §12); CI presets turn them into errors with
# CMAKE_COMPILE_WARNING_AS_ERROR.
function(pliant_set_warnings target)
    target_compile_options(${target} PRIVATE
        -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion
        -Wmissing-declarations)
endfunction()
