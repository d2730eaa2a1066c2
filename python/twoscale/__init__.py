"""The Holzschuch–Pacanowski two-scale BRDF from precomputed tables.

``Material`` is the RGB model of one material (at 0.645, 0.526, 0.444 µm)
evaluated over NumPy arrays of directions; ``lookup`` holds the table
lookups and ``reference`` the f64 reference of each quantity; ``mitsuba``
registers a Mitsuba 3 BSDF (imported on demand: it needs the ``mitsuba``
package).

Directions are unit vectors in the local frame (normal +z); ``wi`` points
towards the light and ``wo`` towards the viewer. Lengths are in µm.
"""

from . import lookup, merl, reference
from ._native import RGB_WAVELENGTHS, Material
from .fit import fit  # the function; the module runs as `python -m twoscale.fit`

__all__ = ["Material", "RGB_WAVELENGTHS", "fit", "lookup", "merl", "reference"]
