#!/usr/bin/env bash
# Median wall time of a whole command over N runs (default 21), e.g.
#   scripts/time_command.sh 21 target/release/rodloop diagram --out /tmp/d
# Prints the median, min and max in milliseconds. Uses only bash and date.
set -euo pipefail
n=$1; shift
times=()
for _ in $(seq "$n"); do
  t0=$(date +%s%N)
  "$@" >/dev/null
  t1=$(date +%s%N)
  times+=($(( (t1 - t0) / 1000 )))
done
sorted=($(printf '%s\n' "${times[@]}" | sort -n))
mid=$(( n / 2 ))
awk -v med="${sorted[$mid]}" -v lo="${sorted[0]}" -v hi="${sorted[$((n-1))]}" -v n="$n" -v cmd="$*" \
  'BEGIN { printf "%s\n  runs %d: median %.2f ms (min %.2f, max %.2f)\n", cmd, n, med/1000, lo/1000, hi/1000 }'
