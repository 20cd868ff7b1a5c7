#!/bin/bash
# bad input: expect exit 2, exactly one line on stderr, nothing on stdout
B=./bk/build/bkfront
t() { out=$($B "$@" 2>/tmp/bi_err); rc=$?; nl=$(wc -l < /tmp/bi_err); ns=${#out};
  if [ "$rc" = 2 ] && [ "$nl" = 1 ] && [ "$ns" = 0 ]; then s=OK; else s=DEFECT; fi
  printf '%s\trc=%s\tstderr_lines=%s\tstdout_chars=%s\t%s\t| %s\n' "$s" "$rc" "$nl" "$ns" "$*" "$(head -c 200 /tmp/bi_err)"; }
t period --mu 1 --nu 1
t period --mu 1 --nu -1.5
t period --mu 0 --nu 0
t period --mu -1 --nu 0
t period --mu nan --nu 0
t period --mu 1 --nu inf
t period --mu 1e7 --nu 0
t period --mu 1 --nu 0 --tol 1e-15
t period --mu 1 --nu 0 --tol 0.5
t period --mu 1x --nu 0
t period --mu 1 --nu 0 --bogus
t period --mu 1 --nu
t period --mu 2:1:0 --nu 0
t speeds --gamma 0 --c 0.3
t speeds --gamma -2
t speeds --c -0.1
t speeds --nu 0.999999999999999999999
t speeds --nu 1
t speeds --S 0
t speeds --S -5
t speeds --S nan
t speeds --n 0
t speeds --n -3
t speeds --n 2.5
t speeds --nmax 0
t speeds --tol 0
t speeds --stability-tol 1e-3
t speeds --stability --stability-tol 1
t speeds --stability --c 0
t speeds --gamma 2 --c 0.3 --nu -0.96 --S 20 --n 3 --nmax 5
t speeds --format xml
t stability --n 13
t stability --n 0
t stability
t stability --n 1 --root 2
t stability --n 1 --c 0
t stability --n 1 --tol 1
t stability --n 1 --per-kappa 0
t stability --n 1 --kappa-count 8
t stability --n 1 --line --kappa-count 0
t check --n 0
t check --tmax 0
t check --tmax -5
t check --rel-tol 1
t check --perturb 1
t check --seed -1
t check --N 513
t check --N 1024 --N-max 512
t check --gamma 2 --c 0.3 --nu -0.96 --S 20 --stepper nope
t check --nu 1
t speeds --gamma 1e-7
t speeds --gamma 2 --c 1e7
t speeds --gamma 0.3 --c 0.05 --nu 0.5 --S 60 --n 1e9
# added for seed 20261130 (options main gained since d1690bb)
t speeds --tol 1e-15
t speeds --stability --stability-tol 1e-9
t stability --n 1 --line --kappa-count 100001
t check --points 31
t check --resolution 2
t check --grid nope
t check --runs sometimes
t check --frame nope
t speeds --model chain --N 1
t speeds --method nope
t stability --n 1 --per-kappa 51
t speeds --gamma 2 --c 0.3 --nu -0.96 --S 1e300
# valid input at an edge (arbitrated for seed 20261130): exit 0 with an answer, never a number that is not one
v() { out=$($B "$@" 2>/tmp/bi_err); rc=$?;
  if [ "$rc" = 0 ] && [ -n "$out" ]; then s=OK; else s=DEFECT; fi
  printf '%s\trc=%s\tvalid-edge\t%s\t| %s\n' "$s" "$rc" "$*" "$(printf '%s' "$out" | grep -E 'no front|^1\t' | head -c 200)"; }
# n above n_max: an empty table and the reason, as speeds --n 13 (its documented contract), not bad input
v check --n 13
v speeds --n 13
# the Hopf edge: T = 6.2831853072633619 (model asymptotic, T_err 1.1e-14); Poincare-Lindstedt for
# u'' + u + 2 mu nu u u' = 0 with r^2 = 4 (1 - nu^2) gives T = 2 pi (1 + (2 nu)^2 r^2 / 24) = 2 pi + 8.3775e-11
v period --mu 1 --nu 0.99999999999
