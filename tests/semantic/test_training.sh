#!/usr/bin/env bash
# The training script end to end at a toy size: two sequences rendered by the simulator, a 3-epoch run, the same
# run stopped after epoch 2 and continued with --resume (the exported model must be byte-identical: an interrupted
# two-hour training can be carried on), and the ONNX read by OpenCV's DNN module with one logit map per class.
#   test_training.sh SIM_BINARY SOURCE_DIR WORK_DIR
set -euo pipefail
sim=$1 src=$2 work=$3
py=/usr/bin/python3
if ! $py -c "import torch, onnx, cv2, numpy" 2>/dev/null; then
  if [ "${CI:-}" = "true" ]; then echo "FAIL: $py lacks torch/onnx/cv2/numpy (bash deploy/install-deps.sh)"; exit 1; fi
  echo "SKIP: $py lacks torch/onnx/cv2/numpy (bash deploy/install-deps.sh installs them)"; exit 77
fi
rm -rf "$work" && mkdir -p "$work"
"$src/src/semantic/training/render_data.sh" "$sim" "$src/params/sim.yaml" "$work/train" 9001 9002 3 > "$work/render.log"
"$src/src/semantic/training/render_data.sh" "$sim" "$src/params/sim.yaml" "$work/val" 9003 9003 2 >> "$work/render.log"
args=(--train "$work/train" --val "$work/val" --epochs 3 --batch 2 --input-width 96 --input-height 48 --threads 1
      --eval-every 3 --head-channels 16)
$py "$src/src/semantic/training/train.py" "${args[@]}" --out "$work/whole.onnx" > "$work/whole.log" 2>&1
grep -q "epoch 3" "$work/whole.log" || { cat "$work/whole.log"; echo "FAIL: the whole run did not reach epoch 3"; exit 1; }

$py "$src/src/semantic/training/train.py" "${args[@]}" --out "$work/part.onnx" > "$work/part.log" 2>&1 &
pid=$!
# Stopped once epoch 2's checkpoint is written (the epoch's own line comes before its checkpoint).
for _ in $(seq 600); do grep -q "checkpoint after epoch 2" "$work/part.log" && break; sleep 0.1; done
kill "$pid" 2>/dev/null || true
wait "$pid" 2>/dev/null || true
[ -f "$work/part.ckpt" ] || { cat "$work/part.log"; echo "FAIL: no checkpoint after epoch 2"; exit 1; }
[ ! -f "$work/part.onnx" ] || { echo "FAIL: the interrupted run finished before it was stopped (test too fast)"; exit 1; }
$py "$src/src/semantic/training/train.py" "${args[@]}" --out "$work/part.onnx" --resume > "$work/resume.log" 2>&1
grep -q "resumed from .*epoch 2" "$work/resume.log" || { cat "$work/resume.log"; echo "FAIL: not resumed at epoch 2"; exit 1; }
cmp "$work/whole.onnx" "$work/part.onnx" || { echo "FAIL: the resumed model differs from the uninterrupted one"; exit 1; }

# Other arguments than the checkpoint's: refused with a message naming the checkpoint.
if $py "$src/src/semantic/training/train.py" "${args[@]}" --lr 0.01 --out "$work/part.onnx" \
    --resume > "$work/mismatch.log" 2>&1; then
  echo "FAIL: a checkpoint written with another learning rate was continued"; exit 1
fi
grep -q "part.ckpt was written with other arguments" "$work/mismatch.log" || { cat "$work/mismatch.log"; exit 1; }

$py - "$work/whole.onnx" "$work/whole.json" <<'PY'
import json, sys
import cv2, numpy as np
net = cv2.dnn.readNetFromONNX(sys.argv[1])
net.setInput(np.zeros((1, 1, 48, 96), np.float32))
out = net.forward()
report = json.load(open(sys.argv[2]))
classes = len(report["val_iou"])
assert out.shape[:2] == (1, classes), f"output {out.shape}, expected {classes} class maps"
assert report["steps"] > 0 and report["train_frames"] == 6, report
print(f"OpenCV reads the model: output {out.shape}, {report['steps']} steps")
PY
echo "PASS"
