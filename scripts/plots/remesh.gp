# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# remesh.png: PSNR against the grid level per mesh (`pliant bench remesh`), with the issue's
# level-7 bounds (mean of the reference's two PSNRs minus 3 dB).
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 800,520 font ",10" noenhanced
set output outdir."/remesh.png"
f = datadir."/remesh.csv"
if (!exists("quick")) quick = 0
# The issue's bound per mesh, in the same order (a quick run has the first three meshes).
meshes = quick ? "spot blub cube_minus_sphere" : "spot blub cube_minus_sphere cactus fox"
bounds = "71.45 71.95 73.10 71.65 66.80"
sel(c, m) = (strcol(2) eq c && strcol(6) eq m)
set title "Remeshing quality: PSNR = 20 log10(bbox diagonal / two-sided RMS distance)"
set grid
set xlabel "grid level (vertices 2*4^level + 2)"
set ylabel "PSNR (dB)"
set xtics 1
set xrange [3.8:7.4]
set key bottom right
plot for [i=1:words(meshes)] f every ::1 using (sel(word(meshes,i),"psnr_db") ? $3 : NaN):7 w lp pt 7 lc i t word(meshes,i), \
     for [i=1:words(meshes)] '+' using (7.08 + 0.04*i):(word(bounds,i)+0):(0) every ::0::0 w p pt 2 ps 1.5 lc i notitle, \
     NaN w p pt 2 ps 1.5 lc rgb "black" t "issue 3 bound at level 7 (x, per mesh colour)"
