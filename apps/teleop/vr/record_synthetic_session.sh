#!/usr/bin/env bash
# Records a VR pose stream through the whole real path, without a headset: pmg_vr_bridge serves the
# page, headless Chromium runs it with ?synthetic=1 (the pattern of include/pmg/teleop/vr_synthetic.hpp),
# the bridge publishes PMG_VR_POSE and lcm-logger records it. The LCM traffic stays on a private
# loopback URL (ttl=0). This is how data/vr/sessions/synthetic_walk.lcmlog was made:
#
#   apps/teleop/vr/record_synthetic_session.sh data/vr/sessions/synthetic_walk.lcmlog 4
#
#   record_synthetic_session.sh OUT.lcmlog [SECONDS=4] [BIN_DIR=<checkout>/build/bin]
set -euo pipefail
out="${1:?usage: record_synthetic_session.sh OUT.lcmlog [SECONDS] [BIN_DIR]}"
secs="${2:-4}"
bin="${3:-$(cd "$(dirname "$0")/../../.." && pwd)/build/bin}"
chromium="${PMG_CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}"
[[ -x "$bin/pmg_vr_bridge" ]] || { echo "no $bin/pmg_vr_bridge (build first)" >&2; exit 1; }
[[ -n "$chromium" ]] || { echo "chromium not found (set PMG_CHROMIUM)" >&2; exit 1; }
command -v lcm-logger >/dev/null || { echo "lcm-logger not found" >&2; exit 1; }

work="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM -- "-$p" 2>/dev/null || kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
url="udpm://239.255.76.97:7697?ttl=0"
port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"

setsid "$bin/pmg_vr_bridge" --bind 127.0.0.1 --port "$port" --cert-dir "$work/cert" --lcm-url "$url" --no-token \
  --duration $((secs + 30)) >"$work/bridge.log" 2>&1 &
pids+=($!)
setsid lcm-logger -q -f --lcm-url="$url" -c PMG_VR_POSE "$work/raw.lcmlog" &
pids+=($!)
for _ in $(seq 50); do grep -q "https://127.0.0.1" "$work/bridge.log" 2>/dev/null && break; sleep 0.1; done
setsid "$chromium" --headless=new --no-sandbox --ignore-certificate-errors --disable-gpu --disable-dev-shm-usage \
  --no-first-run --disable-extensions --disable-background-networking --disable-sync --mute-audio \
  --user-data-dir="$work/profile" "https://127.0.0.1:$port/?synthetic=1" >"$work/chromium.log" 2>&1 &
pids+=($!)
# Record SECONDS from the first pose on.
for _ in $(seq 300); do [[ -s "$work/raw.lcmlog" ]] && break; sleep 0.05; done
[[ -s "$work/raw.lcmlog" ]] || { echo "no pose arrived; bridge log:" >&2; cat "$work/bridge.log" >&2; exit 1; }
sleep "$secs"
kill -INT "${pids[1]}"  # lcm-logger: flush and close
wait "${pids[1]}" 2>/dev/null || true
cp "$work/raw.lcmlog" "$out"
echo "recorded $(stat -c %s "$out") bytes to $out"
