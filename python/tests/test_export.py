"""`generator export --format npy` (docs/export.md): the .npy arrays, read with
NumPy alone and decoded and interpolated at grid nodes as docs/export.md
says, reproduce the runtime's lookups (``twoscale.lookup``)."""

import json
import subprocess

import numpy as np
import pytest

import twoscale


@pytest.fixture(scope="session")
def exported(tmp_path_factory, cargo_build):
    """``(directory, tables.json)`` of an npy export of T1, T2, T3 (every
    precision each allows)."""
    generator = cargo_build("generator") / "generator"
    out = tmp_path_factory.mktemp("export")
    subprocess.run(
        [generator, "export", "--points", "0",
         "--table", "t1", "--table", "t2", "--table", "t3", "--out", out],
        check=True,
    )
    return out, json.loads((out / "tables.json").read_text())["tables"]


def nodes(meta, axis):
    return np.array(meta["axes"][axis]["node_values"])


def test_t1_nodes_are_the_runtime_g1(exported):
    out, tables = exported
    meta = tables["t1-smith-g1"]
    g1 = np.load(out / "t1-smith-g1.f32.npy")
    k_p = np.load(out / "t1-smith-g1.aux.npy")
    assert g1.dtype == np.float32 and g1.shape == (64, 1000)
    p, a_scaled = nodes(meta, 0), nodes(meta, 1)
    j, i = np.meshgrid(np.arange(0, 64, 3), np.arange(1, 1000, 37), indexing="ij")
    j, i = j.ravel(), i.ravel()
    # a = ã / k_p: the runtime multiplies back by its closed-form k_p.
    got = twoscale.lookup.g1(p[j], a_scaled[i] / k_p[j])
    np.testing.assert_allclose(got, g1[j, i], rtol=0, atol=2e-6)
    # Not trivially close: neighbouring nodes differ by far more.
    assert np.max(np.abs(g1[j, i] - g1[j, np.minimum(i + 1, 999)])) > 1e-3
    # unorm16: offset + code * step, within the rounding the JSON states.
    unorm = meta["precisions"]["unorm16"]
    codes = np.load(out / "t1-smith-g1.unorm16.npy")
    assert codes.dtype == np.uint16
    decoded = np.float32(unorm["offset"]) + codes.astype(np.float32) * np.float32(unorm["step"])
    err = np.max(np.abs(decoded.astype(np.float64) - g1))
    assert err == pytest.approx(unorm["rounding_max"], rel=1e-6)
    assert err <= unorm["rounding_budget"]


def bspline_at_nodes(coefficients):
    """The uniform cubic B-spline at its nodes: (c[j-1] + 4 c[j] + c[j+1]) / 6
    along every axis (coefficient j sits at node j - 1)."""
    values = coefficients.astype(np.float64)
    for axis in range(values.ndim):
        values = np.moveaxis(values, axis, 0)
        values = (values[:-2] + 4 * values[1:-1] + values[2:]) / 6
        values = np.moveaxis(values, 0, axis)
    return values


def test_t2_spline_at_nodes_is_the_runtime_sigma_ratio(exported):
    out, tables = exported
    meta = tables["t2-sigma-ratio"]
    coefficients = np.load(out / "t2-sigma-ratio.f32.npy")
    assert coefficients.shape == (74, 70, 34)
    q = bspline_at_nodes(coefficients)
    cos, big_b, c = nodes(meta, 0), nodes(meta, 1), nodes(meta, 2)
    rng = np.random.default_rng(13)
    # c node 0 is c = 1, where σrel = 0.
    idx = (rng.integers(0, 72, 300), rng.integers(0, 68, 300), rng.integers(1, 32, 300))
    r0 = np.sqrt(-np.expm1(-(c[idx[2]] - 1) / 2 * np.log1p(big_b[idx[1]] ** 2)))
    want = q[idx] * r0
    got = twoscale.lookup.sigma_ratio(np.arccos(cos[idx[0]]), big_b[idx[1]], c[idx[2]])
    np.testing.assert_allclose(got, want, rtol=2e-5)
    # The unorm16 coefficients decode within their stated rounding.
    unorm = meta["precisions"]["unorm16"]
    codes = np.load(out / "t2-sigma-ratio.unorm16.npy")
    decoded = np.float32(unorm["offset"]) + codes.astype(np.float32) * np.float32(unorm["step"])
    assert np.max(np.abs(decoded - coefficients)) <= unorm["rounding_budget"]


def test_t3_nodes_are_the_runtime_convolution(exported):
    out, tables = exported
    meta = tables["t3-convolution"]
    values = np.load(out / "t3-convolution.f32.npy")
    assert values.shape == (28, 10, 12, 12, 34)
    # unorm16: the file's codes with a per-node (offset, step), decoded in f32
    # to exactly the f32 export.
    codes = np.load(out / "t3-convolution.unorm16.npy")
    scales = np.load(out / "t3-convolution.unorm16-scales.npy")
    decoded = scales[..., :1] + codes.astype(np.float32) * scales[..., 1:]
    assert decoded.dtype == np.float32
    np.testing.assert_array_equal(decoded, values)
    u, c, beta, p = (nodes(meta, d) for d in range(4))
    rng = np.random.default_rng(7)
    n = 200
    idx = tuple(rng.integers(0, len(x), n) for x in (u, c, beta, p))
    args = (u[idx[0]], c[idx[1]], beta[idx[2]], p[idx[3]])
    node = values[idx]
    # Every θh beyond atan(τ_max) is ξ = 1: channel 33, exactly. (θh = 0 is
    # not ξ = 0 in general: the edge term's smoothed onset is positive there.)
    tau_max = meta["params"]["tau_max"]
    beyond = 0.5 * (np.arctan(tau_max) + np.pi / 2)
    np.testing.assert_allclose(
        twoscale.lookup.conv(np.full(n, beyond), *args), np.exp(node[:, 33]), rtol=1e-4
    )
    # Not trivially close: the other end of the profile differs.
    assert np.median(np.abs(node[:, 33] - node[:, 2])) > 1
    # T3a at θh = 0: s · k(0) = s = exp(channel 0).
    np.testing.assert_allclose(
        twoscale.lookup.conv(np.zeros(n), *args, fit=True), np.exp(node[:, 0]), rtol=1e-4
    )
