# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# subdiv.png: butterfly refinement throughput against the output level (`pliant bench subdiv`).
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 800,520 font ",10" noenhanced
set output outdir."/subdiv.png"
f = datadir."/subdiv.csv"
sel(c, m) = (strcol(2) eq c && strcol(6) eq m)
set title "Modified butterfly refinement n -> n+1 (positions, 3 planes)"
set grid
set logscale y
set xlabel "output level"
set xtics 1
set ylabel "million output vertices per second"
set key top right
set yrange [*:1e4]
plot f every ::1 using (sel("refine float 1 thread","output_vertices_per_s") ? $3 : NaN):($7/1e6) w lp pt 7 lc 1 t "pliant, float, 1 thread", \
     f every ::1 using (sel("refine float 2 threads","output_vertices_per_s") ? $3 : NaN):($7/1e6) w lp pt 5 lc 2 t "pliant, float, 2 threads", \
     f every ::1 using (sel("refine double 1 thread","output_vertices_per_s") ? $3 : NaN):($7/1e6) w lp pt 6 lc 3 t "pliant, double, 1 thread", \
     f every ::1 using (sel("OpenMesh ModifiedButterflyT","output_vertices_per_s") ? $3 : NaN):($7/1e6) w lp pt 9 lc 4 t "OpenMesh ModifiedButterflyT"
