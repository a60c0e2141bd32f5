#!/usr/bin/env bash
# Times the real explorer under Xvfb with software Vulkan: seconds from
# launch to the first frame with the tree and curve ready, and frame
# statistics (interval between frames, UI-thread milliseconds) while the
# job runs, from `flexiso open --frame-log`.
#
# Usage: scripts/explorer-timing.sh FILE [SECONDS]
#   FILE     the volume to open (e.g. ../shared/data/colin27_ch2.nrrd)
#   SECONDS  how long to keep the window after launch (default 15)
#   INTERACT=1 moves the mouse over the window every 20 ms meanwhile, as a
#            user would (every move repaints).
# Needs: xvfb, mesa-vulkan-drivers, xdotool (see .ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."
INPUT="$1"
SECS="${2:-15}"
BIN="${CARGO_TARGET_DIR:-target}/release/flexiso"
[ -x "$BIN" ] || cargo build --release
OUT="$(mktemp -d)"
Xvfb -displayfd 3 -screen 0 1600x1000x24 -nolisten tcp 3>"$OUT/display" >"$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
APP_PID=""
trap '[ -n "$APP_PID" ] && kill "$APP_PID" 2>/dev/null; kill "$XVFB_PID" 2>/dev/null; true' EXIT
for _ in $(seq 1 50); do [ -s "$OUT/display" ] && break; sleep 0.1; done
export DISPLAY=":$(head -1 "$OUT/display")"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
sleep 0.5

start=$(date +%s.%N)
"$BIN" open "$INPUT" --size 1400x900 --frame-log "$OUT/frames.tsv" >"$OUT/app.log" 2>&1 &
APP_PID=$!
ready=""
end=$(( $(date +%s) + SECS ))
i=0
while [ "$(date +%s)" -lt "$end" ]; do
  if [ -z "$ready" ] && grep -q "idle" "$OUT/frames.tsv" 2>/dev/null; then
    ready=$(date +%s.%N)
  fi
  if [ -n "${INTERACT:-}" ]; then
    i=$((i + 1))
    xdotool mousemove $((300 + (i * 7) % 600)) $((300 + (i * 3) % 300)) 2>/dev/null || true
  fi
  sleep 0.02
done
kill "$APP_PID" 2>/dev/null || true
APP_PID=""

python3 - "$OUT/frames.tsv" "$start" "${ready:-}" <<'PY'
import statistics, sys
path, start, ready = sys.argv[1], float(sys.argv[2]), sys.argv[3]
rows = [l.rstrip("\n").split("\t") for l in open(path).readlines()[1:]]
rows = [(float(t), float(f), float(u), s) for t, f, u, s in rows]
print("launch to tree ready: " + (f"{float(ready) - start:.2f} s" if ready else "not within the time given"))
busy = [r for r in rows if r[3] != "idle"]
if len(busy) > 1:
    f = sorted(r[1] for r in busy[1:])
    u = sorted(r[2] for r in busy)
    print(f"while the job ran: {len(busy)} frames; interval median {statistics.median(f):.1f} ms, "
          f"max {f[-1]:.1f} ms; UI thread median {statistics.median(u):.2f} ms, max {u[-1]:.1f} ms")
idle = [r for r in rows if r[3] == "idle"]
if idle:
    u = sorted(r[2] for r in idle)
    print(f"after: {len(idle)} frames; UI thread median {statistics.median(u):.2f} ms, max {u[-1]:.1f} ms")
stages, last = [], None
for t, _, _, s in rows:
    if s != last:
        stages.append(f"{s} {t:.1f}s")
        last = s
print("stages (seconds since the first frame): " + ", ".join(stages))
PY
