# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# cmake -DDIR=folder -DFILES=a;b;... -P viewer_prepare.cmake: the scripted viewer run's clean
# start in its working folder DIR: removes FILES (exports and screenshots of an earlier run) and
# writes a stand-in for an earlier screenshot, pliant-view-0000.png, which the run's P and F12
# presses must not overwrite (viewer_check_screenshots.cmake).
foreach(f IN LISTS FILES)
    file(REMOVE "${DIR}/${f}")
endforeach()
file(WRITE "${DIR}/pliant-view-0000.png" "an earlier screenshot\n")
