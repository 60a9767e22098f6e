#!/usr/bin/env bash
# 60 hard states (branches 1-3 of the paper's two-segment rods, D1/D0 = 0.5, 0.1,
# 0.001): solve each at the default accuracy and at --accuracy high, and print whether it
# converged, the energy with its estimate, the difference to the high-accuracy energy, the
# stability index and the wall time.
# Usage: scripts/extreme_contrast.sh [path/to/rodloop] > table.tsv
set -u
BIN=${1:-target/release/rodloop}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
printf "d1\tbranch\tlbar\tstatus\tenergy\testimate\thigh_energy\tdiff_vs_high\tindex\tseconds\n"
for d1 in 0.5 0.1 0.001; do
  scene=data/scenes/inhomogeneous-d1-$d1.toml
  for case in "1 1.1" "1 1.2" "1 1.3" "1 1.4" "1 1.5" "1 1.7" "1 1.9" "1 2.5" "1 2.7" "1 2.9" \
              "2 1.1" "2 1.2" "2 1.3" "2 1.4" "2 1.5" "2 1.7" "2 1.9" "3 2.1" "3 2.2" "3 2.3"; do
    set -- $case
    b=$1; l=$2
    t0=$(date +%s.%N)
    if "$BIN" solve --scene "$scene" --lbar "$l" --branch "$b" --out "$OUT/d" >/dev/null 2>"$OUT/err"; then
      t1=$(date +%s.%N)
      e=$(python3 -c "import json;d=json.load(open('$OUT/d/summary.json'));print(d['energy'],d['error_estimate'],d['index'])")
      if "$BIN" solve --scene "$scene" --lbar "$l" --branch "$b" --accuracy high --out "$OUT/h" >/dev/null 2>&1; then
        h=$(python3 -c "import json;print(json.load(open('$OUT/h/summary.json'))['energy'])")
      else
        h=nan
      fi
      set -- $e
      diff=$(python3 -c "print('%.1e' % abs($1-$h))" 2>/dev/null || echo nan)
      printf "%s\t%s\t%s\tok\t%.10f\t%.1e\t%s\t%s\t%s\t%.3f\n" "$d1" "$b" "$l" "$1" "$2" "$h" "$diff" "$3" "$(echo "$t1 - $t0" | bc)"
    else
      t1=$(date +%s.%N)
      printf "%s\t%s\t%s\tFAILED: %s\t\t\t\t\t\t%.3f\n" "$d1" "$b" "$l" "$(head -c 200 "$OUT/err" | tr '\n' ' ')" "$(echo "$t1 - $t0" | bc)"
    fi
  done
done
