"""The runtime's table lookups (float32 inside), over NumPy arrays.

Arguments broadcast against each other; angles are in radians.
"""

from . import _native
from ._columns import broadcast_call


def g1(p, a):
    """Smith G1 of the EPD from table T1, at shape ``p`` and ``a = β tan θ``
    (HP17 36–38)."""
    return broadcast_call(_native.g1, p, a, reference=False)


def sigma_ratio(theta_i, b_over_lambda, c):
    """σrel/σs from table T2 at incidence ``theta_i``, ``B = b/λ`` and
    K-correlation exponent ``c`` (HP17 19)."""
    return broadcast_call(_native.sigma_ratio, theta_i, b_over_lambda, c, reference=False)


def conv(theta_h, u, c, beta, p, fit=False):
    """The convolution C(θh; u, c, β, p) (HP17 40) from table T3b, or from the
    paper's fitted form T3a with ``fit=True``."""
    return broadcast_call(
        _native.conv, theta_h, u, c, beta, p, source="fit" if fit else "table"
    )


def fresnel(n, k, cos_theta):
    """The runtime's unpolarised Fresnel reflectance of η = n + ik."""
    return broadcast_call(_native.fresnel, n, k, cos_theta, reference=False)


def brdf(wi, wo, *, beta, p, sigma_s, b, c, n, k, lam):
    """The runtime's one-wavelength conductor ρ(wi, wo) in sr⁻¹ (the model of
    ``generator query brdf``), for (N, 3) directions; returns (N,)."""
    return _native.brdf(
        wi, wo, beta=beta, p=p, sigma_s=sigma_s, b=b, c=c, n=n, k=k, lam=lam, reference=False
    )
