"""Relative variance of the sampling weight, E[w²]/E[w]² − 1 with
w = ρ cos θo / pdf (failed samples count as w = 0), of the twoscale sampler
at σs = 0 (the EPD conductor, η = 1 + 6.6i): against Mitsuba 3's
`roughconductor` (Beckmann, visible normals, same α, η, k) in the same
process at p = 1, and against exact visible-normal sampling at every p (the
variance of w under D_vis, by quadrature), with the variance of the D cos θm
sampler used before (by quadrature). Prints a Markdown table per comparison
(docs/design/visible-normals.md); `--quick` runs a few rows. `--halo`
prints instead the variance of the presets and of materials with strong
halos (σs up to 0.1 µm, b 1–20 µm, β 0.01–0.5) at 0°/45°/70°/85°, against
the issue's targets (≤ 0.1 at θi ≤ 70°, ≤ 0.5 at 85°;
docs/design/halo-sampling.md). `--spectral` prints the variance of the
spectral sampler's weight (`Material.sample_spectral`, one wavelength) at
the sampler models' wavelengths, where the sampler is the model at λ, and
at the models between them, where it is the nearest sampler model's
(docs/design/rgb-integration.md). `--equal-noise` prints, for a few
presets, the variance (green) beside that of `roughconductor` (Beckmann,
α = β, η = 1 + 6.6i) at the same incidence: with the cost ratio of
`studies brdf-timing`, the time to equal noise
(docs/design/halo-sampling.md).

    python python/examples/sampler_variance.py [--samples N] [--quick] [--halo | --spectral | --equal-noise]
        [--markdown FILE]

`--markdown FILE` also writes the tables to FILE under a line naming the
command (docs/figures/visible-normals.md, docs/figures/halo-sampling.md,
docs/figures/equal-noise.md); the samples are drawn from fixed seeds, so
the same code writes the same file.
"""

import argparse
import contextlib
import io
import os
import sys

import numpy as np
from scipy.special import expit, gammainccinv, gammaincinv

import twoscale

ETA = [(1.0, 6.6)] * 3


def direction(theta_deg):
    t = np.radians(theta_deg)
    return np.array([np.sin(t), 0.0, np.cos(t)])


def relative_variance(w):
    """E[w²]/E[w]² − 1 per channel of weights w (N, 3)."""
    w = np.asarray(w, dtype=np.float64)
    m1, m2 = w.mean(axis=0), (w * w).mean(axis=0)
    return m2 / (m1 * m1) - 1.0


def material(beta, p):
    return twoscale.Material(beta=beta, p=p, sigma_s=0.0, eta=ETA)


def twoscale_variance(beta, p, theta, n, seed=1):
    """Per channel, of `twoscale.Material.sample` (weight 0 where it fails)."""
    return material_variance(material(beta, p), theta, n, seed)


def material_variance(mat, theta, n, seed=1):
    """Per channel, of `mat.sample` at incidence θi (weight 0 where it fails)."""
    rng = np.random.default_rng(seed)
    wi = np.broadcast_to(direction(theta).astype(np.float32), (n, 3))
    u = rng.random((n, 3), dtype=np.float32)
    _, pdf, weight = mat.sample(np.ascontiguousarray(wi), u)
    return relative_variance(np.where((pdf > 0)[:, None], weight, 0.0))


GOLD = twoscale.Material.preset("gold-rough").eta


def gold_spectrum():
    """Gold's measured index as `eta=(lam, n, k)`: the 1 nm table of the
    preset's spectral model."""
    bakes = twoscale.Material.preset("gold-rough").spectral_bakes()
    eta = np.asarray(bakes["eta"], dtype=np.float64)
    lam = bakes["eta_first"] + bakes["eta_step"] * np.arange(len(eta))
    return (lam, eta[:, 0], eta[:, 1])


def halo_materials(spectral=False):
    """(name, Material): the presets and gold with strong halos, the
    issue's (β 0.1, p 1, σs 0.1, b 3, c 1.6) first; with `spectral`, gold's
    index over the spectrum rather than at the paper's wavelengths."""
    out = [(name, twoscale.Material.preset(name)) for name in twoscale.Material.presets()]
    eta = gold_spectrum() if spectral else GOLD
    for beta, sigma_s, b, c in [(0.1, 0.1, 3.0, 1.6), (0.01, 0.1, 1.0, 2.0), (0.01, 0.1, 20.0, 2.0),
                                (0.5, 0.1, 1.0, 2.0), (0.5, 0.1, 20.0, 2.0), (0.1, 0.05, 10.0, 3.0)]:
        name = f"strong halo (β {beta}, p 1, σs {sigma_s}, b {b:g}, c {c}, gold)"
        out.append((name, twoscale.Material(beta=beta, p=1.0, sigma_s=sigma_s, b=b, c=c, eta=eta)))
    return out


def halo_rows(thetas, n, materials=None):
    """The variance of the presets and strong halos, every channel, with ✗
    where the issue's target (≤ 0.1 at θi ≤ 70°, ≤ 0.5 at 85°) is missed."""
    print("| material | " + " | ".join(f"{t}°" for t in thetas) + " |")
    print("|---|" + "---|" * len(thetas))
    rows = []
    for name, mat in materials or halo_materials():
        cells = []
        for theta in thetas:
            v = material_variance(mat, theta, n)
            target = 0.1 if theta <= 70 else 0.5
            cells.append(channels(v) + ("" if np.all(v <= target) else " ✗"))
            rows.append((name, theta, v, target))
        print(f"| {name} | " + " | ".join(cells) + " |")
    return rows


def spectral_variance(mat, theta, lam, n, seed=1):
    """Of `mat.sample_spectral` at incidence θi and wavelength `lam` µm, the
    weight `eval_spectral · cos θo / pdf` (0 where it fails)."""
    rng = np.random.default_rng(seed)
    wi = np.ascontiguousarray(np.broadcast_to(direction(theta).astype(np.float32), (n, 3)))
    u = rng.random((n, 3), dtype=np.float32)
    lams = np.full(n, lam, dtype=np.float32)
    wo, pdf = mat.sample_spectral(wi, u, lams)
    ok = pdf > 0
    rho = mat.eval_spectral(wi, np.where(ok[:, None], wo, [0, 0, 1]).astype(np.float32), lams)
    w = np.where(ok, rho * wo[:, 2] / np.where(ok, pdf, 1.0), 0.0)
    return relative_variance(w[:, None])[0]


def spectral_rows(thetas, n, materials=None):
    """Per material and θi, the weight's variance at each model between two
    sampler models (where the sampler is up to 0.04 µm away) against the
    variance interpolated linearly in λ between those two (where it is the
    model at λ): the largest ratio, and the variances at the worst model."""
    lams = twoscale.Material.preset("gold-rough").spectral_bakes()["wavelengths"]
    print("| material | θi | largest ratio, between / sampler models (at λ) | variance there: between, sampler models around |")
    print("|---|---|---|---|")
    rows = []
    for name, mat in materials or halo_materials(spectral=True):
        for theta in thetas:
            v = [spectral_variance(mat, theta, float(lam), n) for lam in lams]
            worst = (0.0, 0.0, 0.0, 0.0, 0.0)
            for k in range(1, len(lams) - 1, 2):
                f = (lams[k] - lams[k - 1]) / (lams[k + 1] - lams[k - 1])
                expected = (1 - f) * v[k - 1] + f * v[k + 1]
                ratio = v[k] / expected if expected > 0 else np.inf
                if ratio > worst[0]:
                    worst = (ratio, lams[k], v[k], v[k - 1], v[k + 1])
            ratio, lam, vk, va, vb = worst
            print(f"| {name} | {theta}° | {ratio:.3f} ({lam:.3f} µm) | {fmt(vk)}: {fmt(va)}, {fmt(vb)} |")
            rows.append((name, theta, ratio))
    return rows


def equal_noise_rows(n):
    """Per (preset, θi): the variance of the green weight of the preset and
    of `roughconductor` at α = β."""
    print("| preset (β) | θi | twoscale relvar (green) | roughconductor relvar (green) |")
    print("|---|---|---|---|")
    rows = []
    for name, theta in [("gold-hp17-geometry", 45), ("gold-hp17-geometry", 85), ("gold-rough", 45),
                        ("gold-rough", 85), ("aluminium", 85), ("silver", 85)]:
        mat = twoscale.Material.preset(name)
        ts = material_variance(mat, theta, n)[1]
        rc = mitsuba_variance(mat.beta, theta, n)[1]
        print(f"| {name} ({mat.beta:.2g}, p {mat.p:g}) | {theta}° | {fmt(ts)} | {fmt(rc)} |")
        rows.append((name, theta, ts, rc))
    return rows


def mitsuba_variance(alpha, theta, n, seed=1):
    """Per channel, of `roughconductor` (beckmann, sample_visible)."""
    import drjit as dr
    import mitsuba as mi

    bsdf = mi.load_dict({
        "type": "roughconductor", "distribution": "beckmann", "alpha": alpha,
        "sample_visible": True,
        "eta": {"type": "rgb", "value": [e[0] for e in ETA]},
        "k": {"type": "rgb", "value": [e[1] for e in ETA]},
    })
    rng = np.random.default_rng(seed)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    wi = direction(theta)
    si.wi = mi.Vector3f(*[np.full(n, x, dtype=np.float32) for x in wi])
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    u = rng.random((3, n), dtype=np.float32)
    bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    weight = np.asarray(weight, dtype=np.float64).reshape(3, n).T
    ok = np.asarray(bs.pdf) > 0
    return relative_variance(np.where(ok[:, None], weight, 0.0))


def quadrature_variances(beta, p, theta, n_radius=2400, n_angle=720):
    """Per channel, the variance of w under exact visible-normal sampling
    (D_vis) and under the D cos θm sampler the project used before (HP17
    49–50), by quadrature over the stretched slope plane in polar
    coordinates: the radius from the Gamma(1/p) quantile of the D cos
    measure (r^{2p} ~ Gamma(1/p)), logit-spaced, the angle even. Under
    D_vis, w = ρ cos θo · 4 cos θi / (G1(i) D(m)); the constant G1(i) does
    not change a relative variance, so w ∝ ρ(i, o) cos θo / D(m) with ρ the
    runtime model's eval. Under D cos, w = ρ cos θo · 4 (i·m) / (D cos θm).
    Returns (visible, d_cos)."""
    v = np.linspace(-14.0, 14.0, n_radius)
    dv = v[1] - v[0]
    q = expit(v)
    dq = q * (1 - q) * dv
    # each tail from its own side, so that neither is rounded away
    y = np.where(v < 0, gammaincinv(1 / p, q), gammainccinv(1 / p, expit(-v)))
    r = y ** (0.5 / p)
    phi = (np.arange(n_angle) + 0.5) / n_angle * 2 * np.pi
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    weight_r = np.broadcast_to(dq[:, None], rr.shape)
    wi = direction(theta)
    sx, sy = beta * rr * np.cos(pp), beta * rr * np.sin(pp)
    m = np.stack([-sx, -sy, np.ones_like(sx)], axis=-1)
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    cos_im = m @ wi
    o = 2 * cos_im[..., None] * m - wi
    visible = np.clip(cos_im / m[..., 2], 0.0, None)  # ∝ (c − s x̃)₊, the D_vis factor
    keep = (visible > 0) & (o[..., 2] > 1e-7)
    mm, oo = m[keep], o[keep]
    tan2 = (mm[:, 0] ** 2 + mm[:, 1] ** 2) / mm[:, 2] ** 2
    d = np.exp(-((tan2 / beta**2) ** p)) / mm[:, 2] ** 4
    wis = np.ascontiguousarray(np.broadcast_to(wi.astype(np.float32), oo.shape))
    rho = material(beta, p).eval(wis, oo.astype(np.float32)).astype(np.float64)
    w_vis = rho * oo[:, 2:3] / d[:, None]
    w_dcos = w_vis * (cos_im[keep] / mm[:, 2])[:, None]

    def rel(mass, w):
        total = mass.sum()
        mk = mass[keep][:, None]
        m1 = (mk * w).sum(axis=0) / total
        m2 = (mk * w * w).sum(axis=0) / total
        return m2 / (m1 * m1) - 1.0

    return rel(visible * weight_r, w_vis), rel(np.asarray(weight_r), w_dcos)


def visible_variance(beta, p, theta):
    """Per channel, of w under exact visible-normal sampling (quadrature)."""
    return quadrature_variances(beta, p, theta)[0]


def fmt(x):
    return f"{x:.4f}" if x >= 1e-3 else f"{x:.1e}"


def channels(v):
    return " / ".join(fmt(x) for x in v)


def beckmann_rows(alphas, thetas, n):
    print("| α | θi | twoscale (R / G / B) | Mitsuba, visible normals | target 1.1 × Mitsuba + 0.002 | exact D_vis (quadrature) | D cos, the previous sampler (quadrature) |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for alpha in alphas:
        for theta in thetas:
            ts = twoscale_variance(alpha, 1.0, theta, n)
            mi_ = mitsuba_variance(alpha, theta, n)
            ex, dcos = quadrature_variances(alpha, 1.0, theta)
            target = 1.1 * mi_ + 0.002
            ok = "" if np.all(ts <= target) else " ✗"
            print(f"| {alpha} | {theta}° | {channels(ts)}{ok} | {channels(mi_)} | {channels(target)} "
                  f"| {channels(ex)} | {channels(dcos)} |")
            rows.append((alpha, theta, ts, mi_, ex))
    return rows


def shape_rows(ps, betas, thetas, n):
    print("| p | β | θi | twoscale (R / G / B) | exact D_vis (quadrature) | ratio (max over channels) | D cos, the previous sampler (quadrature) |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for p in ps:
        for beta in betas:
            for theta in thetas:
                ts = twoscale_variance(beta, p, theta, n)
                ex, dcos = quadrature_variances(beta, p, theta)
                ratio = np.max(ts / ex)
                print(f"| {p} | {beta} | {theta}° | {channels(ts)} | {channels(ex)} | {ratio:.3f} "
                      f"| {channels(dcos)} |")
                rows.append((p, beta, theta, ts, ex))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--quick", action="store_true", help="a few rows")
    parser.add_argument("--halo", action="store_true", help="the presets and strong halos")
    parser.add_argument("--spectral", action="store_true",
                        help="the spectral sampler between its sampler models")
    parser.add_argument("--equal-noise", action="store_true",
                        help="a few presets beside roughconductor")
    parser.add_argument("--markdown", metavar="FILE",
                        help="also write the tables to FILE (docs/figures/)")
    args = parser.parse_args()
    if args.markdown is not None and not os.path.isdir(os.path.dirname(args.markdown) or "."):
        sys.exit(f"error: {args.markdown}: no directory {os.path.dirname(args.markdown)}")
    if args.markdown is None:
        run(args)
        return
    # The tables go to stdout as they are computed and, at the end, to FILE.
    captured = io.StringIO()
    with contextlib.redirect_stdout(_Tee(sys.stdout, captured)):
        run(args)
    command = " ".join(["python python/examples/sampler_variance.py"] + sys.argv[1:])
    try:
        with open(args.markdown, "w", encoding="utf-8") as f:
            f.write(f"# Relative variance of the sampling weight: {_subject(args)}\n\n"
                    f"Written by `{command}` "
                    "(do not edit: rerun the command). E[w²]/E[w]² − 1 per channel of "
                    "w = ρ cos θo / pdf, failed samples counting as w = 0.\n\n")
            f.write(captured.getvalue())
    except OSError as e:
        sys.exit(f"error: {args.markdown}: {e.strerror}")


def _subject(args):
    """What the tables of `args` measure (the title of `--markdown`'s file)."""
    if args.halo:
        return "the presets and strong halos (docs/design/halo-sampling.md)"
    if args.spectral:
        return "the spectral sampler between its sampler models (docs/design/rgb-integration.md)"
    if args.equal_noise:
        return "presets beside roughconductor (docs/design/halo-sampling.md)"
    return "visible normals at σs = 0 (docs/design/visible-normals.md)"


class _Tee(io.TextIOBase):
    """Writes to every stream it holds."""

    def __init__(self, *streams):
        self.streams = streams

    def write(self, text):
        for stream in self.streams:
            stream.write(text)
        return len(text)


def run(args):
    if args.halo:
        halo_rows([0, 45, 70, 85], args.samples)
        return
    if args.spectral:
        spectral_rows([0, 45, 70, 85], args.samples)
        return
    llvm = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
    if os.path.exists(llvm):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    if args.equal_noise:
        equal_noise_rows(args.samples)
        return
    if args.quick:
        beckmann_rows([0.2, 0.5], [45, 85], args.samples)
        print()
        shape_rows([0.3, 4.0], [0.2], [45, 85], args.samples)
        return
    beckmann_rows([0.02, 0.05, 0.2, 0.5, 1.0], [0, 45, 70, 80, 85], args.samples)
    print()
    shape_rows([0.3, 0.6, 2.0, 4.0], [0.05, 0.5], [0, 45, 70, 85], args.samples)


if __name__ == "__main__":
    main()
