# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# bandwidth.png: state-streaming bandwidth per peer against the grid level (`pliant bench net`),
# with the session suite's measured fast-mode traffic when session.csv exists.
if (!exists("datadir")) datadir = "bench-results"
if (!exists("outdir")) outdir = datadir
set datafile separator ","
set terminal pngcairo size 800,520 font ",10" noenhanced
set output outdir."/bandwidth.png"
f = datadir."/net.csv"
s = datadir."/session.csv"
have_session = system("[ -f '".s."' ] && echo 1 || echo 0") + 0
sel(c, m) = (strcol(2) eq c && strcol(6) eq m)
ssel(c, m, p) = (strcol(2) eq c && strcol(6) eq m && int($4) == p)
set title "State streaming at 60 Hz: bandwidth out per peer (each peer sends its share to the others)"
set grid
set logscale y
set xlabel "grid level (vertices)"
set xtics ("4\n(514)" 4, "5\n(2,050)" 5, "6\n(8,194)" 6, "7\n(32,770)" 7, "8\n(131,074)" 8)
set xrange [3.8:8.2]
set ylabel "Mbit/s per peer (UDP payload + headers)"
set key top left
# The paper: 10K vertices (level 6.15: 2*4^L+2 = 10,000) at 20 Mbit/s with 2 peers.
set label 1 "paper: 10K vertices, 2 peers, 20 Mbit/s" at first 6.15, first 20 point pt 9 ps 2 lc rgb "red" offset 1,-1 tc rgb "red"
if (have_session) {
plot f every ::1 using (sel("f64 2 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 7 lc 1 t "f64, 2 peers", \
     f every ::1 using (sel("f32 2 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 5 lc 2 t "f32, 2 peers", \
     f every ::1 using (sel("f64 4 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 6 dt 2 lc 1 t "f64, 4 peers", \
     s every ::1 using (ssel("fast","bytes_out_per_sim_s_per_peer",2) ? $3 : NaN):($7*8/1e6) w p pt 3 ps 2 lc 3 t "measured session, fast, 2 peers (payload)", \
     s every ::1 using (ssel("exact","bytes_out_per_sim_s_per_peer",2) ? $3 : NaN):($7*8/1e6) w p pt 2 ps 2 lc 4 t "measured session, exact (1 kHz halos), 2 peers"
} else {
plot f every ::1 using (sel("f64 2 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 7 lc 1 t "f64, 2 peers", \
     f every ::1 using (sel("f32 2 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 5 lc 2 t "f32, 2 peers", \
     f every ::1 using (sel("f64 4 peers","stream_wire_bits_per_s_per_peer") ? $3 : NaN):($7/1e6) w lp pt 6 dt 2 lc 1 t "f64, 4 peers"
}
