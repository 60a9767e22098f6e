#!/usr/bin/env sh
# The paper's Sec. 5 statements on the two-segment rod checked against computed lowest
# states (docs/src/two-segment.md, "The paper's Sec. 5 statements"). About 10 s after the build.
set -eu
cd "$(dirname "$0")/.."
exec cargo run --release -q -p rodloop-diagram --example sec5_checks
