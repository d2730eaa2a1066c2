"""The NumPy round trip as a test oracle (not a plugin users can pick): a
Mitsuba BSDF that converts each wavefront to NumPy and calls
:class:`twoscale.Material` (``eval``, ``pdf``, ``sample``) directly, with
the ``twoscale`` plugin's direction convention (twoscale.mitsuba). Called
directly on evaluated arrays (outside symbolic loops) it needs no Dr.Jit
flag changed; it cannot run inside Mitsuba's symbolic loops."""

import drjit as dr
import mitsuba as mi
import numpy as np

from twoscale.mitsuba import _material

#: The oracle's plugin name (test-only).
NAME = "twoscale_numpy_oracle"


def _rows(*vectors):
    """Mitsuba 3-vectors (scalar or wavefronts, of width 1 or N) as (N, 3)
    float32 arrays."""
    arrays = [np.asarray(v, dtype=np.float32).reshape(3, -1).T for v in vectors]
    n = max(len(a) for a in arrays)
    return [np.ascontiguousarray(np.broadcast_to(a, (n, 3))) for a in arrays]


def _scalar_variant():
    return mi.variant().startswith("scalar")


def _vector(rows):
    if _scalar_variant():
        return mi.Vector3f(*(float(x) for x in rows[0]))
    return mi.Vector3f(np.ascontiguousarray(rows.T))


def _color(rows):
    if _scalar_variant():
        return mi.Color3f(*(float(x) for x in rows[0]))
    return mi.Color3f(np.ascontiguousarray(rows.T))


def _float(values):
    if _scalar_variant():
        return mi.Float(float(values[0]))
    return mi.Float(np.ascontiguousarray(values))


def _bsdf_class():
    """The BSDF class for the current variant (``mi.BSDF`` is per variant)."""

    class NumpyOracleBSDF(mi.BSDF):
        """The two-scale BRDF through NumPy (front side only, glossy reflection)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.material = _material(props)
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def _eval_rows(self, camera, light):
            """ρ(wi=light, wo=camera) · cos θ(light), (N, 3)."""
            value = self.material.eval(light, camera)
            return value * np.maximum(light[:, 2:3], 0.0)

        @staticmethod
        def _active(ctx, active):
            """``active`` where the context asks for the glossy component."""
            return mi.Bool(active) & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            u1 = np.asarray(sample1, dtype=np.float32).reshape(1, -1)
            u2 = np.asarray(sample2, dtype=np.float32).reshape(2, -1)
            camera, u = _rows(si.wi, np.concatenate(np.broadcast_arrays(u1, u2[:1], u2[1:])))
            light, pdf, _ = self.material.sample(camera, u)
            ok = pdf > 0
            weight = np.zeros_like(light)
            weight[ok] = self._eval_rows(camera[ok], light[ok]) / pdf[ok, None]
            bs = mi.BSDFSample3f()
            bs.wo = _vector(light)
            bs.pdf = _float(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            active = self._active(ctx, active) & (bs.pdf > 0)
            return bs, dr.select(active, _color(weight), 0.0)

        def eval(self, ctx, si, wo, active=True):
            value = _color(self._eval_rows(*_rows(si.wi, wo)))
            return dr.select(self._active(ctx, active), value, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            pdf = _float(self.material.pdf(*_rows(si.wi, wo)))
            return dr.select(self._active(ctx, active), pdf, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            camera, light = _rows(si.wi, wo)
            value = _color(self._eval_rows(camera, light))
            pdf = _float(self.material.pdf(camera, light))
            active = self._active(ctx, active)
            return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

        def to_string(self):
            return f"NumpyOracleBSDF[{self.material!r}]"

    return NumpyOracleBSDF


def register() -> None:
    """Registers the oracle with the current variant (`NAME`)."""
    cls = _bsdf_class()
    mi.register_bsdf(NAME, lambda props: cls(props))
