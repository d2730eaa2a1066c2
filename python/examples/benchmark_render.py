"""Render cost per sample of the ``twoscale`` BSDF against Mitsuba's
``roughconductor`` (Beckmann), in ``llvm_ad_rgb`` and ``llvm_ad_spectral``.

    python python/examples/benchmark_render.py [--scene sphere|cornell] [--size 256] [--spp 64]
        [--repeat 3] [--presets NAME,…] [--variant V] [--evaluated]

Renders a scene with each BSDF, once to warm up (JIT compilation, plugin
construction) and then ``--repeat`` rounds that render every BSDF in turn
(so that each is exposed to the same load), and prints the process CPU time
(user + system, all threads) per sample (pixels × spp) of the timed
renders, and the ratio to ``roughconductor`` in the same variant, in the
same run. ``--scene sphere`` (the default) is the sphere of the
Beckmann-limit check (`sphere_scene`: a constant emitter and a directional
light, path tracer of depth 2); ``--scene cornell`` is Mitsuba's Cornell box
with its two boxes and a ball in the BSDF under test, path depth 6
(`cornell_scene`). ``--presets`` adds rows for those presets in their
default RGB mode (integrated over the spectrum). Each variant runs in its own process,
in Mitsuba's default symbolic mode (loops and calls recorded once);
``--evaluated`` switches symbolic loops and calls off in that process (the
wavefront mode), for comparison. The default 256 × 256 pixels keep the
per-render cost of recording the kernel (≈ 15 ms, whatever the samples)
small: at 64 × 64 it was a fifth of `roughconductor`'s time. ``--variant scalar_rgb`` measures the
scalar path.
"""

import argparse
import os
import subprocess
import sys
import time
from twoscale._cli import positive_int, run

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"


#: Gold's (η, k) per RGB channel.
GOLD = ([0.163, 0.584, 1.403], [3.56, 2.15, 1.925])


def sphere_scene(bsdf, size=64, spp=64):
    """A unit sphere of `bsdf` seen from 4.5 units (field of view 30°)
    under a constant emitter of radiance 0.5 and a directional light of
    irradiance 5 from (−1, −1, −2); a path tracer of depth 2 and a box
    pixel filter, so that the pixels are independent estimates."""
    import mitsuba as mi

    look = mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0])
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 30, "to_world": look,
                   "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.5}},
        "sun": {"type": "directional", "direction": [-1, -1, -2],
                "irradiance": {"type": "rgb", "value": 5.0}},
    })


def cornell_scene(bsdf, size=64, spp=64):
    """Mitsuba's Cornell box (`mi.cornell_box()`: diffuse walls, an area
    light) with its two boxes and a ball of radius 0.3 on the floor in
    `bsdf`, a path tracer of depth 6 and a box pixel filter: real geometry,
    where most paths meet the BSDF under test after a diffuse bounce."""
    import mitsuba as mi

    scene = mi.cornell_box()
    scene["integrator"]["max_depth"] = 6
    scene["sensor"]["film"].update({"width": size, "height": size, "rfilter": {"type": "box"}})
    scene["sensor"]["sampler"] = {"type": "independent", "sample_count": spp}
    scene["under-test"] = bsdf
    for shape in ("small-box", "large-box"):
        scene[shape]["bsdf"] = {"type": "ref", "id": "under-test"}
    scene["ball"] = {"type": "sphere", "center": [-0.05, -0.7, 0.65], "radius": 0.3,
                     "bsdf": {"type": "ref", "id": "under-test"}}
    return mi.load_dict(scene)


SCENES = {"sphere": sphere_scene, "cornell": cornell_scene}


def roughconductor(alpha, eta, k):
    """Mitsuba's `roughconductor`: Beckmann, visible normals (its default), α, η, k per channel."""
    return {"type": "roughconductor", "distribution": "beckmann", "alpha": alpha,
            "eta": {"type": "rgb", "value": list(eta)}, "k": {"type": "rgb", "value": list(k)}}


def beckmann_pair(alpha, eta=GOLD[0], k=GOLD[1], plugin="twoscale"):
    """The Beckmann limit: the plugin `plugin` at β = α, p = 1, σs = 0, and
    `roughconductor` with the same α, η, k."""
    twoscale_bsdf = {"type": plugin, "beta": alpha, "p": 1.0, "sigma_s": 0.0,
                     "eta": ", ".join(f"{a} {b}" for a, b in zip(eta, k))}
    return twoscale_bsdf, roughconductor(alpha, eta, k)


def measure(variant, scene_name, size, spp, repeat, evaluated, presets=()):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    if evaluated:
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    mode = "evaluated" if evaluated else "symbolic"
    import twoscale.mitsuba as tm

    tm.register()
    eta, k = GOLD
    if mi.is_spectral:
        # an explicit material needs one index for every channel in spectral variants
        eta, k = [0.584] * 3, [2.15] * 3
    beckmann, rough = beckmann_pair(0.1, eta, k)
    bsdfs = {
        # The paper's wavelengths (the presets' default is the integrated RGB, below).
        "twoscale gold-hp17-geometry": {"type": "twoscale", "material": "gold-hp17-geometry",
                                        "rgb_mode": "paper-wavelengths"},
        "twoscale Beckmann (p=1, σs=0)": beckmann,
        "roughconductor beckmann": rough,
    }
    if mi.is_rgb:
        bsdfs["twoscale gold-hp17-geometry, integrated RGB"] = {
            "type": "twoscale", "material": "gold-hp17-geometry", "rgb_mode": "integrated"}
    for preset in presets:
        bsdfs.setdefault(f"twoscale {preset}", {"type": "twoscale", "material": preset})
    scenes = {name: SCENES[scene_name](bsdf, size, spp) for name, bsdf in bsdfs.items()}
    def render(scene, **kwargs):
        # The image is evaluated and the kernels finished here: otherwise
        # the next render (another BSDF's, in turn) would run this one's.
        dr.eval(mi.render(scene, spp=spp, **kwargs))
        dr.sync_thread()

    for scene in scenes.values():
        render(scene)  # warm-up
    seconds = dict.fromkeys(scenes, 0.0)
    for seed in range(repeat):
        for name, scene in scenes.items():
            start = time.process_time()
            render(scene, seed=seed + 1)
            seconds[name] += time.process_time() - start
    cost = {name: t / (repeat * size * size * spp) for name, t in seconds.items()}
    base = cost["roughconductor beckmann"]
    for name, c in cost.items():
        print(f"{variant:16s} {mode:9s} {scene_name:7s} {name:44s} {c * 1e9:10.1f} ns CPU/sample  ×{c / base:.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", choices=sorted(SCENES), default="sphere")
    parser.add_argument("--presets", default="", help="comma-separated presets to add as rows")
    parser.add_argument("--size", type=positive_int, default=256)
    parser.add_argument("--spp", type=positive_int, default=64)
    parser.add_argument("--repeat", type=positive_int, default=3)
    parser.add_argument("--variant", choices=["scalar_rgb", "llvm_ad_rgb", "llvm_ad_spectral"])
    parser.add_argument("--evaluated", action="store_true")
    args = parser.parse_args()
    presets = [p for p in args.presets.split(",") if p]
    import twoscale

    unknown = sorted(set(presets) - set(twoscale.Material.presets()))
    if unknown:
        parser.error(f"unknown presets {', '.join(unknown)} (presets: {', '.join(twoscale.Material.presets())})")
    if args.variant:
        measure(args.variant, args.scene, args.size, args.spp, args.repeat, args.evaluated, presets)
        return
    env = dict(os.environ)
    if os.path.exists(LLVM):
        env.setdefault("DRJIT_LIBLLVM_PATH", LLVM)
    for variant in ("llvm_ad_rgb", "llvm_ad_spectral"):
        subprocess.run([sys.executable, __file__, "--variant", variant, "--scene", args.scene,
                        "--presets", args.presets, "--size", str(args.size),
                        "--spp", str(args.spp), "--repeat", str(args.repeat)]
                       + (["--evaluated"] if args.evaluated else []), env=env, check=True)


if __name__ == "__main__":
    run(main)
