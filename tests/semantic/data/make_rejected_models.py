#!/usr/bin/python3
"""Writes the small ONNX models of test_segmenter.cpp: a two-class 'segmenter' (one 3x3 convolution and a
ReLU6 on an 8x8 grey image) in the forms OpenCV 4.6 rejects, and their repairs by repair_onnx.py.

  rejected_identity.onnx   the convolution's weights reach it through an Identity on an initialiser
  rejected_clip.onnx       the ReLU6 is opset 11's Clip with min/max inputs
  repaired_identity.onnx, repaired_clip.onnx   the same after src/semantic/training/repair_onnx.py

  /usr/bin/python3 tests/semantic/data/make_rejected_models.py   (run from the repository root)
"""

import os
import subprocess
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

HERE = os.path.dirname(os.path.abspath(__file__))
REPAIR = os.path.join(HERE, "..", "..", "..", "src", "semantic", "training", "repair_onnx.py")


def model(identity, clip_inputs):
    rng = np.random.default_rng(38)
    weights = numpy_helper.from_array(rng.normal(0, 1, (2, 1, 3, 3)).astype(np.float32), "conv_w")
    inits = [weights]
    nodes = []
    w_name = "conv_w"
    if identity:
        nodes.append(helper.make_node("Identity", ["conv_w"], ["conv_w_copy"], name="weights_identity"))
        w_name = "conv_w_copy"
    nodes.append(helper.make_node("Conv", ["image", w_name], ["conv"], name="conv", kernel_shape=[3, 3], pads=[1, 1, 1, 1]))
    if clip_inputs:
        inits += [numpy_helper.from_array(np.array(0, np.float32), "clip_min"),
                  numpy_helper.from_array(np.array(6, np.float32), "clip_max")]
        nodes.append(helper.make_node("Clip", ["conv", "clip_min", "clip_max"], ["logits"], name="relu6_clip"))
    else:
        nodes.append(helper.make_node("Clip", ["conv"], ["logits"], name="relu6_clip", min=0.0, max=6.0))
    graph = helper.make_graph(nodes, "rejected", [helper.make_tensor_value_info("image", TensorProto.FLOAT,
                                                                                  [1, 1, 8, 8])],
                              [helper.make_tensor_value_info("logits", TensorProto.FLOAT, [1, 2, 8, 8])], inits)
    m = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 11 if clip_inputs else 10)])
    m.ir_version = 7
    onnx.checker.check_model(m)
    return m


def main():
    for name, identity, clip_inputs in [("identity", True, False), ("clip", False, True)]:
        rejected = os.path.join(HERE, f"rejected_{name}.onnx")
        onnx.save(model(identity, clip_inputs), rejected)
        subprocess.run([sys.executable, REPAIR, rejected, os.path.join(HERE, f"repaired_{name}.onnx")], check=True)


if __name__ == "__main__":
    main()
