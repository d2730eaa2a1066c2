"""The diffraction lobe's half-vector sampler (runtime/src/bake/halo.rs,
`HaloBake`, `Azimuth`) in Dr.Jit: its density and draw."""

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from .math import NEWTON_TOL, acos_approx, log2_axis, newton_in_bracket
from .visible import guide_bin, guide_scan


class Halo:
    """`HaloBake::pdf` and `sample_h` over a :class:`~twoscale.drjit.lookups.Bakes`'
    ``halo_*`` tables (a mixin of :class:`~twoscale.drjit.lobes.Channel`)."""

    @staticmethod
    def _at_node(x, node, position, n):
        """`halo::at_node`: the last node `k ≤ n − 2` with `node(k) ≤ x`
        from a `position` within one node of it (the three nodes around
        it gathered at once: no dependent second gather)."""
        k = mi.UInt32(dr.clip(position, 0.0, float(n - 2)))
        lower = (k > 0) & (x < node(k))
        upper = (k + 2 < n) & (x >= node(dr.minimum(k + 1, n - 1)))
        return dr.select(lower, k - 1, dr.select(upper, k + 1, k))

    def _row_cell(self, wi):
        """`HaloBake::row_cell` at `u = B cos θi`: the row below (from the C
        bake's u axis, as its own look-up finds it) and the fraction
        `(u − u_j)/(u_j+1 − u_j)` ."""
        n_u = self.shapes["halo_u"][0]
        u = dr.clip(self.f["big_b"] * wi.z, 0.0, self.halo_u_top)
        uf = mi.Float(u)
        position = ((log2_axis(1.0 + uf / self.s["conv_u0"]) + uf * self.f["conv_u_linear"])
                    * self.f["conv_u_scale"])
        j = self._at_node(
            u, lambda j: dr.gather(mi.Float, self.t["halo_u"], self._node_row(j, n_u)),
            position, n_u)
        row = self._node_row(j, n_u)
        u0 = dr.gather(mi.Float, self.t["halo_u"], row)
        inv_du = dr.gather(mi.Float, self.t["halo_inv_du"], row)
        return row, dr.clip((u - u0) * inv_du, 0.0, 1.0)

    def _halo_zeta(self, row, k):
        n_s = self.shapes["halo_zeta"][1]
        return dr.gather(mi.Float, self.t["halo_zeta"], row * n_s + k)

    def _halo_cum(self, row, k, tail=False):
        """Row `row`'s cumulative mass at node `k`, or with `tail` (a mask)
        the mass above it (`lookups.sampler_tables`)."""
        n_s = self.shapes["halo_zeta"][1]
        side = dr.select(tail, n_s, 0) if isinstance(tail, mi.Bool) else 0
        return dr.gather(mi.Float, self.t["halo_cum"], row * (2 * n_s) + side + k)

    def _halo_coef(self, row, k):
        """`[start, slope]` of row `row`'s cell `k`."""
        n_s = self.shapes["halo_zeta"][1]
        c = dr.gather(mi.Vector2f, self.t["halo_coef"], row * n_s + k)
        column = self.columns["halo_coef"]
        return c[column["start"]], c[column["slope"]]

    @staticmethod
    def _azimuth(sin_i, cos_i, sin_h, cos_h):
        """`halo::Azimuth::new`: `(H, [A₂, A₁, A₀], F(H))` of the azimuth law
        `∝ (i·h)(cos θo)₊` and whether it exists; `F(H)` from
        `x = cos H` without a sine or cosine."""
        a, b = sin_i * sin_h, cos_i * cos_h
        kappa = cos_i / (2.0 * cos_h)
        wide = b - a >= kappa
        exists = (cos_h > 0.0) & (wide | (b + a > kappa))
        x = dr.clip((kappa - b) / a, -1.0, 1.0)
        big_h = dr.select(wide, math.pi, acos_approx(x))
        sin = dr.select(wide, 0.0, dr.sqrt(dr.maximum(1.0 - x * x, 0.0)))
        x = dr.select(wide, -1.0, x)
        coef = (2.0 * cos_h * a * a, (4.0 * cos_h * b - cos_i) * a, (2.0 * cos_h * b - cos_i) * b)
        half = 0.5 * coef[0] * (big_h + x * sin) + coef[1] * sin + coef[2] * big_h
        return big_h, coef, half, exists & (half > 0.0)

    @staticmethod
    def _azimuth_cdf(coef, psi):
        """`halo::cdf`: `A₂ (ψ + sin ψ cos ψ)/2 + A₁ sin ψ + A₀ ψ`."""
        s, c = dr.sin(psi), dr.cos(psi)
        return 0.5 * coef[0] * (psi + s * c) + coef[1] * s + coef[2] * psi

    def _zeta_cell(self, row, z, sec_h, tan_h):
        """`HaloBake::zeta_cell`: the cell of ζ in `row` from the C bake's θh
        axis at `sec θh`, `tan θh` (f32), corrected by one node."""
        n_s = self.shapes["halo_zeta"][1]
        x = sec_h + tan_h * dr.gather(mi.Float, self.t["halo_row_inv_w"], row)
        position = log2_axis(x) * dr.gather(mi.Float, self.t["halo_row_node_scale"], row)
        return self._at_node(z, lambda k: self._halo_zeta(row, k), position, n_s)

    def _row_pdf(self, row, z, sec_h, tan_h):
        """`HaloBake::row_pdf`: `(start_k + slope_k (ζ − ζ_k)) / M_j`."""
        n_s = self.shapes["halo_zeta"][1]
        k = self._zeta_cell(row, z, sec_h, tan_h)
        start, slope = self._halo_coef(row, k)
        d = start + slope * (z - self._halo_zeta(row, k))
        inv_total = dr.gather(mi.Float, self.t["halo_inv_total"], row)
        ok = z <= self._halo_zeta(row, n_s - 1)
        return dr.select(ok, dr.maximum(d, 0.0) * inv_total, 0.0)

    def halo_pdf(self, wi, sin_h, cos_h, cos_o):
        """`HaloBake::pdf`: `Σ_j w_j p_j(ζ) cos θo / (4 N(θh))`."""
        sin_i = dr.minimum(dr.sqrt(wi.x * wi.x + wi.y * wi.y), 1.0)
        _, _, half, exists = self._azimuth(sin_i, wi.z, sin_h, cos_h)
        zeta = sin_h * sin_h / (1.0 + cos_h)
        j, t = self._row_cell(wi)
        # The C bake's θh axis variables (`HaloBake::pdf_zeta`).
        sec_h = 1.0 / dr.maximum(cos_h, 1e-3)
        tan_h = dr.clip(sin_h, 0.0, 1.0) * sec_h
        p = dr.select(t < 1.0, (1.0 - t) * self._row_pdf(j, zeta, sec_h, tan_h), 0.0)
        p += dr.select(t > 0.0, t * self._row_pdf(j + 1, zeta, sec_h, tan_h), 0.0)
        return dr.select(exists, p * dr.maximum(cos_o, 0.0) / (8.0 * half), 0.0)

    def halo_sample(self, wi, pick, along):
        """`HaloBake::sample_h`: a half-vector and whether the row had mass."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        n_s = self.shapes["halo_zeta"][1]
        j, t = self._row_cell(wi)
        lower = pick < 1.0 - t
        row = dr.select(lower, j, j + 1)
        azimuth = dr.select(lower, pick / (1.0 - t), (pick - (1.0 - t)) / t)
        azimuth = dr.clip(azimuth, 0.0, below_one)
        total = self._halo_cum(row, n_s - 1)
        # From the row's end where `along ≥ ½` (`lookups.sampler_tables`):
        # the last k with cum(k) ≤ along·total is the last with
        # tail(k) ≥ (1 − along) total, compared as −tail(k) ≤ −(1 − along) total.
        upper = along >= 0.5
        target = dr.select(upper, -((1.0 - along) * total), along * total)
        # The row's guide (`guide::scan` in `HaloBake::sample_h`), its top
        # one cell higher (`guide_bin`).
        edges = self.shapes["halo_guide"][1]
        b = guide_bin(self.s, along)
        lo = mi.UInt32(dr.gather(mi.Float, self.t["halo_guide"], row * edges + b))
        hi = mi.UInt32(dr.gather(mi.Float, self.t["halo_guide"], row * edges + b + 1))
        hi = dr.minimum(hi + 1, n_s - 2)

        def signed_cum(k):
            c = self._halo_cum(row, k, upper)
            return dr.select(upper, -c, c)

        k = guide_scan(lo, hi, self._halo_scan_cells(), target, signed_cum)
        rest = dr.maximum(target - signed_cum(k), 0.0)
        start, slope = self._halo_coef(row, k)
        z0, z1 = self._halo_zeta(row, k), self._halo_zeta(row, k + 1)
        den = start + dr.sqrt(dr.maximum(start * start + 2.0 * slope * rest, 0.0))
        s = dr.select(den > 0.0, 2.0 * rest / den, 0.0)
        z = z0 + dr.minimum(s, z1 - z0)
        cos_h = 1.0 - z
        sin_h = dr.sqrt(dr.maximum(z * (2.0 - z), 0.0))
        sin_i = dr.minimum(dr.sqrt(wi.x * wi.x + wi.y * wi.y), 1.0)
        side = dr.select(azimuth < 0.5, -1.0, 1.0)
        rest = dr.select(azimuth < 0.5, 2.0 * azimuth, 2.0 * azimuth - 1.0)
        big_h, coef, half, exists = self._azimuth(sin_i, wi.z, sin_h, cos_h)
        psi = side * self._solve_azimuth(coef, big_h, half, rest * half)
        has = sin_i > 0.0
        cos_phi_i = dr.select(has, wi.x / sin_i, 1.0)
        sin_phi_i = dr.select(has, wi.y / sin_i, 0.0)
        cp, sp = dr.cos(psi), dr.sin(psi)
        h = mi.Vector3f(sin_h * (cos_phi_i * cp - sin_phi_i * sp),
                        sin_h * (sin_phi_i * cp + cos_phi_i * sp), cos_h)
        return h, (total > 0.0) & exists

    def _halo_scan_cells(self):
        """The widest bracket of the rows' guides: the fixed scan's length."""
        if not hasattr(self, "_halo_scan"):
            g = np.asarray(self.t["halo_guide"].numpy()).reshape(-1, self.shapes["halo_guide"][-1])
            widths = np.diff(g.astype(np.float64), axis=1)
            # Models no lane reads may hold anything (NaN where a test poisons them).
            widths = widths[np.isfinite(widths)]
            self._halo_scan = int(widths.max()) if widths.size else 0
        return self._halo_scan

    @staticmethod
    def _solve_azimuth(coef, big_h, half, target):
        """`Azimuth::solve`: Newton's method in a shrinking bracket (a
        symbolic loop, each lane until a step is ≤ `NEWTON_TOL`, at most 40 steps)."""
        psi = dr.select(half > 0.0, big_h * dr.clip(target / half, 0.0, 1.0), 0.0)
        return newton_in_bracket(
            lambda psi: Halo._azimuth_cdf(coef, psi) - target,
            lambda psi: (coef[0] * dr.cos(psi) + coef[1]) * dr.cos(psi) + coef[2],
            psi, big_h, NEWTON_TOL)
