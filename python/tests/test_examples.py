"""The example scripts run and write what they say."""

import pathlib
import subprocess
import sys

import numpy as np
import pytest

import twoscale

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def test_render_presets_writes_a_png_per_preset(tmp_path):
    subprocess.run(
        [sys.executable, EXAMPLES / "render_presets.py", "--out", tmp_path, "--size", "24", "--spp", "4"],
        check=True,
    )
    import mitsuba as mi

    names = [f"render-{n}.png" for n in twoscale.Material.presets()] + ["render-halo-closeup.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
    for name in names:
        image = np.asarray(mi.Bitmap(str(tmp_path / name)))
        assert image.shape == (24, 24, 3)
        assert image.max() > 0  # something was lit


def test_render_energy_writes_its_strip(tmp_path):
    subprocess.run(
        [sys.executable, EXAMPLES / "render_energy.py", "--out", tmp_path, "--size", "16", "--spp", "4"],
        check=True,
    )
    import mitsuba as mi

    assert [p.name for p in tmp_path.iterdir()] == ["render-energy-compensation.png"]
    image = np.asarray(mi.Bitmap(str(tmp_path / "render-energy-compensation.png")))
    assert image.shape == (16, 64, 3)
    # each compensated sphere is brighter than its uncompensated neighbour
    means = [image[:, 16 * k:16 * (k + 1)].astype(float).mean() for k in range(4)]
    assert means[1] > means[0] and means[3] > means[2], means


# One bad input per example script: argparse's checks (status 2), or what
# only shows when it runs (an OSError: status 1). The modules each needs.
BAD_INPUT = {
    "benchmark_render.py": (["--size", "-5"], ["mitsuba"]),
    "fit_recovery.py": (["--case", "nope"], ["scipy"]),
    "fit_report.py": (["--materials", "0"], ["scipy"]),
    "profile_drjit_bsdf.py": (["no-such-material"], ["mitsuba"]),
    "render_energy.py": (["--spp", "0"], ["mitsuba"]),
    "render_fit.py": (["--size", "big"], ["mitsuba", "scipy"]),
    "render_noise.py": (["--alphas", "1.5"], ["mitsuba"]),
    "render_presets.py": (["--out", "{file}", "--size", "8", "--spp", "1"], ["mitsuba"]),
    "sampler_variance.py": (["--samples", "-5"], ["scipy"]),
    "spectral_kernel_cost.py": (["no-such-material"], ["mitsuba"]),
}


def test_every_example_is_listed():
    assert sorted(BAD_INPUT) == sorted(p.name for p in EXAMPLES.glob("*.py"))


@pytest.mark.parametrize("name", sorted(BAD_INPUT))
def test_examples_give_help_and_refuse_bad_input_without_a_traceback(name, tmp_path):
    """``--help`` prints the usage; bad input prints ``error: …`` and exits
    non-zero with no traceback (spectral_kernel_cost.py --help crashed)."""
    args, modules = BAD_INPUT[name]
    for module in modules:
        pytest.importorskip(module)
    done = subprocess.run([sys.executable, EXAMPLES / name, "--help"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: "), done.stdout
    occupied = tmp_path / "a-file"
    occupied.write_text("not a directory")
    args = [a.replace("{file}", str(occupied)) for a in args]
    done = subprocess.run([sys.executable, EXAMPLES / name, *args], capture_output=True, text=True)
    assert done.returncode != 0, done.stdout
    assert "Traceback" not in done.stderr, done.stderr
    assert "error: " in done.stderr, done.stderr
