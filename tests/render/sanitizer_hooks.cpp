// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// LeakSanitizer settings for the render tests (read only by sanitizer builds). Mesa keeps small
// allocations until exit that it never frees (llvmpipe's JIT shader variants, made on its
// rasterizer threads, and OSMesa's per-thread state): 100-1600 bytes per run. Mesa is built
// without frame pointers, so their stacks stop inside Mesa's JIT code and no suppression can
// match them, and the slow unwinder hangs in that code. Leak checking is therefore off for this
// binary only; ASan's and UBSan's other checks stay on. pliant's GL objects are RAII-owned.

extern "C" const char* __lsan_default_options();

extern "C" const char* __lsan_default_options()
{
    return "detect_leaks=0";
}
