#!/usr/bin/env bash
# Render the HTML report in headless Chromium to a PNG screenshot, as a person would see it.
#
#   scripts/screenshot_report.sh [REPORT_DIR] [PNG]
#
# REPORT_DIR defaults to out/report (made with `rodloop report --out REPORT_DIR` when it holds
# no report.html yet), PNG to REPORT_DIR/report.png. The window is WIDTH x HEIGHT CSS pixels
# (default 1280 x 4000: the top of the page) and the image is SCALE times that (default 1;
# docs/report.png is made with SCALE=0.5). Installs Debian's `chromium` package when
# no chromium is on PATH (needs root and a reachable package mirror). Prints the console
# messages Chromium logged while loading the page; exits non-zero if there is any.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-out/report}
png=${2:-$dir/report.png}
width=${WIDTH:-1280}
height=${HEIGHT:-4000}
scale=${SCALE:-1}

if ! command -v chromium >/dev/null 2>&1; then
  echo "chromium not found: installing Debian's chromium package" >&2
  if [ "$(id -u)" -ne 0 ]; then
    echo "error: installing chromium needs root (run: apt-get update && apt-get install -y chromium)" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq chromium >/dev/null
fi

if [ ! -f "$dir/report.html" ]; then
  cargo build --release --quiet
  "${CARGO_TARGET_DIR:-target}/release/rodloop" report --quiet --out "$dir"
fi

page="file://$(cd "$dir" && pwd)/report.html"
profile=$(mktemp -d)
log=$(mktemp)
trap 'rm -rf "$profile" "$log"' EXIT
mkdir -p "$(dirname "$png")"
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --user-data-dir="$profile" --enable-logging=stderr --v=0 --hide-scrollbars \
  --force-device-scale-factor="$scale" \
  --screenshot="$png" --window-size="$width,$height" "$page" 2>"$log" || {
  cat "$log" >&2
  echo "error: chromium failed to render $page" >&2
  exit 1
}
console=$(grep -E 'CONSOLE|Uncaught' "$log" || true)
if [ -n "$console" ]; then
  echo "console messages while loading $page:" >&2
  echo "$console" >&2
fi
echo "wrote $png ($(du -k "$png" | cut -f1) KB) from $page"
# Chromium logs console errors as INFO:CONSOLE lines; the page has no script, so any
# console message is a fault.
if [ -n "$console" ]; then
  echo "error: the page logged console messages" >&2
  exit 1
fi
