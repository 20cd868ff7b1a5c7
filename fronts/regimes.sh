#!/bin/sh
# The regime map of issue 18 at gamma 2 .. 4, c 0.3, S 20, nu in (-1, -0.8):
# which regime, and how many fronts, a direct simulation reaches from noise
# and from the global oscillation (perturbed in its longest mode), two seeds
# each, with the Floquet boundaries of the global oscillation drawn over it.
# Usage: fronts/regimes.sh [OUTDIR] [BKFRONT]; FINE=1 for the fine grid.
# Coarse: 9 x 4 points x 2 states x 2 seeds = 144 runs of t = 400 on N 256,
# 41 CPU seconds (measured 2026-11-25; 87 s wall on a shared 2-core machine).
# Fine (FINE=1): 19 x 13 x 2 x 4 = 1976 runs, about 14 times that (~9.5 CPU
# minutes: 5 min on 2 free cores), or mpirun on a cluster.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here/regimes}
cli=${2:-$here/../build/bkfront}
mkdir -p "$out"
if [ "${FINE:-0}" = 1 ]; then
  grid="--x nu=-0.99:-0.81:19 --y gamma=1:4:13 --seeds 1:4:4"
else
  grid="--x nu=-0.98:-0.82:9 --y gamma=1:4:4 --seeds 1,2"
fi
# --resume: a run stopped half-way continues where it was
"$cli" sweep $grid --inits 'uniform:amp=0.01;oscillation:j=1,amp=0.01' --gamma 2 --c 0.3 \
  --S 20 --tmax 400 --N 256 --resume --out "$out/map.tsv"
# the Floquet boundaries of the global oscillation, gamma by gamma
{
  printf 'gamma\tnu\tkind\n'
  for g in $(seq 1 0.125 4); do
    "$cli" floquet --diagram --gamma "$g" --c 0.3 --search -0.999:-0.75 --tol 1e-6 |
      awk -F'\t' -v g="$g" '/^#/ { next } !h { h = 1; next }
        $5 == "period_doubling" || $5 == "long_wave" { printf "%s\t%s\t%s\n", g, $2, $5 }'
  done | sort -t "$(printf '\t')" -k3,3 -k1,1g   # one line per kind
} > "$out/thresholds.tsv"
gnuplot -e "plotdir='$here/../plots'; fmt='png'; out='$out/regimes.png'; files='$out/map.tsv $out/thresholds.tsv'" \
  "$here/../plots/sweep_map.gp"
echo "$out/map.tsv $out/thresholds.tsv $out/regimes.png"
