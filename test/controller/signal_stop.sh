#!/usr/bin/env bash
# pmg_controller stops cleanly on SIGTERM / SIGINT in every run mode (defect 7 of issue 11): a
# long lockstep run and a real-time run are signalled after 2 s; each must exit 0, print its summary
# ("stopped by a signal") and leave a readable event log behind.
# Usage: signal_stop.sh <pmg_controller> <config>
set -u
ctl="$1"
config="$2"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail=0
for mode in lockstep realtime; do
  for sig in TERM INT; do
    log="$out/$mode-$sig.lcmlog"
    "$ctl" --config "$config" --"$mode" --duration 600 --no-lcm --log "$log" > "$out/$mode-$sig.txt" 2>&1 &
    pid=$!
    sleep 2
    kill -"$sig" "$pid"
    wait "$pid"
    rc=$?
    if [ "$rc" -ne 0 ]; then echo "$mode SIG$sig: exit $rc"; cat "$out/$mode-$sig.txt"; fail=1; fi
    grep -q "stopped by a signal" "$out/$mode-$sig.txt" || { echo "$mode SIG$sig: no summary"; cat "$out/$mode-$sig.txt"; fail=1; }
    [ -s "$log" ] || { echo "$mode SIG$sig: no event log"; fail=1; }
  done
done
[ $fail -eq 0 ] && echo "pmg_controller: lockstep and real-time runs stop on SIGTERM and SIGINT with their summary and log"
exit $fail
