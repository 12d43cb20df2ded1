#!/usr/bin/python3
"""Rewrites the ONNX nodes OpenCV 4.6's importer rejects, so a model exported elsewhere loads in
agvslam::semantic::Segmenter:

  Identity          its consumers read its input instead, the node goes (OpenCV rejects an Identity whose
                    input is an initialiser, which torch emits for shared weights)
  Clip, 3 inputs    ReLU6 and the like from opset >= 11: constant min/max inputs become the min/max attributes of
                    opset 10's Clip (the graph's opset is set to 10 when that is all it needs)

  /usr/bin/python3 src/semantic/training/repair_onnx.py IN.onnx OUT.onnx
"""

import sys

import onnx
from onnx import numpy_helper


def strip_identities(model):
    graph = model.graph
    outputs = {o.name for o in graph.output}
    rename, keep = {}, []
    for node in graph.node:
        if node.op_type == "Identity" and node.output[0] not in outputs:
            rename[node.output[0]] = node.input[0]
        else:
            keep.append(node)
    for node in keep:
        for i, name in enumerate(node.input):
            while name in rename:
                name = rename[name]
            node.input[i] = name
    del graph.node[:]
    graph.node.extend(keep)
    return len(rename)


def clip_inputs_to_attributes(model):
    """Returns how many Clip nodes were rewritten; exits when a bound is not a constant."""
    graph = model.graph
    constants = {t.name: numpy_helper.to_array(t) for t in graph.initializer}
    for node in graph.node:
        if node.op_type == "Constant":
            constants[node.output[0]] = numpy_helper.to_array(node.attribute[0].t)
    rewritten = 0
    for node in graph.node:
        if node.op_type != "Clip" or len(node.input) == 1:
            continue
        bounds = list(node.input[1:])
        del node.input[1:]
        for name, value in zip(["min", "max"], bounds):
            if not value:
                continue
            if value not in constants:
                sys.exit(f"repair_onnx: Clip '{node.name}' has a non-constant {name} input '{value}'")
            node.attribute.append(onnx.helper.make_attribute(name, float(constants[value])))
        rewritten += 1
    if rewritten:
        for opset in model.opset_import:
            if opset.domain in ("", "ai.onnx"):
                opset.version = 10
    return rewritten


def opencv_rejects(model):
    """Names and types of the nodes OpenCV 4.6 would still reject."""
    return [(n.name, n.op_type) for n in model.graph.node
            if n.op_type == "Identity" or (n.op_type == "Clip" and len(n.input) > 1)]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    model = onnx.load(sys.argv[1])
    identities = strip_identities(model)
    clips = clip_inputs_to_attributes(model)
    left = opencv_rejects(model)
    if left:
        sys.exit(f"repair_onnx: still rejected: {left}")
    onnx.checker.check_model(model)
    onnx.save(model, sys.argv[2])
    print(f"repair_onnx: {identities} Identity nodes removed, {clips} Clip nodes rewritten -> {sys.argv[2]}")


if __name__ == "__main__":
    main()
