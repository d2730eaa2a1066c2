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
``rgb_mode``   string   ``integrated`` or ``paper-wavelengths``
                        (``twoscale.RGB_MODES``; default: the material's,
                        :attr:`twoscale.Material.rgb_mode`), RGB variants
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

**Implementation and variants.** The BSDF is written in Dr.Jit
(:mod:`twoscale.drjit`: the runtime bakes each material, the plugin
mirrors its ``eval``, ``pdf`` and ``sample`` with Dr.Jit operations), so it
runs in Mitsuba's default symbolic mode and :func:`register` changes no
Dr.Jit flag. Run in ``scalar_rgb``, ``llvm_ad_rgb`` and ``llvm_ad_spectral``
(four wavelengths per path, the runtime's model at any wavelength);
``cuda_ad_*`` run the same code but have not been run (no GPU here);
polarised and monochrome variants are refused.

**Differentiable parameters** (``mi.traverse``): ``lambertian``, ``albedo``
(plastic and subsurface bases) and ``halo_factor`` (a factor on the
diffraction lobe, default 1, materials with σs > 0); see
:mod:`twoscale.drjit` for why only these.
"""

import mitsuba as mi

import twoscale

#: Plugin name.
NAME = "twoscale"

#: Material keywords passed through as strings (the runtime's options and
#: the RGB mode).
OPTION_KEYS = (*twoscale.OPTIONS, "rgb_mode")
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


def register() -> None:
    """register(): registers the ``twoscale`` BSDF (:mod:`twoscale.drjit`)
    with the current Mitsuba variant. No Dr.Jit flag is changed."""
    if not mi.variant():
        raise RuntimeError("call mi.set_variant(...) before twoscale.mitsuba.register()")
    from twoscale import drjit

    cls = drjit.bsdf_class()
    mi.register_bsdf(NAME, lambda props: cls(props))
