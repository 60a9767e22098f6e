#!/usr/bin/env bash
# The guide's timed diagrams, phase and enclosed solve: for each command, the median wall time of
# RUNS whole-command runs (scripts/time_command.sh) and the critical lengths it printed
# (critical.csv: kind, from → to, L̄_cr ± error estimate) or the solved energy.
# Run it on an otherwise idle machine; it prints the load average before and after.
#
#   scripts/targets.sh [RUNS]        (default 5; builds the release binary first;
#                                     FULL=1 adds the two-segment enclosed diagram at high)
#   SCENES="homogeneous-enclosed …" scripts/targets.sh 1   (only those diagrams, then phase and solve)
set -euo pipefail
runs=${1:-5}
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/rodloop"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
crit() {
  awk -F, 'NR>1 && $3!="collapse" { printf "    %s %s→%s  %.12f ± %.1e\n", $3, $4, $5, $2, $7 }' "$1/critical.csv"
}
n=0
timed() {
  n=$((n + 1))
  local out="$tmp/run$n"
  local quiet=()
  [ "$1" = diagram ] && quiet=(--quiet)
  scripts/time_command.sh "$runs" "$bin" "$@" "${quiet[@]}" --out "$out" 2>/dev/null | sed -n 2p | sed "s|^ *|$* : |"
}
for s in ${SCENES:-inhomogeneous-d1-0.5 inhomogeneous-d1-0.1 inhomogeneous-d1-0.001 homogeneous-enclosed inhomogeneous-d1-0.5-enclosed}; do
  accs="default high"
  # The two-segment enclosed diagram at high accuracy takes minutes: only with FULL=1.
  [ "$s" = inhomogeneous-d1-0.5-enclosed ] && [ "${FULL:-0}" != 1 ] && accs=default
  for acc in $accs; do
    timed diagram --scene "data/scenes/$s.toml" --accuracy "$acc"
    crit "$tmp/run$n"
  done
done
timed phase --scene data/scenes/inhomogeneous-d1-0.5.toml --param d1 --to 0.001
echo "    phase.csv rows: $(($(wc -l < "$tmp/run$n/phase.csv") - 1))"
timed solve --scene data/scenes/homogeneous-enclosed.toml --lbar 1.4 --branch 2
grep -o '"energy": *[^,]*\|"error_estimate": *[^,]*' "$tmp/run$n/summary.json" | tr '\n' ' '; echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
