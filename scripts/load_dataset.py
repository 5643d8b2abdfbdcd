"""Load an ltmsim dataset (docs/dataset.md) with numpy alone.

    import sys; sys.path.insert(0, "scripts")
    from load_dataset import load_sample, iterate
    features, mask, labels = load_sample("out/ds/samples/000000")
    for features, mask, labels in iterate("out/ds", split="train"):
        ...

features: a dict channel name -> float32 array of shape (rows, columns) (features.npz holds the
          same channels as features.exr), row 0 the top (+y) edge of the camera image;
mask:     a uint16 array (rows, columns): 0 background, k the k-th defect of labels["defects"];
labels:   the sample's labels.json as a dict.

mask.png is decoded here (zlib and the five PNG row filters, greyscale 16-bit only, as ltmsim
writes it), so no image library is needed.
"""
import json
import os
import struct
import zlib

import numpy as np

__all__ = ["load_sample", "iterate", "read_png16"]


def _paeth(a, b, c):
    p = a.astype(np.int32) + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


def read_png16(path):
    """A 16-bit greyscale PNG (non-interlaced) as a uint16 array (rows, columns)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, header = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + length
    if header is None:
        raise ValueError(f"{path}: no IHDR chunk")
    width, height, depth, colour, _, _, interlace = header
    if depth != 16 or colour != 0 or interlace != 0:
        raise ValueError(f"{path}: expected a 16-bit greyscale, non-interlaced PNG "
                         f"(bit depth {depth}, colour type {colour}, interlace {interlace})")
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    stride, bpp = 2 * width, 2
    raw = raw.reshape(height, stride + 1)
    out = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.uint8)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        cur = np.zeros(stride, dtype=np.int32)
        if kind == 0:
            cur = line
        elif kind == 2:
            cur = (line + prev) & 0xFF
        elif kind in (1, 3, 4):  # these depend on the bytes to the left: byte by byte
            for x in range(stride):
                left = cur[x - bpp] if x >= bpp else 0
                up = int(prev[x])
                upleft = int(prev[x - bpp]) if x >= bpp else 0
                if kind == 1:
                    pred = left
                elif kind == 3:
                    pred = (left + up) // 2
                else:
                    pred = int(_paeth(np.int32(left), np.int32(up), np.int32(upleft)))
                cur[x] = (line[x] + pred) & 0xFF
        else:
            raise ValueError(f"{path}: unknown PNG filter {kind} in row {y}")
        out[y] = cur.astype(np.uint8)
        prev = out[y]
    return out.view(">u2").astype(np.uint16).reshape(height, width)


def load_sample(folder):
    """(features, mask, labels) of one sample folder."""
    with np.load(os.path.join(folder, "features.npz")) as z:
        features = {name: z[name] for name in z.files}
    mask = read_png16(os.path.join(folder, "mask.png"))
    with open(os.path.join(folder, "labels.json")) as f:
        labels = json.load(f)
    return features, mask, labels


def iterate(dataset, split=None):
    """(features, mask, labels) of every sample listed in DATASET/index.jsonl, in order; only
    those of `split` if given."""
    with open(os.path.join(dataset, "index.jsonl")) as f:
        for line in f:
            entry = json.loads(line)
            if split is not None and entry["split"] != split:
                continue
            yield load_sample(os.path.join(dataset, entry["folder"]))
