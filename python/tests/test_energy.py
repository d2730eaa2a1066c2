"""The energy-compensation option (`multiple_scattering="kulla-conty"`,
docs/model.md §2.11) through Python: the keyword, its refusal, a material
file, the white furnace by the mean sampling weight, and the reference."""

import numpy as np
import pytest

import twoscale

GOLD = [(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]


def albedo(material, theta_deg, n=200_000, seed=5):
    """Mean sampling weight ρ cos θo / pdf at incidence θ (per channel)."""
    t = np.radians(theta_deg)
    wi = np.broadcast_to(np.array([np.sin(t), 0.0, np.cos(t)], dtype=np.float32), (n, 3))
    u = np.random.default_rng(seed).random((n, 3), dtype=np.float32)
    _, _, weight = material.sample(wi, u)
    return weight.mean(axis=0), weight.std(axis=0) / np.sqrt(n)


@pytest.mark.parametrize("theta", [0, 60, 85])
def test_white_furnace_is_one(theta):
    """β = 1, p = 1 loses up to half the light; compensated, the white
    furnace is 1 ± 0.005 (plus 4 standard errors)."""
    kw = dict(beta=1.0, p=1.0, eta=GOLD, colour="white")
    off, _ = albedo(twoscale.Material(**kw), theta)
    on, se = albedo(twoscale.Material(**kw, multiple_scattering="kulla-conty"), theta)
    assert np.all(off < 0.95), off
    assert np.all(np.abs(on - 1.0) < 0.005 + 4 * se), (on, se)


def test_keyword_names_and_refusal():
    m = twoscale.Material.preset("gold-rough", multiple_scattering="kulla-conty")
    assert m.options["multiple_scattering"] == "kulla-conty"
    assert twoscale.Material.preset("gold-rough").options["multiple_scattering"] == "none"
    assert twoscale.OPTIONS["multiple_scattering"] == ("none", "kulla-conty")
    with pytest.raises(ValueError, match="multiple_scattering must be one of 'none' or "
                                         "'kulla-conty', got 'kc'"):
        twoscale.Material(beta=0.1, p=1, eta=GOLD, multiple_scattering="kc")


def test_material_file_takes_the_option():
    text = ("[material]\nbeta = 0.6\np = 1\neta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]\n"
            'multiple_scattering = "kulla-conty"\n')
    m = twoscale.Material.from_toml_string(text)
    kw = twoscale.Material(beta=0.6, p=1, eta=GOLD, multiple_scattering="kulla-conty")
    wi = np.array([[0.3, 0.1, 0.9487]], dtype=np.float32)
    wo = np.array([[-0.5, 0.2, 0.8426]], dtype=np.float32)
    assert np.array_equal(m.eval(wi, wo), kw.eval(wi, wo))
    off = twoscale.Material(beta=0.6, p=1, eta=GOLD)
    assert np.all(m.eval(wi, wo) > off.eval(wi, wo))


def test_reference_has_the_lobe_without_diffraction():
    """eval_reference adds the reference's lobe (σs = 0) and agrees with
    eval to 1e-4 relative; with diffraction it refuses."""
    m = twoscale.Material(beta=0.6, p=0.6, eta=GOLD, multiple_scattering="kulla-conty")
    wi = np.array([[0.5, 0.0, 0.866], [0.95, 0.0, 0.3122]], dtype=np.float32)
    wo = np.array([[-0.45, 0.05, 0.89], [0.2, 0.9, 0.3873]], dtype=np.float32)
    ref = m.eval_reference(wi, wo)
    assert np.all(np.abs(m.eval(wi, wo) - ref) <= 1e-4 * ref)
    halo = twoscale.Material.preset("gold-rough", multiple_scattering="kulla-conty")
    with pytest.raises(ValueError, match="without diffraction"):
        halo.eval_reference(wi, wo)
