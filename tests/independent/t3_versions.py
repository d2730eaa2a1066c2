"""T3b's error against the exact C by sub-domain, for two builds side by side.

Draws points from `generator verify`'s distribution over T3's whole domain
(θh uniform in [0, 0.999 π/2]) and prints median / p95 / max of
|table / reference − 1| for each generator: where C > 1e-3 C(0) overall and
split by p, β, u and θh, and in the tails (1e-9 < C/C(0) ≤ 1e-3); "BRDF-like"
is the part inside brdf_scipy.py's ranges (β ≥ 0.05, p ≥ 0.5, u ≤ 100,
θh ≤ 1.2). The reference column is the first generator's.

    OLD=path/to/old/generator OLD_TABLES=path/to/old/tables \
    NEW=target/release/generator python3 tests/independent/t3_versions.py [points] [seed]

Used to compare the format-1 table (commit f2bd3e8, built with its own
generator) with the format-2 one (docs/design/t3-normalised-angle.md). Needs no SciPy.
"""
import math
import os
import random
import subprocess
import sys

from conv_scipy import quantile


def query(generator, tables, csv):
    args = [generator, "query", "conv"] + (["--tables", tables] if tables else [])
    out = subprocess.run(args, input=csv, capture_output=True, text=True, check=True).stdout
    return [[float(x) for x in line.split(",")] for line in out.strip().split("\n")[1:]]


def main():
    points = int(sys.argv[1]) if len(sys.argv) > 1 else 1500
    rng = random.Random(int(sys.argv[2]) if len(sys.argv) > 2 else 7)
    rows = []
    for _ in range(points):
        u = math.exp(rng.uniform(math.log(0.1), math.log(3000.1))) - 0.1
        c = 1 + math.exp(rng.uniform(math.log(0.01), math.log(9)))
        beta = math.exp(rng.uniform(math.log(0.002), 0))
        p = rng.uniform(5 ** -0.5, 0.2 ** -0.5) ** -2
        theta_h = rng.uniform(0, math.pi / 2 * 0.999)
        rows.append((u, c, beta, p, theta_h))
        rows.append((u, c, beta, p, 0.0))  # C(0), for the 1e-3 C(0) cut
    csv = "u,c,beta,p,theta_h\n" + "".join(",".join(repr(x) for x in r) + "\n" for r in rows)
    new = query(os.environ["NEW"], os.environ.get("NEW_TABLES"), csv)
    old = query(os.environ["OLD"], os.environ.get("OLD_TABLES"), csv)
    buckets = {}
    for k in range(0, len(rows), 2):
        u, c, beta, p, theta_h = rows[k]
        reference, c0 = new[k][7], new[k + 1][7]
        brdf_like = beta >= 0.05 and p >= 0.5 and u <= 100 and theta_h <= 1.2
        if not reference > 1e-3 * c0:
            if reference > 1e-9 * c0:
                keys = ["tail"] + (["tail, BRDF-like"] if brdf_like else [])
                for key in keys:
                    o, n = buckets.setdefault(key, ([], []))
                    o.append(abs(old[k][6] / reference - 1))
                    n.append(abs(new[k][6] / reference - 1))
            continue
        keys = ["all"] + (["BRDF-like"] if brdf_like else []) + [
                "p < 0.35" if p < 0.35 else ("0.35 <= p < 1" if p < 1 else "p >= 1"),
                "beta < 0.05" if beta < 0.05 else "beta >= 0.05",
                "u < 100" if u < 100 else "u >= 100",
                "theta_h < 1.2" if theta_h < 1.2 else "theta_h >= 1.2"]
        for key in keys:
            o, n = buckets.setdefault(key, ([], []))
            o.append(abs(old[k][6] / reference - 1))
            n.append(abs(new[k][6] / reference - 1))
    for key, (o, n) in buckets.items():
        print(f"{key:16s} n {len(o):5d} | old median {quantile(o, .5):.2e} p95 {quantile(o, .95):.2e} "
              f"max {max(o):.2e} | new median {quantile(n, .5):.2e} p95 {quantile(n, .95):.2e} max {max(n):.2e}")


if __name__ == "__main__":
    main()
