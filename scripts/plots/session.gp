# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# session.png: per-peer compute against the number of peers, with and without partitioning
# (`pliant bench session`).
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 1200,480 font ",10" noenhanced
set output outdir."/session.png"
f = datadir."/session.csv"
stats f every ::1 using 3 nooutput
lmin = int(STATS_min)
lmax = int(STATS_max)
sel(c, m, l) = (strcol(2) eq c && strcol(6) eq m && int($3) == l)
set multiplot layout 1,2 title "Distributed simulation (simulated network, 1 thread per peer): compute per peer"
set grid
set xlabel "peers"
set xrange [0.8:4.2]
set xtics 1
set logscale y
set ylabel "seconds in steps per simulated second (busiest peer, wall)"
set key top right font ",9"
plot for [L=lmin:lmax] f every ::1 using (sel("exact","step_s_per_sim_s_max",L) ? $4 : NaN):7 w lp pt 7 lc (L-4) t sprintf("exact, level %d", L), \
     for [L=lmin:lmax] f every ::1 using (sel("fast","step_s_per_sim_s_max",L) ? $4 : NaN):7 w lp pt 5 dt 2 lc (L-4) t sprintf("fast, level %d", L), \
     for [L=lmin:lmax] f every ::1 using (sel("no partitioning","step_s_per_sim_s_max",L) ? $4 : NaN):7 w l dt 3 lw 2 lc (L-4) t sprintf("no partitioning, level %d", L)
unset logscale y
set yrange [0:*]
set ylabel "busiest peer's compute / one process stepping all nodes"
set arrow 1 from 1.9, 0.55 to 2.1, 0.55 nohead lw 3 lc rgb "red"
set label 1 "paper: -45 % (x1.8)" at 2.12, 0.55 tc rgb "red"
set arrow 2 from 3.9, 0.30 to 4.1, 0.30 nohead lw 3 lc rgb "dark-green"
set label 2 "target 4 peers" at 3.4, 0.25 tc rgb "dark-green"
plot for [L=lmin:lmax] f every ::1 using (sel("exact","compute_vs_single_max",L) ? $4 : NaN):7 w lp pt 7 lc (L-4) t sprintf("exact, level %d", L), \
     for [L=lmin:lmax] f every ::1 using (sel("fast","compute_vs_single_max",L) ? $4 : NaN):7 w lp pt 5 dt 2 lc (L-4) t sprintf("fast, level %d", L), \
     1/x w l dt 3 lc rgb "black" t "ideal 1/peers", \
     1 w l lc rgb "gray" t "no partitioning"
unset multiplot
