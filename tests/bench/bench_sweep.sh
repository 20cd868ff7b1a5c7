#!/bin/sh
# bkfront sweep's scaling (make bench): a 40-point sweep of ~1-s runs with
# 1 and 2 threads (goal: 2 threads >= 1.8 times faster), the cost of a point
# besides its run (points of a 0.01-long run on 8 grid points: scheduling,
# row, fsync), and the peak memory of 40 and 400 such points (it must not
# grow with the points).  With the MPI build (second argument, default
# build/mpi/bkfront, when it and mpirun exist) the same under mpirun -np 1
# and -np 2 (one compute thread per rank, rank 0's beside its manager), on
# this machine only (shared memory and loopback), and the peak memory of
# each rank.  Usage: bench_sweep.sh BKFRONT [MPI_BKFRONT]
set -eu
cli=${1:-build/bkfront}
mpi_cli=${2:-build/mpi/bkfront}
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

[ -x "$mpi_cli" ] && command -v mpirun >/dev/null 2>&1 || { echo "sweep under mpirun: skipped ($mpi_cli or mpirun missing; make mpi)"; exit 0; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpirun="mpirun --oversubscribe --mca btl self,vader --mca oob_tcp_if_include lo --mca btl_tcp_if_include lo"
# each rank under its own time(1): its peak memory in $dir/NAME.RANK
ranked() {
  name=$1
  np=$2
  shift 2
  wall $mpirun -np "$np" sh -c '/usr/bin/time -f "%M" -o "$0.$OMPI_COMM_WORLD_RANK" "$@"' \
    "$dir/$name" "$mpi_cli" sweep "$@"
}
m1=$(ranked np1 1 $grid --out "$dir/np1.tsv")
m2=$(ranked np2 2 $grid --out "$dir/np2.tsv")
for t in np1 np2; do
  cmp -s "$dir/one.tsv" "$dir/$t.tsv" || { echo "bench_sweep: mpirun $t differs from 1 thread"; exit 1; }
done
tiny_mpi="--init uniform:amp=0.01 --tmax 0.01 --N 8 --frames 1 --no-progress"
s40=$(ranked s40 2 --x seed=1:40:40 $tiny_mpi --out "$dir/s40.tsv")
s400=$(ranked s400 2 --x seed=1:400:400 $tiny_mpi --out "$dir/s400.tsv")
peak() { cat "$dir/$1".* | sort -n | tail -n 1; }
awk -v m1="$m1" -v m2="$m2" -v a="$s40" -v b="$s400" -v p1="$(peak np2)" \
    -v p40="$(peak s40)" -v p400="$(peak s400)" -v t1="$t1" 'BEGIN {
  split(m1, x, " "); split(m2, y, " "); split(a, u, " "); split(b, v, " ");
  printf "sweep under mpirun (loopback), the same 40 points: -np 1 %.2f s, -np 2 %.2f s, speed-up %.2f (goal >= 1.8); 1 thread without MPI %.2f s\n", x[1], y[1], x[1] / y[1], t1;
  printf "  CPU (mpirun and its ranks): -np 1 %.1f s, -np 2 %.1f s (%.2f cores busy)\n", x[3], y[3], y[3] / y[1];
  printf "per point besides its run under -np 2 ((400 - 40 points of tmax 0.01, N 8) / 360): %.2f ms (%.2f%% of a 1-s point); mpirun start and end %.2f s\n", 1000 * (v[1] - u[1]) / 360, 100 * (v[1] - u[1]) / 360, u[1] - 40 * (v[1] - u[1]) / 360;
  printf "peak memory of a rank: 40 points of 1 s %d KB; tiny points: 40 %d KB, 400 %d KB\n", p1, p40, p400 }'
