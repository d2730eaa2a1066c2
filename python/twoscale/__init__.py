"""The Holzschuch–Pacanowski two-scale BRDF from precomputed tables.

``Material`` is the RGB model of one material (linear sRGB; ``rgb_mode`` below)
evaluated over NumPy arrays of directions; ``lookup`` holds the table
lookups and ``reference`` the f64 reference of each quantity; ``mitsuba``
registers a Mitsuba 3 BSDF (imported on first use of ``twoscale.mitsuba``:
it needs the ``mitsuba`` package); ``fit`` fits the model to a measured
BRDF (``twoscale.fit.fit``, ``python -m twoscale.fit``; imported on first
use of ``twoscale.fit``, with SciPy).

Directions are unit vectors in the local frame (normal +z), arrays of shape
``(..., 3)`` that broadcast together as NumPy's do; ``wi`` points towards
the light and ``wo`` towards the viewer. Lengths are in µm.

``OPTIONS`` maps each option keyword of ``Material`` to the names of its
values (the default first), ``BASES`` lists the base layers and
``RGB_MODES`` the RGB models (``rgb_mode``: the paper's wavelengths, the
default of (n, k) pairs, or the integral over the spectrum, the default of
a preset and of a spectrum): the runtime's one list of each
(``twoscale::validate::Named``). ``__version__`` is the crates' version.
"""

import importlib
from types import ModuleType

from . import lookup, merl, reference
from ._native import BASES, OPTIONS, RGB_MODES, RGB_WAVELENGTHS, Material

__all__ = [
    "BASES", "Material", "OPTIONS", "RGB_MODES", "RGB_WAVELENGTHS", "fit", "lookup", "merl",
    "reference",
]

# The crates' version (Cargo's), which is also the package's.
from ._native import __version__  # noqa: E402

__all__.append("__version__")


def __getattr__(name: str) -> ModuleType:
    """``twoscale.fit`` and ``twoscale.mitsuba`` without an explicit import
    (PEP 562): not imported with the package, so ``import twoscale`` needs
    neither SciPy's optimiser nor Mitsuba, and ``python -m twoscale.fit``
    runs the module once."""
    if name in ("fit", "mitsuba"):
        return importlib.import_module("." + name, __name__)
    raise AttributeError(f"module 'twoscale' has no attribute '{name}'")
