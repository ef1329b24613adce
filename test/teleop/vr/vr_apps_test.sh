#!/usr/bin/env bash
# pmg_vr_bridge and pmg_vr_replay as an operator runs them:
#  - the bridge generates its certificate + token on first run (key and token 0600), prints the URL
#    and fingerprint, serves the page over HTTPS (curl, checked against the generated certificate),
#    reuses the certificate on the next run and stops cleanly on SIGTERM and SIGINT (exit 0, summary);
#  - bad command lines exit 2, setup errors exit 1 naming the file;
#  - pmg_vr_replay replays the shipped recording (exit 0) and refuses a file that is not a log.
#   vr_apps_test.sh BIN_DIR SOURCE_DIR
set -uo pipefail
bin="${1:?usage: vr_apps_test.sh BIN_DIR SOURCE_DIR}"
src="${2:?usage: vr_apps_test.sh BIN_DIR SOURCE_DIR}"
work="$(mktemp -d)"
bridge_pid=""
cleanup() {
  [[ -n "$bridge_pid" ]] && kill -KILL "$bridge_pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
ok() { echo "ok   $*"; }
url="udpm://239.255.76.98:$((17000 + $$ % 5000))?ttl=0"

# Starts the bridge in the background on a free port; sets bridge_pid and port.
start_bridge() {
  "$bin/pmg_vr_bridge" --bind 127.0.0.1 --port 0 --cert-dir "$work/cfg" --lcm-url "$url" --stats-period 0.5 "$@" \
    >"$work/bridge.out" 2>&1 &
  bridge_pid=$!
  port=""
  for _ in $(seq 100); do
    port="$(sed -n 's|^  https://127.0.0.1:\([0-9]*\)/.*|\1|p' "$work/bridge.out" | head -1)"
    [[ -n "$port" ]] && break
    sleep 0.05
  done
}
stop_bridge() {  # SIGNAL; expects exit 0 within 3 s and the summary line
  kill "-$1" "$bridge_pid"
  local rc=124
  for _ in $(seq 60); do
    if ! kill -0 "$bridge_pid" 2>/dev/null; then wait "$bridge_pid"; rc=$?; break; fi
    sleep 0.05
  done
  bridge_pid=""
  if [[ $rc -eq 0 ]] && grep -q "pmg_vr_bridge: stopped after" "$work/bridge.out"; then ok "SIG$1: clean stop"; else
    fail "SIG$1: exit $rc"; cat "$work/bridge.out"; fi
}

start_bridge
if [[ -z "$port" ]]; then fail "bridge did not print its URL"; cat "$work/bridge.out"; exit 1; fi
grep -q "generated now" "$work/bridge.out" && ok "certificate generated" || fail "no 'generated now'"
grep -Eq "SHA-256 fingerprint ([0-9A-F]{2}:){31}[0-9A-F]{2}" "$work/bridge.out" && ok "fingerprint printed" || fail "fingerprint"
token="$(cat "$work/cfg/token")"
grep -q "?token=$token" "$work/bridge.out" && ok "URL carries the token" || fail "token not in the URL"
[[ "$(stat -c %a "$work/cfg/bridge.key")" == 600 && "$(stat -c %a "$work/cfg/token")" == 600 ]] && ok "key and token 0600" \
  || fail "modes $(stat -c %a "$work/cfg/bridge.key") $(stat -c %a "$work/cfg/token")"
if command -v curl >/dev/null; then
  code="$(curl -s -o "$work/index.html" -w '%{http_code} %{content_type}' --cacert "$work/cfg/bridge.crt" \
    "https://127.0.0.1:$port/")"
  [[ "$code" == "200 text/html; charset=utf-8" ]] && cmp -s "$work/index.html" "$src/data/vr/web/index.html" \
    && ok "page served over HTTPS, certificate verifies for 127.0.0.1" || fail "GET /: $code"
  code="$(curl -s -o /dev/null -w '%{http_code}' --path-as-is --cacert "$work/cfg/bridge.crt" \
    "https://127.0.0.1:$port/../../CMakeLists.txt")"
  [[ "$code" == 404 ]] && ok "traversal refused" || fail "traversal: $code"
else
  echo "skip curl checks (no curl)"
fi
sleep 0.6
grep -q "clients 0  rx" "$work/bridge.out" && ok "stats line" || fail "no stats line"
stop_bridge TERM
start_bridge
grep -q "(reused)" "$work/bridge.out" && ok "certificate reused" || fail "certificate not reused"
stop_bridge INT

"$bin/pmg_vr_bridge" --port 70000 >/dev/null 2>&1; rc=$?
[[ $rc -eq 2 ]] && ok "bad port: exit 2" || fail "bad port: exit $rc"
"$bin/pmg_vr_bridge" --duration nan >/dev/null 2>&1; rc=$?
[[ $rc -eq 2 ]] && ok "--duration nan: exit 2" || fail "--duration nan: exit $rc"
touch "$work/not_a_dir"
out="$("$bin/pmg_vr_bridge" --cert-dir "$work/not_a_dir" --port 0 --lcm-url "$url" 2>&1)"; rc=$?
[[ $rc -eq 1 && "$out" == *"not_a_dir"* ]] && ok "cert dir is a file: exit 1 naming it" || fail "cert dir: $rc $out"
chmod 644 "$work/cfg/bridge.key"
out="$("$bin/pmg_vr_bridge" --cert-dir "$work/cfg" --port 0 --lcm-url "$url" 2>&1)"; rc=$?
[[ $rc -eq 1 && "$out" == *"chmod 600"* ]] && ok "readable key: exit 1" || fail "readable key: $rc $out"
chmod 600 "$work/cfg/bridge.key"

out="$("$bin/pmg_vr_replay" --log "$src/data/vr/sessions/synthetic_walk.lcmlog" --speed 20 --lcm-url "$url" 2>&1)"; rc=$?
[[ $rc -eq 0 && "$out" == *"failed 0"* ]] && ok "replay of the shipped session" || fail "replay: $rc $out"
echo "not a log" >"$work/x.lcmlog"
out="$("$bin/pmg_vr_replay" --log "$work/x.lcmlog" --lcm-url "$url" 2>&1)"; rc=$?
[[ $rc -eq 1 && "$out" == *"x.lcmlog"* ]] && ok "not a log: exit 1 naming it" || fail "not a log: $rc $out"
out="$("$bin/pmg_vr_replay" --log "$src/data/vr/sessions/synthetic_walk.lcmlog" --speed 0 2>&1)"; rc=$?
[[ $rc -eq 2 ]] && ok "--speed 0: exit 2" || fail "--speed 0: $rc"

echo "$failures failures"
[[ $failures -eq 0 ]]
