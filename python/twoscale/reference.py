"""The f64 reference of each quantity (``generator::reference``: quadratures,
no tables), with the same arguments as :mod:`twoscale.lookup`.

Slow by design (C and the BRDF cost milliseconds per point); rows run in
parallel without the GIL. A point where a quadrature fails raises
``ValueError`` naming the row.
"""

from . import _native
from ._columns import broadcast_call


def g1(p, a):
    """Smith G1 of the EPD, Λ by quadrature."""
    return broadcast_call(_native.g1, p, a, reference=True)


def sigma_ratio(theta_i, b_over_lambda, c):
    """σrel/σs by quadrature of the K-correlation spectrum."""
    return broadcast_call(_native.sigma_ratio, theta_i, b_over_lambda, c, reference=True)


def conv(theta_h, u, c, beta, p):
    """The convolution C by direct 2-D quadrature."""
    return broadcast_call(_native.conv, theta_h, u, c, beta, p, source="reference")


def fresnel(n, k, cos_theta):
    """Unpolarised Fresnel reflectance of η = n + ik in f64."""
    return broadcast_call(_native.fresnel, n, k, cos_theta, reference=True)


def brdf(wi, wo, *, beta, p, sigma_s, b, c, n, k, lam):
    """The one-wavelength conductor ρ(wi, wo) in sr⁻¹ with exact Λ, σrel and
    C; returns (N,) float64. ``Material.eval_reference`` is the RGB form."""
    return _native.brdf(
        wi, wo, beta=beta, p=p, sigma_s=sigma_s, b=b, c=c, n=n, k=k, lam=lam, reference=True
    )
