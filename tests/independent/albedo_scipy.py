#!/usr/bin/env python3
"""Independent check of the directional albedo E(μ; β, p) (docs/model.md §2.10) with SciPy.

Written from the definition, in a different parametrisation from the Rust
reference (`reference::albedo`, which integrates over stretched slopes):
here over the outgoing direction o, in spherical coordinates,

    E(μ) = ∫₀¹ dμo ∫₀^{2π} dφo  D(h) G(i, o) / (4 μ),     h = (i + o)/|i + o|,

with the Beckmann NDF (the EPD at p = 1)
D(h) = exp(−tan²θh/α²) / (π α² cos⁴θh) and Beckmann's closed-form
Λ(a) = (erf(1/a) − 1)/2 + a exp(−1/a²)/(2√π), a = α tan θ;
G = G1(i) G1(o) (separable) or 1/(1 + Λ(i) + Λ(o)) (height-correlated).
QUADPACK (scipy.integrate.quad) nested, the inner azimuthal integral split at
the mirror azimuth φo = π, the outer one at μo = μ (the peak of narrow
lobes), relative tolerance 1e-11.

    pip install scipy
    python3 tests/independent/albedo_scipy.py

Prints `alpha, mu, masking, E` rows; `tests/albedo.rs` holds these values
(to 12 digits) and checks the Rust reference against them.
"""
import math

from scipy.integrate import quad


def beckmann_lambda(a):
    if a <= 0.0:
        return 0.0
    mu = 1.0 / a
    return 0.5 * (math.erf(mu) - 1.0) + math.exp(-mu * mu) / (2.0 * mu * math.sqrt(math.pi))


def albedo(alpha, mu, masking):
    si = math.sqrt(max(0.0, 1.0 - mu * mu))
    wi = (si, 0.0, mu)
    lam_i = beckmann_lambda(alpha * si / mu)

    def d(cos_h):
        c2 = cos_h * cos_h
        tan2 = (1.0 - c2) / c2
        return math.exp(-tan2 / (alpha * alpha)) / (math.pi * alpha * alpha * c2 * c2)

    def inner(mu_o):
        so = math.sqrt(max(0.0, 1.0 - mu_o * mu_o))
        lam_o = beckmann_lambda(alpha * so / mu_o) if mu_o > 0 else float("inf")
        if masking == "separable":
            g = 1.0 / ((1.0 + lam_i) * (1.0 + lam_o))
        else:
            g = 1.0 / (1.0 + lam_i + lam_o)

        def f(phi):
            o = (so * math.cos(phi), so * math.sin(phi), mu_o)
            s = [wi[k] + o[k] for k in range(3)]
            n = math.sqrt(sum(x * x for x in s))
            return d(s[2] / n)

        # The mirror direction is at φo = π.
        a, _ = quad(f, 0.0, math.pi, epsabs=0, epsrel=1e-11, limit=400)
        b, _ = quad(f, math.pi, 2.0 * math.pi, epsabs=0, epsrel=1e-11, limit=400)
        return g * (a + b) / (4.0 * mu)

    lo, _ = quad(inner, 0.0, mu, epsabs=1e-13, epsrel=1e-11, limit=400)
    hi, _ = quad(inner, mu, 1.0, epsabs=1e-13, epsrel=1e-11, limit=400) if mu < 1.0 else (0.0, 0)
    return lo + hi


def main():
    for alpha in (0.1, 0.5, 1.0):
        for mu in (0.2, 0.5, 0.9, 1.0):
            for masking in ("separable", "height-correlated"):
                print(f"({alpha}, {mu}, {masking!r}, {albedo(alpha, mu, masking):.12f}),")


if __name__ == "__main__":
    main()
