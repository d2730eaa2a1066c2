#!/usr/bin/env python3
"""Independent check of `generator query brdf` (docs/model.md §2.5, conductor) with SciPy.

Rebuilds the two-scale BRDF from the formulas of docs/model.md §2, written here from scratch:
Λ from the 1-D form of docs/model.md §2.2 (QUADPACK), σrel/σs from docs/model.md §2.4, F and
Q̄ = Q/2 from docs/model.md §2.3 / (HP17 10) in complex arithmetic, C from
`conv_scipy.conv` (nested QUADPACK around the half vector), and

    ρ = A ρ_CT + ρ_CTD,   A = exp(−(4π σrel cos θd / λ)²),
    ρ_CT  = F(θd) D(θh) G / (4 cos θi cos θo),   G = G1(θi) G1(θo),
    ρ_CTD = Q̄ G (1 − A) (c − 1) σs² b² / (2π σrel² λ²) · C(θh; (b/λ) cos θd, c, β, p).

Points: β ∈ [0.05, 1], p ∈ [0.5, 5], σs ∈ [0.005, 0.1] µm, b ∈ [0.5, 20] µm,
c ∈ [1.2, 6], n ∈ [0.2, 2.5], k ∈ [0.5, 8], λ ∈ [0.4, 0.7] µm, both directions
with θ ≤ 75° (the moderate part of the domain where nested double-precision
QUADPACK reliably reaches 1e-8; see conv_scipy.py).

    pip install scipy
    cargo build --release -p generator
    python3 tests/independent/brdf_scipy.py [points] [seed] [--against-reference]

With --against-reference, SciPy is skipped and `table` is measured against the
generator's own f64 `reference` column (fast, for many points; the reference
itself is what the default mode checks). With --c-points, the points' arguments
of C are printed instead (CSV `u,c,beta,p,theta_h`, the input of
`studies t3-angle-at-points`).

Exits 1 if `reference` misses 1e-6 relative, or `table` misses 1% at the
median or 5% at the 95th percentile.
"""
import cmath
import math
import os
import random
import subprocess
import sys
from pathlib import Path

from scipy.integrate import quad

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conv_scipy import conv, ndf, quantile  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def smith_lambda(p, a):
    if a <= 0:
        return 0.0
    mu = 1.0 / a
    norm = p / (math.pi * math.gamma(1.0 / p))
    f = lambda r: r * norm * math.exp(-(r * r) ** p) * (math.sqrt(max(r * r - mu * mu, 0.0)) - mu * math.acos(min(mu / r, 1.0)))
    # The integrand decays like exp(−r^(2p)); its scale is 1.
    top = mu + 50.0 ** (1.0 / (2 * p)) + 10.0
    v, _ = quad(f, mu, top, points=[mu + 0.1, mu + 1, mu + 3], limit=400, epsabs=0.0, epsrel=1e-12)
    return 2.0 * a * v


def sigma_ratio(theta_i, big_b, c):
    s, ct = math.sin(theta_i), math.cos(theta_i)

    def captured(phi):
        r = s * math.cos(phi) + math.sqrt(max(1 - s * s * math.sin(phi) ** 2, 0.0))
        return -math.expm1(-(c - 1) / 2 * math.log1p(big_b * big_b * r * r))

    h = math.pi / 2
    pts = set()
    for w in (ct * 10, ct, ct * ct * big_b, 0.01, 0.1):
        for x in (h - w, h + w):
            if 0 < x < math.pi:
                pts.add(x)
    v, _ = quad(captured, 0, math.pi, points=sorted(pts), limit=400, epsabs=0.0, epsrel=1e-12)
    return math.sqrt(v / math.pi)


def fresnel(eta, cos_t):
    sin2 = 1 - cos_t * cos_t
    c = cmath.sqrt(eta * eta - sin2)
    fs = abs((cos_t - c) / (cos_t + c)) ** 2
    fp = abs((eta * eta * cos_t - c) / (eta * eta * cos_t + c)) ** 2
    return 0.5 * (fs + fp)


def q_bar(eta, wi, wo):
    ti, to = math.atan2(math.hypot(wi[0], wi[1]), wi[2]), math.atan2(math.hypot(wo[0], wo[1]), wo[2])
    phi = math.atan2(wo[1], wo[0]) - math.atan2(wi[1], wi[0]) - math.pi
    e2 = eta * eta
    ci, co = cmath.sqrt(e2 - math.sin(ti) ** 2), cmath.sqrt(e2 - math.sin(to) ** 2)
    q0 = (e2 - 1) / (math.cos(ti) + ci)
    q1 = (e2 - 1) / (e2 * math.cos(ti) + ci)
    q2 = 1 / (math.cos(to) + co)
    q3 = 1 / (e2 * math.cos(to) + co)
    qss = q0 * q2 * math.cos(phi)
    qsp = q0 * q3 * co * math.sin(phi)
    qps = q1 * q2 * ci * math.sin(phi)
    qpp = q1 * q3 * (ci * co * math.cos(phi) - e2 * math.sin(ti) * math.sin(to))
    return 0.5 * (abs(qss) ** 2 + abs(qsp) ** 2 + abs(qps) ** 2 + abs(qpp) ** 2)


def brdf(beta, p, sigma_s, b, c, n, k, lam, wi, wo):
    eta = complex(n, k)
    hs = [a + b_ for a, b_ in zip(wi, wo)]
    ln = math.sqrt(sum(x * x for x in hs))
    h = [x / ln for x in hs]
    cos_d = sum(a * b_ for a, b_ in zip(wi, h))
    theta_h = math.atan2(math.hypot(h[0], h[1]), h[2])
    tan = lambda w: math.hypot(w[0], w[1]) / w[2]
    g = 1 / ((1 + smith_lambda(p, beta * tan(wi))) * (1 + smith_lambda(p, beta * tan(wo))))
    rho_ct = fresnel(eta, cos_d) * ndf(h[2], beta, p) * g / (4 * wi[2] * wo[2])
    theta_i = math.atan2(math.hypot(wi[0], wi[1]), wi[2])
    sigma_rel = sigma_s * sigma_ratio(theta_i, b / lam, c)
    x = (4 * math.pi * sigma_rel * cos_d / lam) ** 2
    a_spec = math.exp(-x)
    halo = q_bar(eta, wi, wo) * g * (-math.expm1(-x)) * (c - 1) * sigma_s**2 * b**2 / (2 * math.pi * sigma_rel**2 * lam**2)
    return a_spec * rho_ct + halo * conv(theta_h, b / lam * cos_d, c, beta, p)


def direction(rng):
    theta = rng.uniform(0, math.radians(75))
    phi = rng.uniform(0, 2 * math.pi)
    return [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    against_reference = "--against-reference" in sys.argv[1:]
    points = int(args[0]) if len(args) > 0 else 40
    seed = int(args[1]) if len(args) > 1 else 11
    rng = random.Random(seed)
    rows = []
    for _ in range(points):
        params = [math.exp(rng.uniform(math.log(0.05), 0)), rng.uniform(0.5, 5),
                  math.exp(rng.uniform(math.log(0.005), math.log(0.1))),
                  math.exp(rng.uniform(math.log(0.5), math.log(20))), rng.uniform(1.2, 6),
                  rng.uniform(0.2, 2.5), rng.uniform(0.5, 8), rng.uniform(0.4, 0.7)]
        rows.append(params + direction(rng) + direction(rng))
    if "--c-points" in sys.argv[1:]:
        print("u,c,beta,p,theta_h")
        for r in rows:
            beta, p, _, b, c, _, _, lam = r[:8]
            wi, wo = r[8:11], r[11:14]
            hs = [a + b_ for a, b_ in zip(wi, wo)]
            ln = math.sqrt(sum(x * x for x in hs))
            h = [x / ln for x in hs]
            cos_d = sum(a * b_ for a, b_ in zip(wi, h))
            theta_h = math.atan2(math.hypot(h[0], h[1]), h[2])
            print(",".join(repr(x) for x in [b / lam * cos_d, c, beta, p, theta_h]))
        return
    header = "beta,p,sigma_s,b,c,n,k,lambda,ix,iy,iz,ox,oy,oz"
    csv = header + "\n" + "".join(",".join(repr(x) for x in r) + "\n" for r in rows)
    out = subprocess.run([os.environ.get("GENERATOR", str(ROOT / "target/release/generator")), "query", "brdf"],
                         input=csv, capture_output=True, text=True, check=True).stdout
    ref_err, table_err = [], []
    for r, line in zip(rows, out.strip().split("\n")[1:]):
        fields = [float(x) for x in line.split(",")]
        table, reference = fields[14], fields[15]
        exact = reference if against_reference else brdf(*r[:8], r[8:11], r[11:14])
        ref_err.append(abs(reference / exact - 1))
        table_err.append(abs(table / exact - 1))
    if against_reference:
        print(f"{points} points: table against the generator's reference (SciPy skipped)")
    else:
        print(f"{points} points: reference vs scipy max rel {max(ref_err):.3e} (target 1e-6)")
    print(f"table: median {quantile(table_err, 0.5):.3e} (target 1e-2), p95 {quantile(table_err, 0.95):.3e} "
          f"(target 5e-2), p99 {quantile(table_err, 0.99):.3e}, max {max(table_err):.3e}")
    ok = max(ref_err) <= 1e-6 and quantile(table_err, 0.5) <= 0.01 and quantile(table_err, 0.95) <= 0.05
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
