# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Warnings per target (docs/style.md §12); CI presets turn them into errors with
# CMAKE_COMPILE_WARNING_AS_ERROR.
function(pliant_set_warnings target)
    target_compile_options(${target} PRIVATE
        -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion
        -Wmissing-declarations
        # GCC 12 at -O3 reports std::string copies as overlapping memcpy (GCC bug 105329) and,
        # with -march=native on AVX-512 machines, std::vector::resize of small structs as writes
        # past the allocation (-Wstringop-overflow / -overread / -Warray-bounds: GCC bugs 106199,
        # 105651, 107852), all false positives inside libstdc++'s inlined code. The warnings are
        # kept for other compilers; the ASan+UBSan leg checks the real bounds at run time.
        "$<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict;-Wno-stringop-overflow;-Wno-stringop-overread;-Wno-array-bounds>")
endfunction()
