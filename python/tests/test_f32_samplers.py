"""The f32 samplers invert their tables to f32 accuracy (issue 43 item 1):
the visible marginal's draw `x̃(u0)` of the port (visible.py, f32, from the
end where `u0 ≥ ½`: `lookups.sampler_tables`) against the tabulated
marginal `Φ` in f64 (the same tables): `|Φ(x̃) − u0 N|` relative to the
mass of x̃'s cell, which bounds the drawn density's relative error over
the cell. Measured max 5.0e-5 (Beckmann limit, θi = 89.5°; p99 ≤ 3.8e-6
at every θi, the f32 rounding of the returned normal included; 4e-8 with
the samplers in f64). Likewise the halo's draw of `ζ` in a row
(halo.py): `|F(ζ) − u total|` per cell mass, max 3.0e-5 (θi = 89°; 7.3e-3
without reading the row from its end where `u ≥ ½`)."""

import os

import numpy as np
import pytest

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")

import twoscale  # noqa: E402
from twoscale.drjit.models import Model  # noqa: E402

MATERIALS = {
    "beckmann-limit": lambda: twoscale.Material(
        beta=0.1, p=1.0, sigma_s=0.0, eta=[(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]),
    "gold-hp17-geometry": lambda: twoscale.Material.preset(
        "gold-hp17-geometry", rgb_mode="paper-wavelengths"),
}


def marginal(bakes, wi):
    """`Φ(x)` of the visible marginal at the unit `wi` (f64, from the
    bakes), the cells' nodes and masses, and `N`."""
    beta = float(bakes["visible_beta"])
    rows, p2 = np.asarray(bakes["visible_rows"], np.float64), np.asarray(bakes["visible_p2"])
    x_nodes = np.concatenate([-rows[:0:-1], rows])
    p_nodes = np.concatenate([p2[:0:-1], p2]).astype(np.float64)
    mass = np.asarray(bakes["visible_mass"], np.float64)
    moment = np.asarray(bakes["visible_moment"], np.float64)
    length = np.hypot(beta * wi[0], wi[2])
    c, s = wi[2] / length, beta * wi[0] / length

    def phi(x):
        j = np.clip(np.searchsorted(x_nodes, x, side="right") - 1, 0, len(x_nodes) - 2)
        x0, p0 = x_nodes[j], p_nodes[j]
        k = (p_nodes[j + 1] - p0) / (x_nodes[j + 1] - x0)
        a, tau = c - s * x0, x - x0
        return c * mass[j] - s * moment[j] + tau * (
            a * p0 + tau * (0.5 * (a * k - s * p0) - tau * (s * k / 3.0))), j

    top = min(c / s, x_nodes[-1]) if s > 0.0 else x_nodes[-1]
    ends = np.minimum(x_nodes, top)
    cells = np.diff(phi(ends)[0])
    return phi, cells, float(phi(np.array([top]))[0][0]), beta


@pytest.mark.parametrize("name", list(MATERIALS))
@pytest.mark.parametrize("theta", [0.0, 60.0, 85.0, 89.5])
def test_visible_marginal_inverts_its_table(name, theta):
    material = MATERIALS[name]()
    channel = Model(material).channels[0]
    t = np.radians(theta)
    wi = np.array([np.sin(t), 0.0, np.cos(t)], np.float32)
    phi, cells, norm, beta = marginal(material.bakes()[0], wi.astype(np.float64))
    n = 100_000
    rng = np.random.default_rng(7)
    u0, u1 = rng.random(n).astype(np.float32), rng.random(n).astype(np.float32)
    lanes = mi.Vector3f(*[mi.Float(np.full(n, v, np.float32)) for v in wi])
    m, ok = channel.visible_sample(lanes, mi.Float(u0), mi.Float(u1))
    dr.eval(m, ok)
    assert np.all(np.asarray(ok))
    x = -np.asarray(m.x, np.float64) / np.asarray(m.z, np.float64) / beta
    value, j = phi(x)
    err = np.abs(value - u0.astype(np.float64) * norm) / cells[j]
    assert err.max() <= 1e-4, (float(np.quantile(err, 0.99)), float(err.max()))


@pytest.mark.parametrize("theta", [30.0, 60.0, 85.0, 89.0])
def test_halo_row_inverts_its_table(theta):
    """The halo's ζ draw in row j (the lower row of `HaloBake::row_cell`,
    forced by the pick) against the row's cumulative law in f64: `F(ζ) =
    cum_k + start_k (ζ − ζ_k) + slope_k (ζ − ζ_k)²/2`, ζ from the returned
    half-vector (`sin²θh / (1 + cos θh)`)."""
    material = MATERIALS["gold-hp17-geometry"]()
    channel = Model(material).channels[0]
    bakes = material.bakes()[0]
    t = np.radians(theta)
    wi = np.array([np.sin(t), 0.0, np.cos(t)], np.float32)
    n = 100_000
    lanes = mi.Vector3f(*[mi.Float(np.full(n, v, np.float32)) for v in wi])
    row, frac = channel._row_cell(lanes)
    row, frac = int(np.asarray(row)[0]), float(np.asarray(frac)[0])
    assert frac < 1.0
    rng = np.random.default_rng(3)
    along = rng.random(n).astype(np.float32)
    pick = (rng.random(n) * (1.0 - frac) * 0.999).astype(np.float32)
    h, ok = channel.halo_sample(lanes, mi.Float(pick), mi.Float(along))
    hx, hy, hz = (np.asarray(v, np.float64) for v in (h.x, h.y, h.z))
    ok = np.asarray(ok)
    assert ok.mean() > 0.99
    z = (hx * hx + hy * hy) / (1.0 + hz)
    nodes = np.asarray(bakes["halo_zeta"], np.float64)[row]
    cum = np.asarray(bakes["halo_cum"], np.float64)[row]
    coef = np.asarray(bakes["halo_coef"], np.float64)[row]
    columns = channel.columns["halo_coef"]
    k = np.clip(np.searchsorted(nodes, z, side="right") - 1, 0, len(nodes) - 2)
    d = z - nodes[k]
    law = cum[k] + coef[k, columns["start"]] * d + 0.5 * coef[k, columns["slope"]] * d * d
    err = (np.abs(law - along * cum[-1]) / np.diff(cum)[k])[ok]
    assert err.max() <= 1e-4, (float(np.quantile(err, 0.99)), float(err.max()))


def test_guide_bin_is_the_exact_bin_or_the_one_below():
    """`visible.guide_bin` in f32 against `guide::position` in f64 (`e + f +
    octaves + linear·m`, mirrored): the exact bin, or the one below within
    2⁻⁹ above a bin's edge (the brackets take one more cell at their top for
    it), never the one above."""
    from twoscale.drjit.visible import guide_bin

    bakes = MATERIALS["beckmann-limit"]().bakes()[0]
    s = {k: float(bakes[k]) for k in ("guide_octaves", "guide_linear")}
    rng = np.random.default_rng(11)
    u = np.concatenate([rng.random(200_000), 10.0 ** rng.uniform(-12, 0, 100_000),
                        1.0 - 10.0 ** rng.uniform(-7, -0.31, 100_000)]).astype(np.float32)
    got = np.asarray(guide_bin(s, mi.Float(u)), np.int64)
    u64 = u.astype(np.float64)
    m = np.where(u64 < 0.5, u64, 1.0 - u64)
    mant, exp = np.frexp(m)  # m = mant 2^exp, mant ∈ [½, 1): e = exp − 1, f = 2 mant − 1
    half_pos = s["guide_octaves"] - 1.0 + 0.5 * s["guide_linear"]
    half = (np.maximum(exp - 1.0 + (2.0 * mant - 1.0) + s["guide_octaves"], 0.0)
            + s["guide_linear"] * m)
    position = np.where(u64 < 0.5, half, 2.0 * half_pos - half)
    exact = np.clip(np.floor(position), 0, int(2 * half_pos) - 1).astype(np.int64)
    assert np.all((got == exact) | (got == exact - 1))
    inside = position - np.floor(position) >= 2.0 ** -9
    assert np.all(got[inside] == exact[inside])
