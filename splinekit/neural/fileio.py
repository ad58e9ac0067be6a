"""The ``.nsdf`` file: one trained network (weights, latent codes, architecture, normalization).

A NumPy ``.npz`` archive read with ``allow_pickle=False`` (never pickle: a model file may come from
anyone), holding

* ``header``: UTF-8 JSON as uint8 bytes: ``{"magic": "splinekit-neural", "version": 1, "kind":
  "sdf" | "occupancy" | "family", "architecture": {...}, "center": [x, y, z], "scale": s,
  "info": {...}}``;
* ``W0, b0, W1, b1, ...``: float32 weights ``(fan_in, fan_out)`` and biases, in layer order;
* ``codes``: float32 latent codes ``(shapes, latent)`` (``(0, 0)`` without a latent code).

Written atomically (a temporary file renamed into place). Anything else (not a zip, a foreign
archive, a wrong magic or version, weights that do not fit the architecture, non-finite numbers)
raises FileFormatError naming the file and the problem.
"""

from __future__ import annotations

import json
import zipfile

import numpy as np

from .._atomic import atomic_write
from .._validate import as_path
from ..errors import FileFormatError, SplineKitError
from .network import Architecture

__all__ = ["KINDS", "MAGIC", "SUFFIX", "VERSION", "read", "write"]

MAGIC = "splinekit-neural"
VERSION = 1
SUFFIX = ".nsdf"
KINDS = ("sdf", "occupancy", "family")


def write(path, kind: str, arch: Architecture, params, codes, center, scale: float, info=None) -> str:
    """Write one model file; returns the path."""
    header = {"magic": MAGIC, "version": VERSION, "kind": kind, "architecture": arch.to_dict(),
              "center": [float(c) for c in center], "scale": float(scale), "info": info or {}}
    arrays = {"header": np.frombuffer(json.dumps(header).encode("utf-8"), dtype=np.uint8)}
    for k, layer in enumerate(params):
        arrays[f"W{k}"] = np.asarray(layer["W"], dtype=np.float32)
        arrays[f"b{k}"] = np.asarray(layer["b"], dtype=np.float32)
    arrays["codes"] = np.zeros((0, 0), np.float32) if codes is None else np.asarray(codes, dtype=np.float32)

    def save(tmp):
        with open(tmp, "wb") as fh:  # a file object: np.savez would append ".npz" to a name
            np.savez(fh, **arrays)

    return atomic_write(as_path(path), save, what="neural model")


def _bad(path, why: str) -> FileFormatError:
    return FileFormatError(f"{path!r} is not a splinekit neural model file ({SUFFIX}): {why}")


def read(path):
    """``(kind, arch, params, codes or None, center (3,), scale, info)`` of a model file."""
    path = as_path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
    except FileNotFoundError:
        raise FileFormatError(f"{path!r} does not exist") from None
    except IsADirectoryError:
        raise FileFormatError(f"{path!r} is a folder, not a model file") from None
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, RuntimeError) as exc:
        raise _bad(path, f"not a NumPy archive ({exc})") from None
    raw = arrays.get("header")
    if raw is None or raw.dtype != np.uint8 or raw.ndim != 1:
        raise _bad(path, "no header")
    try:
        header = json.loads(raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise _bad(path, "the header is not JSON") from None
    if not isinstance(header, dict) or header.get("magic") != MAGIC:
        raise _bad(path, "wrong magic")
    if header.get("version") != VERSION:
        raise _bad(path, f"version {header.get('version')!r}, this splinekit reads version {VERSION}")
    kind = header.get("kind")
    if kind not in KINDS:
        raise _bad(path, f"unknown kind {kind!r}")
    try:
        arch = Architecture(**header["architecture"])
        center = np.asarray(header["center"], dtype=np.float64)
        scale = float(header["scale"])
    except (SplineKitError, KeyError, TypeError, ValueError) as exc:
        raise _bad(path, f"malformed header ({exc})") from None
    if center.shape != (3,) or not np.isfinite(center).all() or not (np.isfinite(scale) and scale > 0):
        raise _bad(path, f"bad normalization (center {center.tolist()}, scale {scale!r})")
    params = []
    for k, (fan_in, fan_out) in enumerate(arch.layer_sizes):
        W, b = arrays.get(f"W{k}"), arrays.get(f"b{k}")
        if W is None or b is None or W.shape != (fan_in, fan_out) or b.shape != (fan_out,):
            raise _bad(path, f"layer {k} does not match the architecture (expected {(fan_in, fan_out)})")
        params.append({"W": W, "b": b})
    codes = arrays.get("codes")
    want = (0, 0) if arch.latent == 0 else (None, arch.latent)
    if codes is None or codes.ndim != 2 or (want[0] is not None and codes.shape != want) or codes.shape[1] != want[1]:
        raise _bad(path, f"latent codes of shape {None if codes is None else codes.shape} for latent size {arch.latent}")
    for name, arr in [(f"W{k}", p["W"]) for k, p in enumerate(params)] + [(f"b{k}", p["b"]) for k, p in enumerate(params)] + [("codes", codes)]:
        if arr.dtype != np.float32:
            raise _bad(path, f"{name} is {arr.dtype}, expected float32")
        if not np.isfinite(arr).all():
            raise _bad(path, f"{name} holds non-finite numbers")
    extra = sorted(set(arrays) - {"header", "codes"} - {f"{c}{k}" for k in range(len(params)) for c in "Wb"})
    if extra:
        raise _bad(path, f"unexpected arrays {extra}")
    info = header.get("info") if isinstance(header.get("info"), dict) else {}
    return kind, arch, params, (codes if arch.latent else None), center, scale, info
