"""The runtime's table lookups (float32 inside), over NumPy arrays.

Arguments are numbers or arrays that broadcast against each other; the
result has their broadcast shape (a float for numbers), float64. Angles are
in radians, lengths in µm.

Each function refuses arguments outside its table's domain: a
``ValueError`` names the first such row, the parameter, its value and the
table's domain (read from the table's header). With ``clamp=True`` it
answers them as the renderer-facing model does, at the nearest edge of the
domain.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _native
from ._columns import broadcast_call

__all__ = ["g1", "sigma_ratio", "conv", "fresnel", "brdf"]


def g1(p: ArrayLike, a: ArrayLike, *, clamp: bool = False) -> float | NDArray[np.float64]:
    """g1(p, a, *, clamp=False): Smith G1 of the EPD from table T1, at shape
    ``p`` and ``a = β tan θ`` (HP17 36–38), both dimensionless."""
    return broadcast_call(_native.g1, p, a, reference=False, clamp=clamp)


def sigma_ratio(
    theta_i: ArrayLike, b_over_lambda: ArrayLike, c: ArrayLike, *, clamp: bool = False
) -> float | NDArray[np.float64]:
    """sigma_ratio(theta_i, b_over_lambda, c, *, clamp=False): σrel/σs from
    table T2 at incidence ``theta_i`` (radians), ``B = b/λ`` (b and λ in the
    same unit) and K-correlation exponent ``c`` (HP17 19)."""
    return broadcast_call(
        _native.sigma_ratio, theta_i, b_over_lambda, c, reference=False, clamp=clamp
    )


def conv(
    theta_h: ArrayLike,
    u: ArrayLike,
    c: ArrayLike,
    beta: ArrayLike,
    p: ArrayLike,
    fit: bool = False,
    *,
    clamp: bool = False,
) -> float | NDArray[np.float64]:
    """conv(theta_h, u, c, beta, p, fit=False, *, clamp=False): the
    convolution C(θh; u, c, β, p) (HP17 40) from table T3b, or from the
    paper's fitted form T3a with ``fit=True``: ``theta_h`` in radians,
    ``u = (b/λ) cos θd``, the K-correlation exponent ``c`` and the EPD's
    ``beta`` and ``p``, all dimensionless."""
    return broadcast_call(
        _native.conv, theta_h, u, c, beta, p, source="fit" if fit else "table", clamp=clamp
    )


def fresnel(
    n: ArrayLike, k: ArrayLike, cos_theta: ArrayLike, *, clamp: bool = False
) -> float | NDArray[np.float64]:
    """fresnel(n, k, cos_theta, *, clamp=False): the runtime's unpolarised
    Fresnel reflectance of η = n + ik at incidence cos θ."""
    return broadcast_call(_native.fresnel, n, k, cos_theta, reference=False, clamp=clamp)


def brdf(
    wi: ArrayLike,
    wo: ArrayLike,
    *,
    beta: float,
    p: float,
    sigma_s: float,
    b: float,
    c: float,
    n: float,
    k: float,
    lam: float,
    clamp: bool = False,
) -> NDArray[np.float64]:
    """brdf(wi, wo, *, beta, p, sigma_s, b, c, n, k, lam, clamp=False): the
    runtime's one-wavelength conductor ρ(wi, wo) in sr⁻¹ (the model of
    ``generator query brdf``) with σs and b in µm, η = n + ik at wavelength
    ``lam`` in µm. ``wi`` (towards the light) and ``wo`` (towards the viewer)
    are ``(..., 3)`` and broadcast together; the result has their leading
    shape."""
    return _native.brdf(
        wi, wo, beta=beta, p=p, sigma_s=sigma_s, b=b, c=c, n=n, k=k, lam=lam,
        reference=False, clamp=clamp,
    )
