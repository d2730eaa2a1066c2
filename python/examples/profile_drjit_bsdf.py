"""Where the Dr.Jit plugin's time goes: ``Model.eval``, ``pdf`` and
``sample_direction`` of ``twoscale.drjit`` and their parts, timed on
2^18 random pairs in ``llvm_ad_rgb``, one Dr.Jit thread, best of
``--rounds`` (each a traced kernel, compiled once and then cached).

    python python/examples/profile_drjit_bsdf.py [--against OLD] [--rounds 15] [MATERIAL ...]

MATERIAL is a preset, ``beckmann`` (the render benchmark's p = 1, σs = 0
gold conductor) or ``roughconductor`` (Mitsuba's, Beckmann, α 0.1, visible
normals, the same index: its ``eval``, ``pdf`` and ``sample``, which also
returns the weight); default ``beckmann gold-hp17-geometry``. ``--against``
times the same three calls of another copy of the package
``python/twoscale/drjit/`` (e.g. ``git archive REV python/twoscale/drjit |
tar -x -C /tmp`` and ``--against /tmp/python/twoscale/drjit``) in
alternation with this one, rounds interleaved, so that a change is
compared under the same load. Prints ns per lane (one thread).
"""

import argparse
import importlib.util
import os
import sys
import time

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import twoscale  # noqa: E402
import twoscale.drjit as tb  # noqa: E402
from twoscale._cli import positive_int, run  # noqa: E402

LANES = 1 << 18
GOLD = [(0.163, 3.56), (0.584, 2.15), (1.403, 1.925)]


def material(name):
    if name == "beckmann":
        return twoscale.Material(beta=0.1, p=1.0, sigma_s=0.0, eta=GOLD)
    # `Model` is the paper's wavelengths (the presets' default, integrated
    # RGB, evaluates eight such models per pair).
    return twoscale.Material.preset(name, rgb_mode="paper-wavelengths")


def roughconductor_calls(wi, wo, u):
    """Mitsuba's `roughconductor` at the `beckmann` material's α and index."""
    bsdf = mi.load_dict({
        "type": "roughconductor", "distribution": "beckmann", "alpha": 0.1, "sample_visible": True,
        "eta": {"type": "rgb", "value": [e[0] for e in GOLD]},
        "k": {"type": "rgb", "value": [e[1] for e in GOLD]},
    })
    si = dr.zeros(mi.SurfaceInteraction3f, LANES)
    si.wi, si.n = wi, mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    ctx = mi.BSDFContext()
    return {
        "eval": lambda: bsdf.eval(ctx, si, wo),
        "pdf": lambda: bsdf.pdf(ctx, si, wo),
        "sample (with its weight)": lambda: bsdf.sample(ctx, si, u.x, mi.Point2f(u.y, u.z)),
    }


def best_times(calls, rounds):
    """The best time (s) of each call over `rounds`, calls interleaved."""
    for f in calls.values():
        dr.eval(f())
        dr.sync_thread()
    best = dict.fromkeys(calls, float("inf"))
    for _ in range(rounds):
        for key, f in calls.items():
            start = time.perf_counter()
            dr.eval(f())
            dr.sync_thread()
            best[key] = min(best[key], time.perf_counter() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("materials", nargs="*", default=["beckmann", "gold-hp17-geometry"],
                        choices=["beckmann", "roughconductor", *twoscale.Material.presets()],
                        metavar="MATERIAL", help="a preset, beckmann or roughconductor")
    parser.add_argument("--against")
    parser.add_argument("--rounds", type=positive_int, default=15)
    args = parser.parse_args()
    dr.set_thread_count(1)
    modules = {"this": tb}
    if args.against:
        # The copy as a package of its own (its modules import each other relatively).
        spec = importlib.util.spec_from_file_location(
            "against", os.path.join(args.against, "__init__.py"),
            submodule_search_locations=[args.against])
        modules["against"] = sys.modules["against"] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(modules["against"])
    rng = np.random.default_rng(1)

    def directions():
        v = rng.normal(size=(3, LANES))
        v[2] = np.abs(v[2])
        return mi.Vector3f((v / np.linalg.norm(v, axis=0)).astype(np.float32))

    wi, wo = directions(), directions()
    u = mi.Vector3f(rng.random((3, LANES)).astype(np.float32))
    dr.eval(wi, wo, u)
    for name in args.materials:
        if name == "roughconductor":
            calls = roughconductor_calls(wi, wo, u)
            for key, t in best_times(calls, args.rounds).items():
                print(f"{name:20s} {key:36s} {t / LANES * 1e9:8.1f} ns/lane")
            continue
        m = material(name)
        calls = {}
        for label, module in modules.items():
            model = module.Model(m)
            calls[f"{label} eval"] = lambda model=model: model.eval(wo, wi)
            calls[f"{label} pdf"] = lambda model=model: model.pdf(wi, wo)
            calls[f"{label} sample_direction"] = lambda model=model: model.sample_direction(wi, u)
        model = tb.Model(m)
        ch = model.channels[0]
        calls["  geometry + masking"] = lambda: model.masking(model.geometry(wi, wo)[1])
        # As the model calls them: f32 unit directions and uniforms.
        calls["  lobe_weights (one channel)"] = lambda: ch.lobe_weights(wi.z)
        calls["  visible_pdf"] = lambda: ch.visible_pdf(wi, wo)
        calls["  visible_sample"] = lambda: ch.visible_sample(wi, u.x, u.y)
        if ch.diffraction:
            geo = model.geometry(wi, wo)[1]
            calls["  halo_pdf (one channel)"] = lambda: ch.halo_pdf(wi, geo["sin_h"], geo["cos_h"], wo.z)
            calls["  diffraction_sample (one channel)"] = lambda: ch.diffraction_sample(
                wi, u.x, u.y)
            calls["  conv (one channel)"] = lambda: ch.conv(
                geo["sin_h"], geo["cos_h"], ch.f["big_b"] * geo["cos_d"])
        for key, t in best_times(calls, args.rounds).items():
            print(f"{name:20s} {key:36s} {t / LANES * 1e9:8.1f} ns/lane")


if __name__ == "__main__":
    run(main)
