# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Warnings per target (STYLE.md §12); CI presets turn them into errors with
# CMAKE_COMPILE_WARNING_AS_ERROR.
function(pliant_set_warnings target)
    target_compile_options(${target} PRIVATE
        -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion
        -Wmissing-declarations
        # GCC 12 at -O3 reports std::string copies as overlapping memcpy (GCC bug 105329, a
        # false positive inside libstdc++); the warning is kept for other compilers.
        $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>)
endfunction()
