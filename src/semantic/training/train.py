#!/usr/bin/python3
"""Trains the shipped semantic segmenter (PSPNet, MobileNetV2 backbone, pyramid pooling bins 1, 2, 3, 6) on
simulator sequences and exports it to ONNX for OpenCV's DNN module (agvslam::semantic::Segmenter).

Runs on the CPU with Debian's torch (/usr/bin/python3; deploy/install-deps.sh installs it). Deterministic for a
given seed and thread count. The data are folders written by render_data.sh: <seq>/image_0/NNNNNN.png (grey left
images) and <seq>/class_0/NNNNNN.png (one class id per pixel, ids of include/agvslam/sim/semantic_classes.h).

  src/semantic/training/render_data.sh build/release/bin/agvslam-sim params/sim.yaml /work/semdata/train 5000 5099 10
  src/semantic/training/render_data.sh build/release/bin/agvslam-sim params/sim.yaml /work/semdata/val 5100 5119 10
  /usr/bin/python3 src/semantic/training/train.py --train /work/semdata/train --val /work/semdata/val \
      --out params/models/pspnet_mnv2.onnx

With the defaults (1000 training frames, 30 epochs of 125 steps, batch 8, 2 threads) this is sized for about
1 h 15 min on two otherwise idle cores (about 1.2 s per step; measured as 2.3 CPU-seconds per step on one
thread). The network at 288 x 192: MobileNetV2 x0.5 with output stride 8 (the last two stages dilated),
0.69 M parameters, 2.8 MB as ONNX. A checkpoint is written after every epoch (OUT with .ckpt); a run that was
stopped continues where it was with the same arguments and --resume, to the same bytes as an uninterrupted run.

The exported graph is what OpenCV 4.6 reads: opset 10 (ReLU6 is a Clip with min/max attributes, not the 3-input
Clip of opset >= 11), fixed-size average pooling in the pyramid (adaptive pooling only exports where the feature
map divides evenly, so the pooling windows are computed here for the fixed input size), integer-factor nearest
upsampling inside the pyramid (the same in every Resize convention), no Identity nodes (rewired after export). The
network outputs class logits at 1/OS of the input; the segmenter upsamples them bilinearly (half-pixel centres,
as cv::resize and torch's align_corners=False, which the loss here uses).
"""

import argparse
import json
import math
import os
import random
import sys
import time

import cv2
import numpy as np
import onnx
import torch
import torch.nn as nn
import torch.nn.functional as F

import repair_onnx

CLASS_NAMES = ["background", "floor", "wall", "rack", "pallet/box", "person", "forklift", "agv"]
# Grey level g enters the network as (g - MEAN) * SCALE; params/semantic.yaml repeats these two numbers.
MEAN = 127.5
SCALE = 1.0 / 127.5


def conv_bn(inp, out, kernel, stride=1, dilation=1, groups=1, relu=True):
    layers = [nn.Conv2d(inp, out, kernel, stride, dilation * (kernel - 1) // 2, dilation, groups, bias=False),
              nn.BatchNorm2d(out)]
    if relu:
        layers.append(nn.ReLU6(inplace=True))
    return nn.Sequential(*layers)


class InvertedResidual(nn.Module):
    def __init__(self, inp, out, stride, dilation, expand):
        super().__init__()
        hidden = inp * expand
        self.residual = stride == 1 and inp == out
        layers = [] if expand == 1 else [conv_bn(inp, hidden, 1)]
        layers += [conv_bn(hidden, hidden, 3, stride, dilation, groups=hidden), conv_bn(hidden, out, 1, relu=False)]
        self.body = nn.Sequential(*layers)

    def forward(self, x):
        return x + self.body(x) if self.residual else self.body(x)


def channels(c, width):
    """MobileNetV2's channel rounding: to a multiple of 8, never below 90 % of c * width."""
    v = max(8, int(c * width + 4) // 8 * 8)
    return v + 8 if v < 0.9 * c * width else v


class MobileNetV2(nn.Module):
    """The backbone without its classifier; strides beyond output_stride become dilations (DeepLab's trick)."""

    # expansion, channels, repeats, stride (Sandler et al. 2018, table 2)
    SETTINGS = [(1, 16, 1, 1), (6, 24, 2, 2), (6, 32, 3, 2), (6, 64, 4, 2), (6, 96, 3, 1), (6, 160, 3, 2),
                (6, 320, 1, 1)]

    def __init__(self, in_channels, width, output_stride):
        super().__init__()
        inp = channels(32, width)
        layers = [conv_bn(in_channels, inp, 3, 2)]
        stride, dilation = 2, 1
        for expand, c, repeats, s in self.SETTINGS:
            out = channels(c, width)
            for i in range(repeats):
                block_stride = s if i == 0 else 1
                block_dilation = dilation
                if block_stride > 1 and stride * block_stride > output_stride:
                    dilation *= block_stride
                    block_stride = 1
                elif block_stride > 1:
                    stride *= block_stride
                layers.append(InvertedResidual(inp, out, block_stride, block_dilation, expand))
                inp = out
        self.features = nn.Sequential(*layers)
        self.out_channels = inp

    def forward(self, x):
        return self.features(x)


class PyramidPooling(nn.Module):
    """PSPNet's pyramid pooling module with windows fixed for a feature map of feat_h x feat_w."""

    def __init__(self, in_channels, feat_h, feat_w, bins=(1, 2, 3, 6)):
        super().__init__()
        branch = in_channels // len(bins)
        self.branches = nn.ModuleList()
        for b in bins:
            if feat_h % b or feat_w % b:
                raise ValueError(f"feature map {feat_h}x{feat_w} does not divide into {b}x{b} bins")
            kh, kw = feat_h // b, feat_w // b
            self.branches.append(nn.Sequential(nn.AvgPool2d((kh, kw), (kh, kw)), conv_bn(in_channels, branch, 1),
                                               nn.Upsample(scale_factor=(kh, kw), mode="nearest")))
        self.out_channels = in_channels + branch * len(bins)

    def forward(self, x):
        return torch.cat([x] + [b(x) for b in self.branches], 1)


class PSPNet(nn.Module):
    def __init__(self, num_classes, in_channels, input_h, input_w, width, output_stride, head_channels):
        super().__init__()
        if input_h % output_stride or input_w % output_stride:
            raise ValueError(f"input {input_w}x{input_h} is not a multiple of the output stride {output_stride}")
        self.backbone = MobileNetV2(in_channels, width, output_stride)
        self.ppm = PyramidPooling(self.backbone.out_channels, input_h // output_stride, input_w // output_stride)
        self.head = nn.Sequential(conv_bn(self.ppm.out_channels, head_channels, 3), nn.Dropout2d(0.1),
                                  nn.Conv2d(head_channels, num_classes, 1))

    def forward(self, x):
        return self.head(self.ppm(self.backbone(x)))


def list_frames(root):
    frames = []
    for seq in sorted(os.listdir(root)):
        label_dir = os.path.join(root, seq, "class_0")
        if not os.path.isdir(label_dir):
            continue
        for name in sorted(os.listdir(label_dir)):
            frames.append((os.path.join(root, seq, "image_0", name), os.path.join(label_dir, name)))
    if not frames:
        sys.exit(f"train.py: no <sequence>/class_0/*.png under {root} (render them with render_data.sh)")
    return frames


def load(frames, input_w, input_h, full_labels):
    """Images resized as the segmenter does (cv::resize, INTER_AREA); labels by nearest neighbour for the loss and,
    for validation, also at full resolution for the IoU."""
    images, labels, full = [], [], []
    for image_path, label_path in frames:
        image = cv2.imread(image_path, cv2.IMREAD_GRAYSCALE)
        label = cv2.imread(label_path, cv2.IMREAD_UNCHANGED)
        if image is None or label is None or label.ndim != 2 or image.shape != label.shape:
            sys.exit(f"train.py: cannot read a grey image and a same-size label from {image_path}, {label_path}")
        images.append(cv2.resize(image, (input_w, input_h), interpolation=cv2.INTER_AREA))
        labels.append(cv2.resize(label, (input_w, input_h), interpolation=cv2.INTER_NEAREST))
        if full_labels:
            full.append(label)
    return np.stack(images), np.stack(labels), full


def augment(images, labels, rng):
    """Flips and the photometric changes a real camera adds (gain, offset, gamma, noise); float32 in [0, 255]."""
    out = images.astype(np.float32)
    lab = labels.copy()
    for i in range(len(out)):
        if rng.random() < 0.5:
            out[i] = out[i][:, ::-1]
            lab[i] = lab[i][:, ::-1]
        gamma = math.exp(rng.uniform(-0.4, 0.4))
        out[i] = 255.0 * (out[i] / 255.0) ** gamma
        out[i] = out[i] * rng.uniform(0.6, 1.4) + rng.uniform(-30, 30)
        out[i] += rng.normal(0, rng.uniform(0, 4), out[i].shape).astype(np.float32)
    return np.clip(out, 0, 255), lab


def to_tensor(images):
    return torch.from_numpy((np.ascontiguousarray(images, dtype=np.float32) - MEAN) * SCALE).unsqueeze(1)


def class_weights(labels, num_classes):
    """Inverse square root of the pixel frequency, normalised to a mean of 1: people and vehicles are a few per
    cent of the pixels and would otherwise be given up for the floor and the racks."""
    counts = np.bincount(labels.ravel(), minlength=num_classes)[:num_classes].astype(np.float64)
    w = 1.0 / np.sqrt(np.maximum(counts / counts.sum(), 1e-4))
    return torch.tensor(w / w.mean(), dtype=torch.float32)


def evaluate(model, images, full_labels, num_classes):
    """Per-class IoU at the labels' full resolution, over all validation frames together."""
    model.eval()
    inter = np.zeros(num_classes)
    union = np.zeros(num_classes)
    with torch.no_grad():
        for i in range(len(images)):
            logits = model(to_tensor(images[i:i + 1]))
            h, w = full_labels[i].shape
            pred = F.interpolate(logits, size=(h, w), mode="bilinear", align_corners=False).argmax(1)[0].numpy()
            for c in range(num_classes):
                p, g = pred == c, full_labels[i] == c
                inter[c] += np.logical_and(p, g).sum()
                union[c] += np.logical_or(p, g).sum()
    model.train()
    return [float(inter[c] / union[c]) if union[c] > 0 else float("nan") for c in range(num_classes)]


def export(model, path, input_h, input_w, metadata):
    model.eval()
    dummy = torch.zeros(1, 1, input_h, input_w)
    torch.onnx.export(model, dummy, path, opset_version=10, input_names=["image"], output_names=["logits"],
                      do_constant_folding=True)
    proto = onnx.load(path)
    repair_onnx.strip_identities(proto)
    left = repair_onnx.opencv_rejects(proto)
    if left:
        sys.exit(f"train.py: the export holds nodes OpenCV 4.6 rejects: {left}")
    for key, value in metadata.items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, str(value)
    onnx.checker.check_model(proto)
    onnx.save(proto, path)


def checkpoint_args(args):
    """The arguments a checkpoint must agree on to be continued (not the output paths, threads or --resume)."""
    skip = {"out", "checkpoint", "resume", "threads"}
    return {k: v for k, v in sorted(vars(args).items()) if k not in skip}


def save_checkpoint(path, state):
    # Written beside and renamed, so a run killed while saving leaves the previous checkpoint whole.
    tmp = path + ".tmp"
    torch.save(state, tmp)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", required=True, help="folder of training sequences (render_data.sh)")
    ap.add_argument("--val", required=True, help="folder of validation sequences")
    ap.add_argument("--out", required=True, help="the ONNX file to write; a .json beside it gets the figures")
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--max-steps", type=int, default=0, help="stop after this many steps (0: all epochs)")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--input-width", type=int, default=288, help="px; a multiple of 6 x the output stride")
    ap.add_argument("--input-height", type=int, default=192, help="px; a multiple of 6 x the output stride")
    ap.add_argument("--width-mult", type=float, default=0.5, help="MobileNetV2 channel multiplier")
    ap.add_argument("--output-stride", type=int, default=8, choices=[8, 16, 32])
    ap.add_argument("--head-channels", type=int, default=64)
    ap.add_argument("--seed", type=int, default=38)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--eval-every", type=int, default=10, help="epochs between validation runs")
    ap.add_argument("--checkpoint", default="",
                    help="file written after every epoch (default: OUT with .ckpt); an interrupted run started again "
                         "with the same arguments and --resume continues from it")
    ap.add_argument("--resume", action="store_true", help="continue from --checkpoint when it exists")
    args = ap.parse_args()
    checkpoint = args.checkpoint or os.path.splitext(args.out)[0] + ".ckpt"

    torch.manual_seed(args.seed)
    random.seed(args.seed)
    rng = np.random.default_rng(args.seed)
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    num_classes = len(CLASS_NAMES)

    t0 = time.time()
    train_frames, val_frames = list_frames(args.train), list_frames(args.val)
    train_images, train_labels, _ = load(train_frames, args.input_width, args.input_height, False)
    val_images, _, val_full = load(val_frames, args.input_width, args.input_height, True)
    print(f"{len(train_frames)} training frames, {len(val_frames)} validation frames, loaded in "
          f"{time.time() - t0:.0f} s", flush=True)

    model = PSPNet(num_classes, 1, args.input_height, args.input_width, args.width_mult, args.output_stride,
                   args.head_channels)
    params = sum(p.numel() for p in model.parameters())
    print(f"PSPNet-MobileNetV2 x{args.width_mult}, OS {args.output_stride}, {params / 1e6:.2f} M parameters",
          flush=True)
    weights = class_weights(train_labels, num_classes)
    optimizer = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps_per_epoch = len(train_images) // args.batch
    total = args.epochs * steps_per_epoch
    if args.max_steps:
        total = min(total, args.max_steps)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimizer, args.lr, total_steps=total, pct_start=0.05)

    step, history, first_epoch = 0, [], 0
    if args.resume and os.path.exists(checkpoint):
        state = torch.load(checkpoint)
        if state["args"] != checkpoint_args(args):
            sys.exit(f"train.py: {checkpoint} was written with other arguments ({state['args']}); "
                     f"expected {checkpoint_args(args)}")
        model.load_state_dict(state["model"])
        optimizer.load_state_dict(state["optimizer"])
        schedule.load_state_dict(state["schedule"])
        rng.bit_generator.state = state["numpy_rng"]
        torch.set_rng_state(state["torch_rng"])
        random.setstate(state["python_rng"])
        step, history, first_epoch = state["step"], state["history"], state["epoch"]
        print(f"resumed from {checkpoint}: epoch {first_epoch}, step {step}", flush=True)
    model.train()
    for epoch in range(first_epoch, args.epochs):
        order = rng.permutation(len(train_images))
        losses = []
        for b in range(steps_per_epoch):
            if step >= total:
                break
            idx = order[b * args.batch:(b + 1) * args.batch]
            images, labels = augment(train_images[idx], train_labels[idx], rng)
            logits = model(to_tensor(images))
            logits = F.interpolate(logits, size=labels.shape[1:], mode="bilinear", align_corners=False)
            loss = F.cross_entropy(logits, torch.from_numpy(labels.astype(np.int64)), weight=weights)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            schedule.step()
            losses.append(loss.item())
            step += 1
        print(f"epoch {epoch + 1}: step {step}, loss {np.mean(losses):.3f}, {time.time() - t0:.0f} s", flush=True)
        last = step >= total or epoch + 1 == args.epochs
        if (epoch + 1) % args.eval_every == 0 or last:
            iou = evaluate(model, val_images, val_full, num_classes)
            history.append({"epoch": epoch + 1, "step": step, "iou": iou})
            print("  val IoU " + ", ".join(f"{n} {v:.3f}" for n, v in zip(CLASS_NAMES, iou)), flush=True)
        save_checkpoint(checkpoint, {"args": checkpoint_args(args), "epoch": epoch + 1, "step": step,
                                     "history": history, "model": model.state_dict(),
                                     "optimizer": optimizer.state_dict(), "schedule": schedule.state_dict(),
                                     "numpy_rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state(),
                                     "python_rng": random.getstate()})
        # After the file is in place: a run stopped from here on continues after this epoch.
        print(f"checkpoint after epoch {epoch + 1}: {checkpoint}", flush=True)
        if last:
            break

    iou = history[-1]["iou"]
    metadata = {"classes": ",".join(CLASS_NAMES), "input": f"{args.input_width}x{args.input_height}x1",
                "mean": MEAN, "scale": SCALE, "seed": args.seed, "steps": step}
    export(model, args.out, args.input_height, args.input_width, metadata)
    report = {"command": " ".join(sys.argv), "train": args.train, "val": args.val,
              "train_sequences": sorted({os.path.basename(os.path.dirname(os.path.dirname(f[1])))
                                         for f in train_frames}),
              "val_sequences": sorted({os.path.basename(os.path.dirname(os.path.dirname(f[1]))) for f in val_frames}),
              "train_frames": len(train_frames), "val_frames": len(val_frames), "steps": step,
              "seconds": round(time.time() - t0), "parameters": params,
              "val_iou": dict(zip(CLASS_NAMES, iou)), "history": history}
    with open(os.path.splitext(args.out)[0] + ".json", "w") as f:
        json.dump(report, f, indent=1)
    print(f"wrote {args.out} ({os.path.getsize(args.out) / 1e6:.2f} MB) in {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
