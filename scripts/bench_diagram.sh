#!/usr/bin/env bash
# Time and accuracy of `rodloop diagram` (numeric model, default scene) at each accuracy level:
# median wall time over RUNS whole-command runs, and the largest deviation of the numeric
# critical lengths from the exact layer's (closed-form solutions, error ~1e-14).
# Prints a Markdown table for the guide. Needs only bash and awk.
#
#   scripts/bench_diagram.sh [RUNS]        (default 5; builds the release binary first)
set -euo pipefail
runs=${1:-5}
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/rodloop"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" diagram --model exact --out "$tmp/exact" >/dev/null
echo "| accuracy | median wall time ($runs runs) | max |L̄_cr − exact| over the crossings | largest printed error estimate |"
echo "|---|---|---|---|"
for level in fast default high; do
  times=()
  for _ in $(seq "$runs"); do
    t0=$(date +%s%N)
    "$bin" diagram --accuracy "$level" --quiet --out "$tmp/$level" >/dev/null
    t1=$(date +%s%N)
    times+=($(( (t1 - t0) / 1000000 )))
  done
  median=$(printf '%s\n' "${times[@]}" | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
  # Join numeric and exact critical lengths by index (same kinds and order), crossings only.
  dev=$(awk -F, 'NR==FNR { if (FNR>1) ex[$1]=$2; next }
                 FNR>1 && $3=="crossing" { d=$2-ex[$1]; if (d<0) d=-d; if (d>m) m=d; if ($7>e) e=$7 }
                 END { printf "%.1e|%.1e", m, e }' "$tmp/exact/critical.csv" "$tmp/$level/critical.csv")
  echo "| $level | $(awk -v t="$median" 'BEGIN{printf "%.2f s", t/1000}') | ${dev%|*} | ${dev#*|} |"
done
