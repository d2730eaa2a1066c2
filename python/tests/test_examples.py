"""The example scripts run and write what they say."""

import pathlib
import subprocess
import sys

import numpy as np

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
