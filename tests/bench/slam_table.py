#!/usr/bin/env python3
"""The table of tests/bench/slam_scenarios.sh, from the agvslam-run --json files it left under <data>/slam/.

  slam_table.py ROOT "MODES" SCENARIO... -- SEED...

One line per sequence (ATE per mode, drift, lost frames, share of pose inliers on ground-truth moving objects),
then per scenario the mean and standard deviation over the seeds of ATE, MOVING_INLIERS and lost frames per mode,
and the product targets (issue 37) checked on those means:
  - on a dynamic scene, --dynamic detector cuts MOVING_INLIERS by >= 90 % against off;
  - the detector's mean ATE is within 10 % of gt's;
  - on a scene where off's mean ATE is more than twice gt's (the issue names the new scenes; checked on every
    scene), the detector's is >= 70 % lower than off's.
Runs differ by about +-35 % from seed to seed: single runs prove nothing, read the means with their spread.
"""
import json
import math
import os
import statistics
import sys

# Scenes without moving objects: the masking targets do not apply.
STATIC_SCENES = {"static"}


def load(root, scenario, seed, mode):
    path = f"{root}/{scenario}_{seed}_{mode}.json"
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def figures(j):
    """ATE RMSE (m), moving-inlier share (%), lost frames and drift (m) of one run; nan where missing."""
    nan = float("nan")
    if j is None:
        return {"ate": nan, "mov": nan, "lost": nan, "drift": nan}
    return {
        "ate": j["ate"]["rmse_m"] if "ate" in j else nan,
        "mov": 100 * j["moving_inliers"]["fraction"] if "moving_inliers" in j else nan,
        "lost": j["frames"]["lost"],
        "drift": j.get("drift_m", nan),
    }


def mean_sd(values):
    vals = [v for v in values if not math.isnan(v)]
    if not vals:
        return float("nan"), float("nan"), 0
    sd = statistics.stdev(vals) if len(vals) > 1 else 0.0
    return statistics.fmean(vals), sd, len(vals)


def main(argv):
    root, modes = argv[1], argv[2].split()
    rest = argv[3:]
    sep = rest.index("--")
    scenarios, seeds = rest[:sep], rest[sep + 1:]

    runs = {}  # (scenario, seed, mode) -> figures
    print(f"{'sequence':<16}" + "".join(f"{'ATE ' + m:>13}" for m in modes) + f"{'drift':>9}{'lost':>6}"
          + "".join(f"{'mov ' + m:>14}" for m in modes))
    for sc in scenarios:
        for seed in seeds:
            for m in modes:
                runs[(sc, seed, m)] = figures(load(root, sc, seed, m))
            first = runs[(sc, seed, modes[0])]
            print(f"{sc + '_' + seed:<16}" + "".join(f"{runs[(sc, seed, m)]['ate']:>13.4f}" for m in modes)
                  + f"{first['drift']:>9.4f}" + f"{sum(runs[(sc, seed, m)]['lost'] for m in modes):>6.0f}"
                  + "".join(f"{runs[(sc, seed, m)]['mov']:>13.2f}%" for m in modes))

    print(f"\nper scene over seeds {' '.join(seeds)} (mean +- standard deviation):")
    print(f"{'scene':<9}{'mode':<10}{'ATE m':>20}{'moving inliers %':>22}{'lost frames':>16}{'runs':>6}")
    failures = []
    for sc in scenarios:
        means = {}
        for m in modes:
            stats = {k: mean_sd([runs[(sc, s, m)][k] for s in seeds]) for k in ("ate", "mov", "lost")}
            means[m] = {k: v[0] for k, v in stats.items()}
            a, mv, lo = stats["ate"], stats["mov"], stats["lost"]
            print(f"{sc:<9}{m:<10}{a[0]:>11.4f} +- {a[1]:.4f}{mv[0]:>13.3f} +- {mv[1]:.3f}"
                  f"{lo[0]:>9.1f} +- {lo[1]:.1f}{a[2]:>6}")
        if sc in STATIC_SCENES or not {"detector", "off"} <= set(modes):
            continue
        checks = []
        det, off = means["detector"], means["off"]
        if off["mov"] > 0:
            cut = 100 * (1 - det["mov"] / off["mov"])
            checks.append((f"moving inliers cut {cut:.1f} % (>= 90)", cut >= 90))
        if "gt" in means and means["gt"]["ate"] > 0:
            gt = means["gt"]
            vs_gt = 100 * (det["ate"] / gt["ate"] - 1)
            checks.append((f"ATE vs gt {vs_gt:+.1f} % (<= +10)", vs_gt <= 10))
            if off["ate"] > 2 * gt["ate"]:
                lower = 100 * (1 - det["ate"] / off["ate"])
                checks.append((f"off > 2 x gt: detector {lower:.1f} % lower than off (>= 70)", lower >= 70))
        if "semantic" in means and det["ate"] > 0:
            # Issue 38: the semantic keyframes must not make the pose worse than the geometric detector alone.
            vs_det = 100 * (means["semantic"]["ate"] / det["ate"] - 1)
            checks.append((f"semantic ATE vs detector {vs_det:+.1f} % (<= 0)", vs_det <= 0))
        line = "; ".join(f"{text} {'ok' if ok else 'MISSED'}" for text, ok in checks)
        print(f"  {sc}: {line}")
        failures += [f"{sc}: {text}" for text, ok in checks if not ok]
    print(f"\ntargets: {'all met' if not failures else str(len(failures)) + ' missed'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
