#!/usr/bin/env bash
# More random two-segment scenes than CI checks (tests/random_scenes.rs): N scenes (default
# 8) on a range of SPAN in L̄ (default 1.0). Each scene: closure, sphere, branch and energy of
# every state file, label consistency, nothing unexplained in the completeness certificate,
# and `rodloop solve --branch` finding nothing below the diagram's stable state at two lengths.
#
#   scripts/random_scenes.sh [N] [SPAN]
set -euo pipefail
cd "$(dirname "$0")/.."
RODLOOP_RANDOM_SCENES="${1:-8}" RODLOOP_RANDOM_SPAN="${2:-1.0}" \
  cargo test --release --test random_scenes random_two_segment_scenes -- --nocapture
