"""Renders fits of the two-scale model next to what they fit: Mitsuba 3's
``roughconductor`` written as a MERL file, fitted by ``twoscale.fit``, the
fit's TOML loaded by the plugin's ``filename`` parameter.

    python python/examples/render_fit.py [--out docs/img] [--size 192] [--spp 64]

For each case: the BSDF tabulated at the MERL bin centres (θd > 80° and 1%
of the bins missing, as docs/fitting.md's Mitsuba fits), written with
``twoscale.merl.write``, fitted from the file with the default settings
(conductor with a Lambertian term), the TOML written by ``Fit.toml()``;
then the sphere of ``render_presets.py`` rendered with the original BSDF
and with ``{"type": "twoscale", "filename": ...}``, two seeds each. Writes
``render-fit-roughconductor.png`` (rows: the cases; columns: Mitsuba, the
fit, |difference| × 4) and prints, per case, the fitted β and p, the mean
|difference| of the two renders and the same between two seeds of one
BSDF (the noise), per channel.
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")

import twoscale  # noqa: E402
import twoscale.fit  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
from fit_report import degrade, mitsuba_cases  # noqa: E402
from render_presets import scene, write_png  # noqa: E402
from twoscale import merl  # noqa: E402
from twoscale._cli import positive_int, run  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]
CASES = ("roughconductor beckmann α=0.2", "roughconductor ggx α=0.3")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "docs" / "img")
    parser.add_argument("--size", type=positive_int, default=192)
    parser.add_argument("--spp", type=positive_int, default=64)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tm.register()
    log = lambda *x: print(*x, file=sys.stderr, flush=True)  # noqa: E731
    log(f"load average {os.getloadavg()}")
    cases = {name: (base, bsdf) for name, base, _, bsdf in mitsuba_cases() if name in CASES}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in CASES:
            base, bsdf = cases[name]
            values = degrade(merl.tabulate(merl.mitsuba_brdf(bsdf)), np.random.default_rng(5))
            binary = pathlib.Path(tmp) / "measured.binary"
            merl.write(binary, values)
            t0 = time.perf_counter()
            fitted = twoscale.fit.fit(str(binary), base, verbose=False)
            seconds = time.perf_counter() - t0
            params = pathlib.Path(tmp) / "params.toml"
            params.write_text(fitted.toml(), encoding="utf-8")
            log(f"{name}: fitted in {seconds:.1f} s\n{fitted.toml()}")
            images = {}
            for label, desc in (("mitsuba", bsdf), ("fit", {"type": tm.NAME, "filename": str(params)})):
                s = scene(desc, args.size, args.spp)
                images[label] = [np.asarray(mi.render(s, seed=seed)) for seed in (0, 1)]
            mad = lambda a, b: np.abs(a - b).mean(axis=(0, 1))  # noqa: E731
            diff = (mad(images["fit"][0], images["mitsuba"][1]) + mad(images["fit"][1], images["mitsuba"][0])) / 2
            noise = np.sqrt((mad(*images["fit"]) ** 2 + mad(*images["mitsuba"]) ** 2) / 2)
            mean = np.mean([im.mean(axis=(0, 1)) for im in images["mitsuba"]], axis=0)
            rows.append((name, fitted, seconds, diff, noise, mean, images))
    print("| Mitsuba BSDF | fitted β | fitted p | fit time (s) | mean \\|render difference\\| (r, g, b) "
          "| between two seeds (r, g, b) | mean pixel (r, g, b) |")
    print("|---|---|---|---|---|---|---|")
    fmt = lambda v: ", ".join(f"{x:.4f}" for x in v[:3])  # noqa: E731
    for name, fitted, seconds, diff, noise, mean, _ in rows:
        print(f"| {name} | {fitted.keywords['beta']:.4f} | {fitted.keywords['p']:.3f} | {seconds:.1f} | "
              f"{fmt(diff)} | {fmt(noise)} | {fmt(mean)} |")
    strips = []
    for *_, images in rows:
        a, b = images["mitsuba"][0], images["fit"][0]
        strips.append(np.concatenate([a, b, 4 * np.abs(a - b)], axis=1))
    write_png(np.ascontiguousarray(np.concatenate(strips, axis=0)[..., :3]), args.out / "render-fit-roughconductor.png")


if __name__ == "__main__":
    run(main)
