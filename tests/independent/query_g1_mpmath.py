#!/usr/bin/env python3
"""Independent check of `generator query g1` against mpmath (25 digits).

Draws random (p, a) points, asks the generator binary for `table` and
`reference`, and recomputes G1 = 1/(1 + Λ) with mpmath from the 1-D form of
docs/model.md §2.2, written here from scratch (no code shared with the Rust reference).

    pip install mpmath
    cargo build --release -p generator
    python3 tests/independent/query_g1_mpmath.py [points] [seed]

Prints the largest |table − mpmath| (target 2e-5) and the largest relative
|reference − mpmath| (target 1e-9), and exits 1 if either target is missed.
"""
import math
import os
import random
import subprocess
import sys
from pathlib import Path

import mpmath

mpmath.mp.dps = 25
ROOT = Path(__file__).resolve().parents[2]


def smith_lambda(p, a):
    """Λ(a) = 2a ∫_μ^∞ ρ P22₁(ρ²) (sqrt(ρ² − μ²) − μ acos(μ/ρ)) dρ, μ = 1/a."""
    p, a = mpmath.mpf(p), mpmath.mpf(a)
    mu = 1 / a
    norm = p / (mpmath.pi * mpmath.gamma(1 / p))

    def integrand(rho):
        return rho * norm * mpmath.exp(-rho ** (2 * p)) * (
            mpmath.sqrt(rho**2 - mu**2) - mu * mpmath.acos(mu / rho))

    return 2 * a * mpmath.quad(integrand, [mu, mu * 1.01, mu * 2, mu * 10, mpmath.inf])


def main():
    points = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 11
    rng = random.Random(seed)
    pts = [(rng.uniform(0.2, 5), math.exp(rng.uniform(math.log(0.01), math.log(50))))
           for _ in range(points)]
    csv = "p,a\n" + "".join(f"{p!r},{a!r}\n" for p, a in pts)
    out = subprocess.run([os.environ.get("GENERATOR", str(ROOT / "target/release/generator")), "query", "g1"],
                         input=csv, capture_output=True, text=True, check=True).stdout
    rows = [line.split(",") for line in out.strip().split("\n")[1:]]
    worst_table = worst_reference = 0.0
    for (p, a), row in zip(pts, rows):
        exact = float(1 / (1 + smith_lambda(p, a)))
        worst_table = max(worst_table, abs(float(row[2]) - exact))
        worst_reference = max(worst_reference, abs(float(row[3]) - exact) / exact)
    print(f"{len(rows)} points: max |table - mpmath| = {worst_table:.3e} (target 2e-5), "
          f"max rel |reference - mpmath| = {worst_reference:.3e} (target 1e-9)")
    sys.exit(0 if worst_table <= 2e-5 and worst_reference <= 1e-9 else 1)


if __name__ == "__main__":
    main()
