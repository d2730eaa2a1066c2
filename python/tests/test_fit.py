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


# --- The command line's errors, the module's import ------------------------


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "twoscale.fit", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd)


def assert_one_line_error(done, status, *words):
    assert done.returncode == status, done.stdout + done.stderr
    assert done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), done.stderr
    assert "Traceback" not in done.stderr
    for word in words:
        assert word in lines[0], done.stderr


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    header = struct.pack("<3i", 90, 90, 180)
    files = {
        "truncated": d / "truncated.binary",
        "bad header": d / "header.binary",
        "empty": d / "empty.binary",
    }
    files["truncated"].write_bytes(header + b"\0" * 1000)
    files["bad header"].write_bytes(struct.pack("<3i", 90, 90, 360) + b"\0" * (merl.FILE_BYTES - 12))
    files["empty"].write_bytes(b"")
    return files


@pytest.mark.parametrize("name, words", [
    ("truncated", ["truncated.binary: ", "1012 bytes, expected 34992012"]),
    ("bad header", ["header.binary: ", "header dimensions [90, 90, 360]"]),
    ("empty", ["empty.binary: ", "0 bytes"]),
])
def test_a_file_that_is_not_a_merl_file_is_one_line_and_status_1(bad_files, name, words):
    assert_one_line_error(run_cli(bad_files[name]), 1, *words)


def test_a_missing_file_or_a_directory_is_one_line_and_status_1(tmp_path):
    assert_one_line_error(run_cli(tmp_path / "absent.binary"), 1, "absent.binary", "No such file")
    assert_one_line_error(run_cli(tmp_path), 1, "Is a directory")


@pytest.mark.parametrize("option, words", [
    (["--samples", "-5"], ["samples must be an integer ≥ 100, got -5"]),
    (["--samples", "0"], ["samples must be an integer ≥ 100, got 0"]),
    (["--starts", "0"], ["starts must be an integer ≥ 1, got 0"]),
    (["--seed", "-1"], ["seed must be an integer ≥ 0, got -1"]),
    (["--refine-samples", "-3"], ["refine_samples must be 0 or an integer ≥ 100, got -3"]),
    (["--grazing-k", "-1"], ["grazing_k must be a finite number ≥ 0, got -1.0"]),
    (["--grazing-k", "nan"], ["grazing_k must be a finite number ≥ 0, got nan"]),
])
def test_a_bad_value_is_one_line_and_status_1(tmp_path, model_file, option, words):
    path = tmp_path / "m.binary"
    merl.write(path, model_file)
    assert_one_line_error(run_cli(path, *option), 1, *words)


@pytest.mark.parametrize("args, words", [
    (["FILE", "--samples", "many"], ["argument --samples: invalid int value: 'many'"]),
    (["FILE", "--base", "wood"], ["argument --base: invalid choice: 'wood'"]),
    ([], ["the following arguments are required: file"]),
    (["FILE", "--colour", "x"], ["unrecognized arguments: --colour x"]),
])
def test_a_bad_command_line_is_one_line_and_status_2(tmp_path, args, words):
    path = tmp_path / "m.binary"
    path.write_bytes(b"")
    assert_one_line_error(run_cli(*[path if a == "FILE" else a for a in args]), 2, *words)


def test_an_unwritable_output_is_one_line_and_status_1(tmp_path, model_file):
    path = tmp_path / "m.binary"
    merl.write(path, model_file)
    # Refused before the fit.
    out = tmp_path / "no" / "such" / "params.toml"
    assert_one_line_error(run_cli(path, "--out", out), 1, f"--out {out}: ", "is not a writable directory")


def test_the_module_runs_without_a_runtime_warning_and_the_package_attribute_is_the_module(tmp_path):
    done = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-m", "twoscale.fit", "--help"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "RuntimeWarning" not in done.stderr, done.stderr
    # `import twoscale` alone: twoscale.fit is the module (docs/fitting.md's
    # twoscale.fit.load), imported on first use, SciPy with it.
    code = ("import sys, twoscale; assert 'scipy' not in sys.modules; "
            "import types; assert isinstance(twoscale.fit, types.ModuleType); "
            "assert callable(twoscale.fit.load) and callable(twoscale.fit.fit); print('ok')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout == "ok\n", done.stderr


@pytest.mark.parametrize("keywords, error, words", [
    (dict(samples=-5), ValueError, "samples must be an integer ≥ 100, got -5"),
    (dict(samples=2.5), ValueError, "samples must be an integer ≥ 100, got 2.5"),
    (dict(starts=True), ValueError, "starts must be an integer ≥ 1, got True"),
    (dict(seed=-1), ValueError, "seed must be an integer ≥ 0, got -1"),
    (dict(seed=0.5), ValueError, "seed must be an integer ≥ 0, got 0.5"),
    (dict(max_nfev=0), ValueError, "max_nfev must be None or an integer ≥ 1, got 0"),
    (dict(base="wood"), ValueError, "base must be one of conductor, plastic, subsurface, got 'wood'"),
    (dict(fixed=["bta"]), ValueError, "fixed names parameters of"),
    (dict(fixed="beta"), ValueError, "fixed names parameters of"),
    (dict(bta=0.1), TypeError, "unexpected keyword argument 'bta'"),
])
def test_fit_refuses_bad_arguments_by_name(model_file, keywords, error, words):
    with pytest.raises(error, match=words.replace("(", r"\(").replace(")", r"\)")):
        fit(model_file, verbose=False, **keywords)


def test_fit_refuses_an_array_of_another_shape():
    with pytest.raises(ValueError, match=r"a MERL array has shape \(3, 90, 90, 180\), got \(3, 90, 90\)"):
        fit(np.zeros((3, 90, 90)), verbose=False)


# --- The package, and the readers of a fit's file -------------------------


def test_scipy_is_a_declared_dependency():
    """``pip install ./python`` brings SciPy, which ``twoscale.fit`` needs."""
    import importlib.metadata

    requires = importlib.metadata.requires("twoscale") or []
    assert any(r.split(";")[0].strip().startswith("scipy") and "extra" not in r for r in requires), requires


def test_the_spectral_index_gives_the_same_rgb_model_and_a_spectral_one(model_file):
    """``Fit.toml(spectral_index=True)`` (``--spectral-index``): the index as
    ``eta = { lambda, n, k }`` at the paper's wavelengths, which rebuilds the
    fitted RGB model bit for bit and also has a model at any wavelength;
    the plain file has none."""
    r = fit(model_file, samples=600, starts=1, max_nfev=3, refine_samples=0, verbose=False, **TRUTH)
    plain = twoscale.Material.from_toml_string(r.toml())
    spectral = twoscale.Material.from_toml_string(r.toml(spectral_index=True))
    assert spectral.rgb_mode == "paper-wavelengths"
    wi, wo = stratified_directions(4000, np.random.default_rng(3))
    want = r.material.eval(wi, wo)
    for m in (plain, spectral):
        np.testing.assert_array_equal(m.eval(wi, wo).view(np.uint32), want.view(np.uint32))
    at = spectral.eval_spectral(wi, wo, np.linspace(0.36, 0.83, len(wi)))
    assert np.all(np.isfinite(at)) and np.all((at > 0) == (want[:, 0] > 0))
    with pytest.raises(ValueError, match="needs an index over the spectrum"):
        plain.eval_spectral(wi, wo, np.full(len(wi), 0.5))


def test_mitsuba_spectral_reads_the_spectral_index_and_refuses_the_per_channel_one(tmp_path, model_file):
    pytest.importorskip("mitsuba")
    r = fit(model_file, samples=600, starts=1, max_nfev=3, refine_samples=0, verbose=False, **TRUTH)
    (tmp_path / "plain.toml").write_text(r.toml())
    (tmp_path / "spectral.toml").write_text(r.toml(spectral_index=True))
    code = (
        "import os, sys\n"
        "llvm = '/usr/lib/x86_64-linux-gnu/libLLVM-19.so'\n"
        "os.path.exists(llvm) and os.environ.setdefault('DRJIT_LIBLLVM_PATH', llvm)\n"
        "import mitsuba as mi\n"
        "mi.set_variant('llvm_ad_spectral')\n"
        "import twoscale.mitsuba\n"
        "twoscale.mitsuba.register()\n"
        "bsdf = mi.load_dict({'type': 'twoscale', 'filename': 'spectral.toml'})\n"
        "si = mi.SurfaceInteraction3f()\n"
        "si.wi = mi.Vector3f(0.3, 0.0, 0.954); si.wavelengths = mi.Spectrum([450.0, 520.0, 600.0, 700.0])\n"
        "value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(-0.2, 0.1, 0.975))\n"
        "import numpy as np\n"
        "print('spectral', bool(np.all(np.array(value) > 0)))\n"
        "try:\n"
        "    mi.load_dict({'type': 'twoscale', 'filename': 'plain.toml'})\n"
        "except Exception as e:\n"
        "    print('plain refused:', 'needs an index over the spectrum' in str(e))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    if "llvm_ad_spectral" in done.stderr and "variant" in done.stderr and done.returncode != 0:
        pytest.skip("no llvm_ad_spectral variant")
    assert done.stdout.splitlines() == ["spectral True", "plain refused: True"], done.stdout + done.stderr
