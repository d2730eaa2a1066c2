"""The Mitsuba 3 BSDF ``twoscale`` in Dr.Jit (issue 25), registered by
:func:`twoscale.mitsuba.register` (parameters and direction convention
there).

The per-material bakes come from the Rust runtime (:meth:`twoscale.Material.bakes`,
the only place where the tables are interpreted); they are uploaded once per
material as Dr.Jit arrays, and ``eval`` mirrors ``TwoScale::lobes`` of
runtime/src/brdf/ with Dr.Jit operations only (gathers and arithmetic: no
NumPy, no host callback), so it runs with Mitsuba's symbolic loops and calls
on (the default) and no Dr.Jit flag is switched. The lookups are the runtime's
own interpolations (linear in the 1-D bakes, Catmull–Rom over the padded
``ln C`` grid), written as gathers rather than ``dr.Texture`` fetches because
the bakes' node axes and cubic weights are not a texture's.

**What is ported.** RGB variants: :meth:`Model.eval` (``Rgb::eval``, three RGB channels),
:meth:`Model.pdf` (``Rgb::pdf``: the visible-slope tables, the diffraction
mixture of the spectrum's law and the halo's half-vector densities, the cosine lobe, the baked lobe weights, averaged over the channels) and
:meth:`Model.sample_direction` (``Rgb::sample``'s direction: the channel and
lobe picks, the visible-slope sampler with its Newton solve as a symbolic
loop, the diffraction lobe with the azimuth's Newton solve as another, and
the cosine lobe). A material with ``rgb_mode="integrated"`` gets
:class:`IntegratedModel` (``IntegratedRgb``, from
:meth:`twoscale.Material.integrated_bakes`: the 8 models' lobes weighted by
the colour weights; ``pdf`` and ``sample`` :class:`Model`'s over the three
models the runtime's sampler mixes). The plugin's ``sample`` draws the
light direction given the camera's (as ``twoscale.mitsuba``), with ``pdf``
its density and weight ``eval / pdf``. Particle tracing is not supported.
Spectral variants: :class:`SpectralModel` (``brdf::Spectral``, from
:meth:`twoscale.Material.spectral_bakes`: the 19 models' bakes stacked along
a node axis, the two models around each of the path's four wavelengths
interpolated in λ, with F(θd) at λ from the runtime's table; ``pdf`` and ``sample``
those of the sampler model, every other one, nearest the hero wavelength).

**Precision.** f32 (``mi.Float``) throughout, as Mitsuba's BSDFs: the
geometry, the lobes, the lobe weights, ``pdf``'s mixture and the samplers
(:mod:`~twoscale.drjit.visible`, :mod:`~twoscale.drjit.halo`, their
cumulative tables read from the end where the uniform is ≥ ½,
:func:`~twoscale.drjit.lookups.sampler_tables`); no kernel has an f64
operation (:mod:`twoscale.drjit.ir` counts them). The port
agrees with the runtime in distribution, not per uniform
(docs/design/mitsuba-drjit.md).

**Gradients.** The bakes are fixed per material (the runtime interprets the
tables; a lookup's node positions have no useful derivative), so
``traverse`` exposes only the parameters that enter *after* the lookups, in
closed form (:attr:`Model.params`, ``mi.ParamFlags.Differentiable``):

- ``lambertian``: k_d, the term ``k_d/π`` (every material);
- ``albedo``: the base layer's α (plastic: ``T α/(π n²(1 − α F_dr))``;
  subsurface: HP17 42-47), for a plastic or subsurface base with physical
  colour;
- ``halo_factor``: a factor on the diffraction lobe ρ_CTD (default 1; not
  a runtime parameter: at other values the plugin is no longer
  ``Material.eval``), for materials with σs > 0.

β, p, σs, b, c and η enter the bakes (C, G1, F, the sampler's tables) and
are not exposed. ``parameters_changed`` re-bakes the material at the new
k_d or albedo (``Material.with_layer``: they also set the sampler's lobe
weights), so the primal value stays the runtime's; the derivative is that
of the closed form, with the sampler held fixed (its density is not
differentiated).

**Direction convention** (``twoscale.mitsuba``): ``eval(si, wo) =
ρ(wi=wo, wo=si.wi) · cos θ(wo)``, the light's direction being the model's
incident one.

**Layout** (the runtime's): :mod:`~twoscale.drjit.math` (runtime/src/math/),
:mod:`~twoscale.drjit.lookups` (the bakes' lookups, runtime/src/bake/),
:mod:`~twoscale.drjit.visible` and :mod:`~twoscale.drjit.halo` (the
samplers, bake/visible.rs and bake/halo.rs), :mod:`~twoscale.drjit.lobes`
(one channel's lobes, weights, pdf and draws: brdf/eval.rs, brdf/sample.rs),
:mod:`~twoscale.drjit.models` (:class:`Model`, :class:`IntegratedModel`,
:class:`SpectralModel`: brdf/rgb.rs, integrated.rs, spectral.rs) and
:mod:`~twoscale.drjit.plugin` (the ``mi.BSDF`` classes).
"""

from .models import (
    IntegratedModel,
    Model,
    SpectralModel,
    default_params,
    rgb_model,
)
from .plugin import bsdf_class

__all__ = ["IntegratedModel", "Model", "SpectralModel", "bsdf_class", "default_params", "rgb_model"]
