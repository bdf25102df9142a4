#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
"""closed_pipe.py EXIT FILE COMMAND...: runs COMMAND with stdout and stderr on a pipe whose read
end is closed before it starts (as `pliant ... 2>&1 | head -1` once head has gone), with SIGPIPE
at its default action, as a shell gives it. Passes if COMMAND exits with status EXIT (not killed
by SIGPIPE) and FILE, removed first, exists after it: the work ran to its end."""
import os
import subprocess
import sys

expect, path, command = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
if os.path.exists(path):
    os.remove(path)
read_end, write_end = os.pipe()
os.close(read_end)
# restore_signals (the default) gives the child SIGPIPE's default action back.
done = subprocess.run(command, stdin=subprocess.DEVNULL, stdout=write_end, stderr=write_end,
                      timeout=300, check=False)
os.close(write_end)
if done.returncode != expect:
    sys.exit(f"expected exit {expect}, got {done.returncode} (negative: killed by that signal)")
if not os.path.exists(path):
    sys.exit(f"{path} was not written")
print(f"exit {done.returncode}, {path} written")
