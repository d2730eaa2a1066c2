"""The visible-slope sampler (runtime/src/bake/visible.rs, `VisibleSlopeBake`)
in Dr.Jit: the specular lobe's density and draw."""

import types

import drjit as dr
import mitsuba as mi
import numpy as np

from .math import NEWTON_TOL, log2_axis, newton_in_bracket


def guide_bin(s, u):
    """`guide::bin` of `u` on the guide axis of the constants `s`
    (`guide_octaves`, `guide_linear`), in f32: `guide::position`, `e + f +
    octaves` (`min(u, 1 − u) = 2^e (1 + f)`, floored at 0) plus `linear ·
    min(u, 1 − u)`, mirrored about `u = ½` (`1 − u` is exact for `u ≥ ½`).
    The f32 position is within a few ulps (< 2⁻¹⁰) of the exact one; it is
    lowered by 2⁻¹⁰ before the floor, so the bin is the exact one or the
    one below, and a bracket read from it takes one more cell at its top
    (:func:`guide_scan`'s `hi + 1`)."""
    octaves, linear = s["guide_octaves"], s["guide_linear"]
    half_pos = octaves - 1.0 + 0.5 * linear
    bins = int(2 * half_pos)
    u = mi.Float(u)
    lower = u < 0.5
    m = dr.maximum(dr.select(lower, u, 1.0 - u), 0.0)
    half = dr.maximum(log2_axis_exact(m) + octaves, 0.0) + linear * m
    position = dr.select(lower, half, 2.0 * half_pos - half) - 2.0 ** -10
    return mi.UInt32(dr.clip(position, 0.0, float(bins - 1)))


def log2_axis_exact(m):
    """`e + f` for `m = 2^e (1 + f)` (f32 bits; `m = 0` gives −127)."""
    bits = dr.reinterpret_array(mi.UInt32, m)
    exponent = mi.Float(mi.Int32((bits >> 23) & 0xFF) - 127)
    frac = dr.reinterpret_array(mi.Float, (bits & 0x007FFFFF) | 0x3F800000) - 1.0
    return exponent + frac


def guide_scan(lo, hi, cells, target, cum):
    """`guide::scan` with a fixed `cells + 1` comparisons (the widest
    bracket of the guide, and the cell above it that :func:`guide_bin`'s
    lowered bin may need; the caller extends `hi` by one): `lo` plus the
    count of `k ∈ (lo, hi]` with `cum(k) ≤ target`, gathers that do not
    wait on one another."""
    j = mi.UInt32(lo)
    for step in range(1, cells + 2):
        k = dr.minimum(lo + step, hi)
        j += dr.select((lo + step <= hi) & (cum(k) <= target), 1, 0)
    return j


class Visible:
    """`VisibleSlopeBake::pdf` and `sample` over a :class:`~twoscale.drjit.lookups.Bakes`'
    ``visible_*`` tables (a mixin of :class:`~twoscale.drjit.lobes.Channel`)."""

    def _visible_node(self, name, k):
        return dr.gather(mi.Float, self.t[name], k)

    def _visible_guide(self, name, k):
        return mi.UInt32(dr.gather(mi.Float, self.t[name], k))

    def _visible_scan_cells(self):
        """The widest brackets of the marginal's and the conditional's guides
        (`VisibleSlopeBake::marginal_bracket`, `VisibleSlopeBake::conditional_bracket`): the
        fixed scans' lengths, from the tables."""
        if not hasattr(self, "_scan_cells"):
            g = np.asarray(self.t["visible_marginal_guide"].numpy()).reshape(
                self.shapes["visible_marginal_guide"]).astype(np.int64)
            c = np.asarray(self.t["visible_conditional_guide"].numpy()).reshape(
                self.shapes["visible_conditional_guide"]).astype(np.int64)
            marginal = int(np.max(g[1:, 1:] - g[:-1, :-1]))
            conditional = int(np.max(np.maximum(c[1:, 1:], c[:-1, 1:])
                                     - np.minimum(c[1:, :-1], c[:-1, :-1])))
            self._scan_cells = (max(marginal, 0), max(conditional, 0))
        return self._scan_cells

    def _visible_locate(self, a, name, scale):
        """`visible::locate`: the cell `[a0, a1]` of the nodes `name` that
        holds `a ≥ 0` (from its axis position, corrected by one node where
        the axis position and the nodes disagree), its index and the fraction
        in it. The four nodes around the axis position are gathered at once,
        so the correction costs no second dependent gather."""
        n = self.shapes[name][0]
        position = log2_axis(1.0 + mi.Float(a) * self.f["visible_inv_sigma"]) * scale
        k = mi.UInt32(dr.clip(position, 0.0, float(n - 2)))
        before = self._visible_node(name, dr.maximum(k, 1) - 1)
        at0, at1 = self._visible_node(name, k), self._visible_node(name, k + 1)
        after = self._visible_node(name, dr.minimum(k + 2, n - 1))
        lower = (k > 0) & (a < at0)
        upper = (k + 2 < n) & (a >= at1)
        k = dr.select(lower, k - 1, dr.select(upper, k + 1, k))
        a0 = dr.select(lower, before, dr.select(upper, at1, at0))
        a1 = dr.select(lower, at0, dr.select(upper, after, at1))
        return k, dr.clip((a - a0) / (a1 - a0), 0.0, 1.0), a0, a1

    @staticmethod
    def _visible_cell_integral(c, sn, x0, p0, k, tau):
        """`VisibleSlopeBake::cell_integral`: `∫₀^τ (c − s x̃)(P0 + k t) dt`
        over a cell from its left node `x0`."""
        a = c - sn * x0
        return tau * (a * p0 + tau * (0.5 * (a * k - sn * p0) - tau * (sn * k / 3.0)))

    def _visible_phi(self, c, sn, j, tail=None):
        """`Φ` at x̃ node `j`: `c ∫P2_tab − s ∫x̃ P2_tab` from `−r_max`, or
        where the mask `tail` is set the same integrals from `j` to `r_max`
        (`lookups.sampler_tables`)."""
        side = 0 if tail is None else dr.select(tail, self.shapes["visible_mass"][0] // 2, 0)
        return (c * self._visible_node("visible_mass", side + j)
                - sn * self._visible_node("visible_moment", side + j))

    def _visible_incidence(self, wi):
        """`VisibleSlopeBake::incidence` of the unit `wi` (`wi.z > 0`):
        the stretched incidence `c, s, |i'|`, its unit tangential direction,
        the last cell `j_end` the visible marginal reaches, the visible
        length `τ_end` of it and `N_tab`."""
        beta, r_max = self.f["visible_beta"], self.f["visible_r_max"]
        rows_n = self.shapes["visible_rows"][0]
        tangential = dr.sqrt(wi.x * wi.x + wi.y * wi.y)
        bt = beta * tangential
        length = dr.sqrt(bt * bt + wi.z * wi.z)
        has_t = tangential > 0.0
        t0 = dr.select(has_t, wi.x / tangential, 1.0)
        t1 = dr.select(has_t, wi.y / tangential, 0.0)
        c, sn = wi.z / length, bt / length
        # `VisibleSlopeBake::extent`: the cell of μ = c/s where it is inside.
        reaches = sn * r_max > c
        mu = c / sn
        i_mu, _, x0, x1 = self._visible_locate(dr.select(reaches, mu, 0.0), "visible_rows",
                                               self.f["visible_row_scale"])
        p0 = self._visible_node("visible_p2", i_mu)
        k = (self._visible_node("visible_p2", i_mu + 1) - p0) / (x1 - x0)
        j_mu = rows_n - 1 + i_mu
        phi_end = c * self.f["visible_mass_end"] - sn * self.f["visible_moment_end"]
        j_end = dr.select(reaches, j_mu, mi.UInt32(2 * rows_n - 3))
        tau_end = dr.select(reaches, mu - x0, self.f["visible_h_end"])
        # The marginal's mass in j_end's cell, and the f32 offset `base` that
        # turns the tables' tails into tails of the marginal: `norm − Φ_j =
        # tail_j − base` (`visible_sample` from the end).
        last = self._visible_cell_integral(c, sn, x0, p0, k, mu - x0)
        last = dr.select(reaches, last, c * self.f["visible_mass_last"]
                         - sn * self.f["visible_moment_last"])
        norm = dr.select(reaches, self._visible_phi(c, sn, j_mu) + last, phi_end)
        # `VisibleSlopeBake::guide_incidence`: μ's row cell, or beyond r_max
        # the cell of r_max/μ among the guide's tail nodes.
        tail = self.shapes["visible_marginal_guide"][0] - rows_n
        k_tail = mi.UInt32(dr.clip((1.0 - sn * r_max / c) * tail, 0.0, float(tail - 1)))
        guide_a = dr.select(reaches, i_mu, rows_n - 1 + k_tail)
        return types.SimpleNamespace(c=c, sn=sn, length=length, t0=t0, t1=t1, j_end=j_end,
                                     tau_end=tau_end, norm=norm, guide_a=guide_a,
                                     last=last)

    def visible_pdf(self, wi, wo):
        """`VisibleSlopeBake::pdf`: the specular lobe's solid-angle density."""
        beta, r_max = self.f["visible_beta"], self.f["visible_r_max"]
        cols_n = self.shapes["visible_cols"][0]
        inc = self._visible_incidence(wi)
        c, sn, t0, t1 = inc.c, inc.sn, inc.t0, inc.t1
        sum_ = wi + wo
        # Stretched slopes of h (|i + o| cancels).
        inv_bz = 1.0 / (beta * sum_.z)
        sx, sy = -sum_.x * inv_bz, -sum_.y * inv_bz
        x = sx * t0 + sy * t1
        y = -sx * t1 + sy * t0
        valid = (sum_.z > 0.0) & (c - sn * x > 0.0) & (dr.abs(x) <= r_max) & (dr.abs(y) <= r_max)
        # The tabulated density at (x̃, ỹ).
        i, lam, _, _ = self._visible_locate(dr.abs(x), "visible_rows", self.f["visible_row_scale"])

        def blend(name, k0, k1):
            a0 = self._visible_node(name, k0)
            return a0 + lam * (self._visible_node(name, k1) - a0)

        def dens(k):
            d0 = dr.gather(mi.Float, self.t["visible_dens"], i * cols_n + k)
            d1 = dr.gather(mi.Float, self.t["visible_dens"], (i + 1) * cols_n + k)
            return d0 + lam * (d1 - d0)

        p2 = blend("visible_p2", i, i + 1)
        kk, tt, _, _ = self._visible_locate(dr.abs(y), "visible_cols", self.f["visible_col_scale"])
        g0, g1 = dens(kk), dens(kk + 1)
        total = blend("visible_cum", i * (2 * cols_n) + cols_n - 1,
                      (i + 1) * (2 * cols_n) + cols_n - 1)
        g = (g0 + tt * (g1 - g0)) / total
        # 1/cos⁴θh = (1 + |slope|²)² with the unstretched slope β (sx, sy).
        slope_sq = beta * beta * (sx * sx + sy * sy)
        sec4 = (1.0 + slope_sq) * (1.0 + slope_sq)
        value = p2 * g * sec4 / (8.0 * inc.norm * beta * beta * inc.length)
        return dr.select(valid, value, 0.0)

    def visible_sample(self, wi, u0, u1):
        """`VisibleSlopeBake::sample`: a visible EPD normal for the unit `wi`
        from two uniforms, and whether the tables gave mass."""
        beta = self.f["visible_beta"]
        cols_n = self.shapes["visible_cols"][0]
        inc = self._visible_incidence(wi)
        c, sn = inc.c, inc.sn
        # From the end where `u0 ≥ ½`: the last j with Φ_j ≤ u0 N is the
        # last with `tail_j − base ≥ (1 − u0) N` (`_visible_phi`'s tails,
        # `base = tail_{j_end} − last`), compared as `−tail_j ≤ −((1 − u0) N + base)`.
        upper = u0 >= 0.5
        base = self._visible_phi(c, sn, inc.j_end, mi.Bool(True)) - inc.last
        target = dr.select(upper, -((1.0 - u0) * inc.norm + base), u0 * inc.norm)

        def signed_phi(j):
            phi = self._visible_phi(c, sn, j, upper)
            return dr.select(upper, -phi, phi)

        # The last node j ≤ j_end with Φ_j ≤ target (Φ_0 = 0), in the
        # guide's bracket (`VisibleSlopeBake::marginal_bracket`).
        edges = self.shapes["visible_marginal_guide"][1]
        scan_marginal, scan_conditional = self._visible_scan_cells()
        b = guide_bin(self.s, u0)
        hi = dr.minimum(self._visible_guide("visible_marginal_guide",
                                            (inc.guide_a + 1) * edges + b + 1), inc.j_end)
        lo = dr.minimum(self._visible_guide("visible_marginal_guide", inc.guide_a * edges + b), hi)
        hi = dr.minimum(hi + 1, inc.j_end)  # `guide_bin`'s bin may be the one below
        j = guide_scan(lo, hi, scan_marginal, target, signed_phi)
        x0, p0 = self._visible_node("visible_x", j), self._visible_node("visible_px", j)
        x1 = self._visible_node("visible_x", j + 1)
        h = x1 - x0
        k = (self._visible_node("visible_px", j + 1) - p0) / h
        tau_max = dr.select(j == inc.j_end, inc.tau_end, h)
        rest = target - signed_phi(j)
        x = x0 + self._solve_cell(c, sn, x0, p0, k, tau_max, rest)
        # The conditional at |x̃|: its row is the cell j itself, mirrored
        # where x̃ < 0 (`VisibleSlopeBake::row` of |x̃|, but without locating).
        rows_n = self.shapes["visible_rows"][0]
        negative = j < rows_n - 1
        i = dr.select(negative, rows_n - 2 - j, j - (rows_n - 1))
        a0, a1 = dr.select(negative, -x1, x0), dr.select(negative, -x0, x1)
        lam = dr.clip((dr.abs(x) - a0) / (a1 - a0), 0.0, 1.0)

        # From the row's end where |2u − 1| ≥ ½ (`lookups.sampler_tables`):
        # the last column with cum ≤ a·total is the last with
        # tail ≥ (1 − a) total, compared as −tail ≤ −(1 − a) total.
        a = dr.abs(2.0 * u1 - 1.0)
        upper = a >= 0.5
        side = dr.select(upper, cols_n, 0)

        def signed_cum(col):
            a0 = self._visible_node("visible_cum", i * (2 * cols_n) + side + col)
            a1 = self._visible_node("visible_cum", (i + 1) * (2 * cols_n) + side + col)
            c = a0 + lam * (a1 - a0)
            return dr.select(upper, -c, c)

        def dens(col):
            d0 = dr.gather(mi.Float, self.t["visible_dens"], i * cols_n + col)
            d1 = dr.gather(mi.Float, self.t["visible_dens"], (i + 1) * cols_n + col)
            return d0 + lam * (d1 - d0)

        signed = 2.0 * u1 - 1.0
        total = dr.abs(signed_cum(dr.select(upper, 0, cols_n - 1)))
        q = dr.select(upper, -((1.0 - a) * total), a * total)
        # `VisibleSlopeBake::conditional_bracket`: between the rows' own
        # cells, its top one cell higher (`guide_bin`).
        bq = guide_bin(self.s, a)
        gi = [self._visible_guide("visible_conditional_guide", i * edges + bq + d) for d in (0, 1)]
        gn = [self._visible_guide("visible_conditional_guide", (i + 1) * edges + bq + d)
              for d in (0, 1)]
        kk = guide_scan(dr.minimum(gi[0], gn[0]),
                        dr.minimum(dr.maximum(gi[1], gn[1]) + 1, cols_n - 2),
                        scan_conditional, q, signed_cum)
        y0 = self._visible_node("visible_cols", kk)
        w = self._visible_node("visible_cols", kk + 1) - y0
        g0, g1 = dens(kk), dens(kk + 1)
        r = dr.maximum(q - signed_cum(kk), 0.0)
        # (g1 − g0) w τ²/2 + g0 w τ = r, the root in [0, 1] without cancellation.
        b = g0 * w
        disc = dr.maximum(b * b + 2.0 * (g1 - g0) * w * r, 0.0)
        denom = b + dr.sqrt(disc)
        tau_y = dr.select(denom > 0.0, dr.clip(2.0 * r / denom, 0.0, 1.0), 0.0)
        y = dr.copysign(y0 + tau_y * w, signed)
        # Back to the surface: slope β (x̃ t + ỹ t⊥), m = (−slope, 1)/|…|.
        sx = beta * (x * inc.t0 - y * inc.t1)
        sy = beta * (x * inc.t1 + y * inc.t0)
        inv = 1.0 / dr.sqrt(1.0 + sx * sx + sy * sy)
        return mi.Vector3f(-sx * inv, -sy * inv, inv), inc.norm > 0.0

    @staticmethod
    def _solve_cell(c, sn, x0, p0, k, tau_max, rest):
        """`visible::solve_cell`: Newton's method in a shrinking bracket (a
        symbolic loop, each lane until a step, or Newton's predicted error
        after it, is ≤ `NEWTON_TOL` of the cell's scale, at most 40 steps)."""
        a = c - sn * x0

        def density(t):
            return (a - sn * t) * (p0 + k * t)

        # Start from the root without the cubic term: f0 t + b t²/2 = rest.
        f0 = density(0.0 * a)
        b = a * k - sn * p0
        disc = f0 * f0 + 2.0 * b * rest
        denom = f0 + dr.sqrt(dr.maximum(disc, 0.0))
        t = dr.select(denom > 0.0, dr.clip(2.0 * rest / denom, 0.0, tau_max), 0.5 * tau_max)
        tol = NEWTON_TOL * (dr.abs(x0) + tau_max)
        return newton_in_bracket(
            lambda t: Visible._visible_cell_integral(c, sn, x0, p0, k, t) - rest, density,
            t, tau_max, tol, lambda t: k * (a - sn * t) - sn * (p0 + k * t))
