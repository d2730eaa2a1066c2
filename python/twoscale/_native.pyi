"""Type stubs of the extension module ``twoscale._native`` (python/src/lib.rs).

The docstrings are the extension's own (``help(twoscale.Material.eval)``);
these stubs give the types. Arrays of directions are ``(..., 3)``: anything
``numpy.asarray`` reads as numbers, float32 and float64 arrays without
conversion.
"""

import os
from typing import Any, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Material",
    "RGB_WAVELENGTHS",
    "OPTIONS",
    "BASES",
    "RGB_MODES",
    "g1",
    "sigma_ratio",
    "conv",
    "fresnel",
    "brdf",
    "merl_decode",
    "merl_encode",
    "merl_index",
    "merl_bin_centres",
    "MERL_SCALE",
    "MERL_FILE_BYTES",
]

RGB_WAVELENGTHS: list[float]
OPTIONS: dict[str, tuple[str, ...]]
BASES: tuple[str, ...]
RGB_MODES: tuple[str, ...]

@final
class Material:
    def __new__(
        cls,
        *,
        beta: float,
        p: float,
        eta: list[tuple[float, float]] | tuple[ArrayLike, ArrayLike, ArrayLike],
        sigma_s: float | None = None,
        b: float | None = None,
        c: float | None = None,
        base: str | None = None,
        albedo: float | None = None,
        lambertian: float | None = None,
        masking: str | None = None,
        sigma_rel: str | None = None,
        colour: str | None = None,
        halo_weight: str | None = None,
        multiple_scattering: str | None = None,
        rgb_mode: str | None = None,
    ) -> Material: ...
    @staticmethod
    def preset(
        name: str,
        *,
        masking: str | None = None,
        sigma_rel: str | None = None,
        colour: str | None = None,
        halo_weight: str | None = None,
        multiple_scattering: str | None = None,
        rgb_mode: str | None = None,
    ) -> Material: ...
    @staticmethod
    def presets() -> list[str]: ...
    @staticmethod
    def from_toml(path: str | os.PathLike[str]) -> Material: ...
    @staticmethod
    def from_toml_string(text: str) -> Material: ...
    def eval(self, wi: ArrayLike, wo: ArrayLike) -> NDArray[np.float32]: ...
    def eval_spectral(
        self, wi: ArrayLike, wo: ArrayLike, lam: ArrayLike
    ) -> NDArray[np.float32]: ...
    def pdf(self, wi: ArrayLike, wo: ArrayLike) -> NDArray[np.float32]: ...
    def pdf_spectral(
        self, wi: ArrayLike, wo: ArrayLike, lam: ArrayLike
    ) -> NDArray[np.float32]: ...
    def sample_spectral(
        self, wi: ArrayLike, u: ArrayLike, lam: ArrayLike
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]: ...
    def sample(
        self, wi: ArrayLike, u: ArrayLike
    ) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]: ...
    def eval_reference(self, wi: ArrayLike, wo: ArrayLike) -> NDArray[np.float64]: ...
    def bakes(
        self,
    ) -> list[
        dict[str, float | str | dict[str, list[str]] | NDArray[np.float32] | NDArray[np.float64]]
    ]: ...
    def spectral_bakes(self) -> dict[str, Any]: ...
    def integrated_bakes(self) -> dict[str, Any]: ...
    def with_layer(
        self, *, albedo: float | None = None, lambertian: float | None = None
    ) -> Material: ...
    @property
    def beta(self) -> float: ...
    @property
    def p(self) -> float: ...
    @property
    def sigma_s(self) -> float: ...
    @property
    def b(self) -> float: ...
    @property
    def c(self) -> float: ...
    @property
    def eta(self) -> list[tuple[float, float]]: ...
    @property
    def base(self) -> str: ...
    @property
    def albedo(self) -> float | None: ...
    @property
    def lambertian(self) -> float: ...
    @property
    def options(self) -> dict[str, str]: ...
    @property
    def rgb_mode(self) -> str: ...

def g1(
    p: NDArray[np.float64], a: NDArray[np.float64], *, reference: bool, clamp: bool = False
) -> NDArray[np.float64]: ...
def sigma_ratio(
    theta_i: NDArray[np.float64],
    big_b: NDArray[np.float64],
    c: NDArray[np.float64],
    *,
    reference: bool,
    clamp: bool = False,
) -> NDArray[np.float64]: ...
def conv(
    theta_h: NDArray[np.float64],
    u: NDArray[np.float64],
    c: NDArray[np.float64],
    beta: NDArray[np.float64],
    p: NDArray[np.float64],
    *,
    source: str,
    clamp: bool = False,
) -> NDArray[np.float64]: ...
def fresnel(
    n: NDArray[np.float64],
    k: NDArray[np.float64],
    cos_theta: NDArray[np.float64],
    *,
    reference: bool,
    clamp: bool = False,
) -> NDArray[np.float64]: ...
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
    reference: bool,
    clamp: bool = False,
) -> NDArray[np.float64]: ...

# The MERL file format (python/src/merl.rs, used by twoscale.merl).
MERL_SCALE: list[float]
MERL_FILE_BYTES: int

def merl_decode(data: bytes, scaled: bool) -> NDArray[np.float64]: ...
def merl_encode(values: NDArray[np.float64], scaled: bool) -> bytes: ...
def merl_index(wi: NDArray[np.float64], wo: NDArray[np.float64]) -> NDArray[np.int64]: ...
def merl_bin_centres(
    bins: NDArray[np.int64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
