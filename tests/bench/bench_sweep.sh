#!/bin/sh
# bkfront sweep's scaling (make bench): a 40-point sweep of ~1-s runs with
# 1 and 2 threads (goal: 2 threads >= 1.8 times faster), the cost of a point
# besides its run (points of a 0.01-long run on 8 grid points: scheduling,
# row, fsync), and the peak memory of 40 and 400 such points (it must not
# grow with the points).  Usage: bench_sweep.sh BKFRONT
set -eu
cli=${1:-build/bkfront}
dir=$(mktemp -d /tmp/bkf_bench_sweep.XXXXXX)
trap 'rm -rf "$dir"' EXIT
grid="--x nu=-0.98:-0.82:10 --seeds 1:4:4 --init uniform:amp=0.01 --tmax 150 --N 512 --no-progress"
# elapsed s, peak KB, CPU s (user + system)
wall() { /usr/bin/time -f "%e %M %U %S" "$@" 2>&1 >/dev/null | tail -n 1 | awk '{print $1, $2, $3 + $4}'; }
r1=$(wall "$cli" sweep $grid --threads 1 --out "$dir/one.tsv")
r2=$(wall "$cli" sweep $grid --threads 2 --out "$dir/two.tsv")
t1=${r1%% *}
t2=${r2%% *}
cmp -s "$dir/one.tsv" "$dir/two.tsv" || { echo "bench_sweep: 1 and 2 threads differ"; exit 1; }
tiny="--init uniform:amp=0.01 --tmax 0.01 --N 8 --frames 1 --threads 1 --no-progress"
o40=$(wall "$cli" sweep --x seed=1:40:40 $tiny --out "$dir/o40.tsv")
o400=$(wall "$cli" sweep --x seed=1:400:400 $tiny --out "$dir/o400.tsv")
awk -v t1="$t1" -v t2="$t2" -v r1="$r1" -v r2="$r2" -v a="$o40" -v b="$o400" 'BEGIN {
  split(a, x, " "); split(b, y, " "); split(r1, p, " "); split(r2, q, " ");
  printf "sweep, 40 points of ~1 s (tmax 150, N 512): 1 thread %.2f s, 2 threads %.2f s, speed-up %.2f (goal >= 1.8)\n", t1, t2, t1 / t2;
  printf "  CPU: 1 thread %.1f s (%.2f cores busy), 2 threads %.1f s (%.2f cores busy; below 2: the machine is shared)\n", p[3], p[3] / t1, q[3], q[3] / t2;
  printf "per point besides its run (400 points of tmax 0.01, N 8): %.2f ms (%.2f%% of a 1-s point)\n", 1000 * y[1] / 400, 100 * y[1] / 400;
  printf "peak memory: 40 points %d KB, 400 points %d KB\n", x[2], y[2] }'
