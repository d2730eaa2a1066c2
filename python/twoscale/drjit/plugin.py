"""The Mitsuba BSDF classes (``mi.BSDF`` is per variant): the Dr.Jit one
over :mod:`twoscale.drjit.models`, and the scalar RGB one, which calls the
runtime directly."""

import drjit as dr
import mitsuba as mi
import numpy as np

from twoscale.mitsuba import _material

from .models import SpectralModel, rgb_model


def _scalar_bsdf_class():
    """The BSDF in scalar RGB variants: one direction per call, handed to
    the runtime (:class:`twoscale.Material`) directly; Dr.Jit's scalar
    variants have no arrays to gather from. No differentiable parameters."""

    def vector(v):
        return np.array([v[0], v[1], v[2]], dtype=np.float32)

    class TwoScaleScalarBSDF(mi.BSDF):
        """The two-scale BRDF, scalar RGB variants (front side, glossy)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            if not mi.is_rgb:
                raise RuntimeError(f"twoscale: variant {mi.variant()} is not supported "
                                   "(scalar_rgb is; spectral variants: llvm_ad_spectral)")
            self.material = _material(props)
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def _on(self, ctx, active):
            return bool(active) and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        def _eval(self, si, wo):
            value = self.material.eval(vector(wo), vector(si.wi)) * max(float(wo[2]), 0.0)
            return mi.Color3f(*(float(x) for x in value))

        def _pdf(self, si, wo):
            return float(self.material.pdf(vector(si.wi), vector(wo)))

        def eval(self, ctx, si, wo, active=True):
            return self._eval(si, wo) if self._on(ctx, active) else mi.Color3f(0.0)

        def pdf(self, ctx, si, wo, active=True):
            return self._pdf(si, wo) if self._on(ctx, active) else 0.0

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            u = np.array([sample1, sample2[0], sample2[1]], dtype=np.float32)
            wo, pdf, _ = self.material.sample(vector(si.wi), u)
            bs = mi.BSDFSample3f()
            bs.wo = mi.Vector3f(*(float(x) for x in wo))
            bs.pdf = float(pdf) if self._on(ctx, active) else 0.0
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.GlossyReflection
            bs.sampled_component = 0
            if not bs.pdf > 0.0:
                return bs, mi.Color3f(0.0)
            return bs, self._eval(si, bs.wo) / bs.pdf

        def to_string(self):
            return f"TwoScaleBSDF[{self.material!r}]"

    return TwoScaleScalarBSDF


def bsdf_class():
    """The BSDF class for the current variant (``mi.BSDF`` is per variant),
    registered as ``twoscale`` by :func:`twoscale.mitsuba.register`."""
    if mi.variant().startswith("scalar"):
        return _scalar_bsdf_class()

    class TwoScaleBSDF(mi.BSDF):
        """The two-scale BRDF in Dr.Jit (front side only, glossy reflection)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            if mi.is_polarized or not (mi.is_rgb or mi.is_spectral):
                raise RuntimeError(f"twoscale: variant {mi.variant()} is not supported "
                                   "(rgb and unpolarised spectral variants are)")
            self.model = (SpectralModel if mi.is_spectral else rgb_model)(_material(props))
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        @staticmethod
        def _active(ctx, active):
            return mi.Bool(active) & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        @staticmethod
        def _lams(si):
            """The path's wavelengths in µm (Mitsuba's are in nm)."""
            return [si.wavelengths[j] * 1e-3 for j in range(len(si.wavelengths))]

        def _eval(self, si, wo):
            """ρ(wi=wo, wo=si.wi) · cos θ(wo): RGB, or at the path's wavelengths."""
            if mi.is_spectral:
                value = mi.Spectrum(*self.model.eval_spectral(wo, si.wi, self._lams(si)))
            else:
                value = self.model.eval(wo, si.wi)
            return value * dr.maximum(wo.z, 0.0)

        def _pdf(self, si, wo):
            """The density of `sample` (at the hero wavelength, spectral)."""
            if mi.is_spectral:
                return self.model.pdf_spectral(si.wi, wo, self._lams(si)[0])
            return self.model.pdf(si.wi, wo)

        def eval(self, ctx, si, wo, active=True):
            return dr.select(self._active(ctx, active), self._eval(si, wo), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            return dr.select(self._active(ctx, active), self._pdf(si, wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            active = self._active(ctx, active)
            return (dr.select(active, self._eval(si, wo), 0.0),
                    dr.select(active, self._pdf(si, wo), 0.0))

        def sample(self, ctx, si, sample1, sample2, active=True):
            # The light direction from the runtime's sampler given the camera
            # direction (as twoscale.mitsuba), its density and eval / pdf.
            u = mi.Vector3f(sample1, sample2.x, sample2.y)
            if mi.is_spectral:
                wo, ok = self.model.sample_spectral(si.wi, u, self._lams(si)[0])
            else:
                wo, ok = self.model.sample_direction(si.wi, u)
            bs = mi.BSDFSample3f()
            bs.wo = wo
            bs.pdf = dr.select(ok, self._pdf(si, wo), 0.0)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            active = self._active(ctx, active) & ok & (bs.pdf > 0.0)
            weight = self._eval(si, wo) / dr.select(active, bs.pdf, 1.0)
            return bs, dr.select(active, weight, 0.0)

        def _exposed(self):
            """The keys of `Model.params` this material has (module doc)."""
            m = self.model.material
            keys = ["lambertian"]
            if m.base != "conductor" and m.options.get("colour") != "white":
                keys.append("albedo")
            if self.model.channels_have_diffraction:
                keys.append("halo_factor")
            return keys

        def traverse(self, callback):
            for key in self._exposed():
                callback.put(key, self.model.params[key], mi.ParamFlags.Differentiable)

        def parameters_changed(self, keys):
            # k_d and the albedo also set the sampler's baked lobe weights:
            # re-bake the material at their (detached) values; the params
            # (changed in place by mi.SceneParameters) stay the model's.
            m, params = self.model.material, self.model.params
            changed = {}
            for key in ("albedo", "lambertian"):
                if key in keys:
                    value = float(dr.detach(params[key])[0] if dr.is_array_v(params[key])
                                  else params[key])
                    if value != float(getattr(m, key) or 0.0):
                        changed[key] = value
            if changed:
                self.model = type(self.model)(m.with_layer(**changed), params)

        def to_string(self):
            return f"TwoScaleBSDF[{self.model.material!r}]"

    return TwoScaleBSDF
