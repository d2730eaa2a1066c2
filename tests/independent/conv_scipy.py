#!/usr/bin/env python3
"""Independent check of `generator query conv` (docs/model.md §2.5's C) with SciPy.

Recomputes C(θh; u, c, β, p) by nested adaptive quadrature (QUADPACK through
scipy.integrate.quad) in polar coordinates around the half vector h — the
frame the generator's default direct quadrature does not use — written here
from scratch:

    C(θh) = ∫_0^{π/2} k(2u sin γ) cos²γ sin γ ∫_0^{2π} D(θm(γ, φ)) dφ dγ,
    cos θm = cos θh cos γ + sin θh sin γ cos φ,
    D(θ) = p / (π β² Γ(1/p)) · exp(−(tan²θ / β²)^p) / cos⁴θ   (cos θ > 0).

Points are drawn over the moderate part of the domain, where nested
double-precision QUADPACK reliably reaches 1e-8: u ∈ [0, 100], c ∈ [1.01, 10],
β ∈ [0.05, 1], p ∈ [0.5, 5], θh ∈ [0, 1.2]. (The extremes — β down to 0.002,
u up to 3000, p down to 0.2 — are covered by the Rust tests, which compare
two independent methods, zonal harmonics and direct quadrature.)

    pip install scipy
    cargo build --release -p generator
    python3 tests/independent/conv_scipy.py [points] [seed]

Exits 1 if `reference` misses 1e-6 relative, or if `table` (T3b) misses 1% at
the median or 5% at the 95th percentile of the points where C > 1e-3 C(0);
prints the same figures for `fit` (T3a, the paper's form; no target).
"""
import math
import os
import random
import subprocess
import sys
from pathlib import Path

from scipy.integrate import quad

ROOT = Path(__file__).resolve().parents[2]


def ndf(cos_t, beta, p):
    if cos_t <= 0.0:
        return 0.0
    tan2 = max(1.0 - cos_t * cos_t, 0.0) / (cos_t * cos_t)
    norm = p / (math.pi * beta * beta * math.gamma(1.0 / p))
    return norm * math.exp(-((tan2 / (beta * beta)) ** p)) / cos_t**4


def conv(theta_h, u, c, beta, p):
    ch, sh = math.cos(theta_h), math.sin(theta_h)

    def ring(gamma):
        cg, sg = math.cos(gamma), math.sin(gamma)
        # D along the ring; breakpoints where θm crosses the NDF's scales.
        pts = []
        for s in (0.25, 0.5, 1.0, 2.0, 3.0):
            target = math.cos(math.atan(beta * s))
            if sh * sg > 0:
                x = (target - ch * cg) / (sh * sg)
                if -1 < x < 1:
                    pts.append(math.acos(x))
        if sh * sg > 0:
            x = -ch * cg / (sh * sg)  # the horizon of D
            if -1 < x < 1:
                pts.append(math.acos(x))
        f = lambda phi: ndf(ch * cg + sh * sg * math.cos(phi), beta, p)
        v, _ = quad(f, 0.0, math.pi, points=sorted(set(pts)) or None, limit=400,
                    epsabs=0.0, epsrel=1e-11)
        return 2.0 * v

    def outer(gamma):
        x = 2.0 * u * math.sin(gamma)
        k = (1.0 + x * x) ** (-(c + 1.0) / 2.0)
        return k * math.cos(gamma) ** 2 * math.sin(gamma) * ring(gamma)

    pts = {theta_h}
    for s in (0.25, 0.5, 1.0, 2.0, 3.0):
        w = math.atan(beta * s)
        for g in (theta_h - w, theta_h + w, w - theta_h):
            if 0 < g < math.pi / 2:
                pts.add(g)
    if u > 0:
        for s in (0.3, 1, 3, 10, 30, 100):
            g = s / (2 * u)
            if g < math.pi / 2:
                pts.add(g)
    pts = sorted(x for x in pts if 0 < x < math.pi / 2)
    v, _ = quad(outer, 0.0, math.pi / 2, points=pts or None, limit=400,
                epsabs=0.0, epsrel=1e-10)
    return v


def quantile(xs, q):
    xs = sorted(xs)
    return xs[round((len(xs) - 1) * q)] if xs else float("nan")


def main():
    points = int(sys.argv[1]) if len(sys.argv) > 1 else 60
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    rng = random.Random(seed)
    rows = []
    for _ in range(points):
        u = math.exp(rng.uniform(math.log(0.1), math.log(100.1))) - 0.1
        c = 1 + math.exp(rng.uniform(math.log(0.01), math.log(9)))
        beta = math.exp(rng.uniform(math.log(0.05), 0))
        p = rng.uniform(0.5, 5)
        theta_h = rng.uniform(0, 1.2)
        rows.append((u, c, beta, p, theta_h))
    csv = "u,c,beta,p,theta_h\n" + "".join(",".join(repr(x) for x in r) + "\n" for r in rows)
    out = subprocess.run([os.environ.get("GENERATOR", str(ROOT / "target/release/generator")), "query", "conv"],
                         input=csv, capture_output=True, text=True, check=True).stdout
    ref_err, table_err, fit_err = [], [], []
    for r, line in zip(rows, out.strip().split("\n")[1:]):
        fields = [float(x) for x in line.split(",")]
        fit, table, reference = fields[5], fields[6], fields[7]
        exact = conv(r[4], r[0], r[1], r[2], r[3])
        c0 = conv(0.0, r[0], r[1], r[2], r[3])
        ref_err.append(abs(reference / exact - 1))
        if exact > 1e-3 * c0:
            table_err.append(abs(table / exact - 1))
            fit_err.append(abs(fit / exact - 1))
    print(f"{points} points: reference vs scipy max rel {max(ref_err):.3e} (target 1e-6)")
    print(f"table (T3b) where C > 1e-3 C(0) ({len(table_err)} points): median {quantile(table_err, 0.5):.3e} "
          f"(target 1e-2), p95 {quantile(table_err, 0.95):.3e} (target 5e-2), max {max(table_err):.3e}")
    print(f"fit (T3a, paper's form): median {quantile(fit_err, 0.5):.3e}, p95 {quantile(fit_err, 0.95):.3e}, "
          f"max {max(fit_err):.3e}")
    ok = max(ref_err) <= 1e-6 and quantile(table_err, 0.5) <= 0.01 and quantile(table_err, 0.95) <= 0.05
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
