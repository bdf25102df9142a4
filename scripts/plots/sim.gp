# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# sim.png: membrane step time and CPU share against grid nodes (`pliant bench sim`).
# gnuplot -e "datadir='bench-results'; outdir='bench-results'" scripts/plots/sim.gp
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 1200,480 font ",10" noenhanced
set output outdir."/sim.png"
f = datadir."/sim.csv"
sel(c, m) = (strcol(2) eq c && strcol(6) eq m)
set multiplot layout 1,2 title "Membrane simulation (RKF45, double): step time and CPU share"
set logscale x
set grid
set xlabel "grid nodes"
set ylabel "ns per node-step"
set y2label "ms per step"
set logscale y
set logscale y2
set yrange [*:*]
set ytics nomirror
set y2tics
set key bottom right font ",9"
plot f every ::1 using (sel("1 thread","ns_per_node_step") ? $4 : NaN):7 w lp pt 7 lc 1 t "wall ns/node-step, 1 thread", \
     f every ::1 using (sel("1 thread","cpu_ns_per_node_step") ? $4 : NaN):7 w lp pt 9 lc 3 t "CPU ns/node-step, 1 thread", \
     f every ::1 using (sel("2 threads","ns_per_node_step") ? $4 : NaN):7 w lp pt 5 lc 2 t "wall ns/node-step, 2 threads", \
     f every ::1 using (sel("1 thread","ms_per_step") ? $4 : NaN):7 axes x1y2 w lp pt 6 dt 2 lc 1 t "ms/step, 1 thread (right)", \
     f every ::1 using (sel("2 threads","ms_per_step") ? $4 : NaN):7 axes x1y2 w lp pt 4 dt 2 lc 2 t "ms/step, 2 threads (right)"
unset y2label
unset y2tics
unset logscale y2
set ytics mirror
set ylabel "CPU share (core-seconds per simulated second)"
set arrow 1 from graph 0, first 0.3 to graph 1, first 0.3 nohead dt 3 lc rgb "black"
set arrow 2 from graph 0, first 1 to graph 1, first 1 nohead dt 1 lc rgb "gray"
set label 1 "paper: 30K nodes under 30 % CPU" at first 30000, first 0.3 point pt 9 ps 2 lc rgb "red" offset 1,-1
set label 2 "one core" at graph 0.02, first 1.15
plot f every ::1 using (sel("1 thread","cpu_share") ? $4 : NaN):7 w lp pt 7 lc 1 t "measured, 1 thread (process CPU time)", \
     f every ::1 using (sel("1 thread","cpu_share_from_step_time") ? $4 : NaN):7 w lp pt 6 dt 2 lc 1 t "1 thread, from ms/step x steps per sim. s", \
     f every ::1 using (sel("2 threads","cpu_share") ? $4 : NaN):7 w lp pt 5 lc 2 t "measured, 2 threads (both cores' CPU time)"
unset multiplot
