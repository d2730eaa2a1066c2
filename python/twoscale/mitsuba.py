"""A Mitsuba 3 BSDF ``twoscale`` backed by :class:`twoscale.Material`.

Call :func:`register` once after ``mi.set_variant(...)``; then
``{"type": "twoscale", "material": "gold-rough"}`` (a preset, options as
string keywords), ``{"type": "twoscale", "filename": "params.toml"}`` (a
material file, e.g. a fit's) or explicit parameters (see :func:`bsdf_dict`)
load it. In a scene file: ``<bsdf type="twoscale"><string name="filename"
value="params.toml"/></bsdf>``.

**Parameters** (one of ``material``, ``filename`` or ``beta``/``p``/``eta``):

============== ======== ====================================================
name           type     meaning
============== ======== ====================================================
``material``   string   a shipped preset (``twoscale.Material.presets()``)
``filename``   string   a material file (TOML, docs/fitting.md), read by
                        :meth:`twoscale.Material.from_toml` after Mitsuba's
                        file resolver; it gives every parameter and option,
                        so no other parameter may be given with it
``beta``, ``p`` float   the EPD's width and shape
``eta``        string   ``"n k, n k, n k"``: the index, red, green, blue
``sigma_s``,   float    the nano-roughness (µm, µm, exponent); defaults 0, 1, 2
``b``, ``c``
``base``       string   ``conductor`` (default), ``plastic``, ``subsurface``
``albedo``     float    the base's albedo (plastic and subsurface only)
``lambertian`` float    k_d of a Lambertian term (default 0)
``masking``,   string   the options (``twoscale.OPTIONS``; default: the
``sigma_rel``,          paper's model), with ``material`` or explicit
``colour``,             parameters (``multiple_scattering="kulla-conty"``
``halo_weight``,        adds the energy-compensation lobe, docs/model.md
``multiple_``           §2.11)
``scattering``
============== ======== ====================================================

**Direction convention.** Mitsuba's ``si.wi`` points towards the camera
(the viewer), and the ``wo`` of ``eval``/``pdf``/``sample`` towards the light.
The model's incident direction is the light's (``twoscale.Material.eval(wi,
wo)`` has ``wi`` towards the light), and the model is not reciprocal for
σs > 0 (σrel depends on θi), so:

- ``eval(si, wo) = ρ(wi=wo, wo=si.wi) · cos θ(wo)``: the light's direction is
  the model's incident one, as the paper's measurement geometry has it;
- ``sample(si, u)`` draws the light direction from the model's sampler
  *given the camera direction* (``Material.sample(wi=si.wi, u)``): its lobes
  are those of ρ(si.wi, ·), which differ from ρ(·, si.wi) only through
  σrel(θ), so it remains a good importance sampler;
- ``pdf(si, wo) = Material.pdf(wi=si.wi, wo=wo)``, the density of that
  sampler (to 3e-5, docs/model.md §2.1), and ``sample``'s weight is ``eval / pdf`` at the sampled direction.

This is radiance transport (``ctx.mode == TransportMode.Radiance``, what
the path tracers use); particle tracing (importance transport) is not
supported: it would need the two roles swapped.

So ``eval``, ``pdf``, ``sample`` and ``eval_pdf`` are mutually consistent
(the χ² test checks ``sample`` against ``pdf``; the tests check the weight is
``eval / pdf`` and that ``eval_pdf`` returns both).

**Variants.** In JIT variants (``llvm_ad_rgb``) each call converts a whole
wavefront to NumPy and back, which needs symbolic loops and calls switched
off: :func:`register` does that. ``scalar_rgb`` also works (one direction per
call, so every call pays Python's overhead).
"""

import drjit as dr
import mitsuba as mi
import numpy as np

import twoscale

#: Plugin name.
NAME = "twoscale"

#: Material keywords passed through as strings (the runtime's options).
OPTION_KEYS = tuple(twoscale.OPTIONS)
#: Material keywords passed through as floats.
FLOAT_KEYS = ("beta", "p", "sigma_s", "b", "c", "albedo", "lambertian")


def bsdf_dict(material: twoscale.Material) -> dict[str, str | float]:
    """bsdf_dict(material): the ``mi.load_dict`` description of a
    :class:`twoscale.Material` (explicit parameters, lengths in µm; ``eta``
    as the string ``"n k, n k, n k"``, red, green, blue)."""
    d: dict[str, str | float] = {"type": NAME, "base": material.base}
    for key in FLOAT_KEYS:
        value = getattr(material, key)
        if value is not None:
            d[key] = float(value)
    d["eta"] = ", ".join(f"{n!r} {k!r}" for n, k in material.eta)
    d.update(material.options)
    return d


def _parse_eta(text):
    try:
        pairs = [tuple(float(x) for x in part.split()) for part in text.split(",")]
    except ValueError:
        pairs = []
    if len(pairs) != 3 or any(len(p) != 2 for p in pairs):
        raise ValueError(f"eta must read 'n k, n k, n k' (red, green, blue), got '{text}'")
    return pairs


def _material(props):
    """The twoscale.Material described by a plugin's properties."""
    options = {k: props[k] for k in OPTION_KEYS if k in props}
    if "filename" in props:
        others = [k for k in ("material", "eta", "base", *FLOAT_KEYS, *OPTION_KEYS) if k in props]
        if others:
            raise ValueError(
                "twoscale BSDF: filename= gives the whole material, options included; "
                f"remove {', '.join(others)}"
            )
        path = mi.file_resolver().resolve(props["filename"])
        return twoscale.Material.from_toml(str(path))
    if "material" in props:
        return twoscale.Material.preset(props["material"], **options)
    keywords = {k: float(props[k]) for k in FLOAT_KEYS if k in props}
    if "eta" not in props:
        raise ValueError("twoscale BSDF: give material= (a preset), filename= (a material file) "
                         "or beta=, p=, eta=, ...")
    keywords["eta"] = _parse_eta(props["eta"])
    if "base" in props:
        keywords["base"] = props["base"]
    return twoscale.Material(**keywords, **options)


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

    class TwoScaleBSDF(mi.BSDF):
        """The two-scale BRDF (front side only, glossy reflection)."""

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
            return f"TwoScaleBSDF[{self.material!r}]"

    return TwoScaleBSDF


def register() -> None:
    """register(): registers the ``twoscale`` BSDF with the current Mitsuba variant; in
    JIT variants, switches symbolic loops and calls off (the BSDF runs on
    NumPy arrays, so Mitsuba must hand it evaluated wavefronts)."""
    if not mi.variant():
        raise RuntimeError("call mi.set_variant(...) before twoscale.mitsuba.register()")
    if not _scalar_variant():
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    cls = _bsdf_class()
    mi.register_bsdf(NAME, lambda props: cls(props))
