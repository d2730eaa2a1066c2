"""The model's lobes (runtime/src/brdf/eval.rs: `TwoScale::lobes`,
`base_value`, Q̄) and the sampler's lobe weights, lobe pick and draws
(runtime/src/brdf/sample.rs) in Dr.Jit, for one channel
(:class:`Channel`)."""

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from .halo import Halo
from .lookups import LOBES, Q_FACTORS, Bakes, gather4
from .math import finite_or_zero
from .visible import Visible


def exp_and_one_minus_over(x, srs):
    """`brdf::exp_and_one_minus_over`: `(e^−t, (1 − e^−t)/s)`, `t = x s`, in
    the type of `x` (f32 in the lobes). Below `t = 0.1` the second is
    `x (1 − e^−t)/t` by its series to `t⁶` (truncation < 3e-12 relative),
    where `1 − e^−t` would cancel (in f32, `2^−24/t` relative); above, the
    division (≤ 6e-7 relative in f32)."""
    t = x * srs
    e = dr.exp(-t)
    series = 1.0 - t * (1.0 / 2.0 - t * (1.0 / 6.0 - t * (1.0 / 24.0 - t * (
        1.0 / 120.0 - t * (1.0 / 720.0 - t * (1.0 / 5040.0))))))
    return e, dr.select(t < 0.1, x * series, (1.0 - e) / srs)


class Channel(Bakes, Visible, Halo):
    """One channel (one model at one wavelength): its bakes
    (:class:`~twoscale.drjit.lookups.Bakes`), the visible-slope and halo
    samplers, and the lobes, their weights and draws."""

    def lobe_weights(self, cos_i):
        """`DirectionBake::lobe_weights`: `[specular, diffraction, base, multiple]`,
        sum 1 (f32)."""
        columns = self.weight_columns
        if columns in ([], [0]):
            # The specular lobe alone (or no lobe): weights [1, 0, 0, 0] everywhere.
            return [mi.Float(1.0)] + [mi.Float(0.0)] * 3
        i, frac = self.direction_cell(cos_i)
        a = gather4(self.t["direction_weights"], i)
        b = gather4(self.t["direction_weights"], i + 1)
        col = self.weight_index
        # Lobes whose weight is 0 at every node contribute exact zeros.
        w = [dr.maximum(dr.fma(frac, b[col[k]] - a[col[k]], a[col[k]]), 0.0)
             if k in columns else mi.Float(0.0) for k in range(len(LOBES))]
        total = sum(w[k] for k in columns)
        ok = total > 0.0
        return [dr.select(ok, w[0] / total, 1.0)] + [
            dr.select(ok, w[k] / total, 0.0) if k in columns else w[k]
            for k in range(1, len(LOBES))]

    def diffraction_pdf(self, wi, wo, geo):
        """`TwoScale::diffraction_pdf` where C is baked (the plugin requires
        it): the half-vector draw's `HaloBake::pdf`, returned in f32."""
        return dr.select(geo["cos_d"] > 0.0,
                         mi.Float(self.halo_pdf(wi, geo["sin_h"], geo["cos_h"], wo.z)), 0.0)

    def diffraction_sample(self, wi, u0, u1):
        """The diffraction lobe's direction where C is baked
        (`TwoScale::sample_diffraction`: a reflected half-vector of
        `halo_sample`) and whether it exists (f32)."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        m, ok = self.halo_sample(wi, dr.minimum(u1, below_one), u0)
        m = mi.Vector3f(m)
        k = 2.0 * dr.dot(wi, m)
        return k * m - wi, ok & (k > 0.0)

    # -- the model (`TwoScale::lobes`, runtime/src/brdf/eval.rs) ---------
    def q_bar(self, fi, fo, along, across):
        """`QConstants::combine` (Q̄ from the factors `[a, Re U, Im U, Re W, Im W]`,
        :data:`~twoscale.drjit.lookups.Q_FACTORS`, at θi and θo and the
        pair's `along = −(wi·wo)ₜ`, `across`), f32."""
        fi, fo = [fi[n] for n in Q_FACTORS], [fo[n] for n in Q_FACTORS]
        s_sq = along * along + across * across
        ok = s_sq > 0.0
        along = dr.select(ok, along, 1.0)
        across = dr.select(ok, across, 0.0)
        inv_s_sq = dr.select(ok, 1.0 / s_sq, 1.0)
        # ui uo along − η² (wi wo) s², complex.
        uu_re = fi[1] * fo[1] - fi[2] * fo[2]
        uu_im = fi[1] * fo[2] + fi[2] * fo[1]
        ww_re = fi[3] * fo[3] - fi[4] * fo[4]
        ww_im = fi[3] * fo[4] + fi[4] * fo[3]
        e_re, e_im = self.f["q_eta_sq_re"], self.f["q_eta_sq_im"]
        pp_re = uu_re * along - (e_re * ww_re - e_im * ww_im) * s_sq
        pp_im = uu_im * along - (e_re * ww_im + e_im * ww_re) * s_sq
        norm_ui = fi[1] * fi[1] + fi[2] * fi[2]
        norm_uo = fo[1] * fo[1] + fo[2] * fo[2]
        q = (fi[0] * fo[0] * (along * along)
             + (fi[0] * norm_uo + norm_ui * fo[0]) * (across * across)
             + pp_re * pp_re + pp_im * pp_im)
        return 0.5 * self.f["q_e_norm_sqr"] * q * inv_s_sq

    def base_value(self, f_i, f_o, cos_i, cos_o, params):
        """`TwoScale::base_value`: ρ_base + k_d/π (HP17 42-47), with the
        albedo α and k_d of `params` (differentiable: closed forms after
        the lookups). Plastic: `T α / (π n² (1 − α F_dr))`; subsurface:
        `T α/(4π (cos θi' + cos θo')) + T α/(2π) e^−r (1 + e^−(4/3) A r)`,
        `r = √(3(1 − α))`, `T = (1 − F(θi))(1 − F(θo))`; f32."""
        s, d = self.s, self.f
        lambertian = params["lambertian"] * (1.0 / math.pi)
        if s["colour"] == "white" or s["base"] == "conductor":
            return lambertian
        alpha = params["albedo"]
        t = (1.0 - f_i) * (1.0 - f_o)
        if s["base"] == "plastic":
            plastic = alpha * d["base_inv_n_sq"] / (math.pi * (1.0 - alpha * d["f_dr_int"]))
            return t * plastic + lambertian

        def refracted(cos):
            return dr.sqrt(dr.maximum(1.0 - (1.0 - cos * cos) * d["base_inv_n_sq"], 0.0))

        root = dr.sqrt(dr.maximum(3.0 * (1.0 - alpha), 0.0))
        multi = alpha / (2.0 * math.pi) * dr.exp(-root) * (
            1.0 + dr.exp(-4.0 / 3.0 * d["base_a_f"] * root))
        single = t * (alpha / (4.0 * math.pi)) / dr.maximum(
            refracted(cos_i) + refracted(cos_o), 1e-12)
        return single + t * multi + lambertian

    def lobes(self, pair, params, c_value=None):
        """`TwoScale::lobes`: (specular, diffraction, base, multiple) at a pair
        (:meth:`Model.pair`'s terms), in f32, the diffraction lobe times
        `params["halo_factor"]` and the base layer's with `params`' albedo and
        k_d (:meth:`base_value`). ρ_spec = A_spec F(θd) · `g D/(4 cos θi cos θo)`
        (the pair's), ρ_CTD = Q̄ G halo (1 − A)/σrel² C (HP17 22, 37); C
        from this model's bake unless `c_value` is given
        (``TwoScale::surface_terms_with``)."""
        s, f = self.s, self.f
        cos_i, cos_o, cos_d = pair["cos_i"], pair["cos_o"], pair["cos_d"]
        at_i, at_o = self.direction_values(cos_i), self.direction_values(cos_o)
        # A_spec and (1 − A)/σrel² from one exponential.
        if s["sigma_s"] > 0.0:
            r_i, r_o = at_i["sigma_ratio"], at_o["sigma_ratio"]
            ratio_sq = (0.5 * (r_i * r_i + r_o * r_o) if s["sigma_rel"] == "symmetrised"
                        else r_i * r_i)
            sigma_rel_sq = f["sigma_s_sq"] * ratio_sq
        else:
            sigma_rel_sq = mi.Float(0.0)
        a_spec, one_minus_a_over = exp_and_one_minus_over(f["x_scale"] * pair["cos_d_sq"],
                                                           sigma_rel_sq)
        fresnel_d = mi.Float(1.0) if s["colour"] == "white" else self.direction_fresnel(cos_d)
        specular = a_spec * fresnel_d * pair["rho_geo"]

        if self.diffraction:
            if s["colour"] == "white":
                q = mi.Float(1.0)
            elif s["has_q"]:
                q = dr.maximum(self.q_bar(at_i, at_o, pair["along"], pair["across"]), 0.0)
            else:
                q = mi.Float(0.0)
            if s["halo_weight"] == "incident":
                one_minus_a_over = exp_and_one_minus_over(f["x_scale"] * cos_i * cos_i,
                                                           sigma_rel_sq)[1]
            if c_value is None:
                c_value = dr.maximum(self.conv(pair["sin_h"], pair["cos_h"], f["big_b"] * cos_d),
                                     0.0)
            g = pair["g"]
            diffraction = dr.select(g > 0.0, (q * g) * (f["halo_scale"] * one_minus_a_over)
                                    * c_value, 0.0) * params["halo_factor"]
        else:
            diffraction = mi.Float(0.0)
        base = self.base_value(at_i["fresnel"], at_o["fresnel"], cos_i, cos_o, params)
        # ρ_ms = F_ms (1 − E_s(μi)) (1 − E_s(μo)) / (π (1 − E_avg)), docs/model.md §2.11.
        multiple = (f["multiple_scale"] * at_i["lost"] * at_o["lost"] if self.has_multiple
                    else mi.Float(0.0))
        return (finite_or_zero(specular), finite_or_zero(diffraction), finite_or_zero(base),
                finite_or_zero(multiple))

    def node_terms(self, pair, params):
        """`spectral::NodeTerms::new`: (σrel²/σs², Q̄, F(θd), ρ_base + k_d/π
        + ρ_ms) of this model at a pair (:meth:`Model.pair`'s terms), f32."""
        s, f = self.s, self.f
        at_i, at_o = self.direction_values(pair["cos_i"]), self.direction_values(pair["cos_o"])
        r_i, r_o = at_i["sigma_ratio"], at_o["sigma_ratio"]
        ratio_sq = (0.5 * (r_i * r_i + r_o * r_o) if s["sigma_rel"] == "symmetrised"
                    else r_i * r_i)
        if s["colour"] == "white":
            q, fresnel_d = mi.Float(1.0), mi.Float(1.0)
        else:
            q = (dr.maximum(self.q_bar(at_i, at_o, pair["along"], pair["across"]), 0.0)
                 if s["has_q"] else mi.Float(0.0))
            fresnel_d = self.direction_fresnel(pair["cos_d"])
        base = self.base_value(at_i["fresnel"], at_o["fresnel"], pair["cos_i"], pair["cos_o"],
                               params)
        multiple = (f["multiple_scale"] * at_i["lost"] * at_o["lost"] if self.has_multiple
                    else mi.Float(0.0))
        plain = finite_or_zero(base) + finite_or_zero(multiple)
        return ratio_sq, q, fresnel_d, plain

def draw(model, selected, w, pick, wi, u1, u2, valid):
    """`sample::pick_lobe` of the weights `w` with `pick`, then `TwoScale::sample_lobe`'s
    direction from `u1, u2`: a visible normal of the shared specular bake, the
    diffraction law of the channel (model) where `selected[n]`, the cosine lobe
    for the base and the compensation lobe. Returns the direction
    (``mi.Vector3f``, normalised: `upper_unit`; all in f32, the samplers'
    normals cast to f32) and whether one was drawn."""
    cumulative, last, chosen = mi.Float(0.0), mi.UInt32(0), mi.Int32(-1)
    for n in range(4):
        positive = w[n] > 0.0
        cumulative += dr.select(positive, w[n], 0.0)
        last = dr.select(positive, n, last)
        chosen = dr.select((chosen < 0) & positive & (pick < cumulative), n, chosen)
    lobe = dr.select(chosen < 0, last, mi.UInt32(chosen))
    m, ok = model.channels[0].visible_sample(wi, u1, u2)
    m = mi.Vector3f(m)
    o = 2.0 * dr.dot(wi, m) * m - wi
    if getattr(model, "diffraction_stack", None) is not None:
        # One draw from each lane's own channel.
        k = mi.UInt32(0)
        for n in range(1, len(selected)):
            k = dr.select(selected[n], n, k)
        od, ok_d = model.diffraction_stack.at(k).diffraction_sample(wi, u1, u2)
        o = dr.select(lobe == 1, od, o)
        ok = dr.select(lobe == 1, ok_d, ok)
    else:
        for n, channel in enumerate(model.channels):
            if channel.diffraction:
                od, ok_d = channel.diffraction_sample(wi, u1, u2)
                here = (lobe == 1) & selected[n]
                o = dr.select(here, od, o)
                ok = dr.select(here, ok_d, ok)
    if any(n in ch.weight_columns for ch in model.channels for n in (2, 3)):
        # The cosine lobe (traced only when some channel can pick lobe 2 or 3).
        r, phi = dr.sqrt(u1), 2.0 * math.pi * u2
        sin_phi, cos_phi = dr.sincos(phi)
        ob = mi.Vector3f(r * cos_phi, r * sin_phi, dr.sqrt(dr.maximum(1.0 - u1, 0.0)))
        o = dr.select(lobe >= 2, ob, o)
        ok = dr.select(lobe >= 2, True, ok)
    ok &= ~((lobe == 1) & ~model.channels_have_diffraction)
    o = dr.normalize(o)
    ok &= valid & (o.z > 0.0) & dr.all(dr.isfinite(o))
    return o, ok
