"""The f64 reference of each quantity (the reference crate: quadratures, no
tables), with the same arguments as :mod:`twoscale.lookup`.

Slow by design (C and the BRDF cost milliseconds per point); rows run in
parallel without the GIL. A point where a quadrature fails raises
``ValueError`` naming the row.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _native
from ._columns import broadcast_call

__all__ = ["g1", "sigma_ratio", "conv", "fresnel", "brdf"]


def g1(p: ArrayLike, a: ArrayLike) -> float | NDArray[np.float64]:
    """g1(p, a): Smith G1 of the EPD at shape ``p`` and ``a = β tan θ``, Λ by
    quadrature."""
    return broadcast_call(_native.g1, p, a, reference=True)


def sigma_ratio(
    theta_i: ArrayLike, b_over_lambda: ArrayLike, c: ArrayLike
) -> float | NDArray[np.float64]:
    """sigma_ratio(theta_i, b_over_lambda, c): σrel/σs at incidence
    ``theta_i`` (radians), ``B = b/λ`` and exponent ``c``, by quadrature of the
    K-correlation spectrum."""
    return broadcast_call(_native.sigma_ratio, theta_i, b_over_lambda, c, reference=True)


def conv(
    theta_h: ArrayLike, u: ArrayLike, c: ArrayLike, beta: ArrayLike, p: ArrayLike
) -> float | NDArray[np.float64]:
    """conv(theta_h, u, c, beta, p): the convolution C(θh; u, c, β, p) by
    direct 2-D quadrature (``theta_h`` in radians, the others
    dimensionless)."""
    return broadcast_call(_native.conv, theta_h, u, c, beta, p, source="reference")


def fresnel(n: ArrayLike, k: ArrayLike, cos_theta: ArrayLike) -> float | NDArray[np.float64]:
    """fresnel(n, k, cos_theta): the unpolarised Fresnel reflectance of
    η = n + ik at incidence cos θ, in f64."""
    return broadcast_call(_native.fresnel, n, k, cos_theta, reference=True)


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
) -> NDArray[np.float64]:
    """brdf(wi, wo, *, beta, p, sigma_s, b, c, n, k, lam): the one-wavelength
    conductor ρ(wi, wo) in sr⁻¹ with exact Λ, σrel and C (σs, b and ``lam``
    in µm); ``wi``, ``wo`` ``(..., 3)`` broadcast together, the result has
    their leading shape, float64. ``Material.eval_reference`` is the RGB
    form."""
    return _native.brdf(
        wi, wo, beta=beta, p=p, sigma_s=sigma_s, b=b, c=c, n=n, k=k, lam=lam, reference=True
    )
