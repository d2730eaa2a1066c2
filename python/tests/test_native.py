"""The package against `generator query` (same rows, same runtime and
reference code: values must agree exactly), and its error handling."""

import numpy as np
import pytest

import twoscale
from twoscale import lookup, reference

RNG = np.random.default_rng(14)


def assert_same_f32(ours, printed):
    """The runtime's f32 values: the query prints them in shortest form, so
    compare after rounding both to f32."""
    np.testing.assert_array_equal(np.float32(ours), np.float32(printed))


def hemisphere(n, z_min=0.05):
    """n unit vectors with z in [z_min, 1]."""
    z = RNG.uniform(z_min, 1.0, n)
    phi = RNG.uniform(0.0, 2 * np.pi, n)
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def test_g1_matches_query(generator_query):
    p, a = RNG.uniform(0.3, 4.0, 64), RNG.uniform(0.05, 6.0, 64)
    out = generator_query("g1", {"p": p, "a": a})
    assert_same_f32(lookup.g1(p, a), out["table"])
    np.testing.assert_array_equal(reference.g1(p, a), out["reference"])


def test_sigma_ratio_matches_query(generator_query):
    th, bb, c = RNG.uniform(0, 1.5, 48), RNG.uniform(0.5, 40, 48), RNG.uniform(1.2, 4, 48)
    out = generator_query("sigma-ratio", {"theta_i": th, "B": bb, "c": c})
    assert_same_f32(lookup.sigma_ratio(th, bb, c), out["table"])
    np.testing.assert_array_equal(reference.sigma_ratio(th, bb, c), out["reference"])


def test_fresnel_matches_query(generator_query):
    n, k, cos = RNG.uniform(0.1, 3, 64), RNG.uniform(0, 5, 64), RNG.uniform(0, 1, 64)
    out = generator_query("fresnel", {"n": n, "k": k, "cos_theta": cos})
    assert_same_f32(lookup.fresnel(n, k, cos), out["table"])
    np.testing.assert_array_equal(reference.fresnel(n, k, cos), out["reference"])


def test_conv_matches_query(generator_query):
    m = 12
    cols = {
        "u": RNG.uniform(0.5, 20, m),
        "c": RNG.uniform(1.3, 3.5, m),
        "beta": RNG.uniform(0.02, 0.5, m),
        "p": RNG.uniform(0.5, 2.5, m),
        "theta_h": RNG.uniform(0, 0.6, m),
    }
    out = generator_query("conv", cols)
    args = (cols["theta_h"], cols["u"], cols["c"], cols["beta"], cols["p"])
    assert_same_f32(lookup.conv(*args), out["table"])
    assert_same_f32(lookup.conv(*args, fit=True), out["fit"])
    np.testing.assert_array_equal(reference.conv(*args), out["reference"])


BRDF_PARAMS = [
    dict(beta=0.0598, p=1.0, sigma_s=0.0273, b=4.8418, c=2.0, n=0.584, k=2.15, lam=0.526),
    dict(beta=0.3, p=0.6, sigma_s=0.05, b=2.0, c=1.6, n=1.5, k=0.0, lam=0.645),
]


@pytest.mark.parametrize("params", BRDF_PARAMS)
def test_brdf_matches_query(generator_query, params):
    n = 12
    wi, wo = hemisphere(n), hemisphere(n)
    wo[:4] = wi[:4] * [-1, -1, 1]  # near the specular peak
    wi, wo = wi.astype(np.float32), wo.astype(np.float32)  # the query reads f32
    cols = {k: np.full(n, v) for k, v in params.items() if k != "lam"}
    cols["lambda"] = np.full(n, params["lam"])
    for name, d in (("i", wi), ("o", wo)):
        for j, axis in enumerate("xyz"):
            cols[name + axis] = d[:, j]
    out = generator_query("brdf", cols)
    assert_same_f32(lookup.brdf(wi, wo, **params), out["table"])
    np.testing.assert_array_equal(reference.brdf(wi, wo, **params), out["reference"])
    assert np.all(out["reference"] > 0)


def test_material_channels_match_query(generator_query):
    """Material.eval and eval_reference are the one-wavelength model of each
    channel at RGB_WAVELENGTHS with the channel's index."""
    m = twoscale.Material.preset("gold-hp17-geometry")
    n = 10
    wi, wo = hemisphere(n).astype(np.float32), hemisphere(n).astype(np.float32)
    wo[:5] = wi[:5] * [-1, -1, 1]
    rgb, rgb_ref = m.eval(wi, wo), m.eval_reference(wi, wo)
    for ch, lam in enumerate(twoscale.RGB_WAVELENGTHS):
        n_, k_ = m.eta[ch]
        params = dict(beta=m.beta, p=m.p, sigma_s=m.sigma_s, b=m.b, c=m.c, n=n_, k=k_, lam=lam)
        cols = {k: np.full(n, np.float32(v)) for k, v in params.items() if k != "lam"}
        cols["lambda"] = np.full(n, np.float32(lam))
        for name, d in (("i", wi), ("o", wo)):
            for j, axis in enumerate("xyz"):
                cols[name + axis] = d[:, j]
        out = generator_query("brdf", cols)
        np.testing.assert_array_equal(rgb[:, ch], out["table"].astype(np.float32))
        np.testing.assert_array_equal(rgb_ref[:, ch], out["reference"])


@pytest.mark.parametrize("name", twoscale.Material.presets())
def test_sample_pdf_eval_agree(name):
    m = twoscale.Material.preset(name)
    n = 4000
    wi = hemisphere(n)
    dirs, pdf, weight = m.sample(wi, RNG.random((n, 3)))
    ok = pdf > 0
    assert ok.mean() > 0.5
    np.testing.assert_array_equal(dirs[~ok], 0)
    np.testing.assert_array_equal(weight[~ok], 0)
    np.testing.assert_allclose(np.linalg.norm(dirs[ok], axis=1), 1, rtol=1e-5)
    assert np.all(dirs[ok, 2] > 0)
    np.testing.assert_allclose(m.pdf(wi[ok], dirs[ok]), pdf[ok], rtol=1e-6)
    expected = m.eval(wi[ok], dirs[ok]) * dirs[ok, 2:3] / pdf[ok, None]
    np.testing.assert_allclose(weight[ok], expected, rtol=1e-5)


def test_pdf_integrates_to_at_most_one():
    """∫ pdf dω over the hemisphere, by a midpoint rule in (cos θ, φ)."""
    m = twoscale.Material.preset("gold-rough")
    k = 400
    z = (np.arange(k) + 0.5) / k
    phi = (np.arange(2 * k) + 0.5) / (2 * k) * 2 * np.pi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1 - zz**2)
    wo = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    wi = np.tile([[np.sin(0.5), 0.0, np.cos(0.5)]], (len(wo), 1))
    integral = m.pdf(wi, wo).sum() * (1 / k) * (2 * np.pi / (2 * k))
    assert 0.95 < integral <= 1.0 + 1e-3


def test_float32_and_float64_agree_and_parallel_equals_serial():
    m = twoscale.Material.preset("marble")
    wi, wo = hemisphere(10000), hemisphere(10000)
    big = m.eval(wi, wo)  # parallel path (N ≥ 2048)
    small = np.concatenate([m.eval(wi[j : j + 1000], wo[j : j + 1000]) for j in range(0, 10000, 1000)])
    np.testing.assert_array_equal(big, small)
    np.testing.assert_array_equal(m.eval(wi.astype(np.float32), wo.astype(np.float32)), big)
    assert big.dtype == np.float32 and big.shape == (10000, 3)
    assert m.pdf(wi, wo).shape == (10000,)


def test_bad_arrays_raise_value_error():
    m = twoscale.Material.preset("marble")
    good = np.array([[0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match=r"wi must have shape \(N, 3\)"):
        m.eval(np.zeros((2, 2)), good)
    with pytest.raises(ValueError, match="float32 or float64.*int64"):
        m.eval(np.zeros((1, 3), dtype=np.int64), good)
    with pytest.raises(ValueError, match="wo must be a float32 or float64 array.*list"):
        m.eval(good, [[0, 0, 1]])
    with pytest.raises(ValueError, match="wi has 2 rows but wo has 1"):
        m.pdf(np.tile(good, (2, 1)), good)
    with pytest.raises(ValueError, match="wi has 1 rows but u has 3"):
        m.sample(good, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="do not broadcast"):
        lookup.g1([1.0, 1.0], [1.0, 2.0, 3.0])


def test_bad_parameters_raise_value_error():
    gold = [(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]
    with pytest.raises(ValueError, match="unknown material|nope"):
        twoscale.Material.preset("nope")
    with pytest.raises(ValueError, match=r"p must be in \[0.2, 5\]"):
        twoscale.Material(beta=0.1, p=7, eta=gold)
    with pytest.raises(ValueError, match="beta must be in"):
        twoscale.Material(beta=-1, p=1, eta=gold)
    with pytest.raises(ValueError, match="sigma_s must be finite and ≥ 0"):
        twoscale.Material(beta=0.1, p=1, eta=gold, sigma_s=-0.1)
    with pytest.raises(ValueError, match="c must be finite and > 1"):
        twoscale.Material(beta=0.1, p=1, eta=gold, c=1.0)
    with pytest.raises(ValueError, match="eta must be three"):
        twoscale.Material(beta=0.1, p=1, eta=gold[:2])
    with pytest.raises(ValueError, match="needs albedo"):
        twoscale.Material(beta=0.1, p=1, eta=gold, base="plastic")
    with pytest.raises(ValueError, match="albedo= is for base"):
        twoscale.Material(beta=0.1, p=1, eta=gold, albedo=0.5)
    with pytest.raises(ValueError, match="base must be"):
        twoscale.Material(beta=0.1, p=1, eta=gold, base="glass")
    with pytest.raises(ValueError, match="colour must be one of 'physical', 'white'"):
        twoscale.Material.preset("marble", colour="grey")
    with pytest.raises(ValueError, match="covers conductors"):
        twoscale.Material.preset("marble").eval_reference(np.ones((1, 3)), np.ones((1, 3)))


def test_explicit_material_equals_preset():
    ref = twoscale.Material.preset("white-plastic", sigma_rel="symmetrised")
    m = twoscale.Material(
        beta=ref.beta, p=ref.p, sigma_s=ref.sigma_s, b=ref.b, c=ref.c, eta=ref.eta,
        base=ref.base, albedo=ref.albedo, lambertian=ref.lambertian, **ref.options,
    )
    assert m.options["sigma_rel"] == "symmetrised"
    wi, wo = hemisphere(100), hemisphere(100)
    np.testing.assert_array_equal(m.eval(wi, wo), ref.eval(wi, wo))
