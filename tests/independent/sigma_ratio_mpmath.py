#!/usr/bin/env python3
"""Independent check of `generator query sigma-ratio` against mpmath (30 digits).

Draws random (θi, B, c) over T2's domain (docs/model.md §3) (θi uniform, and half the points
with cos θi log-uniform down to 1e-4 to probe grazing incidence), asks the
generator for `table` and `reference`, and recomputes σrel/σs with mpmath from
the 1-D form of docs/model.md §2.4, written here from scratch, with breakpoints at the
features near φ = π/2 (widths ~cos θi and ~B cos²θi).

    pip install mpmath
    cargo build --release -p generator
    python3 tests/independent/sigma_ratio_mpmath.py [points] [seed]

Exits 1 if `table` misses 1e-4 relative or `reference` misses 1e-9 relative.
"""
import math
import os
import random
import subprocess
import sys
from pathlib import Path

import mpmath as mp

mp.mp.dps = 30
ROOT = Path(__file__).resolve().parents[2]


def sigma_ratio(theta_i, big_b, c):
    theta_i, big_b, c = mp.mpf(theta_i), mp.mpf(big_b), mp.mpf(c)
    s, cos_t = mp.sin(theta_i), mp.cos(theta_i)

    def captured(phi):
        radius = s * mp.cos(phi) + mp.sqrt(1 - s**2 * mp.sin(phi) ** 2)
        return 1 - (1 + big_b**2 * radius**2) ** (-(c - 1) / 2)

    h = mp.pi / 2
    widths = [cos_t * 10, cos_t, cos_t**2 * big_b, cos_t**2 * big_b / 10, mp.mpf("0.01"), mp.mpf("0.1")]
    points = {mp.mpf(0), mp.pi / 4, h, mp.pi}
    for w in widths:
        for p in (h - w, h + w):
            if 0 < p < mp.pi:
                points.add(p)
    return mp.sqrt(mp.quad(captured, sorted(points), maxdegree=10) / mp.pi)


def main():
    points = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    rng = random.Random(seed)
    rows = []
    for k in range(points):
        theta = rng.uniform(0, math.pi / 2) if k % 2 == 0 else math.acos(math.exp(rng.uniform(math.log(1e-4), 0)))
        rows.append((theta, math.exp(rng.uniform(math.log(0.1), math.log(3000))),
                     1 + math.exp(rng.uniform(math.log(0.01), math.log(99)))))
    csv = "theta_i,B,c\n" + "".join(f"{t!r},{b!r},{c!r}\n" for t, b, c in rows)
    out = subprocess.run([os.environ.get("GENERATOR", str(ROOT / "target/release/generator")), "query", "sigma-ratio"],
                         input=csv, capture_output=True, text=True, check=True).stdout
    worst_table = worst_reference = 0.0
    for (t, b, c), line in zip(rows, out.strip().split("\n")[1:]):
        fields = line.split(",")
        exact = float(sigma_ratio(t, b, c))
        worst_table = max(worst_table, abs(float(fields[3]) / exact - 1))
        worst_reference = max(worst_reference, abs(float(fields[4]) / exact - 1))
    print(f"{points} points: max rel |table - mpmath| = {worst_table:.3e} (target 1e-4), "
          f"max rel |reference - mpmath| = {worst_reference:.3e} (target 1e-9)")
    sys.exit(0 if worst_table <= 1e-4 and worst_reference <= 1e-9 else 1)


if __name__ == "__main__":
    main()
