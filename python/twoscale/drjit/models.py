"""The models in Dr.Jit (runtime/src/brdf/: `Rgb`, `IntegratedRgb`,
`Spectral`): :class:`Model` (RGB), :class:`IntegratedModel` and
:class:`SpectralModel`, over the channels of :mod:`twoscale.drjit.lobes`."""

import copy
import math
import types

import drjit as dr
import mitsuba as mi
import numpy as np

import twoscale

from .lobes import Channel, draw, exp_and_one_minus_over
from .lookups import c_of_ln, cell_at, gather4, sampler_tables, upload
from .math import finite_or_zero


def default_params(material: twoscale.Material):
    """The differentiable parameters of :class:`Model` at `material`'s
    values (``mi.Float`` kernel inputs): ``lambertian`` (k_d), ``albedo``
    (the base layer's; 0 for a conductor) and ``halo_factor`` (1)."""
    return {
        "lambertian": dr.opaque(mi.Float, material.lambertian),
        "albedo": dr.opaque(mi.Float, material.albedo or 0.0),
        "halo_factor": dr.opaque(mi.Float, 1.0),
    }


class Model:
    """The RGB model of a :class:`twoscale.Material` in Dr.Jit: its three
    channels' bakes uploaded once; :meth:`eval` is ``Material.eval``.

    `params` (:func:`default_params`) hold the parameters that enter after
    the lookups (k_d, the base albedo, a factor on the diffraction lobe), as
    Dr.Jit variables that may carry gradients; at the material's values and
    a factor of 1, :meth:`eval` is the runtime's."""

    def __init__(self, material: twoscale.Material, params=None, bakes=None):
        self.material = material
        self.params = default_params(material) if params is None else params
        bakes = material.bakes() if bakes is None else bakes
        self.channels = [Channel(b) for b in bakes]
        first = self.channels[0].s
        self.p = dr.opaque(mi.Float, first["p"])
        self.epd_norm = dr.opaque(mi.Float, first["epd_norm"])
        self.epd_inv_beta_sq = dr.opaque(mi.Float, first["epd_inv_beta_sq"])
        self.height_correlated = first["masking"] == "height-correlated"
        self.channels_have_diffraction = any(ch.diffraction for ch in self.channels)
        self.diffraction_stack = diffraction_stack(self.channels, bakes)

    def d(self, h):
        """`Epd::d`: `norm e^−(tan²θ/β²)^p / cos⁴θ`."""
        cos_sq = h.z * h.z
        inv_cos4 = 1.0 / (cos_sq * cos_sq)
        tan_sq = (h.x * h.x + h.y * h.y) / cos_sq
        y = dr.power(tan_sq * self.epd_inv_beta_sq, self.p)
        value = self.epd_norm * inv_cos4 * dr.exp(-y)
        return dr.select((h.z > 0.0) & (y < 104.0) & dr.isfinite(value), value, 0.0)

    def geometry(self, wi, wo):
        """The pair's geometry and D(h) (`TwoScale::geometry`), in f32, and
        whether both directions are above the horizon. From `s = wi + wo`
        (unit `wi`, `wo`): `h = s/|s|`, `cos θd = wi·h = |s|/2` (one root,
        no dot product to round), `sin θh` from `s`'s tangential part;
        where `wi` and `wo` mirror each other the tangential sums cancel
        exactly (Sterbenz), so `sin θh` near the peak keeps the inputs'
        rounding only."""
        wi, wo = mi.Vector3f(wi), mi.Vector3f(wo)
        valid = dr.all(dr.isfinite(wi)) & dr.all(dr.isfinite(wo))
        wi, wo = dr.normalize(wi), dr.normalize(wo)
        valid &= (wi.z > 0.0) & (wo.z > 0.0)
        s = wi + wo
        tangential_sq = s.x * s.x + s.y * s.y
        norm_sq = tangential_sq + s.z * s.z
        inv_norm = dr.rsqrt(norm_sq)
        h = s * inv_norm
        return valid, {
            "wi": wi,
            "wo": wo,
            "cos_d": dr.clip(0.5 * norm_sq * inv_norm, 0.0, 1.0),
            "cos_h": dr.clip(h.z, 0.0, 1.0),
            "sin_h": dr.minimum(dr.sqrt(tangential_sq) * inv_norm, 1.0),
            "d": self.d(h),
            "along": -(wi.x * wo.x + wi.y * wo.y),
            "across": -(wi.x * wo.y - wi.y * wo.x),
        }

    def masking(self, geo):
        """G at a pair (`TwoScale::with_masking`), f32: `G1(i) G1(o)`, or
        height-correlated `G1(i) G1(o)/(G1(i) + G1(o) − G1(i) G1(o))` (the
        runtime's `1/(1/G1(i) + 1/G1(o) − 1)` with one division; 0 where a
        G1 is 0)."""
        wi, wo = geo["wi"], geo["wo"]
        ch = self.channels[0]

        def tangential(w):
            return dr.sqrt(mi.Float(w.x * w.x + w.y * w.y))

        g1_i = ch.g1(tangential(wi), mi.Float(wi.z))
        g1_o = ch.g1(tangential(wo), mi.Float(wo.z))
        g = g1_i * g1_o
        if self.height_correlated:
            den = g1_i + g1_o - g
            g = dr.select(den > 0.0, g / den, 0.0)
        return g

    def pair(self, geo):
        """The terms of a pair every channel's (model's) lobes share, f32:
        the cosines, G, `rho_geo = G D/(4 cos θi cos θo)` and the
        half-vector's and Q̄'s arguments."""
        cos_i, cos_o, cos_d = geo["wi"].z, geo["wo"].z, geo["cos_d"]
        g = self.masking(geo)
        return {
            "cos_i": cos_i, "cos_o": cos_o, "cos_d": cos_d, "cos_d_sq": cos_d * cos_d,
            "g": g, "rho_geo": g * geo["d"] / (4.0 * cos_i * cos_o),
            "sin_h": geo["sin_h"], "cos_h": geo["cos_h"],
            "along": geo["along"], "across": geo["across"],
        }

    def eval(self, wi, wo):
        """``Rgb::eval``: ρ(wi, wo) per channel (sr⁻¹) as an ``mi.Color3f``: ``wi``
        towards the light, ``wo`` towards the viewer (``Material.eval``'s
        convention); 0 below the horizon."""
        valid, geo = self.geometry(wi, wo)
        pair = self.pair(geo)
        values = []
        for channel in self.channels:
            spec, diff, base, multiple = channel.lobes(pair, self.params)
            values.append(finite_or_zero((spec + diff) + (base + multiple)))
        return dr.select(valid, mi.Color3f(*values), 0.0)

    def pdf(self, wi, wo):
        """`Material.pdf(wi, wo)` (``Rgb::pdf``): the mean over the channels of
        `Σ_k w_k(wi) pdf_k(wi, wo)`, as an ``mi.Float``; 0 below the horizon."""
        valid, geo = self.geometry(wi, wo)
        wi, wo = geo["wi"], geo["wo"]
        specular = mi.Float(self.channels[0].visible_pdf(wi, wo))
        base = wo.z * (1.0 / math.pi)
        total = mi.Float(0.0)
        for channel in self.channels:
            w = channel.lobe_weights(wi.z)
            value = dr.select(w[0] > 0.0, w[0] * specular, 0.0)
            if channel.diffraction:
                value += dr.select(w[1] > 0.0, w[1] * channel.diffraction_pdf(wi, wo, geo), 0.0)
            # The base and the compensation lobe share the cosine-weighted density.
            value += dr.select(w[2] + w[3] > 0.0, (w[2] + w[3]) * base, 0.0)
            total += finite_or_zero(value)
        return dr.select(valid, finite_or_zero(total * (1.0 / 3.0)), 0.0)

    def sample_direction(self, wi, u):
        """``Rgb::sample``'s direction for incidence `wi` and three uniforms
        `u` (an ``mi.Vector3f``): a channel picked with `u[0]`, its lobe with
        the rescaled `u[0]`, the lobe's direction from `u[1], u[2]`. Returns
        the direction (``mi.Vector3f``) and whether one was drawn."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        wi_f = mi.Vector3f(wi)
        valid = dr.all(dr.isfinite(wi_f))
        wi = dr.normalize(wi_f)
        valid &= wi.z > 0.0
        pick = 3.0 * dr.clip(u.x, 0.0, below_one)
        k = dr.minimum(mi.UInt32(pick), 2)
        lobe_pick = dr.clip(pick - mi.Float(k), 0.0, below_one)
        u1 = dr.clip(u.y, 0.0, below_one)
        u2 = dr.clip(u.z, 0.0, below_one)
        # The picked channel's lobe weights.
        weights = [ch.lobe_weights(wi.z) for ch in self.channels]
        w = [dr.select(k == 0, weights[0][n], dr.select(k == 1, weights[1][n], weights[2][n]))
             for n in range(4)]
        return draw(self, [k == n for n in range(len(self.channels))], w, lobe_pick,
                     wi, u1, u2, valid)

class NodeScalars:
    """A stack's scalars at per-lane model `k`: a quantity of `arrays` (one
    value per model) gathered at `k` (once per view), the others those of
    `shared`."""

    def __init__(self, shared, arrays, dtype, k):
        self.shared, self.arrays, self.dtype, self.k, self.cache = shared, arrays, dtype, k, {}

    def __getitem__(self, name):
        if name not in self.arrays:
            return self.shared[name]
        if name not in self.cache:
            self.cache[name] = dr.gather(self.dtype, self.arrays[name], self.k)
        return self.cache[name]


class NodeChannel(Channel):
    """The 19 models of ``Material.spectral_bakes()`` as one channel: each
    quantity that differs between the models (``per_node``) uploaded once,
    stacked along a node axis; :meth:`at` gives the channel of a per-lane
    model `k` (its rows offset by `k` models, its scalars gathered at `k`),
    so that a lane reads the models it needs and no other."""

    # Read as Python floats (branches, literals), by `Model` from model 0
    # (D, G) or from the shared tables: one value for every model.
    SHARED = {"sigma_s", "b", "colour", "has_q", "sigma_rel", "halo_weight", "base",
              "conv_baked", "masking", "conv_u0",
              "conv_cos_h_min", "masking_beta", "masking_g1", "beta", "p", "epd_norm",
              "epd_inv_beta_sq"}

    # The tables read through `_node_row`: stacked even where the models agree.
    ROWS = ("direction_rows", "direction_weights", "conv_ln_c", "radial_inv_m", "halo_u",
            "halo_inv_du", "halo_inv_total", "halo_zeta", "halo_coef", "halo_cum", "halo_guide",
            "halo_row_inv_w", "halo_row_node_scale")

    def __init__(self, models, per_node, count):
        clash = sorted(n for n in per_node if n in self.SHARED or n.startswith("visible_"))
        if clash:
            raise ValueError(f"twoscale: the spectral models differ in {clash}")
        super().__init__({k: (v[0] if k in per_node else v) for k, v in models.items()})
        self.specialise(models)
        tables = sampler_tables(models)
        stacked = {k: tables[k] for k in per_node}
        stacked.update({k: np.stack([tables[k]] * count) for k in self.ROWS if k not in per_node})
        arrays = {k: v for k, v in stacked.items() if np.ndim(v) > 1}
        for name, v in arrays.items():
            self.t[name] = upload(v)
        # As `Channel`'s packets, over the stacked grids (a packet never
        # crosses a row, so never a model).
        ln_c = np.ascontiguousarray(arrays["conv_ln_c"], dtype=np.float32).ravel()
        ln_c = np.concatenate([ln_c, np.zeros(3, np.float32)])
        self.conv_quads = upload(np.lib.stride_tricks.sliding_window_view(ln_c, 4))
        scalars = {k: np.asarray(v, np.float64) for k, v in stacked.items() if k not in arrays}
        if "eta_re" in scalars or "f_dr_int" in scalars:
            # The base layer's constants per model (as `Channel`'s).
            n = np.maximum(np.abs(np.broadcast_to(models["eta_re"], count)), 1e-3)
            f_dr = np.broadcast_to(models["f_dr_int"], count).astype(np.float64)
            scalars["base_inv_n_sq"] = 1.0 / (n * n)
            scalars["base_a_f"] = (1.0 - f_dr) / (1.0 + f_dr)
        self.node_f = {k: mi.Float(v) for k, v in scalars.items()}
        self.halo_u_nodes = self.shapes["halo_u"][0]

    def at(self, k):
        """This stack at the per-lane model `k` (``mi.UInt32``)."""
        view = copy.copy(self)
        view.k = k
        view.f = NodeScalars(self.f, self.node_f, mi.Float, k)
        n_u = self.halo_u_nodes
        view.halo_u_top = dr.gather(mi.Float, self.t["halo_u"], view._node_row(n_u - 1, n_u))
        return view

    def _node_row(self, i, n):
        return i + self.k * n


def diffraction_stack(channels, bakes):
    """The channels' bakes as one :class:`NodeChannel` (channel `k` at a
    lane's `k`), so that `draw` runs one diffraction draw per lane, from its
    own channel, rather than one per channel; None with fewer than two
    channels, one without the lobe, or channels that differ in what
    `NodeChannel` shares."""
    if len(channels) < 2 or not all(ch.diffraction for ch in channels):
        return None
    per_node = [k for k, v in bakes[0].items()
                if any(not np.array_equal(v, b[k]) for b in bakes[1:])]
    models = {k: (np.stack([b[k] for b in bakes]) if k in per_node else v)
              for k, v in bakes[0].items()}
    try:
        return NodeChannel(models, per_node, len(bakes))
    except ValueError:
        return None


class SpectralModel(Model):
    """The model at any wavelength of a :class:`twoscale.Material`
    (``brdf::Spectral``, ``Material.eval_spectral``) in Dr.Jit: the 19
    models of ``Material.spectral_bakes()`` sharing the surface; at λ the
    surface lobes at λ itself (F(θd) from the table over λ and √cos θ,
    ``FresnelBake``; C from the lower model's bake at u = b cos θd/λ) with σrel/σs and
    Q̄/F(θd) interpolated linearly in λ between the two models; the base
    lobes interpolated in λ (docs/model.md §2.12). ``pdf`` and
    ``sample_direction`` at λ are those of the nearest of the sampler
    models, every other one (``Spectral::pdf``, ``Spectral::sample``).

    As ``Spectral::eval4``, the pair's geometry, D and G are computed once
    per path and each wavelength reads the two models around it (of the
    stacked bakes, :class:`NodeChannel`; C the lower one's only); ``pdf``
    and ``sample`` read the nearest model only."""

    def __init__(self, material: twoscale.Material, params=None):
        spectral = material.spectral_bakes()
        models, per_node = spectral["models"], set(spectral["per_node"])
        # The shared surface (geometry, G, the visible-slope sampler): model 0's.
        first = {k: (v[0] if k in per_node else v) for k, v in models.items()}
        super().__init__(material, params, [first])
        self.stack = NodeChannel(models, per_node, len(spectral["wavelengths"]))
        self.nodes = [float(np.float32(x)) for x in spectral["wavelengths"]]
        self.node_table = mi.Float(spectral["wavelengths"])
        self.fresnel = upload(np.asarray(spectral["fresnel"], np.float32))
        self.fresnel_shape = spectral["fresnel"].shape
        self.eta_first = float(np.float32(spectral["eta_first"]))
        self.eta_step = float(np.float32(spectral["eta_step"]))
        self.white = spectral["colour"] == "white"

    def clamped(self, lam):
        """`Spectral::clamped`: λ (µm, f32) clamped to the models' range (NaN → the first)."""
        return dr.select(lam > self.nodes[0], dr.minimum(lam, self.nodes[-1]), self.nodes[0])

    def cell(self, lam):
        """`spectral::cell`: the model `k` and fraction `f` of the clamped λ."""
        k = mi.UInt32(0)
        for node in self.nodes[1:-1]:
            k += dr.select(lam > node, 1, 0)
        a = dr.gather(mi.Float, self.node_table, k)
        b = dr.gather(mi.Float, self.node_table, k + 1)
        f = (lam - a) / (b - a)
        return k, dr.select(f > 0.0, dr.minimum(f, 1.0), 0.0)

    def fresnel_at(self, lam, cos):
        """`FresnelBake::at`: F at λ (f32) and `cos θ` (f32), bilinear on the
        table's 1 nm rows and its `√cos θ` nodes (the cell of `cos θ` on the
        direction bake's axis, `DirectionCell::coarser`)."""
        rows, cols = self.fresnel_shape
        t = (lam - self.eta_first) / self.eta_step
        j = dr.minimum(mi.UInt32(dr.floor(dr.maximum(t, 0.0))), rows - 2)
        f = dr.clip(t - mi.Float(j), 0.0, 1.0)
        ch = self.channels[0]
        n = ch.shapes["direction_rows"][0]
        i, frac = ch.direction_cell(cos)
        m, g = cell_at((mi.Float(i) + frac) * (1.0 / ((n - 1) // (cols - 1))), cols)

        def row(r):
            a = dr.gather(mi.Float, self.fresnel, r * cols + m)
            b = dr.gather(mi.Float, self.fresnel, r * cols + m + 1)
            return a + g * (b - a)

        low, high = row(j), row(j + 1)
        return low + f * (high - low)

    def eval_spectral(self, wi, wo, lams):
        """ρ(wi, wo) at each wavelength of `lams` (µm; a sequence of
        ``mi.Float``), as a list of ``mi.Float`` (``Spectral::eval4``):
        each model's terms at the pair (:meth:`Channel.node_terms`), then
        the surface lobes at λ itself with C from the lower model's bake
        (``Spectral::at_lambda``)."""
        valid, geo = self.geometry(wi, wo)
        pair = self.pair(geo)
        cos_i, cos_d, g = pair["cos_i"], pair["cos_d"], pair["g"]
        s = self.channels[0].s
        out = []
        for lam in lams:
            lam = self.clamped(mi.Float(lam))
            k, f = self.cell(lam)
            # The two models around λ: their terms at the pair.
            lower, upper = self.stack.at(k), self.stack.at(k + 1)
            ta = lower.node_terms(pair, self.params)
            tb = upper.node_terms(pair, self.params)

            def lerp(j):
                return dr.fma(f, tb[j] - ta[j], ta[j])

            # λ_k/λ: B, (4π/λ)² and the halo's 1/λ² from model k's.
            ratio = lower.f["lambda"] / lam
            ratio_sq = ratio * ratio
            x_scale = lower.f["x_scale"] * ratio_sq
            sigma_rel_sq = (lower.f["sigma_s_sq"] * lerp(0) if s["sigma_s"] > 0.0
                            else mi.Float(0.0))
            a_spec, one_minus_a_over = exp_and_one_minus_over(x_scale * pair["cos_d_sq"],
                                                                sigma_rel_sq)
            fl = mi.Float(1.0) if self.white else self.fresnel_at(lam, cos_d)
            specular = a_spec * fl * pair["rho_geo"]
            if lower.diffraction:
                if self.white:
                    q = mi.Float(1.0)
                else:
                    # F(θd, λ) ((1 − f) Q̄_k/F_k + f Q̄_k+1/F_k+1), one division.
                    fa, fb = ta[2], tb[2]
                    coloured = (fa > 0.0) & (fb > 0.0)
                    fa = dr.select(coloured, fa, 1.0)
                    fb = dr.select(coloured, fb, 1.0)
                    qa, qb = ta[1], tb[1]
                    q = dr.select(coloured,
                                  fl * ((1.0 - f) * qa * fb + f * qb * fa) / (fa * fb),
                                  lerp(1))
                if s["halo_weight"] == "incident":
                    one_minus_a_over = exp_and_one_minus_over(x_scale * cos_i * cos_i,
                                                               sigma_rel_sq)[1]
                halo = lower.f["halo_scale"] * ratio_sq * one_minus_a_over
                # C from the lower model's bake only, at u = b cos θd/λ.
                c_value = lower.conv(pair["sin_h"], pair["cos_h"], lower.f["big_b"] * ratio * cos_d)
                diffraction = dr.select(
                    g > 0.0, (q * g) * halo * dr.maximum(c_value, 0.0), 0.0
                ) * self.params["halo_factor"]
            else:
                diffraction = mi.Float(0.0)
            value = finite_or_zero(specular) + finite_or_zero(diffraction) + lerp(3)
            out.append(dr.select(valid, finite_or_zero(dr.maximum(value, 0.0)), 0.0))
        return out

    def nearest(self, lam):
        """`Spectral::nearest`: the index of the sampler model (the even
        ones) nearest λ, the lower on a tie."""
        lam = self.clamped(mi.Float(lam))
        k, _ = self.cell(lam)
        e = k - (k & 1)
        a = dr.gather(mi.Float, self.node_table, e)
        b = dr.gather(mi.Float, self.node_table, e + 2)
        return dr.select(lam + lam <= a + b, e, e + 2)

    def pdf_spectral(self, wi, wo, lam):
        """`Spectral::pdf`: `TwoScale::pdf` of the sampler model nearest λ."""
        valid, geo = self.geometry(wi, wo)
        wi, wo = geo["wi"], geo["wo"]
        node = self.stack.at(self.nearest(lam))
        specular = mi.Float(self.channels[0].visible_pdf(wi, wo))
        base = wo.z * (1.0 / math.pi)
        w = node.lobe_weights(wi.z)
        value = dr.select(w[0] > 0.0, w[0] * specular, 0.0)
        if node.diffraction:
            value += dr.select(w[1] > 0.0, w[1] * node.diffraction_pdf(wi, wo, geo), 0.0)
        value += dr.select(w[2] + w[3] > 0.0, (w[2] + w[3]) * base, 0.0)
        return dr.select(valid, finite_or_zero(value), 0.0)

    def sample_spectral(self, wi, u, lam):
        """`Spectral::sample`'s direction: `TwoScale::sample_direction` of
        the sampler model nearest λ (the lobe picked with `u[0]`, its direction
        from `u[1], u[2]`). Returns the direction and whether one was drawn."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        wi_f = mi.Vector3f(wi)
        valid = dr.all(dr.isfinite(wi_f))
        wi = dr.normalize(wi_f)
        valid &= wi.z > 0.0
        node = self.stack.at(self.nearest(lam))
        pick = dr.clip(u.x, 0.0, below_one)
        u1 = dr.clip(u.y, 0.0, below_one)
        u2 = dr.clip(u.z, 0.0, below_one)
        # The nearest model as the one channel `draw` reads (the visible
        # slopes are shared by the models).
        one = types.SimpleNamespace(channels=[node],
                                    channels_have_diffraction=self.channels_have_diffraction)
        return draw(one, [mi.Bool(True)], node.lobe_weights(wi.z), pick, wi, u1, u2, valid)


class IntegratedModel(Model):
    """The integrated RGB model (``brdf::IntegratedRgb``, ``rgb_mode =
    "integrated"``) of a :class:`twoscale.Material` in Dr.Jit, from
    :meth:`twoscale.Material.integrated_bakes`: the 8 models' lobes weighted
    by the colour weights (``R_kc`` over `√cos θd` for the surface lobes,
    ``P_kc`` for the base and compensation lobes); :meth:`eval` is
    ``Material.eval``. ``pdf`` and ``sample_direction`` are :class:`Model`'s
    over the three models the runtime's sampler mixes (``channels``), which
    is ``IntegratedRgb::pdf`` and ``IntegratedRgb::sample``. `params` as
    :class:`Model`'s."""

    def __init__(self, material: twoscale.Material, params=None):
        integrated = material.integrated_bakes()
        models = integrated["models"]
        sampler = [int(k) for k in integrated["sampler_nodes"]]
        super().__init__(material, params, [models[k] for k in sampler])
        shared = dict(zip(sampler, self.channels))
        self.nodes = [shared[k] if k in shared else Channel(b) for k, b in enumerate(models)]
        self.colour_nodes = integrated["surface"].shape[0]
        # R_kc a row per node of `√cos θd`, padded to whole packets of four.
        surface = np.asarray(integrated["surface"], np.float32).reshape(self.colour_nodes, -1)
        self.surface_packets = -(-surface.shape[1] // 4)
        self.surface = upload(np.pad(surface, ((0, 0), (0, 4 * self.surface_packets
                                                         - surface.shape[1]))))
        self.plain = [[dr.opaque(mi.Float, float(x)) for x in row] for row in integrated["plain"]]
        # C read at `conv_nodes`, ln C at every node by `conv_weights` over those.
        self.conv_nodes = [int(k) for k in integrated["conv_nodes"]]
        self.conv_weights = [[float(w) for w in row] for row in integrated["conv_weights"]]

    def surface_weights(self, cos_d):
        """``ColourBake::surface_at``: `R_kc` at `cos θd`, linear in
        `√cos θd` between nodes, in f32 (a list over k of three values)."""
        n = self.colour_nodes
        t = dr.sqrt(dr.clip(cos_d, 0.0, 1.0)) * (n - 1)
        m = dr.minimum(mi.UInt32(dr.floor(t)), n - 2)
        f = t - mi.Float(m)
        # The two rows, each as packets of four floats.
        packets = self.surface_packets
        a = [v for j in range(packets) for v in gather4(self.surface, m * packets + j)]
        b = [v for j in range(packets) for v in gather4(self.surface, (m + 1) * packets + j)]
        return [[dr.fma(f, b[3 * k + c] - a[3 * k + c], a[3 * k + c]) for c in range(3)]
                for k in range(len(self.nodes))]

    def conv_values(self, pair):
        """``IntegratedRgb::ln_conv`` and its interpolation: C at every node
        from ln C at ``conv_nodes`` (a list over the nodes; ``None`` each
        when the surface has no diffraction lobe)."""
        if not self.nodes[0].diffraction:
            return [None] * len(self.nodes)
        ln = []
        for k in self.conv_nodes:
            node = self.nodes[k]
            ln.append(node.ln_conv(pair["sin_h"], pair["cos_h"], node.f["big_b"] * pair["cos_d"]))
        values = []
        for row in self.conv_weights:
            x = row[0] * ln[0]
            for w, v in zip(row[1:], ln[1:]):
                x = dr.fma(w, v, x) if w != 0.0 else x
            values.append(c_of_ln(x))
        return values

    def eval(self, wi, wo):
        """ρ(wi, wo) in linear sRGB (sr⁻¹) as an ``mi.Color3f``
        (``IntegratedRgb::eval``; arguments as :meth:`Model.eval`'s)."""
        valid, geo = self.geometry(wi, wo)
        pair = self.pair(geo)
        r = self.surface_weights(pair["cos_d"])
        c_values = self.conv_values(pair)
        out = [mi.Float(0.0)] * 3
        for k, node in enumerate(self.nodes):
            spec, diff, base, multiple = node.lobes(pair, self.params, c_values[k])
            surface = spec + diff
            # The compensation lobe's colour is F_avg's, per node: plain weights.
            rest = base + multiple
            out = [dr.fma(surface, r[k][c], dr.fma(rest, self.plain[k][c], out[c]))
                   for c in range(3)]
        values = [finite_or_zero(dr.maximum(x, 0.0)) for x in out]
        return dr.select(valid, mi.Color3f(*values), 0.0)


def rgb_model(material: twoscale.Material, params=None):
    """The Dr.Jit model of `material`'s RGB (its ``rgb_mode``):
    :class:`IntegratedModel` or :class:`Model` (the paper's wavelengths)."""
    if material.rgb_mode == "integrated":
        return IntegratedModel(material, params)
    return Model(material, params)
