"""Renders rough gold and a β = 0.8 gold conductor with and without the
energy compensation (``multiple_scattering="kulla-conty"``, docs/model.md
§2.11), with Mitsuba 3 and the ``twoscale`` BSDF, in the scene of
``render_presets.py``.

    python python/examples/render_energy.py [--out docs/img] [--size 160] [--spp 64]

Writes ``render-energy-compensation.png`` to ``--out``: left to right,
gold-rough without and with, the β = 0.8 conductor without and with (sRGB,
no tone mapping beyond clamping).
"""

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from render_presets import REPO, scene, write_png  # noqa: E402

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

import twoscale  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
from twoscale._cli import positive_int, run  # noqa: E402

#: Gold (the presets' index) on a wide EPD lobe without nano-roughness.
WIDE = dict(beta=0.8, p=1.5, eta=[(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)])


def materials():
    """The four materials, left to right."""
    for compensation in ("none", "kulla-conty"):
        yield twoscale.Material.preset("gold-rough", multiple_scattering=compensation)
    for compensation in ("none", "kulla-conty"):
        yield twoscale.Material(**WIDE, multiple_scattering=compensation)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "docs" / "img")
    parser.add_argument("--size", type=positive_int, default=160)
    parser.add_argument("--spp", type=positive_int, default=64)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tm.register()
    images = [np.asarray(mi.render(scene(tm.bsdf_dict(m), args.size, args.spp)))
              for m in materials()]
    strip = np.concatenate(images, axis=1)
    write_png(mi.TensorXf(strip), args.out / "render-energy-compensation.png")


if __name__ == "__main__":
    run(main)
