# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# render.png: frames per second at 1280x720 against triangles (`pliant bench render`).
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 800,520 font ",10" noenhanced
set output outdir."/render.png"
f = datadir."/render.csv"
sel(c, m) = (strcol(2) eq c && strcol(6) eq m)
set title "Phong rendering offscreen at 1280x720"
set grid
set logscale xy
set xlabel "triangles"
set ylabel "frames per second"
set key top right
set label 1 "paper: 100K polygons at 25 fps" at first 100000, first 25 point pt 9 ps 2 lc rgb "red" offset 1,1 tc rgb "red"
plot f every ::1 using (sel("texture path","fps") ? $4 : NaN):7 w lp pt 7 lc 1 t "texture path (positions in a float texture)", \
     f every ::1 using (sel("texture path + upload","fps") ? $4 : NaN):7 w lp pt 5 lc 2 t "texture path + upload every frame", \
     f every ::1 using (sel("vertex-buffer path","fps") ? $4 : NaN):7 w lp pt 6 lc 3 t "vertex-buffer path (static buffers)"
