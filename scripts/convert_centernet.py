#!/usr/bin/python3
"""Converts the TF.js CenterNet graph model into a frozen TensorFlow GraphDef for OpenCV DNN.

The TF.js model (MobileNetV3 + CenterNet head, 80 COCO classes) ships as a JSON topology plus a
float16 weight file. OpenCV 4.6 reads frozen GraphDefs but not TF.js, and it does not know the
grappler-fused ops the TF.js converter emits. This script therefore:

  * expands every weight to float32 (the manifest stores floats as float16),
  * splits `_FusedConv2D` / `FusedDepthwiseConv2dNative` into conv + BiasAdd + activation,
  * keeps only the nodes feeding the two raw head outputs, the class heatmap `tower_0/Sigmoid`
    (NHWC 1x128x128x80) and the box distances `tower_0/mul` (NHWC 1x128x128x4: left, top, right,
    bottom in input pixels). TopK/Gather post-processing is dropped: the C++ side decodes peaks.
  * writes int32 constants through `int_val` (OpenCV reads ConcatV2 axes from there) and float
    constants through `tensor_content`.

Standard library only: the protobuf wire format is written by hand.

Usage: convert_centernet.py --json centernet.json --bin centernet.bin --out centernet_coco.pb
"""

import argparse
import base64
import json
import math
import struct
import sys

OUTPUTS = ("tower_0/Sigmoid", "tower_0/mul")
DTYPES = {"DT_FLOAT": 1, "DT_INT32": 3, "DT_BOOL": 10, "DT_INT64": 9}
# Attributes that only matter to TensorFlow's own fused kernels or its optimizer.
DROPPED_ATTRS = ("fused_ops", "num_args", "epsilon", "leakyrelu_alpha")
ACTIVATIONS = {"Relu", "Relu6", "Elu", "Sigmoid", "Tanh"}


# ---------------------------------------------------------------- protobuf wire encoding
def varint(value):
    if value < 0:
        value += 1 << 64  # int64 fields use two's complement, ten bytes
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def field_varint(number, value):
    return varint(number << 3) + varint(value)


def field_bytes(number, payload):
    if isinstance(payload, str):
        payload = payload.encode("utf-8")
    return varint((number << 3) | 2) + varint(len(payload)) + payload


def field_float(number, value):
    return varint((number << 3) | 5) + struct.pack("<f", value)


def packed_varints(number, values):
    return field_bytes(number, b"".join(varint(v) for v in values))


def packed_floats(number, values):
    return field_bytes(number, struct.pack("<%df" % len(values), *values))


# ---------------------------------------------------------------- TensorFlow messages
def tensor_shape(dims):
    # TensorShapeProto.dim = 2, Dim.size = 1
    return b"".join(field_bytes(2, field_varint(1, d)) for d in dims)


def tensor_proto(dtype, shape, values):
    out = field_varint(1, DTYPES[dtype]) + field_bytes(2, tensor_shape(shape))
    if dtype == "DT_INT32":
        out += packed_varints(7, values)  # int_val: OpenCV reads axes and sizes from here
    elif len(values) == 1:
        out += packed_floats(5, values)  # float_val for scalars
    else:
        out += field_bytes(4, struct.pack("<%df" % len(values), *values))  # tensor_content
    return out


def attr_value(json_attr):
    """Encodes one AttrValue given in TF.js JSON form ({"i": "1"}, {"list": {...}}, ...)."""
    key, value = next(iter(json_attr.items()))
    if key == "s":
        return field_bytes(2, base64.b64decode(value))
    if key == "i":
        return field_varint(3, int(value))
    if key == "f":
        return field_float(4, float(value))
    if key == "b":
        return field_varint(5, 1 if value else 0)
    if key == "type":
        return field_varint(6, DTYPES[value])
    if key == "shape":
        return field_bytes(7, tensor_shape(int(d["size"]) for d in value.get("dim", [])))
    if key == "list":
        return field_bytes(1, list_value(value))
    raise ValueError("unsupported attr kind %r" % key)


def list_value(value):
    out = b""
    for s in value.get("s", []):
        out += field_bytes(2, base64.b64decode(s))
    if value.get("i"):
        out += packed_varints(3, [int(i) for i in value["i"]])
    if value.get("f"):
        out += packed_floats(4, [float(f) for f in value["f"]])
    if value.get("type"):
        out += packed_varints(6, [DTYPES[t] for t in value["type"]])
    return out


def node_def(name, op, inputs, attrs):
    """attrs maps names to already encoded AttrValue bytes."""
    out = field_bytes(1, name) + field_bytes(2, op)
    for i in inputs:
        out += field_bytes(3, i)
    for key in sorted(attrs):
        out += field_bytes(5, field_bytes(1, key) + field_bytes(2, attrs[key]))
    return out


# ---------------------------------------------------------------- TF.js model reading
def read_weights(manifest, blob):
    """Returns {name: (dtype, shape, values)} with floats widened to float32."""
    weights, offset = {}, 0
    for group in manifest:
        for w in group["weights"]:
            count = math.prod(w["shape"]) if w["shape"] else 1
            quant = w.get("quantization")
            if quant and quant.get("dtype") == "float16":
                fmt, size = "e", 2
            elif quant:
                raise ValueError("unsupported quantization %r for %s" % (quant, w["name"]))
            elif w["dtype"] == "int32":
                fmt, size = "i", 4
            else:
                fmt, size = "f", 4
            values = struct.unpack_from("<%d%s" % (count, fmt), blob, offset)
            offset += count * size
            dtype = "DT_INT32" if w["dtype"] == "int32" else "DT_FLOAT"
            weights[w["name"]] = (dtype, list(w["shape"]), list(values))
    if offset != len(blob):
        raise ValueError("weights use %d bytes but the .bin has %d" % (offset, len(blob)))
    return weights


def needed_nodes(by_name, outputs):
    """Names of the nodes the outputs depend on."""
    needed, stack = set(), list(outputs)
    while stack:
        name = stack.pop().split(":")[0].lstrip("^")
        if name in needed:
            continue
        if name not in by_name:
            raise ValueError("graph has no node %r" % name)
        needed.add(name)
        stack.extend(by_name[name].get("input", []))
    return needed


def plain_attrs(node):
    return {k: attr_value(v) for k, v in node.get("attr", {}).items()
            if k not in DROPPED_ATTRS and not k.startswith("_")}


def split_fused(node):
    """Yields (name, op, inputs, attrs) for conv, BiasAdd and the optional activation."""
    fused = [base64.b64decode(s).decode() for s in node["attr"]["fused_ops"]["list"]["s"]]
    if not fused or fused[0] != "BiasAdd" or len(fused) > 2 or (
            len(fused) == 2 and fused[1] not in ACTIVATIONS):
        raise ValueError("%s: unsupported fused_ops %r" % (node["name"], fused))
    conv_op = "Conv2D" if node["op"] == "_FusedConv2D" else "DepthwiseConv2dNative"
    name, inputs, attrs = node["name"], node["input"], plain_attrs(node)
    if conv_op == "DepthwiseConv2dNative":
        attrs.pop("use_cudnn_on_gpu", None)
    bias_attrs = {"T": attrs["T"], "data_format": attrs["data_format"]}
    bias_name = name if len(fused) == 1 else name + "/BiasAdd_split"
    yield name + "/conv_split", conv_op, inputs[:2], attrs
    yield bias_name, "BiasAdd", [name + "/conv_split", inputs[2]], bias_attrs
    if len(fused) == 2:
        yield name, fused[1], [bias_name], {"T": attrs["T"]}


def convert_node(node, weights):
    op = node["op"]
    if op == "Const":
        if node["name"] not in weights:
            raise ValueError("constant %s has no weights" % node["name"])
        dtype, shape, values = weights[node["name"]]
        attrs = {"dtype": field_varint(6, DTYPES[dtype]),
                 "value": field_bytes(8, tensor_proto(dtype, shape, values))}
        return [(node["name"], "Const", [], attrs)]
    if op in ("_FusedConv2D", "FusedDepthwiseConv2dNative"):
        return list(split_fused(node))
    return [(node["name"], op, node.get("input", []), plain_attrs(node))]


def convert(model, blob):
    weights = read_weights(model["weightsManifest"], blob)
    nodes = model["modelTopology"]["node"]
    by_name = {n["name"]: n for n in nodes}
    keep = needed_nodes(by_name, OUTPUTS)
    graph, counts = b"", {}
    for node in nodes:  # TF.js lists nodes in a valid topological order
        if node["name"] not in keep:
            continue
        for name, op, inputs, attrs in convert_node(node, weights):
            graph += field_bytes(1, node_def(name, op, inputs, attrs))
            counts[op] = counts.get(op, 0) + 1
    graph += field_bytes(4, field_varint(1, 27))  # VersionDef.producer
    return graph, counts


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", required=True, help="TF.js model.json")
    parser.add_argument("--bin", required=True, help="TF.js weight file")
    parser.add_argument("--out", required=True, help="frozen GraphDef to write")
    args = parser.parse_args()
    with open(args.json, encoding="utf-8") as f:
        model = json.load(f)
    with open(args.bin, "rb") as f:
        blob = f.read()
    try:
        graph, counts = convert(model, blob)
    except (ValueError, KeyError) as error:
        print("convert_centernet: %s" % error, file=sys.stderr)
        return 1
    with open(args.out, "wb") as f:
        f.write(graph)
    summary = ", ".join("%s %d" % kv for kv in sorted(counts.items()))
    print("wrote %s (%d bytes): %s" % (args.out, len(graph), summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
