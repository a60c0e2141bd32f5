#!/usr/bin/env bash
# Opens a session in the real explorer under Xvfb (software Vulkan) and
# saves a screenshot once its volume is loaded and its contours drawn:
# a picture of a composed scene (slices, clipping, named contours, legend)
# as a user sees it.
#
# Usage: scripts/session-screenshot.sh SESSION.json OUT.png [SETTLE_S]
# SETTLE_S (default 25): seconds to wait after the volume is ready, for
# the contours to be extracted and drawn on the software renderer.
# Needs: xvfb, mesa-vulkan-drivers, imagemagick (see .ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."

SESSION="$1"
PNG="$2"
SETTLE="${3:-25}"
OUT="$(mktemp -d)"
BIN="${CARGO_TARGET_DIR:-target}/release/flexiso"
[ -x "$BIN" ] || cargo build --release

rm -f "$OUT/display"
Xvfb -displayfd 3 -screen 0 1600x1000x24 -nolisten tcp 3>"$OUT/display" >"$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
for _ in $(seq 1 50); do
  [ -s "$OUT/display" ] && break
  sleep 0.1
done
[ -s "$OUT/display" ] || { echo "session-screenshot.sh: Xvfb did not start" >&2; exit 1; }
APP_PID=""
cleanup() {
  if [ -n "$APP_PID" ]; then kill "$APP_PID" 2>/dev/null || true; fi
  kill "$XVFB_PID" 2>/dev/null || true
}
trap cleanup EXIT
export DISPLAY=":$(head -1 "$OUT/display")"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
export XDG_STATE_HOME="$OUT/state"
"$BIN" open --session "$SESSION" --size 1600x1000 >"$OUT/app.log" 2>&1 &
APP_PID=$!
for _ in $(seq 1 600); do
  kill -0 "$APP_PID" 2>/dev/null || { cat "$OUT/app.log" >&2; exit 1; }
  grep -q "ready in" "$OUT/app.log" && break
  sleep 0.5
done
grep -q "ready in" "$OUT/app.log" || { echo "the volume did not load" >&2; exit 1; }
sleep "$SETTLE"
import -window root "$PNG"
echo "saved $PNG ($(identify -format '%k' "$PNG") colours)"
cat "$OUT/app.log"
