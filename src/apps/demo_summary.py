#!/usr/bin/env python3
"""The demo's comparison in one line (README's first command):

  demo_summary.py SCENE EVAL_DETECTOR EVAL_OFF RUN_DETECTOR RUN_OFF

EVAL_*: agvslam-eval --json files (ATE against the ground truth); RUN_*: agvslam-run --json files (MOVING_INLIERS:
the share of the pose inliers that lay on moving objects).
"""
import json
import sys


def main(argv):
    if len(argv) != 6:
        print(__doc__, file=sys.stderr)
        return 2
    scene = argv[1]
    loaded = []
    for path in argv[2:]:
        try:
            with open(path) as f:
                loaded.append(json.load(f))
        except (OSError, ValueError) as e:
            print(f"demo_summary: {path}: {e}", file=sys.stderr)
            return 1
    eval_det, eval_off, run_det, run_off = loaded
    ate_det, ate_off = eval_det["ate_m"]["rmse"], eval_off["ate_m"]["rmse"]
    mov_det = 100 * run_det["moving_inliers"]["fraction"]
    mov_off = 100 * run_off["moving_inliers"]["fraction"]
    change = 100 * (ate_det / ate_off - 1) if ate_off > 0 else float("nan")
    print(f"demo: {scene}: ATE with the dynamic-region detector {ate_det:.4f} m, without masking {ate_off:.4f} m "
          f"({change:+.0f} %); pose inliers on moving objects {mov_off:.2f} % -> {mov_det:.2f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
