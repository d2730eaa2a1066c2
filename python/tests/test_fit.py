"""twoscale.fit on small cases: recovery of a model-written MERL file, the
TOML round trip, the command line on files from twoscale.merl.write and
from this test's own writer, and Mitsuba's Beckmann roughconductor."""

import math
import struct
import subprocess
import sys
import tomllib

import numpy as np
import pytest

import twoscale
from twoscale import merl
from twoscale.fit import fit, grazing, load, stratified_directions

TRUTH = dict(beta=0.12, p=1.4, sigma_s=0.02, b=3.0, c=2.5, eta=[(0.3, 3.0), (0.6, 2.4), (1.2, 1.8)])


@pytest.fixture(scope="module")
def model_file():
    """The model at TRUTH tabulated at the bin centres, θd > 80° and 1% of
    the bins missing."""
    values = merl.tabulate(twoscale.Material(**TRUTH).eval)
    rng = np.random.default_rng(0)
    theta_d = np.pi / 2 * (np.arange(90) + 0.5) / 90
    values[:, :, theta_d > math.radians(80), :] = np.nan
    values[:, rng.uniform(size=merl.SHAPE[1:]) < 0.01] = np.nan
    return values


def test_recovers_the_lobe_of_a_model_file_from_a_perturbed_start(model_file):
    start = dict(beta=0.15, p=1.1, sigma_s=0.03, b=2.0, c=2.0, eta=[(0.4, 2.5), (0.5, 2.0), (1.0, 2.2)])
    r = fit(model_file, samples=1500, starts=1, lambertian=False, verbose=False, **start)
    assert abs(r.keywords["beta"] / TRUTH["beta"] - 1) < 0.03
    assert abs(r.keywords["p"] / TRUTH["p"] - 1) < 0.05
    assert r.metrics["relative_rms"] < 0.02
    assert r.metrics["smape"] < 0.02
    assert len(r.metrics["rmse_theta_i"]) == len(r.metrics["rmse_theta_i_deg"]) == 18


def test_the_toml_rebuilds_the_material(model_file):
    r = fit(model_file, samples=600, starts=1, max_nfev=3, verbose=False, **TRUTH)
    data = tomllib.loads(r.toml())
    rebuilt = twoscale.Material(**data["material"])
    wi, wo = stratified_directions(200, np.random.default_rng(1))
    np.testing.assert_array_equal(rebuilt.eval(wi, wo), r.material.eval(wi, wo))
    assert set(data["metrics"]) >= {"rmse", "rmse_theta_i", "smape", "relative_rms"}


def test_grazing_loss_is_hp17_60():
    wi = np.array([[math.sin(1.0), 0, math.cos(1.0)]])
    wo = np.array([[0.0, math.sin(0.5), math.cos(0.5)]])
    p1 = lambda t, k: (1 - 4 * t * t / math.pi**2) ** k  # noqa: E731
    assert grazing(wi, wo, 0.7)[0] == pytest.approx(p1(1.0, 0.7) * p1(0.5, 0.7), rel=1e-12)
    assert grazing(wi, wo, 0.0)[0] == 1.0


@pytest.mark.parametrize("writer", ["twoscale", "own"])
def test_command_line_fits_a_file(tmp_path, model_file, writer):
    path = tmp_path / "m.binary"
    if writer == "twoscale":
        merl.write(path, model_file)
    else:
        # The reference layout, written by hand: header, then red/green/blue
        # blocks of stored values (BRDF / scale, −1 where missing).
        scale = np.array([1.0, 1.15, 1.66])[:, None, None, None] / 1500.0
        stored = np.where(np.isnan(model_file), -1.0, model_file / scale)
        path.write_bytes(struct.pack("<3i", 90, 90, 180) + stored.astype("<f8").tobytes())
    out = tmp_path / "params.toml"
    subprocess.run(
        [sys.executable, "-m", "twoscale.fit", path, "--out", out, "--samples", "800", "--starts", "1"],
        check=True,
    )
    data = tomllib.loads(out.read_text())
    assert abs(data["material"]["beta"] / TRUTH["beta"] - 1) < 0.1
    loaded = load(out)
    assert loaded.beta == pytest.approx(data["material"]["beta"], rel=1e-6)


def test_mitsuba_beckmann_comes_back_as_p_1_and_beta_alpha():
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("llvm_ad_rgb" if "llvm_ad_rgb" in mi.variants() else "scalar_rgb")
    alpha = 0.15
    bsdf = mi.load_dict(
        {
            "type": "roughconductor",
            "distribution": "beckmann",
            "alpha": alpha,
            "eta": {"type": "rgb", "value": [0.2, 0.45, 1.4]},
            "k": {"type": "rgb", "value": [3.9, 2.5, 1.9]},
        }
    )
    wi, wo = stratified_directions(1500, np.random.default_rng(2))
    rgb = merl.mitsuba_brdf(bsdf)(wi, wo)
    r = fit((wi, wo, rgb), epd=True, lambertian=False, starts=1, verbose=False)
    assert abs(r.keywords["p"] - 1) < 0.1
    assert abs(r.keywords["beta"] / alpha - 1) < 0.08
