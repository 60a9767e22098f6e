#!/usr/bin/env bash
# kill -9 / --resume trials: start `rodloop diagram`, kill it with SIGKILL after a random
# delay, finish with --resume, and check that the directory holds exactly one consistent
# run: no temporary or staging files, no lock, and critical.csv identical to an
# uninterrupted run's. Prints the number of trials and of failures.
# Usage: scripts/kill_resume.sh [TRIALS=30] [BIN=target/release/rodloop]
set -u
TRIALS=${1:-30}
BIN=${2:-target/release/rodloop}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BIN" diagram --quiet --out "$WORK/ref" >/dev/null
fail=0
for t in $(seq "$TRIALS"); do
  d="$WORK/t$t"
  "$BIN" diagram --quiet --out "$d" >/dev/null 2>&1 &
  pid=$!
  sleep "$(awk -v s="$t" 'BEGIN { srand(s); printf "%.3f", 0.02 + 0.4 * rand() }')"
  kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  if ! "$BIN" diagram --quiet --resume --out "$d" >/dev/null 2>"$WORK/err"; then
    echo "trial $t: resume failed: $(head -c 300 "$WORK/err")"; fail=$((fail + 1)); continue
  fi
  stray=$(find "$d" -name '.*' -o -name '*.tmp' -o -name '*staging*' | grep -v "^$d$" || true)
  if [ -n "$stray" ]; then echo "trial $t: stray files: $stray"; fail=$((fail + 1)); continue; fi
  if ! cmp -s "$d/critical.csv" "$WORK/ref/critical.csv"; then
    echo "trial $t: critical.csv differs from the uninterrupted run"; fail=$((fail + 1)); continue
  fi
  if ! python3 -c "import json,sys; d=json.load(open('$d/summary.json')); sys.exit(0 if d.get('run_id') else 1)"; then
    echo "trial $t: summary.json has no run_id"; fail=$((fail + 1)); continue
  fi
done
echo "$TRIALS kill -9 / --resume trials: $fail with stray, mixed or wrong outputs"
