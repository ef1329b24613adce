#!/usr/bin/env python3
"""Stopping distance and time of a pmg_policy_sil run (docs/controller.md "Braking steps").

For every seed that did not fall: from the first tick after --after-s at which the shaped command
v_x reached 0, the distance the pelvis still travelled forward (the integral of the achieved v_x,
heading frame) and the time until |v_x| stayed below --still-mps for --still-s. Prints the median
and the largest over the seeds.

  python3 scripts/stop_distance.py OUT_DIR [OUT_DIR ...] [--after-s 19]
(OUT_DIR: pmg_policy_sil --out, with summary.json and seedN.csv; e.g. the stop script
training/results/fidelity/fast20s_ft2/stop/fast_fwd.yaml, whose stop begins at 19 s.)

With --segments STOP[,STOP...] (scripts with several stops, e.g.
training/results/fidelity/run_on/bent_crouched_stops.yaml: stop1,stop2,stop3), every named stop of
every seed instead: from the first tick in it at which the command v_x is 0, the distance the pelvis
went forward through it and the segment after it (episode 0 only; a stop the run did not reach, or
after a fall, is left out). Prints the number of stops, the median, 90th percentile and largest
distance, and how many went on more than 0.5 m and more than 1 m (docs/controller.md "Running on
after a crouched bent walk").
"""
import argparse
import csv
import json
import os
import statistics


def stop_of(path, after_s, still_mps, still_s):
    rows = list(csv.DictReader(open(path)))
    t0, dist, still, t_stop = None, 0.0, 0.0, None
    for prev, row in zip(rows, rows[1:]):
        t = float(row["t"])
        if t0 is None and t > after_s and float(row["vx_cmd"]) == 0.0:
            t0 = t
        if t0 is None or t_stop is not None:
            continue
        dt = t - float(prev["t"])
        v = float(row["vx"])
        dist += v * dt
        still = still + dt if abs(v) < still_mps else 0.0
        if still >= still_s:
            t_stop = t - still_s - t0
    if t0 is None:
        raise SystemExit(f"{path}: the command v_x never reaches 0 after {after_s} s")
    return dist, t_stop


def segment_stops(path, names):
    """[(name, distance)] for each named stop reached in the CSV at path (see --segments)."""
    rows = [r for r in csv.DictReader(open(path)) if r.get("episode", "0") == "0"]
    order = []
    for r in rows:
        if not order or order[-1] != r["segment"]:
            order.append(r["segment"])
    out = []
    for name in names:
        if name not in order:
            continue
        i = order.index(name)
        window = {name, order[i + 1]} if i + 1 < len(order) else {name}
        t0, dist = None, 0.0
        for prev, row in zip(rows, rows[1:]):
            if row["segment"] not in window or prev["segment"] not in window:
                continue
            if t0 is None and row["segment"] == name and float(row["vx_cmd"]) == 0.0:
                t0 = float(row["t"])
            if t0 is not None:
                dist += float(row["vx"]) * (float(row["t"]) - float(prev["t"]))
        if t0 is not None:
            out.append((name, dist))
    return out


def report_segments(d, names):
    runs = json.load(open(os.path.join(d, "summary.json")))["runs"]
    dist = sorted(x for r in runs for _, x in segment_stops(os.path.join(d, f"seed{r['seed']}.csv"), names))
    if not dist:
        print(f"{d}: none of {','.join(names)} reached")
        return
    p90 = dist[min(len(dist) - 1, int(0.9 * len(dist)))]
    print(f"{d}: {len(dist)} stops; distance after the command reached 0: median {statistics.median(dist):.2f} m, "
          f"90th percentile {p90:.2f} m, largest {dist[-1]:.2f} m; went on > 0.5 m: {sum(x > 0.5 for x in dist)}, "
          f"> 1 m: {sum(x > 1.0 for x in dist)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--after-s", type=float, default=19.0, help="the stop is the first zero command after this [s]")
    ap.add_argument("--still-mps", type=float, default=0.05, help="|v_x| below this counts as stopped [m/s]")
    ap.add_argument("--still-s", type=float, default=0.3, help="for this long [s]")
    ap.add_argument("--segments", help="STOP[,STOP...]: every named stop of every seed (see above)")
    a = ap.parse_args()
    for d in a.dirs:
        if not os.path.isfile(os.path.join(d, "summary.json")):
            raise SystemExit(f"stop_distance: {d}/summary.json: missing (a pmg_policy_sil --out directory expected)")
        if a.segments:
            report_segments(d, a.segments.split(","))
            continue
        runs = json.load(open(os.path.join(d, "summary.json")))["runs"]
        stops = [stop_of(os.path.join(d, f"seed{r['seed']}.csv"), a.after_s, a.still_mps, a.still_s)
                 for r in runs if not r["fell"]]
        if not stops:
            print(f"{d}: every seed fell")
            continue
        dist = [s[0] for s in stops]
        times = [s[1] for s in stops if s[1] is not None]
        t_text = (f"median {statistics.median(times):.2f} s over the {len(times)} that stopped before the script ended"
                  if times else "none stopped before the script ended")
        print(f"{d}: {len(stops)} of {len(runs)} seeds standing; distance after the command reached 0: median "
              f"{statistics.median(dist):.2f} m, largest {max(dist):.2f} m; time to |v_x| < {a.still_mps}: {t_text}")


if __name__ == "__main__":
    main()
