"""MERL BRDF files (Matusik et al. 2003), read and written as the data set's
reference reader ``BRDFRead.cpp`` does (Rust: ``twoscale::merl``).

A file holds three int32 dimensions (90, 90, 180) and then red, green and
blue blocks of 90 × 90 × 180 float64 values, bin ``(ih, id, iφ)`` of a block
at ``iφ + 180 (id + 90 ih)``, with ``ih = ⌊√(θh/(π/2))·90⌋``,
``id = ⌊θd/(π/2)·90⌋`` and ``iφ = ⌊φd/π·180⌋`` (φd folded to [0, π) by
reciprocity). The BRDF is the stored value times ``SCALE[channel]``
(1/1500, 1.15/1500, 1.66/1500); a negative stored value is a missing sample.

Arrays have shape ``(3, 90, 90, 180)`` (channel, θh bin, θd bin, φd bin),
float64. ``read`` gives the BRDF in sr⁻¹ with **NaN where a sample is
missing**; ``write`` stores NaN as missing (−1) and refuses a negative or
infinite BRDF value (``ValueError`` with its index), and any other shape.

Round trips: ``write(path, read(path))`` rewrites a file byte for byte
when ``raw=True`` (the stored values as they are). With the default
``raw=False``, ``write`` stores, for each value, a number the reference
reader scales back to exactly that value when there is one, so every array
``read`` returns (and every file ``write`` wrote) round-trips exactly; other
values come back within one ulp (not every float64 is a float64 times the
scale). A file from elsewhere may hold two stored values that scale to the
same BRDF: only the raw mode keeps which.
"""

from __future__ import annotations

import os

import numpy as np

from . import _native

SHAPE = (3, 90, 90, 180)
"""(channel, θh bin, θd bin, φd bin) of a file's values."""
BINS = 90 * 90 * 180
"""Bins per channel."""
SCALE = tuple(_native.MERL_SCALE)
"""BRDF = stored value × SCALE[channel] (red, green, blue)."""
FILE_BYTES = _native.MERL_FILE_BYTES
"""The size of every MERL file."""

__all__ = [
    "BINS",
    "FILE_BYTES",
    "SCALE",
    "SHAPE",
    "bin_centres",
    "decode",
    "encode",
    "index",
    "lookup",
    "read",
    "tabulate",
    "write",
]


def decode(data: bytes, *, raw: bool = False) -> np.ndarray:
    """The values of a file's bytes, ``(3, 90, 90, 180)`` float64: the BRDF
    (NaN where missing), or the stored values with ``raw=True``. Raises
    ``ValueError`` for a wrong size or header."""
    return _native.merl_decode(bytes(data), not raw)


def encode(values, *, raw: bool = False) -> bytes:
    """The bytes of a file holding ``values`` (``(3, 90, 90, 180)``): BRDF
    values (NaN: missing; finite and ≥ 0 otherwise), or with ``raw=True``
    the stored values as they are (negative: missing). Raises
    ``ValueError`` for another shape, or a negative or infinite BRDF value
    (naming its index)."""
    a = np.ascontiguousarray(values, dtype=np.float64)
    return _native.merl_encode(a, not raw)


def read(path: str | os.PathLike, *, raw: bool = False) -> np.ndarray:
    """``decode`` of the file at ``path``; its ``ValueError`` starts with
    the path (``OSError`` if the file cannot be read)."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        return decode(data, raw=raw)
    except ValueError as e:
        raise ValueError(f"{os.fspath(path)}: {e}") from None


def write(path: str | os.PathLike, values, *, raw: bool = False) -> None:
    """Writes ``encode(values, raw=raw)`` to ``path``."""
    data = encode(values, raw=raw)
    with open(path, "wb") as f:
        f.write(data)


def _unit_rows(name, w):
    w = np.asarray(w, dtype=np.float64)
    if w.ndim != 2 or w.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {w.shape}")
    return np.ascontiguousarray(w / np.linalg.norm(w, axis=1, keepdims=True))


def index(wi, wo) -> np.ndarray:
    """The bin (position in a channel block, ``0 ≤ k < BINS``) of each pair
    of directions (``(N, 3)``, normalised here; ``wi`` incident): the
    reference reader's ``lookup_brdf_val`` index. ``values.reshape(3, -1)[:, k]``
    is the RGB there."""
    return _native.merl_index(_unit_rows("wi", wi), _unit_rows("wo", wo))


def lookup(values, wi, wo) -> np.ndarray:
    """The RGB of ``values`` (as ``read`` returns them) at each direction
    pair: ``(N, 3)``, NaN where missing."""
    flat = np.asarray(values).reshape(3, BINS)
    return flat[:, index(wi, wo)].T


def bin_centres(bins=None) -> tuple[np.ndarray, np.ndarray]:
    """``(wi, wo)``, each ``(N, 3)`` float64: the directions at the centre
    of each bin of ``bins`` (integers in ``[0, BINS)``; all bins in order
    when None), θh = (π/2)((ih + ½)/90)², θd = (π/2)(id + ½)/90,
    φd = π(iφ + ½)/180, φh = 0. Some lie below the horizon (``z < 0``);
    such bins hold no measurement."""
    if bins is None:
        return _native.merl_bin_centres()
    return _native.merl_bin_centres(np.ascontiguousarray(bins, dtype=np.int64))


def tabulate(brdf, chunk: int = 1 << 18) -> np.ndarray:
    """A ``(3, 90, 90, 180)`` array of ``brdf(wi, wo)`` (a function of
    ``(N, 3)`` direction arrays returning ``(N, 3)`` RGB in sr⁻¹, e.g.
    ``twoscale.Material.eval``) at the bin centres; NaN where either
    direction is below the horizon."""
    wi, wo = bin_centres()
    out = np.full((BINS, 3), np.nan)
    up = np.flatnonzero((wi[:, 2] > 0) & (wo[:, 2] > 0))
    for start in range(0, len(up), chunk):
        k = up[start : start + chunk]
        out[k] = brdf(wi[k], wo[k])
    return np.ascontiguousarray(out.T).reshape(SHAPE)


def mitsuba_brdf(bsdf):
    """``brdf(wi, wo)`` of a Mitsuba 3 BSDF (a loaded plugin, in the current
    variant, scalar or JIT), for ``tabulate``: ``bsdf.eval`` with the camera
    at ``wo`` and the light at ``wi``, divided by cos θi (Mitsuba's eval
    includes the cosine of its ``wo``, here the light's)."""
    import drjit as dr
    import mitsuba as mi

    def brdf(wi, wo):
        wi, wo = np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64)
        ctx = mi.BSDFContext()
        if dr.is_jit_v(mi.Float):
            si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
            si.wi = mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])
            value = bsdf.eval(ctx, si, mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2]))
            rgb = np.stack([np.array(value[c]) for c in range(3)], axis=1)
        else:
            rgb = np.empty((len(wi), 3))
            si = dr.zeros(mi.SurfaceInteraction3f)
            for j in range(len(wi)):
                si.wi = mi.Vector3f(wo[j])
                rgb[j] = np.array(bsdf.eval(ctx, si, mi.Vector3f(wi[j])))
        return rgb / wi[:, 2:3]

    return brdf
