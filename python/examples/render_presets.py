"""Renders a sphere of every preset, and a close-up of a highlight with a
strong diffraction halo, with Mitsuba 3 and the ``twoscale`` BSDF.

    python python/examples/render_presets.py [--out docs/img] [--size 256] [--spp 64]

Writes ``render-<preset>.png`` and ``render-halo-closeup.png`` (sRGB, no
tone mapping beyond clamping) to ``--out``.
"""

import argparse
import os
import pathlib

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")

import twoscale  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
from twoscale._cli import positive_int, run  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]
CAMERA = [0.0, 0.0, 4.5]
LAMP = [2.5, 2.5, 4.0]

#: A halo stronger than any preset's: σs = 0.06 µm of nano-roughness over a
#: narrow (β = 0.02) Beckmann surface of gold.
HALO = dict(beta=0.02, p=1.0, sigma_s=0.06, b=3.0, c=1.6,
            eta=[(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)])


def scene(bsdf, size, spp, fov=28.0, target=(0, 0, 0)):
    look = mi.ScalarTransform4f().look_at(origin=CAMERA, target=list(target), up=[0, 1, 0])
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective", "fov": fov, "to_world": look,
            "film": {"type": "hdrfilm", "width": size, "height": size},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.15}},
        "lamp": {
            "type": "sphere", "center": LAMP, "radius": 0.12,
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 400.0}},
        },
    })


def write_png(image, path):
    bitmap = mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    bitmap.write(str(path))
    print(f"wrote {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "docs" / "img")
    parser.add_argument("--size", type=positive_int, default=256)
    parser.add_argument("--spp", type=positive_int, default=64)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tm.register()
    for name in twoscale.Material.presets():
        bsdf = {"type": tm.NAME, "material": name}
        write_png(mi.render(scene(bsdf, args.size, args.spp)), args.out / f"render-{name}.png")
    # the highlight of the lamp on the sphere, seen close up
    halo = tm.bsdf_dict(twoscale.Material(**HALO))
    target = highlight_point(LAMP, CAMERA)
    write_png(mi.render(scene(halo, args.size, args.spp, fov=6.0, target=target)),
              args.out / "render-halo-closeup.png")


def highlight_point(lamp, camera):
    """The point of the unit sphere whose normal halves the directions to the
    lamp and to the camera (the mirror highlight, for distant points)."""
    unit = lambda v: np.asarray(v, dtype=float) / np.linalg.norm(v)  # noqa: E731
    return list(unit(unit(lamp) + unit(camera)))


if __name__ == "__main__":
    run(main)
