"""Fitting the two-scale model to a measured BRDF (HP17 §5).

``fit(measured, base="conductor", **start)`` fits β, p, σs, b, c, the complex
index of each channel and the base or Lambertian term to a MERL file (a path
or the array :func:`twoscale.merl.read` returns) or to samples
``(wi, wo, rgb)``, and returns a :class:`Fit` (``.material`` is the fitted
:class:`twoscale.Material`, ``.toml()`` its TOML). From the shell::

    python -m twoscale.fit FILE.binary [--out params.toml] [--base plastic]

**Objective** (HP17 56–60): over directions uniform in (θi, ωo), weighted by
cos θi (HP17 56's ``dωo cos θi dθi``),

    E² = Σ w_C(m) cos θi (m − p(i, o) ρ(i, o))²,
    w_C(m) = (f(m/median, ln 2) / (m/median))^1.4,   f(x, α) = (1 − e^{−αx})/α,
    p(i, o) = p1(θi) p1(θo),   p1(θ) = (1 − 4θ²/π²)^k,

summed over the three channels, ``median`` the cos θi-weighted median of
the channel's measured values. The grazing exponent ``k`` is **given, not
fitted** (``grazing_k``, default 0: no compensation): the paper gives it
only as "≈ 0 for glossy, ≈ 1 for specular", and on model data it trades
off against p.

**Method**: ``scipy.optimize.least_squares`` (trust-region reflective,
bounded) over the logarithms of the positive parameters (β, p, σs, b,
c − 1, n, k; albedo and k_d linear in [0, 1]), on a stratified subsample of
``samples`` directions (jittered strata of (θi, cos θo, φo − φi); MERL bins
looked up with :func:`twoscale.merl.lookup`, missing ones dropped),
started from a moment-based guess (β and p from the backscattering lobe,
θd ≈ 0: ln(q0/q) = (tan²θh/β²)^p with q = ρ cos⁶θh; F0 from the peak) and
from ``starts − 1`` variants of it (diffraction off; β = 0.1, p = 1;
diffraction on; other n), each run for ``START_NFEV`` iterations; the best
is refined. The two-scale fit from the guess alone (no ``start``) first
fits the EPD model (its σs → 0 limit) and starts from that with
diffraction off and on, then from the guess, so it is never worse than the
EPD fit on its own samples. Keywords of ``start`` (``beta=``, ``p=``,
``sigma_s=``, ``b=``, ``c=``, ``eta=``, ``albedo=``, ``lambertian=``) replace
the guess; ``fixed=`` names parameters held at their start. ``epd=True`` is
the plain EPD Cook–Torrance model (σs = 0), HP17 Table 1's "EPD" row.

**Metrics** (HP17 Table 2), on a separate stratified set of directions:
``rmse_theta_i`` = (∫ (m − p ρ)² cos²θi dωo)^½ at θi = 2.5°, 7.5°, …, 87.5°
(mean over channels) and ``rmse`` its RMS over θi per channel; ``smape`` =
mean of |m − p ρ| / (m + p ρ) over valid samples and channels (HP17 uses
images; this is over BRDF samples); ``relative_rms`` = ‖m − p ρ‖ / ‖m‖ over
the same samples.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time

import numpy as np
from scipy.optimize import least_squares

from . import merl
from ._native import Material

#: The compressive weight's exponent (HP17 57).
WC_EXPONENT = 1.4
#: Default subsample size (directions; × 3 channels residuals).
DEFAULT_SAMPLES = 6000
#: Iterations of each start before the best is refined.
START_NFEV = 8
#: θi of the RMSE(θi) metric, degrees.
RMSE_THETA_I_DEG = tuple(2.5 + 5.0 * k for k in range(18))

# name: (lower, upper, log-parametrised)
_BOUNDS = {
    "beta": (1e-3, 3.0, True),
    "p": (0.2, 5.0, True),
    "sigma_s": (1e-4, 0.5, True),
    "b": (0.02, 50.0, True),
    "c": (1.05, 11.0, True),  # as c − 1
    "n": (0.02, 10.0, True),
    "k": (1e-3, 15.0, True),
    "n_dielectric": (1.01, 3.0, True),
    "albedo": (0.0, 1.0, False),
    "lambertian": (0.0, 1.0, False),
}


@dataclasses.dataclass
class Samples:
    """Directions (``(N, 3)``, ``wi`` towards the light), measured RGB
    (``(N, 3)``, finite) and the objective's per-direction weight."""

    wi: np.ndarray
    wo: np.ndarray
    rgb: np.ndarray
    weight: np.ndarray


def stratified_directions(n, rng):
    """About ``n`` direction pairs, jittered-stratified over θi ∈ [0, π/2),
    cos θo ∈ (0, 1] and φo − φi ∈ [0, π) (uniform in (θi, ωo), isotropy
    and the mirror symmetry φ → −φ folding the azimuth), φi = 0."""
    side = max(2, round(n ** (1.0 / 3.0)))
    a, b, c = np.meshgrid(*[np.arange(side)] * 3, indexing="ij")
    u = (np.stack([a.ravel(), b.ravel(), c.ravel()], axis=1) + rng.uniform(size=(side**3, 3))) / side
    theta_i = u[:, 0] * (np.pi / 2)
    cos_o = 1.0 - u[:, 1]
    phi = u[:, 2] * np.pi
    sin_o = np.sqrt(1.0 - cos_o**2)
    wi = np.stack([np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=1)
    wo = np.stack([sin_o * np.cos(phi), sin_o * np.sin(phi), cos_o], axis=1)
    return wi, wo


def samples_of(measured, n, rng, directions=None) -> Samples:
    """The objective's samples of ``measured``: a MERL array or path, at
    ``n`` stratified directions (or the given ``directions`` pair): each is
    looked up in its bin, the model is compared there at the **bin's
    centre** (so the fit sees no binning error), weighted by the direction's
    cos θi; missing bins are dropped. Or ``(wi, wo, rgb)`` arrays: all rows
    with finite RGB, weight cos θi."""
    if isinstance(measured, (str, os.PathLike)):
        measured = merl.read(measured)
    if isinstance(measured, tuple):
        wi, wo, rgb = (np.asarray(a, dtype=np.float64) for a in measured)
        weight = wi[:, 2].copy()
    else:
        wi, wo = stratified_directions(n, rng) if directions is None else directions
        weight = wi[:, 2].copy()
        bins = merl.index(wi, wo)
        rgb = np.asarray(measured).reshape(3, merl.BINS)[:, bins].T
        wi, wo = merl.bin_centres(bins)
    keep = np.all(np.isfinite(rgb), axis=1) & (wi[:, 2] > 0) & (wo[:, 2] > 0)
    return Samples(wi[keep], wo[keep], rgb[keep], weight[keep])


def weighted_median(x, w):
    """The median of ``x`` weighted by ``w``."""
    order = np.argsort(x)
    cw = np.cumsum(w[order])
    return float(x[order][np.searchsorted(cw, 0.5 * cw[-1])])


def compressive_weight(m, median):
    """w_C of HP17 57–58: (f(x, ln 2)/x)^1.4 with x = m/median and
    f(x, α) = (1 − e^{−αx})/α (→ 1 as x → 0)."""
    alpha = math.log(2.0)
    x = np.maximum(m / median, 1e-12)
    return (-np.expm1(-alpha * x) / alpha / x) ** WC_EXPONENT


def grazing(wi, wo, k):
    """p(i, o) = p1(θi) p1(θo), p1(θ) = (1 − 4θ²/π²)^k (HP17 59–60)."""
    if k == 0:
        return np.ones(len(wi))
    t_i = np.arccos(np.clip(wi[:, 2], -1, 1))
    t_o = np.arccos(np.clip(wo[:, 2], -1, 1))
    p1 = lambda t: np.clip(1.0 - 4.0 * t**2 / np.pi**2, 0.0, 1.0) ** k  # noqa: E731
    return p1(t_i) * p1(t_o)


def _names(base, epd, lambertian):
    names = ["beta", "p"]
    if not epd:
        names += ["sigma_s", "b", "c"]
    names += ["n0", "n1", "n2"]
    if base == "conductor":
        names += ["k0", "k1", "k2"]
    else:
        names += ["albedo"]
    if lambertian:
        names += ["lambertian"]
    return names


def _bound(name, base):
    if name[0] in "nk" and name[1:].isdigit():
        return _BOUNDS["n_dielectric" if (name[0] == "n" and base != "conductor") else name[0]]
    return _BOUNDS[name]


def _to_x(name, value, base):
    lo, hi, log = _bound(name, base)
    v = min(max(value, lo), hi)
    if name == "c":
        return math.log(v - 1.0)
    return math.log(v) if log else v


def _from_x(name, x, base):
    lo, hi, log = _bound(name, base)
    if name == "c":
        return 1.0 + math.exp(x)
    return math.exp(x) if log else x


def _x_bounds(name, base):
    lo, hi, log = _bound(name, base)
    if name == "c":
        return math.log(lo - 1.0), math.log(hi - 1.0)
    return (math.log(lo), math.log(hi)) if log else (lo, hi)


def _flat(params):
    """Material keywords → {name: float} of the fit's parameter names."""
    out = {k: float(v) for k, v in params.items() if k in ("beta", "p", "sigma_s", "b", "c", "albedo", "lambertian")}
    for j, (n, k) in enumerate(params.get("eta", [])):
        out[f"n{j}"], out[f"k{j}"] = float(n), float(k)
    return out


def _keywords(flat, base, epd):
    """{name: float} → Material keywords."""
    kw = {
        "beta": flat["beta"],
        "p": flat["p"],
        "sigma_s": 0.0 if epd else flat["sigma_s"],
        "b": flat.get("b", 1.0),
        "c": flat.get("c", 2.0),
        "eta": [(flat[f"n{j}"], flat.get(f"k{j}", 0.0) if base == "conductor" else 0.0) for j in range(3)],
        "base": base,
        "lambertian": flat.get("lambertian", 0.0),
    }
    if base != "conductor":
        kw["albedo"] = flat["albedo"]
    return kw


def _fresnel0(n, k):
    return ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)


def moment_guess(measured, base="conductor"):
    """A start from the data (flat parameter names): β and p from the
    backscattering lobe of a MERL array (θd bins 0–2, all φd):
    ln(q0/q) = (tan²θh/β²)^p with q = ρ cos⁶θh above the floor, fitted in
    log-log; F0 per channel from the peak, ρ(0) = F0 D(0)/4 with
    D(0) = p/(π β² Γ(1/p)). For samples (no MERL array), β = 0.1, p = 1."""
    guess = {"beta": 0.1, "p": 1.0, "sigma_s": 0.01, "b": 1.0, "c": 2.0, "albedo": 0.5, "lambertian": 0.0}
    f0 = np.full(3, 0.5)
    if isinstance(measured, np.ndarray) and measured.shape == merl.SHAPE:
        back = np.nanmean(measured[:, :, :3, :], axis=(2, 3))  # (3, 90)
        t = (np.arange(90) + 0.5) / 90
        theta_h = np.pi / 2 * t * t
        lum = np.nanmean(back, axis=0)
        ok = np.isfinite(lum)
        if ok.sum() > 5:
            floor = np.nanmin(lum[ok])
            q = (lum - floor) * np.cos(theta_h) ** 6
            q0 = q[ok][0]
            sel = ok & (q > 1e-3 * q0) & (q < 0.9 * q0) & (theta_h < 1.3)
            if q0 > 0 and sel.sum() >= 2:
                x = np.log(np.tan(theta_h[sel]) ** 2)
                y = np.log(np.log(q0 / q[sel]))
                slope, icpt = np.polyfit(x, y, 1)
                p = float(np.clip(slope, 0.3, 4.0))
                beta = float(np.clip(math.exp(-icpt / (2 * p)), 2e-3, 2.0))
                guess["beta"], guess["p"] = beta, p
            d0 = guess["p"] / (math.pi * guess["beta"] ** 2 * math.gamma(1 / guess["p"]))
            f0 = np.clip((back[:, 0] - floor) * 4 / d0, 0.02, 0.98)
            guess["lambertian"] = float(np.clip(floor * math.pi, 0, 0.9))
            if base != "conductor":
                guess["albedo"] = float(np.clip(floor * math.pi * 1.5, 0.01, 0.99))
                guess["lambertian"] = 0.0
    for j in range(3):
        if base == "conductor":
            # n = ½ and k from F0 = ((n − 1)² + k²)/((n + 1)² + k²).
            n = 0.5
            k2 = (f0[j] * (n + 1) ** 2 - (n - 1) ** 2) / (1 - f0[j])
            guess[f"n{j}"], guess[f"k{j}"] = n, float(math.sqrt(max(k2, 0.01)))
        else:
            guess[f"n{j}"] = 1.5
    return guess


@dataclasses.dataclass
class Fit:
    """A fitted material: ``keywords`` (``twoscale.Material(**keywords)``
    rebuilds ``material``), the ``metrics``, the objective's final ``cost``
    (½ Σ r²), ``seconds`` of wall time and the subsample size."""

    material: Material
    keywords: dict
    metrics: dict
    cost: float
    seconds: float
    samples: int

    def toml(self) -> str:
        """``[material]`` (Material's keywords) and ``[metrics]``."""
        return _toml({"material": self.keywords, "metrics": self.metrics})


def _toml_value(v):
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    return repr(float(v))


def _toml(tables):
    lines = []
    for name, table in tables.items():
        lines.append(f"[{name}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
        lines.append("")
    return "\n".join(lines)


def predict(material, wi, wo, grazing_k=0.0):
    """p(i, o) ρ(i, o), ``(N, 3)`` float64: the fitted material as the
    objective compares it with the measurement."""
    return material.eval(wi, wo).astype(np.float64) * grazing(wi, wo, grazing_k)[:, None]


def metrics(material, measured, grazing_k=0.0, n=20000, seed=1):
    """HP17 Table 2's metrics of ``material`` against ``measured`` (see the
    module's documentation), on ``n`` stratified directions."""
    rng = np.random.default_rng(seed)
    per = max(1, n // len(RMSE_THETA_I_DEG))
    rows = {"rmse_theta_i": [], "sq": []}
    all_m, all_f = [], []
    for deg in RMSE_THETA_I_DEG:
        # ωo uniform over the hemisphere (stratified in cos θo, φ), θi fixed.
        _, wo = stratified_directions(per, rng)
        ti = math.radians(deg)
        wi = np.tile([math.sin(ti), 0.0, math.cos(ti)], (len(wo), 1))
        s = samples_of(measured, 0, rng, directions=(wi, wo))
        f = predict(material, s.wi, s.wo, grazing_k)
        # ∫ dωo ≈ 2π × the mean over the hemisphere (missing bins count 0).
        sq = 2 * np.pi * np.sum((s.rgb - f) ** 2, axis=0) / len(wo) * math.cos(ti) ** 2
        rows["sq"].append(sq)
        rows["rmse_theta_i"].append(float(np.mean(np.sqrt(sq))))
        all_m.append(s.rgb)
        all_f.append(f)
    return {
        "rmse": [float(x) for x in np.sqrt(np.mean(rows["sq"], axis=0))],
        "rmse_theta_i_deg": list(RMSE_THETA_I_DEG),
        "rmse_theta_i": rows["rmse_theta_i"],
        **_sample_metrics(np.concatenate(all_m), np.concatenate(all_f)),
    }


def _sample_metrics(m, f):
    """sMAPE and ‖m − f‖/‖m‖ over paired values."""
    denom = m + f
    smape = np.where(denom > 0, np.abs(m - f) / np.where(denom > 0, denom, 1), 0.0)
    return {"smape": float(np.mean(smape)), "relative_rms": float(np.linalg.norm(m - f) / np.linalg.norm(m))}


def fit(
    measured,
    base="conductor",
    *,
    samples=DEFAULT_SAMPLES,
    starts=3,
    grazing_k=0.0,
    epd=False,
    lambertian=True,
    fixed=(),
    seed=0,
    max_nfev=None,
    verbose=True,
    **start,
) -> Fit:
    """fit(measured, base="conductor", *, samples=DEFAULT_SAMPLES, starts=3,
    grazing_k=0.0, epd=False, lambertian=True, fixed=(), seed=0,
    max_nfev=None, verbose=True, **start)

    Fits the model to ``measured`` (a MERL file's path or array, or
    ``(wi, wo, rgb)`` samples; see the module's documentation).
    ``base``: "conductor", "plastic" or "subsurface"; ``samples``: the
    subsample size; ``starts``: how many starts; ``lambertian``: fit a
    Lambertian term k_d (else 0); ``start``: Material keywords replacing
    the moment-based guess; ``fixed``: parameter names held at their start
    ("beta", "p", "sigma_s", "b", "c", "n0"…"k2", "albedo", "lambertian")."""
    t0 = time.perf_counter()
    if isinstance(measured, (str, os.PathLike)):
        measured = merl.read(measured)
    rng = np.random.default_rng(seed)
    s = samples_of(measured, samples, rng)
    if len(s.wi) < 50:
        raise ValueError(f"only {len(s.wi)} valid samples")
    median = np.array([weighted_median(s.rgb[:, c], s.weight) for c in range(3)])
    median = np.where(median > 0, median, max(float(np.mean(s.rgb)), 1e-12))
    sqrt_w = np.sqrt(s.weight[:, None] * compressive_weight(s.rgb, median))
    # Normalised by the objective of ρ = 0, so the tolerances are relative.
    sqrt_w /= max(float(np.linalg.norm(sqrt_w * s.rgb)), 1e-300)
    graz = grazing(s.wi, s.wo, grazing_k)[:, None]
    names = [n for n in _names(base, epd, lambertian) if n not in fixed]
    guess = moment_guess(measured, base)
    guess.update(_flat(start))
    if not lambertian:
        guess["lambertian"] = 0.0
    base_flat = dict(guess)

    def material_of(x):
        flat = dict(base_flat)
        flat.update({n: _from_x(n, xi, base) for n, xi in zip(names, x)})
        return flat

    def residuals(x):
        kw = _keywords(material_of(x), base, epd)
        f = Material(**kw).eval(s.wi, s.wo).astype(np.float64)
        return (sqrt_w * (s.rgb - graz * f)).ravel()

    lo, hi = np.array([_x_bounds(n, base) for n in names]).T

    def x_of(flat):
        return np.clip([_to_x(n, flat[n], base) for n in names], lo + 1e-9, hi - 1e-9)

    # Starts: the guess, then diffraction off/on and other indices; for the
    # two-scale model from the guess alone, the EPD fit (its σs → 0 limit)
    # first, with diffraction off and on.
    variants = [{}]
    if not epd and not start and starts > 1:
        e = fit(measured, base, samples=samples, starts=starts, grazing_k=grazing_k, epd=True,
                lambertian=lambertian, fixed=fixed, seed=seed, max_nfev=max_nfev, verbose=verbose)
        from_epd = {k: v for k, v in _flat(e.keywords).items() if k in names}
        variants = [from_epd | {"sigma_s": 1e-4}, from_epd | {"sigma_s": 0.02, "b": 2.0}, {}]
    if not epd and "sigma_s" not in start:
        variants += [{"sigma_s": 1e-4}]
    if "beta" not in start and "p" not in start:
        variants += [{"beta": 0.1, "p": 1.0}]
    if not epd and "sigma_s" not in start:
        variants += [{"sigma_s": 0.05, "b": 5.0}]
    if base == "conductor" and "eta" not in start:
        variants += [{f"n{j}": 1.5 for j in range(3)} | {f"k{j}": 3.0 for j in range(3)}]
    variants = variants[: max(1, starts)]
    log = (lambda *a: print(*a, file=sys.stderr, flush=True)) if verbose else (lambda *a: None)
    log(f"twoscale.fit: {len(s.wi)} samples × 3 channels, {len(names)} parameters, {len(variants)} starts")
    best = None
    for j, v in enumerate(variants):
        flat = dict(guess)
        flat.update(v)
        r = least_squares(residuals, x_of(flat), bounds=(lo, hi), diff_step=1e-4,
                          max_nfev=min(max_nfev or START_NFEV, START_NFEV) if len(variants) > 1 else max_nfev)
        log(f"  start {j}: cost {r.cost:.4g} after {r.nfev} evaluations ({time.perf_counter() - t0:.1f} s)")
        if best is None or r.cost < best.cost:
            best = r
    if len(variants) > 1:
        best = least_squares(residuals, best.x, bounds=(lo, hi), diff_step=1e-4, max_nfev=max_nfev)
        log(f"  refined: cost {best.cost:.4g} after {best.nfev} evaluations ({time.perf_counter() - t0:.1f} s)")
    keywords = _keywords(material_of(best.x), base, epd)
    material = Material(**keywords)
    if isinstance(measured, tuple):
        m = _sample_metrics(s.rgb, predict(material, s.wi, s.wo, grazing_k))
    else:
        m = metrics(material, measured, grazing_k)
    seconds = time.perf_counter() - t0
    log(f"  done in {seconds:.1f} s: " + ", ".join(f"{k}={v:.4g}" for k, v in _flat(keywords).items()))
    return Fit(material, keywords, m, float(best.cost), seconds, len(s.wi))


def load(path) -> Material:
    """The material of a fit's TOML (its ``[material]`` table), read by the
    runtime as the C API and the generator read it
    (:meth:`twoscale.Material.from_toml`); for Mitsuba,
    ``{"type": "twoscale", "filename": path}``."""
    return Material.from_toml(path)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m twoscale.fit", description=__doc__.split("\n\n")[0])
    parser.add_argument("file", help="a MERL .binary file")
    parser.add_argument("--out", help="write the fitted [material] and [metrics] TOML here (default: stdout)")
    parser.add_argument("--base", default="conductor", choices=["conductor", "plastic", "subsurface"])
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES, help="subsample size")
    parser.add_argument("--starts", type=int, default=3)
    parser.add_argument("--grazing-k", type=float, default=0.0, help="HP17 60's exponent k (given, not fitted)")
    parser.add_argument("--epd", action="store_true", help="plain EPD Cook–Torrance (σs = 0)")
    parser.add_argument("--no-lambertian", action="store_true", help="no Lambertian term")
    parser.add_argument("--seed", type=int, default=0)
    a = parser.parse_args(argv)
    result = fit(a.file, a.base, samples=a.samples, starts=a.starts, grazing_k=a.grazing_k, epd=a.epd,
                 lambertian=not a.no_lambertian, seed=a.seed)
    text = result.toml()
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
