"""Render noise at equal samples and time to equal noise of the ``twoscale``
BSDF against Mitsuba's ``roughconductor`` (Beckmann, visible normals), in
``llvm_ad_rgb`` (symbolic mode), on the sphere of benchmark_render.py.

    python python/examples/render_noise.py [--size 64] [--spp 16] [--seeds 16]
        [--ref-renders 64] [--alphas 0.05 0.2 0.5] [--presets] [--where]

For each BSDF: ``--seeds`` renders at ``--spp`` and a reference, the mean
of ``--ref-renders`` more renders; and the process CPU time per sample,
the slope between renders at ``--spp`` and 8 × ``--spp`` (`timed`). Over the pixels the sphere covers whole
(the four corners' camera rays hit it) where the reference exceeds 10⁻³ of
its mean there, and over the three channels:

- the relative variance ``V``, the mean of ``s²_p / ref_p²`` with ``s²_p``
  the unbiased variance of pixel p across the seeds (the variance of one
  render at ``--spp``): every pixel counts alike;
- the mean ``Σ ref_p``.

The two BSDFs' renders use the same seeds (common random numbers: with the
same sampler, as in the Beckmann limit, their noise is correlated), so the
ratios' standard errors are the jackknife's over pairs of renders.

Then the noise ratio at equal samples ``√(V_twoscale / V_rough)``, the cost
ratio, and time to equal noise ``cost ratio × V_twoscale / V_rough``. In
the Beckmann limit (p = 1, σs = 0, gold's η, k; ``--alphas``) both render
the same image (and ``ref_p`` is the mean of the two references); for the
presets (``--presets``: roughconductor with α = β and the preset's η, k
per channel) the images differ and each is relative to its own reference. ``--where`` prints, in the Beckmann limit, the
variance ratio in bins of the view's cos θ at the pixel (grazing or not).
docs/design/render-noise.md.
"""

import argparse
import os
import time

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if os.path.exists(LLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")

import twoscale  # noqa: E402
import twoscale.mitsuba as tm  # noqa: E402
from twoscale._cli import positive_int, run, unit_interval  # noqa: E402

import benchmark_render  # noqa: E402  (this directory: the sphere scene, the Beckmann pair)


def covered(scene):
    """(H, W) bool: the pixels whose four corners' camera rays hit the
    scene (the sphere's outline is convex, so the whole pixel is on it)."""
    sensor = scene.sensors()[0]
    w, h = sensor.film().crop_size()
    ys, xs = np.meshgrid(np.arange(h + 1), np.arange(w + 1), indexing="ij")
    pos = mi.Point2f(np.ravel(xs / w).astype(np.float32), np.ravel(ys / h).astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    hit = np.asarray(scene.ray_test(ray)).reshape(h + 1, w + 1)
    return hit[:-1, :-1] & hit[1:, :-1] & hit[:-1, 1:] & hit[1:, 1:]


def measure(bsdfs, size, spp, seeds, ref_renders, timing=5):
    """The statistics of each of `bsdfs` (module documentation): a dict each
    with the seeds' images `images` (K, H, W, 3), the reference `ref`
    (H, W, 3) and its renders `ref_renders`, the coverage `covered` and the
    CPU time per sample `cost` (`timed`, with `timing` rounds; NaN with none)."""
    scenes = [benchmark_render.sphere_scene(bsdf, size, spp) for bsdf in bsdfs]
    for scene in scenes:
        mi.render(scene, seed=0, spp=spp)  # warm-up: JIT compilation, plugin construction
    images = [[] for _ in scenes]
    for seed in range(1, 1 + seeds + ref_renders):
        for scene, out in zip(scenes, images):
            out.append(np.asarray(mi.render(scene, seed=seed, spp=spp), dtype=np.float64))
    costs = timed(scenes, size, spp, timing) if timing else [np.nan] * len(scenes)
    return [{"images": np.stack(out[:seeds]), "ref": np.mean(out[seeds:], axis=0),
             "ref_renders": np.stack(out[seeds:]), "covered": covered(scene), "cost": cost}
            for scene, out, cost in zip(scenes, images, costs)]


def timed(scenes, size, spp, rounds):
    """The process CPU time per sample of each of `scenes`: the slope between
    renders at `spp` and at 8 `spp` (medians of `rounds` renders each, the
    scenes alternating so that a change of load falls on all), which leaves
    out what a render costs whatever its samples (recording the kernel in
    symbolic mode: ≈ 15 ms, as much as 16 spp at 64² pixels)."""
    medians = []
    for n in (spp, 8 * spp):
        for scene in scenes:
            mi.render(scene, seed=0, spp=n)  # warm-up
        spent = [[] for _ in scenes]
        for r in range(rounds):
            for scene, out in zip(scenes, spent):
                start = time.process_time()
                np.asarray(mi.render(scene, seed=100_000 + r, spp=n))
                out.append(time.process_time() - start)
        medians.append([float(np.median(out)) for out in spent])
    return [(hi - lo) / (size * size * 7 * spp) for lo, hi in zip(*medians)]


def mask_of(*stats):
    """The pixels every one of `stats` covers where each reference exceeds
    10⁻³ of its mean over the covered pixels (every channel)."""
    mask = np.logical_and.reduce([s["covered"] for s in stats])
    for s in stats:
        ref = s["ref"]
        mask &= np.all(ref > 1e-3 * ref[mask].mean(axis=0), axis=-1)
    return mask


def relative_variance(images, ref, mask):
    """`V`, the mean over `mask` and the channels of `s²_p / ref_p²`, and the
    same with each seed left out in turn (for the jackknife)."""
    x = images[:, mask]  # (K, P, 3)
    k = x.shape[0]
    weight = 1.0 / (ref[mask] ** 2 * x[0].size)
    s1, s2 = x.sum(axis=0), (x * x).sum(axis=0)
    v = float(((s2 - s1 * s1 / k) * weight).sum() / (k - 1))
    loo = np.array([float((((s2 - x[j] ** 2) - (s1 - x[j]) ** 2 / (k - 1)) * weight).sum() / (k - 2))
                    for j in range(k)])
    return v, loo


def jackknife(loo):
    """The jackknife's standard error from the leave-one-out values `loo`."""
    k = len(loo)
    return float(np.sqrt((k - 1) / k * ((loo - loo.mean()) ** 2).sum()))


def compare(ours, theirs, shared=False):
    """Noise, mean and cost of `ours` against `theirs` over their common
    mask: a dict of ratios (ours / theirs) with standard errors. `shared`:
    both render the same image, and both variances are relative to the mean
    of the two references. Seed j of one and seed j of the other use the
    same random numbers (and so do their reference renders), so the
    ratios' errors are the jackknife's over the pairs (leave pair j out),
    which keeps the correlation."""
    mask = mask_of(ours, theirs)
    ref_a, ref_b = ours["ref"], theirs["ref"]
    if shared:
        ref_a = ref_b = 0.5 * (ref_a + ref_b)
    v_a, loo_a = relative_variance(ours["images"], ref_a, mask)
    v_b, loo_b = relative_variance(theirs["images"], ref_b, mask)
    variance = v_a / v_b
    se_log_variance = jackknife(np.log(loo_a / loo_b))
    m_a = ours["ref_renders"][:, mask].mean(axis=(1, 2))
    m_b = theirs["ref_renders"][:, mask].mean(axis=(1, 2))
    mean = m_a.sum() / m_b.sum()
    mean_se = jackknife((m_a.sum() - m_a) / (m_b.sum() - m_b))
    cost = ours["cost"] / theirs["cost"]
    return {
        "pixels": int(mask.sum()),
        "relvar": (v_a, v_b),
        "noise": np.sqrt(variance),
        "noise_se": 0.5 * se_log_variance * np.sqrt(variance),  # of √ratio, by the delta method
        "se_log_variance": se_log_variance,
        "mean": mean,
        "mean_se": mean_se,
        "cost": cost,
        "time_to_equal_noise": cost * variance,
        "time_to_equal_noise_se": cost * variance * se_log_variance,
    }


def view_cosines(scene, mask):
    """cos θ between the normal and the direction to the camera at the
    centre of each pixel of `mask` (the unit sphere at the origin)."""
    sensor = scene.sensors()[0]
    w, h = sensor.film().crop_size()
    ys, xs = np.nonzero(mask)
    pos = mi.Point2f(((xs + 0.5) / w).astype(np.float32), ((ys + 0.5) / h).astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    return -np.asarray(dr.dot(si.n, ray.d))


def where(ours, theirs, bsdf, size, spp):
    """Prints the variance ratio (ours / theirs, absolute: both render the
    same image) in bins of the view's cos θ at the pixel."""
    mask = mask_of(ours, theirs)
    cos = view_cosines(benchmark_render.sphere_scene(bsdf, size, spp), mask)
    var = {}
    for name, s in (("ours", ours), ("theirs", theirs)):
        var[name] = s["images"][:, mask].var(axis=0, ddof=1).sum(axis=-1)
    edges = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (cos >= lo) & (cos < hi)
        if sel.sum() == 0:
            continue
        ratio = var["ours"][sel].sum() / var["theirs"][sel].sum()
        print(f"    cos θ ∈ [{lo:.1f}, {hi:.1f}): {sel.sum():5d} pixels, variance ratio {ratio:.3f}")


def row(name, r):
    return (f"| {name} | {r['relvar'][0]:.4g} | {r['relvar'][1]:.4g} | {r['noise']:.4f} ± {r['noise_se']:.1e} "
            f"| {r['mean']:.4f} ± {r['mean_se']:.1e} | {r['cost']:.2f} "
            f"| {r['time_to_equal_noise']:.2f} ± {r['time_to_equal_noise_se']:.1e} |")


HEADER = ("| {} | V twoscale | V roughconductor | noise ratio at equal spp | mean ratio | CPU time ratio "
          "| time to equal noise |\n|---|---|---|---|---|---|---|")


def beckmann_rows(alphas, size, spp, seeds, ref_renders, show_where=False):
    """The Beckmann-limit rows: (α, comparison)."""
    out = []
    print(HEADER.format("α"))
    for alpha in alphas:
        ours_bsdf, rough = benchmark_render.beckmann_pair(alpha, plugin=tm.NAME)
        ours, theirs = measure([ours_bsdf, rough], size, spp, seeds, ref_renders)
        r = compare(ours, theirs, shared=True)
        print(row(alpha, r), flush=True)
        if show_where:
            where(ours, theirs, rough, size, spp)
        out.append((alpha, r))
    return out


def preset_rows(size, spp, seeds, ref_renders):
    """Every preset against roughconductor (α = β, the preset's η, k)."""
    print(HEADER.format("preset (β, p)"))
    for name in twoscale.Material.presets():
        material = twoscale.Material.preset(name)
        eta = [e for e, _ in material.eta]
        k = [k for _, k in material.eta]
        rough = benchmark_render.roughconductor(material.beta, eta, k)
        ours, theirs = measure([{"type": tm.NAME, "material": name}, rough], size, spp, seeds, ref_renders)
        print(row(f"{name} ({material.beta:.3g}, {material.p:.3g})", compare(ours, theirs)), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=positive_int, default=64)
    parser.add_argument("--spp", type=positive_int, default=16)
    parser.add_argument("--seeds", type=positive_int, default=16)
    parser.add_argument("--ref-renders", type=positive_int, default=64)
    parser.add_argument("--alphas", type=unit_interval, nargs="*", default=[0.05, 0.2, 0.5])
    parser.add_argument("--presets", action="store_true")
    parser.add_argument("--where", action="store_true")
    args = parser.parse_args()
    tm.register()
    print(f"{args.size}² pixels, {args.spp} spp, {args.seeds} seeds, reference {args.ref_renders} renders; "
          f"load average {os.getloadavg()[0]:.1f}")
    beckmann_rows(args.alphas, args.size, args.spp, args.seeds, args.ref_renders, args.where)
    if args.presets:
        preset_rows(args.size, args.spp, args.seeds, args.ref_renders)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    run(main)
