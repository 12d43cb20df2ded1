#!/usr/bin/python3
"""Per-class IoU of an ONNX segmenter on rendered sequences (render_data.sh), run the way
agvslam::semantic::Segmenter runs it: OpenCV DNN, the grey frame resized with INTER_AREA to the input size,
(pixel - mean) * scale, the class scores resized bilinearly to the frame, the best class per pixel. Also the
forward time per frame on one thread.

  /usr/bin/python3 src/semantic/training/evaluate.py --model params/models/pspnet_mnv2.onnx --data /work/semdata/val
"""

import argparse
import json
import time

import cv2
import numpy as np

from train import CLASS_NAMES, MEAN, SCALE, list_frames


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True)
    ap.add_argument("--data", required=True, help="folder of sequences with image_0/ and class_0/")
    ap.add_argument("--input-width", type=int, default=288)
    ap.add_argument("--input-height", type=int, default=192)
    ap.add_argument("--json", help="also write the figures here")
    args = ap.parse_args()

    cv2.setNumThreads(1)
    net = cv2.dnn.readNetFromONNX(args.model)
    n = len(CLASS_NAMES)
    inter, union = np.zeros(n), np.zeros(n)
    forward_ms = []
    frames = list_frames(args.data)
    for image_path, label_path in frames:
        grey = cv2.imread(image_path, cv2.IMREAD_GRAYSCALE)
        truth = cv2.imread(label_path, cv2.IMREAD_UNCHANGED)
        small = cv2.resize(grey, (args.input_width, args.input_height), interpolation=cv2.INTER_AREA)
        net.setInput(cv2.dnn.blobFromImage(small, SCALE, (args.input_width, args.input_height), MEAN, False, False))
        t0 = time.perf_counter()
        scores = net.forward()[0]
        forward_ms.append(1000 * (time.perf_counter() - t0))
        up = np.stack([cv2.resize(s, (grey.shape[1], grey.shape[0]), interpolation=cv2.INTER_LINEAR) for s in scores])
        pred = up.argmax(0)
        for c in range(n):
            p, g = pred == c, truth == c
            inter[c] += np.logical_and(p, g).sum()
            union[c] += np.logical_or(p, g).sum()
    iou = {name: (inter[c] / union[c] if union[c] else float("nan")) for c, name in enumerate(CLASS_NAMES)}
    print(f"{len(frames)} frames of {args.data}; forward median {np.median(forward_ms):.1f} ms on one thread")
    print("IoU " + ", ".join(f"{k} {v:.3f}" for k, v in iou.items()))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"model": args.model, "data": args.data, "frames": len(frames), "iou": iou,
                       "forward_median_ms": float(np.median(forward_ms))}, f, indent=1)


if __name__ == "__main__":
    main()
