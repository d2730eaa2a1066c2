"""Fitting the two-scale model to a measured BRDF (HP17 §5).

``fit(measured, base="conductor", **start)`` fits β, p, σs, b, c, the complex
index of each channel and the base or Lambertian term to a MERL file (a path
or the array :func:`twoscale.merl.read` returns) or to samples
``(wi, wo, rgb)``, and returns a :class:`Fit` (``.material`` is the fitted
:class:`twoscale.Material`, ``.toml()`` its TOML, ``.standard_error`` and
``.undetermined`` what the data fix). From the shell::

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

**Method** (docs/design/merl-fit.md): ``scipy.optimize.least_squares``
(trust-region reflective, bounded) over the logarithms of the positive
parameters (β, p, σs, b, c − 1, n, k; albedo and k_d linear in [0, 1]), on
a stratified subsample of ``samples`` directions (jittered strata of
(θi, cos θo, φo − φi); MERL bins looked up with :func:`twoscale.merl.lookup`,
missing ones dropped). The Jacobian is by forward differences of step
``FD_STEP`` in those coordinates, one evaluation per geometric parameter,
one for the three n and one for the three k (each channel's index moves
that channel alone), k_d's column in closed form. Two stages, each start
run to convergence (``START_XTOL``, at most ``START_NFEV`` evaluations):
the EPD model (σs = 0) from a moment-based guess and ``EPD_STARTS``; then
the two-scale model from the EPD fit with each halo start of
``HALO_STARTS`` (σs, b, c), the EPD fit itself being the candidate "no
diffraction". A stage stops once its lowest minimum has been reached from
two starts (``same_minimum``). The lowest cost wins and is refined on
``refine_samples`` directions; a parameter the solver drives to its bound
is held there and the rest refitted (a Lambertian term at 0 is written as
0, σs at its lower bound as 0: no diffraction).
The starts are fixed, so the seed changes only the subsample. Keywords of
``start`` (``beta=``, ``p=``, ``sigma_s=``, ``b=``, ``c=``, ``eta=``,
``albedo=``, ``lambertian=``) replace the guess (with σs, b or c given, the
one start is the guess); ``fixed=`` names parameters held at their start.
``epd=True`` is the plain EPD Cook–Torrance model (σs = 0), HP17 Table 1's
"EPD" row.

**What the data fix.** At the solution, the standard error of each free
parameter is the sandwich estimate
``(JᵀJ)⁻¹ Jᵀ diag(r²) J (JᵀJ)⁻¹`` of the weighted residuals r (valid for
noise of any per-sample variance; the noise is what the residuals are). A
parameter whose standard error exceeds ``UNDETERMINED_SE`` (σ of ln θ, or
of θ for albedo and k_d), or that lies in the numerical null space of the
column-scaled Jacobian (singular value below ``NULL_RCOND`` of the
largest), is **undetermined**: held at its fitted value, listed in
``Fit.undetermined``, and the others' errors recomputed with it held. b and
c are undetermined when σs = 0.

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

try:
    from scipy.optimize import least_squares
except ImportError as e:  # a declared dependency; installed without it (--no-deps)
    raise ImportError("twoscale.fit needs SciPy (a dependency of twoscale): pip install scipy") from e

from . import merl
from ._native import RGB_WAVELENGTHS, Material

#: The compressive weight's exponent (HP17 57).
WC_EXPONENT = 1.4
#: Default subsample size (directions; × 3 channels residuals).
DEFAULT_SAMPLES = 6000
#: Default subsample of the final refinement (directions).
DEFAULT_REFINE_SAMPLES = 200_000
#: The smallest subsample accepted.
MIN_SAMPLES = 100
#: Forward-difference step of the Jacobian, in the solver's coordinates
#: (logarithms: a relative step).
FD_STEP = 3e-4
#: Starts of the EPD stage, besides the guess: (β, p) and the index.
EPD_STARTS = ({"beta": 0.1, "p": 1.0}, {"index": (1.5, 3.0)})
#: Starts of the two-scale stage: (σs µm, b µm, c), from the EPD fit.
HALO_STARTS = ((0.02, 3.0, 2.5), (0.05, 15.0, 3.5), (0.01, 8.0, 2.0), (0.005, 1.0, 1.5))
#: xtol of each start (least_squares' relative step tolerance; the final
#: refinement runs to 1e-8).
START_XTOL = 1e-5
#: At most this many evaluations of each start (converged starts took
#: 16–90; one from far away crawled 559 to a worse minimum).
START_NFEV = 100
#: Two starts reached one minimum when β, p, σs, b and c agree within this
#: in the solver's coordinates (logarithms: a relative difference).
AGREE = 1e-3
#: A parameter with a larger standard error is undetermined.
UNDETERMINED_SE = 0.35
#: Singular values of the column-scaled Jacobian below this share of the
#: largest span its null space.
NULL_RCOND = 1e-7
#: θi of the RMSE(θi) metric, degrees.
RMSE_THETA_I_DEG = tuple(2.5 + 5.0 * k for k in range(18))
#: The bases ``fit`` accepts.
BASES = ("conductor", "plastic", "subsurface")

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
#: The keywords of ``start``.
_START_KEYWORDS = ("beta", "p", "sigma_s", "b", "c", "eta", "albedo", "lambertian")


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
    """{name: float} → Material keywords (b and c only with diffraction)."""
    sigma_s = 0.0 if epd else flat["sigma_s"]
    kw = {"beta": flat["beta"], "p": flat["p"], "sigma_s": sigma_s}
    if sigma_s > 0:
        kw["b"], kw["c"] = flat["b"], flat["c"]
    kw["eta"] = [(flat[f"n{j}"], flat.get(f"k{j}", 0.0) if base == "conductor" else 0.0) for j in range(3)]
    kw["base"] = base
    kw["lambertian"] = flat.get("lambertian", 0.0)
    if base != "conductor":
        kw["albedo"] = flat["albedo"]
    return kw


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
class _Data:
    """The objective's samples, ``√w`` of each residual (``(N, 3)``: cos θi
    w_C(m), normalised so that ρ = 0 has cost ½) and p(i, o) (``(N, 1)``)."""

    s: Samples
    sqrt_w: np.ndarray
    graz: np.ndarray

    @classmethod
    def of(cls, s, grazing_k):
        if len(s.wi) < MIN_SAMPLES:
            raise ValueError(f"only {len(s.wi)} valid samples (at least {MIN_SAMPLES} needed)")
        median = np.array([weighted_median(s.rgb[:, c], s.weight) for c in range(3)])
        median = np.where(median > 0, median, max(float(np.mean(s.rgb)), 1e-12))
        sqrt_w = np.sqrt(s.weight[:, None] * compressive_weight(s.rgb, median))
        sqrt_w /= max(float(np.linalg.norm(sqrt_w * s.rgb)), 1e-300)
        return cls(s, sqrt_w, grazing(s.wi, s.wo, grazing_k)[:, None])


class _Objective:
    """The weighted residuals of the fit, ``√w (m − p ρ)`` over the samples
    and channels, as a function of the solver's coordinates ``x`` of the free
    parameters ``names`` (the others held at ``held``), and their Jacobian."""

    def __init__(self, data, base, epd, names, held):
        self.s, self.sqrt_w, self.graz = data.s, data.sqrt_w, data.graz
        self.base, self.epd = base, epd
        self.names, self.held = list(names), dict(held)
        self.lo, self.hi = np.array([_x_bounds(n, base) for n in self.names]).reshape(-1, 2).T
        self.evaluations = 0
        self._last = (None, None)

    def flat(self, x):
        flat = dict(self.held)
        flat.update({n: _from_x(n, xi, self.base) for n, xi in zip(self.names, x)})
        return flat

    def x_of(self, flat):
        x = np.array([_to_x(n, flat[n], self.base) for n in self.names])
        return np.clip(x, self.lo + 1e-9, self.hi - 1e-9)

    def model(self, flat):
        """ρ at the samples, ``(N, 3)`` float64."""
        self.evaluations += 1
        return Material(**_keywords(flat, self.base, self.epd)).eval(self.s.wi, self.s.wo).astype(np.float64)

    def residuals(self, x):
        x = np.asarray(x, dtype=np.float64)
        if self._last[0] is not None and np.array_equal(x, self._last[0]):
            return self._last[1]
        r = (self.sqrt_w * (self.s.rgb - self.graz * self.model(self.flat(x)))).ravel()
        self._last = (x.copy(), r)
        return r

    def jacobian(self, x):
        """∂r/∂x by forward differences of step ``FD_STEP`` (backward at an
        upper bound): one evaluation per parameter, except that n0, n1, n2
        (and k0, k1, k2) move together, each channel's residuals taking the
        column of its own index; k_d's column is −√w p/π (ρ holds k_d/π)."""
        x = np.asarray(x, dtype=np.float64)
        r0 = self.residuals(x).reshape(-1, 3)
        jac = np.zeros((r0.size, len(self.names)))
        groups = {}
        for i, name in enumerate(self.names):
            if name == "lambertian":
                jac[:, i] = (-self.sqrt_w * self.graz / math.pi).ravel()
            elif name[0] in "nk" and name[1:].isdigit():
                groups.setdefault(name[0], []).append(i)
            else:
                groups[name] = [i]
        for members in groups.values():
            xs = x.copy()
            h = np.where(x[members] + FD_STEP <= self.hi[members], FD_STEP, -FD_STEP)
            xs[members] += h
            d = (self.sqrt_w * (self.s.rgb - self.graz * self.model(self.flat(xs)))).reshape(-1, 3) - r0
            for i, step in zip(members, h):
                column = d / step
                if self.names[i][0] in "nk" and self.names[i][1:].isdigit():
                    mask = np.zeros(3)
                    mask[int(self.names[i][1:])] = 1.0
                    column = column * mask
                jac[:, i] = column.ravel()
        return jac

    def solve(self, flat, max_nfev=None, xtol=1e-8):
        """The local minimum from ``flat``: (its parameters, least_squares' result)."""
        r = least_squares(self.residuals, self.x_of(flat), jac=self.jacobian, bounds=(self.lo, self.hi),
                          max_nfev=max_nfev, xtol=xtol)
        return self.flat(r.x), r


def same_minimum(a, b, names, base):
    """Whether two solutions (flat parameters) are one minimum: each of
    ``names`` within ``AGREE`` in the solver's coordinates (b and c left
    out when σs is at its lower bound in both: no diffraction)."""
    floor = _BOUNDS["sigma_s"][0] * (1 + AGREE)
    if "sigma_s" in names and a["sigma_s"] <= floor and b["sigma_s"] <= floor:
        names = [n for n in names if n not in ("b", "c")]
    return all(abs(_to_x(n, a[n], base) - _to_x(n, b[n], base)) <= AGREE for n in names)


def _at_bounds(objective, result):
    """The free parameters the solver left at a bound: {name: bound value}."""
    out = {}
    for i, name in enumerate(objective.names):
        lo, hi = objective.lo[i], objective.hi[i]
        tol = 1e-4 * (hi - lo)
        x = result.x[i]
        side = result.active_mask[i] or (-1 if x - lo < tol else 1 if hi - x < tol else 0)
        if side:
            out[name] = _from_x(name, lo if side < 0 else hi, objective.base)
    return out


def _errors(objective, x):
    """The standard errors of the free parameters at ``x`` (sandwich
    estimate, in the solver's coordinates: σ of ln θ, of θ for albedo and
    k_d) and the undetermined ones (module documentation):
    ({name: error}, [names])."""
    r = objective.residuals(x)
    jac = objective.jacobian(x)
    free = list(range(len(objective.names)))
    undetermined = []
    while free:
        j = jac[:, free]
        scale = np.linalg.norm(j, axis=0)
        dead = scale <= 0.0
        scale[dead] = 1.0
        u, sv, vt = np.linalg.svd(j / scale, full_matrices=False)
        keep = sv > NULL_RCOND * sv[0] if sv[0] > 0 else np.zeros_like(sv, dtype=bool)
        # The parameters with most weight in the null space, and the errors.
        null = np.sum(vt[~keep] ** 2, axis=0) if np.any(~keep) else np.zeros(len(free))
        null[dead] = 1.0
        # cov = A⁻¹ B A⁻¹ with A = JᵀJ, B = Jᵀ diag(r²) J, on the range of J.
        ur = u[:, keep] * r[:, None]
        inner = ur.T @ ur
        v = vt[keep].T / sv[keep]
        cov = (v @ inner @ v.T) / np.outer(scale, scale)
        se = np.sqrt(np.maximum(np.diag(cov), 0.0))
        bad = (null > 0.5) | (se > UNDETERMINED_SE)
        if not np.any(bad):
            return {objective.names[i]: float(e) for i, e in zip(free, se)}, undetermined
        worst = int(np.argmax(np.where(null > 0.5, np.inf, se)))
        undetermined.append(objective.names[free[worst]])
        del free[worst]
    return {}, undetermined


@dataclasses.dataclass
class Fit:
    """A fitted material: ``keywords`` (``twoscale.Material(**keywords)``
    rebuilds ``material``), the ``metrics``, the objective's final ``cost``
    (½ Σ r², r normalised by the residuals of ρ = 0), ``seconds`` of wall
    time, the subsample size, the ``standard_error`` of each determined
    free parameter (σ of ln θ, of θ for ``albedo`` and ``lambertian``; n0…k2
    per channel) and the ``undetermined`` parameters (module documentation)."""

    material: Material
    keywords: dict
    metrics: dict
    cost: float
    seconds: float
    samples: int
    standard_error: dict = dataclasses.field(default_factory=dict)
    undetermined: tuple = ()

    def toml(self, spectral_index: bool = False) -> str:
        """``[material]`` (Material's keywords) and ``[metrics]`` (with
        ``standard_error`` and ``undetermined``). With ``spectral_index``
        the index is written over the spectrum, ``eta = { lambda, n, k }``
        at the paper's three wavelengths, with ``rgb_mode =
        "paper-wavelengths"``: the same RGB model bit for bit, readable by
        spectral renderers (Mitsuba's ``*_spectral``), which interpolate it
        linearly in 1/λ between them and hold the end values beyond: a
        choice, not a measurement (docs/fitting.md)."""
        material = dict(self.keywords)
        if spectral_index:
            # Rows in increasing λ (blue first); the f32 wavelengths' shortest form.
            rows = sorted(zip((float(str(np.float32(x))) for x in RGB_WAVELENGTHS), material["eta"]))
            material["eta"] = {"lambda": [r[0] for r in rows], "n": [r[1][0] for r in rows],
                               "k": [r[1][1] for r in rows]}
            material["rgb_mode"] = "paper-wavelengths"
        extra = {"standard_error": self.standard_error, "undetermined": list(self.undetermined)}
        return _toml({"material": material, "metrics": {**self.metrics, **extra}})


def _toml_value(v):
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
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



def _check_arguments(measured, base, samples, refine_samples, starts, grazing_k, fixed, max_nfev, seed, start):
    """ValueError (TypeError for an unknown start keyword) naming a bad argument."""
    if isinstance(measured, np.ndarray) and measured.shape != merl.SHAPE:
        raise ValueError(f"measured: a MERL array has shape {merl.SHAPE}, got {measured.shape}")
    if isinstance(measured, tuple) and (
        len(measured) != 3 or any(np.shape(a) != np.shape(measured[0]) or np.ndim(a) != 2 or np.shape(a)[1] != 3
                                  for a in measured)
    ):
        raise ValueError("measured: samples are (wi, wo, rgb), three (N, 3) arrays")
    if base not in BASES:
        raise ValueError(f"base must be one of {', '.join(BASES)}, got {base!r}")
    for name, value, least in (("samples", samples, MIN_SAMPLES), ("starts", starts, 1), ("seed", seed, 0)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise ValueError(f"{name} must be an integer ≥ {least}, got {value!r}")
    if isinstance(refine_samples, bool) or not isinstance(refine_samples, (int, np.integer)) or (
            0 < refine_samples < MIN_SAMPLES or refine_samples < 0):
        raise ValueError(f"refine_samples must be 0 or an integer ≥ {MIN_SAMPLES}, got {refine_samples!r}")
    if max_nfev is not None and (isinstance(max_nfev, bool) or not isinstance(max_nfev, (int, np.integer))
                                 or max_nfev < 1):
        raise ValueError(f"max_nfev must be None or an integer ≥ 1, got {max_nfev!r}")
    if not (isinstance(grazing_k, (int, float, np.floating)) and math.isfinite(grazing_k) and grazing_k >= 0):
        raise ValueError(f"grazing_k must be a finite number ≥ 0, got {grazing_k!r}")
    known = set(_names(base, False, True))
    unknown = [f for f in fixed if f not in known]
    if isinstance(fixed, str) or unknown:
        raise ValueError(f"fixed names parameters of {sorted(known)}, got {fixed!r}")
    for key in start:
        if key not in _START_KEYWORDS:
            raise TypeError(f"fit() got an unexpected keyword argument {key!r}")


def fit(
    measured,
    base="conductor",
    *,
    samples=DEFAULT_SAMPLES,
    refine_samples=DEFAULT_REFINE_SAMPLES,
    starts=len(HALO_STARTS),
    grazing_k=0.0,
    epd=False,
    lambertian=True,
    fixed=(),
    seed=0,
    max_nfev=None,
    verbose=True,
    **start,
) -> Fit:
    """fit(measured, base="conductor", *, samples=DEFAULT_SAMPLES,
    refine_samples=DEFAULT_REFINE_SAMPLES, starts=len(HALO_STARTS), grazing_k=0.0, epd=False, lambertian=True,
    fixed=(), seed=0, max_nfev=None, verbose=True, **start)

    Fits the model to ``measured`` (a MERL file's path or array, or
    ``(wi, wo, rgb)`` samples; see the module's documentation).
    ``base``: "conductor", "plastic" or "subsurface"; ``samples``: the
    subsample size of the starts (≥ ``MIN_SAMPLES``); ``refine_samples``:
    that of the final refinement (0: none; MERL data only, samples are
    used as given); ``starts``: how many starts of each
    stage (the first of ``EPD_STARTS`` and ``HALO_STARTS``); ``seed``: the
    subsample's; ``lambertian``: fit a Lambertian term k_d (else 0);
    ``max_nfev``: at most this many evaluations per start (None: to
    convergence); ``verbose``: progress on stderr; ``start``: Material
    keywords replacing the moment-based guess; ``fixed``: parameter names
    held at their start ("beta", "p", "sigma_s", "b", "c", "n0"…"k2",
    "albedo", "lambertian"). Raises ValueError for a bad argument or a file
    that is not a MERL file, OSError for one that cannot be read."""
    t0 = time.perf_counter()
    _check_arguments(measured, base, samples, refine_samples, starts, grazing_k, fixed, max_nfev, seed, start)
    if isinstance(measured, (str, os.PathLike)):
        measured = merl.read(measured)
    log = (lambda *a: print(*a, file=sys.stderr, flush=True)) if verbose else (lambda *a: None)
    rng = np.random.default_rng(seed)
    data = _Data.of(samples_of(measured, samples, rng), grazing_k)
    guess = moment_guess(measured, base)
    guess.update(_flat(start))
    if not lambertian:
        guess["lambertian"] = 0.0

    def objective(with_halo, values, hold=()):
        """The objective on ``data`` of the model with or without the halo,
        over the parameters neither fixed nor in ``hold``, the others at
        ``values``."""
        names = [n for n in _names(base, not with_halo, lambertian) if n not in fixed and n not in hold]
        return _Objective(data, base, not with_halo, names, values)

    def run(label, obj, flat, xtol=1e-8, nfev=max_nfev):
        flat, r = obj.solve(flat, nfev, xtol)
        log(f"  {label}: cost {r.cost:.4g} after {r.nfev} iterations ({time.perf_counter() - t0:.1f} s)")
        return flat, r, obj

    def free(variant):
        return {k: v for k, v in variant.items() if k not in fixed}

    def stage(label, obj, origin, variants, compare):
        """Runs from ``origin`` updated by each of ``variants`` in turn, until
        the lowest minimum so far has been reached from two of them: the
        (flat, result, objective) of the lowest."""
        runs = []
        for j, v in enumerate(variants):
            shown = "".join(f", {k} {x:g}" for k, x in v.items() if k in ("beta", "p", "sigma_s", "b", "c", "n0", "k0"))
            runs.append(run(f"{label} {j}{shown}", obj, origin | v, START_XTOL, min(max_nfev or START_NFEV, START_NFEV)))
            best = min(runs, key=lambda t: t[1].cost)
            if sum(same_minimum(best[0], f, compare, base) for f, _, _ in runs) >= 2:
                log(f"  the lowest minimum reached from two starts: {label} stage done")
                break
        return best

    log(f"twoscale.fit: {len(data.s.wi)} samples × 3 channels, {len(_names(base, epd, lambertian))} parameters")
    halo_given = any(k in start for k in ("sigma_s", "b", "c"))
    candidates = []
    if epd or not halo_given:
        # The EPD stage: from the guess and the variants not set by `start`.
        variants = [{}]
        for v in EPD_STARTS:
            if "index" in v and base == "conductor" and "eta" not in start:
                n, k = v["index"]
                variants.append({f"n{j}": n for j in range(3)} | {f"k{j}": k for j in range(3)})
            elif "index" not in v and not any(key in start for key in v):
                variants.append(v)
        compare = [n for n in ("beta", "p") if n not in fixed]
        candidates.append(stage("EPD start", objective(False, guess), guess, [free(v) for v in variants[:starts]],
                                compare))
    if not epd:
        # The two-scale stage from the EPD fit (or from the given start).
        origin = guess if halo_given else candidates[0][0] | free({"sigma_s": 0.0})
        halo = [{}] if halo_given else [free({"sigma_s": a, "b": b, "c": c}) for a, b, c in HALO_STARTS[:starts]]
        compare = [n for n in ("beta", "p", "sigma_s", "b", "c") if n not in fixed]
        candidates.append(stage("start", objective(True, origin), origin, halo, compare))
    flat, r, obj = min(candidates, key=lambda t: t[1].cost)
    with_halo = not obj.epd
    # Parameters at a bound are held there (σs at its lower bound is no
    # diffraction), and the rest refined to convergence on a larger
    # subsample: the estimate's noise falls as 1/√N.
    bounds = {}
    refine = bool(refine_samples) and not isinstance(measured, tuple)
    if refine:
        data = _Data.of(samples_of(measured, refine_samples, rng), grazing_k)
    for _ in range(2):
        new = {k: v for k, v in _at_bounds(obj, r).items() if k not in bounds}
        if not new and not refine:
            break
        if new.get("sigma_s") == _BOUNDS["sigma_s"][0]:
            with_halo = False
            new = {k: v for k, v in new.items() if k not in ("sigma_s", "b", "c")}
        bounds |= new
        label = f"on {len(data.s.wi)} samples" + ("".join(f", {k} = {v:g}" for k, v in bounds.items()) if bounds else "")
        held = flat | bounds
        flat, r, obj = run(label, objective(with_halo, held, hold=bounds), held)
        refine = False
    errors, undetermined = _errors(obj, r.x)
    # From the solver's coordinates to the parameter's units: dθ/dx.
    slope = {n: 1.0 if not _bound(n, base)[2] else (flat[n] - 1.0 if n == "c" else flat[n]) for n in errors}
    standard_error = {n: e * slope[n] for n, e in errors.items()}
    if not with_halo and not epd:
        undetermined = [n for n in ("b", "c") if n not in fixed] + undetermined
    keywords = _keywords(flat, base, not with_halo)
    material = Material(**keywords)
    if isinstance(measured, tuple):
        m = _sample_metrics(data.s.rgb, predict(material, data.s.wi, data.s.wo, grazing_k))
    else:
        m = metrics(material, measured, grazing_k)
    seconds = time.perf_counter() - t0
    log(f"  done in {seconds:.1f} s: " + ", ".join(f"{k}={v:.4g}" for k, v in _flat(keywords).items())
        + (f"; undetermined: {', '.join(undetermined)}" if undetermined else ""))
    return Fit(material, keywords, m, float(r.cost), seconds, len(data.s.wi), standard_error, tuple(undetermined))


def load(path) -> Material:
    """The material of a fit's TOML (its ``[material]`` table), read by the
    runtime as the C API and the generator read it
    (:meth:`twoscale.Material.from_toml`); for Mitsuba,
    ``{"type": "twoscale", "filename": path}``."""
    return Material.from_toml(path)


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line ``error: …`` (status 2) for a bad command line."""

    def error(self, message):
        self.exit(2, f"error: {message} (see --help)\n")


def main(argv=None):
    """The command line; returns the exit status (0; 1 with a one-line
    ``error: …`` on stderr for a file or value the fit refuses)."""
    parser = _Parser(prog="python -m twoscale.fit", description=__doc__.split("\n\n")[0])
    parser.add_argument("file", help="a MERL .binary file")
    parser.add_argument("--out", help="write the fitted [material] and [metrics] TOML here (default: stdout)")
    parser.add_argument("--base", default="conductor", choices=BASES)
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES, help=f"subsample size (≥ {MIN_SAMPLES})")
    parser.add_argument("--refine-samples", type=int, default=DEFAULT_REFINE_SAMPLES,
                        help=f"subsample of the final refinement (0: none; else ≥ {MIN_SAMPLES})")
    parser.add_argument("--starts", type=int, default=len(HALO_STARTS), help="starts of each stage")
    parser.add_argument("--grazing-k", type=float, default=0.0, help="HP17 60's exponent k (given, not fitted)")
    parser.add_argument("--epd", action="store_true", help="plain EPD Cook–Torrance (σs = 0)")
    parser.add_argument("--no-lambertian", action="store_true", help="no Lambertian term")
    parser.add_argument("--seed", type=int, default=0, help="the subsample's seed")
    parser.add_argument("--spectral-index", action="store_true",
                        help="write the index as eta = { lambda, n, k } at the paper's wavelengths "
                             "(for spectral renderers; the same RGB model)")
    a = parser.parse_args(argv)
    try:
        folder = os.path.dirname(os.path.abspath(a.out)) if a.out else None
        if folder is not None and not (os.path.isdir(folder) and os.access(folder, os.W_OK)):
            raise ValueError(f"--out {a.out}: {folder} is not a writable directory")
        result = fit(a.file, a.base, samples=a.samples, refine_samples=a.refine_samples, starts=a.starts, grazing_k=a.grazing_k, epd=a.epd,
                     lambertian=not a.no_lambertian, seed=a.seed)
        text = result.toml(spectral_index=a.spectral_index)
        if a.out:
            with open(a.out, "w", encoding="utf-8") as f:
                f.write(text)
        else:
            sys.stdout.write(text)
    except OSError as e:
        print(f"error: {e.filename}: {e.strerror}" if e.filename and e.strerror else f"error: {e}", file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except MemoryError:
        print(f"error: out of memory (--samples {a.samples}, --refine-samples {a.refine_samples})", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
