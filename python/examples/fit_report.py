"""The validation of ``twoscale.fit`` in docs/fitting.md: parameter recovery
on MERL files written from the model itself, fits to Mitsuba 3's
``roughconductor`` (Beckmann, GGX) and ``roughplastic`` written as MERL
files, and the lobe plots (docs/img/fit-*.png).

    python python/examples/fit_report.py [--materials 6] [--img docs/img]

Prints the Markdown tables of docs/fitting.md on stdout (progress on
stderr). Needs matplotlib for the plots (``--img ''`` skips them).
"""

import argparse
import math
import os
import sys
import time

import numpy as np

import twoscale
from twoscale import merl
from twoscale.fit import _sample_metrics as sample_metrics
from twoscale.fit import fit, grazing, predict
from twoscale._cli import positive_int, run

#: The domain of the random materials (log-uniform between the bounds).
DOMAIN = {
    "beta": (0.03, 0.4),
    "p": (0.6, 2.0),
    "sigma_s": (0.005, 0.05),
    "b": (0.5, 8.0),
    "c": (1.5, 4.0),
    "n": (0.2, 2.5),
    "k": (1.0, 6.0),
}
#: θd above which synthetic files are masked (as the MERL acquisition).
MASK_THETA_D_DEG = 80.0
HOLES = 0.01
NOISE = 0.02
GRAZING_K = 1.0
GEOMETRY = ("beta", "p", "sigma_s", "b", "c")


def random_material(rng):
    u = {k: math.exp(rng.uniform(math.log(lo), math.log(hi))) for k, (lo, hi) in DOMAIN.items() if k not in "nk"}
    eta = [
        (math.exp(rng.uniform(*np.log(DOMAIN["n"]))), math.exp(rng.uniform(*np.log(DOMAIN["k"])))) for _ in range(3)
    ]
    return dict(u, eta=eta, base="conductor")


def degrade(values, rng, *, noise=0.0, grazing_k=0.0):
    """θd > 80° and 1% of the bins missing; optionally multiplicative
    Gaussian noise and the grazing loss p(i, o) of HP17 59–60."""
    out = values.copy()
    theta_d = np.pi / 2 * (np.arange(90) + 0.5) / 90
    out[:, :, theta_d > math.radians(MASK_THETA_D_DEG), :] = np.nan
    out[:, rng.uniform(size=merl.SHAPE[1:]) < HOLES] = np.nan
    if grazing_k:
        wi, wo = merl.bin_centres()
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        g = np.ones(merl.BINS)
        g[ok] = grazing(wi[ok], wo[ok], grazing_k)
        out *= g.reshape(merl.SHAPE[1:])
    if noise:
        out *= 1.0 + noise * rng.standard_normal(merl.SHAPE)
    return out


def relative_rms_over_bins(material, values, grazing_k=0.0, n=200_000, seed=3):
    """‖m − p ρ‖ / ‖m‖ over ``n`` random valid bins of ``values`` (at the
    bin centres)."""
    wi, wo = merl.bin_centres()
    flat = values.reshape(3, -1)
    valid = np.flatnonzero(np.all(np.isfinite(flat), axis=0) & (wi[:, 2] > 0) & (wo[:, 2] > 0))
    k = np.random.default_rng(seed).choice(valid, min(n, len(valid)), replace=False)
    m = flat[:, k].T
    return sample_metrics(m, predict(material, wi[k], wo[k], grazing_k))["relative_rms"]


def perturbed(truth, rng, scale=0.25):
    start = {k: truth[k] * math.exp(scale * rng.standard_normal()) for k in GEOMETRY}
    start["c"] = 1.0 + (truth["c"] - 1.0) * math.exp(scale * rng.standard_normal())
    start["eta"] = [(n * math.exp(scale * rng.standard_normal()), k * math.exp(scale * rng.standard_normal())) for n, k in truth["eta"]]
    return start


def recovery(n_materials, rng, log):
    rows = []
    for j in range(n_materials):
        truth = random_material(rng)
        clean = merl.tabulate(twoscale.Material(**truth).eval)
        for case in ("clean", "noisy"):
            noisy = case == "noisy"
            k = GRAZING_K if noisy else 0.0
            values = degrade(clean, rng, noise=NOISE if noisy else 0.0, grazing_k=k)
            start = perturbed(truth, rng)
            t0 = time.perf_counter()
            r = fit(values, "conductor", grazing_k=k, lambertian=False, verbose=False, **start)
            seconds = time.perf_counter() - t0
            err = {g: r.keywords[g] / truth[g] - 1.0 for g in GEOMETRY}
            err["eta"] = max(
                max(abs(a[0] / b[0] - 1), abs(a[1] / b[1] - 1)) for a, b in zip(r.keywords["eta"], truth["eta"])
            )
            # Against the clean truth (noise-free, no grazing loss): the lobe.
            rel = relative_rms_over_bins(r.material, degrade(clean, np.random.default_rng(9)), 0.0)
            rows.append((j, case, truth, r, err, rel, seconds))
            log(f"material {j} {case}: " + ", ".join(f"{g} {e:+.3f}" for g, e in err.items()) + f", rel {rel:.4f}, {seconds:.1f} s")
    return rows


def mitsuba_cases():
    import mitsuba as mi

    eta = {"type": "rgb", "value": [0.2, 0.45, 1.4]}
    k = {"type": "rgb", "value": [3.9, 2.5, 1.9]}
    cases = []
    for alpha in (0.05, 0.1, 0.2, 0.4):
        cases.append((f"roughconductor beckmann α={alpha}", "conductor", alpha,
                      {"type": "roughconductor", "distribution": "beckmann", "alpha": alpha, "eta": eta, "k": k}))
    for alpha in (0.1, 0.3):
        cases.append((f"roughconductor ggx α={alpha}", "conductor", alpha,
                      {"type": "roughconductor", "distribution": "ggx", "alpha": alpha, "eta": eta, "k": k}))
    for alpha in (0.1, 0.3):
        cases.append((f"roughplastic beckmann α={alpha}", "plastic", alpha,
                      {"type": "roughplastic", "distribution": "beckmann", "alpha": alpha,
                       "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}, "nonlinear": False}))
    return [(name, base, alpha, mi.load_dict(d)) for name, base, alpha, d in cases]


def mitsuba_fits(log):
    import mitsuba as mi

    rows = []
    for name, base, alpha, bsdf in mitsuba_cases():
        values = degrade(merl.tabulate(merl.mitsuba_brdf(bsdf)), np.random.default_rng(5))
        rows.append((name, base, alpha, values))
    out = []
    for name, base, alpha, values in rows:
        for epd in (False, True):
            t0 = time.perf_counter()
            r = fit(values, base, epd=epd, verbose=False, lambertian=base == "conductor")
            seconds = time.perf_counter() - t0
            rel = relative_rms_over_bins(r.material, values)
            out.append((name, alpha, epd, r, rel, seconds, values))
            log(f"{name} {'EPD' if epd else 'two-scale'}: β {r.keywords['beta']:.4f} p {r.keywords['p']:.3f} "
                f"rmse {np.mean(r.metrics['rmse']):.4g} rel {rel:.4f} ({seconds:.1f} s)")
    return out


def subsample_study(log, sizes=(2000, 6000, 20000, 60000)):
    """The accuracy cost of subsampling: the GGX α = 0.3 roughconductor
    (no exact answer) fitted on subsamples of each size, judged over 200 000
    valid bins of the whole file."""
    name, base, alpha, bsdf = [c for c in mitsuba_cases() if c[0] == "roughconductor ggx α=0.3"][0]
    values = degrade(merl.tabulate(merl.mitsuba_brdf(bsdf)), np.random.default_rng(5))
    out = []
    for n in sizes:
        t0 = time.perf_counter()
        r = fit(values, base, samples=n, verbose=False)
        seconds = time.perf_counter() - t0
        rel = relative_rms_over_bins(r.material, values)
        out.append((n, r, rel, seconds))
        log(f"subsample {n}: β {r.keywords['beta']:.4f} p {r.keywords['p']:.3f} rel {rel:.4f} ({seconds:.1f} s)")
    return name, out


def lobe_plot(path, title, values, materials, theta_i_deg=(20, 45, 70)):
    """The measured lobe in the plane of incidence per channel, with the
    fitted ones (HP17 Figs. 12–13)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    theta_o = np.radians(np.linspace(-89, 89, 357))
    fig, axes = plt.subplots(1, len(theta_i_deg), figsize=(4 * len(theta_i_deg), 3.2), squeeze=False)
    colours = ["tab:red", "tab:green", "tab:blue"]
    for ax, ti_deg in zip(axes[0], theta_i_deg):
        ti = math.radians(ti_deg)
        wi = np.tile([math.sin(ti), 0.0, math.cos(ti)], (len(theta_o), 1))
        # The viewer on the other side of the normal for θo > 0 (specular side).
        wo = np.stack([-np.sin(theta_o), np.zeros_like(theta_o), np.cos(theta_o)], axis=1)
        m = merl.lookup(values, wi, wo)
        for c in range(3):
            ax.semilogy(np.degrees(theta_o), m[:, c], ".", ms=2, color=colours[c])
        for (label, mat), style in zip(materials, ["-", "--"]):
            f = mat.eval(wi, wo)
            for c in range(3):
                ax.semilogy(np.degrees(theta_o), f[:, c], style, lw=1, color=colours[c],
                            label=label if c == 0 else None)
        ax.set_title(f"θi = {ti_deg}°")
        ax.set_xlabel("θo (°, + = specular side)")
    axes[0][0].set_ylabel("ρ (sr⁻¹)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--materials", type=positive_int, default=6)
    parser.add_argument("--img", default="docs/img")
    parser.add_argument("--seed", type=int, default=28)
    parser.add_argument("--skip-mitsuba", action="store_true")
    parser.add_argument("--subsample-study", action="store_true", help="only the subsample-size table")
    a = parser.parse_args()
    if a.subsample_study:
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb" if "llvm_ad_rgb" in mi.variants() else "scalar_rgb")
        log = lambda *x: print(*x, file=sys.stderr, flush=True)  # noqa: E731
        log(f"load average {os.getloadavg()}")
        name, rows = subsample_study(log)
        print(f"| {name}: samples | valid samples | β | p | rel. RMS over the bins | time (s) |")
        print("|---|---|---|---|---|---|")
        for n, r, rel, seconds in rows:
            print(f"| {n} | {r.samples} | {r.keywords['beta']:.4f} | {r.keywords['p']:.3f} | {100 * rel:.2f}% | {seconds:.1f} |")
        return
    rng = np.random.default_rng(a.seed)
    log = lambda *x: print(*x, file=sys.stderr, flush=True)  # noqa: E731
    log(f"load average {os.getloadavg()}")
    rows = recovery(a.materials, rng, log) if a.materials else []
    print("| material | file | β | p | σs | b | c | max η | rel. RMS (clean truth) | time (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for j, case, truth, r, err, rel, seconds in rows:
        cells = " | ".join(f"{100 * err[g]:+.1f}%" for g in (*GEOMETRY, "eta"))
        print(f"| {j} (β {truth['beta']:.3f}, p {truth['p']:.2f}) | {case} | {cells} | {100 * rel:.2f}% | {seconds:.1f} |")
    print()
    if a.skip_mitsuba:
        return
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb" if "llvm_ad_rgb" in mi.variants() else "scalar_rgb")
    fits = mitsuba_fits(log)
    print("| Mitsuba BSDF | model | β | p | σs (µm) | RMSE (r, g, b) | sMAPE | rel. RMS | time (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, alpha, epd, r, rel, seconds, _ in fits:
        rmse = ", ".join(f"{x:.3g}" for x in r.metrics["rmse"])
        print(f"| {name} | {'EPD' if epd else 'two-scale'} | {r.keywords['beta']:.4f} | {r.keywords['p']:.3f} | "
              f"{r.keywords['sigma_s']:.4f} | {rmse} | {r.metrics['smape']:.4f} | {100 * rel:.2f}% | {seconds:.1f} |")
    if a.img:
        os.makedirs(a.img, exist_ok=True)
        by_name = {}
        for name, alpha, epd, r, rel, seconds, values in fits:
            by_name.setdefault(name, [values]).append(("EPD" if epd else "two-scale", r.material))
        for name in ("roughconductor beckmann α=0.1", "roughconductor ggx α=0.3", "roughplastic beckmann α=0.3"):
            values, *mats = by_name[name]
            file = os.path.join(a.img, "fit-" + name.split(" α")[0].replace(" ", "-") + ".png")
            lobe_plot(file, f"Mitsuba {name}: MERL bins (dots) and fits", values, mats)
            log(f"wrote {file}")


if __name__ == "__main__":
    run(main)
