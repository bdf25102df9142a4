# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DDIR=folder -P fresh_dir.cmake: removes DIR with everything in it and makes it again,
# empty (a setup test's clean start: no files left from an earlier run).
file(REMOVE_RECURSE "${DIR}")
file(MAKE_DIRECTORY "${DIR}")
