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
"""

import copy
import math
import types

import drjit as dr
import mitsuba as mi
import numpy as np

import twoscale
from twoscale.mitsuba import _material

# The constants of `math::log2_axis` (runtime/src/math/mod.rs), in f32.
_LOG2_E = np.float32(math.log2(math.e))
_AXIS_D0 = float(_LOG2_E)
_AXIS_C2 = float(np.float32(3.0) - np.float32(2.5) * _LOG2_E)
_AXIS_C3 = float(np.float32(1.5) * _LOG2_E - np.float32(2.0))


def _log2_axis(x):
    """`math::log2_axis`: `e + m (d0 + m (c2 + m c3))` for `x = 2^e (1 + m)`."""
    bits = dr.reinterpret_array(mi.UInt32, x)
    exponent = mi.Float(mi.Int32((bits >> 23) & 0xFF) - 127)
    m = dr.reinterpret_array(mi.Float, (bits & 0x007FFFFF) | 0x3F800000) - 1.0
    return exponent + m * (_AXIS_D0 + m * (_AXIS_C2 + m * _AXIS_C3))


def _cell_at(t, n):
    """`bake::cell_at`: the cell `i ∈ [0, n − 2]` and fraction of position `t ≥ 0`."""
    t = dr.minimum(dr.maximum(t, 0.0), float(n - 1))
    i = dr.clip(mi.Int32(dr.floor(t)), 0, n - 2)
    return mi.UInt32(i), t - mi.Float(i)


def _lerp_gather(table, width, column, i, frac):
    """Linear interpolation of column `column` of a row-major table of `width`."""
    a = dr.gather(mi.Float, table, i * width + column)
    b = dr.gather(mi.Float, table, (i + 1) * width + column)
    return dr.fma(frac, b - a, a)


def _upload(values):
    """A bake as a Dr.Jit array (``mi.Float``, or ``mi.Float64`` for f64)
    over a copy of `values` aligned to 64 bytes. Dr.Jit maps a NumPy
    array's memory rather than copying it, and gathers a packet
    (:func:`_gather4`) as one load only from an aligned table: elsewhere it
    falls back to four gathers."""
    values = np.ascontiguousarray(values).ravel()
    buf = np.empty(values.nbytes + 64, np.uint8)
    start = -buf.ctypes.data % 64
    out = buf[start:start + values.nbytes].view(values.dtype)
    out[:] = values
    return (mi.Float64 if values.dtype == np.float64 else mi.Float)(out)


def _gather4(table, k):
    """Floats `4k … 4k + 3` of `table`, one packet gather."""
    return dr.gather(mi.Vector4f, table, k)


def _catmull_rom_weights(t):
    """`conv::catmull_rom_weights`."""
    t2 = t * t
    t3 = t2 * t
    return (
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    )


#: The Newton solves' stopping step (relative to `|x0| + τmax` in the
#: visible sampler's cell, in radians for the halo's azimuth). The
#: runtime stops at 1e-13 (visible) and 1e-12 (halo), which sits at or below
#: the f64 noise of the residuals: where it does, Newton's step never gets
#: that small, and the lane bisects in the noise band for 20–30 more steps
#: (≈40% of the visible sampler's lanes). Once a step is ≤ 1e-9, Newton's
#: error after it is ~1e-18 (quadratic convergence), so stopping there gives
#: the runtime's root to f64 noise, far below the f32 direction returned.
_NEWTON_TOL = 1e-9


def _newton_in_bracket(residual, slope, t, hi, tol, curvature=None):
    """The root in [0, hi] of the increasing `residual` from `t`: Newton's
    method kept in a shrinking bracket (a step leaving it, or a slope ≤ 0,
    bisects), a symbolic loop, each lane until a step is ≤ `tol`, at most 40
    steps (`visible::solve_cell`, `halo::Azimuth::solve`)."""
    lo = dr.zeros(mi.Float64, dr.width(t))

    def body(step, done, t, lo, hi):
        f = residual(t)
        lo = dr.select(f < 0.0, t, lo)
        hi = dr.select(f < 0.0, hi, t)
        d = slope(t)
        newton = t - f / d
        inside = (d > 0.0) & (newton >= lo) & (newton <= hi)
        # A converged step is taken even where it rounds onto the bracket's
        # end (f = 0 puts it there): bisecting would leave the root.
        step_size = dr.abs(newton - t)
        converged = inside & (step_size <= tol)
        if curvature is not None:
            # Newton's error after the step, |f''| δ²/(2 f'), within `tol`.
            converged |= inside & (step_size * step_size * dr.abs(curvature(t)) <= 2.0 * tol * d)
        nxt = dr.select(inside & (newton > lo) & (newton < hi), newton, 0.5 * (lo + hi))
        nxt = dr.select(converged, newton, nxt)
        done = converged | (dr.abs(nxt - t) <= tol)
        return step + 1, done, nxt, lo, hi

    _, _, t, _, _ = dr.while_loop(
        (mi.UInt32(0), mi.Bool(False), t, lo, hi),
        lambda step, done, t, lo, hi: (step < 40) & ~done,
        body,
    )
    return t


def _last_at_most(n, below, steps):
    """`visible::last_at_most`: the last `k < n` with `below(k)` (true at 0,
    monotone), by halving (`steps ≥ ⌈log₂ n⌉`)."""
    base, size = mi.UInt32(0), mi.UInt32(n)
    for _ in range(steps):
        half = size // 2
        base = dr.select(below(base + half), base + half, base)
        size -= half
    return base


def _acos_approx(x):
    """`math::acos_approx` (Abramowitz & Stegun 4.4.46), f64."""
    a = dr.minimum(dr.abs(x), 1.0)
    p = 1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (
        -0.0501743046 + a * (0.0308918810 + a * (-0.0170881256 + a * (
            0.0066700901 - 0.0012624911 * a))))))
    r = dr.sqrt(1.0 - a) * p
    return dr.select(x < 0.0, math.pi - r, r)


class _Opaque:
    """A material's constants as opaque Dr.Jit scalars of one type (made on
    first use): kernel inputs rather than literals, so that materials of the
    same structure share compiled kernels."""

    def __init__(self, values, dtype):
        self.values, self.dtype, self.cache = values, dtype, {}

    def __getitem__(self, name):
        if name not in self.cache:
            self.cache[name] = dr.opaque(self.dtype, self.values[name])
        return self.cache[name]


def _finite_or_zero(x):
    return dr.select(dr.isfinite(x), x, 0.0)


def _c_of_ln(ln_c):
    """`bake::c_of_ln`: `e^ln C`, 0 below −104 or where not finite."""
    value = dr.exp(ln_c)
    return dr.select((ln_c > -104.0) & dr.isfinite(value), value, 0.0)


def _exp_and_one_minus_over(x, srs):
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


class _Channel:
    """One channel's constants (Python floats) and bakes (Dr.Jit arrays)."""

    def __init__(self, bakes):
        self.s = {k: float(v) for k, v in bakes.items() if not isinstance(v, np.ndarray)}
        self.shapes = {k: v.shape for k, v in bakes.items() if isinstance(v, np.ndarray)}
        self.t = {k: _upload(v) for k, v in bakes.items() if isinstance(v, np.ndarray)}
        s = self.s
        self.r_max = float(bakes["visible_rows"][-1])
        self.halo_u_top = float(bakes["halo_u"][-1])
        s["visible_r_max"] = self.r_max
        # The marginal's x̃ nodes −r_max … 0 … r_max and P2_tab there
        # (`VisibleSlopeBake::x_node`, `p_node`), and the last node's mass
        # and moment (`Φ` of the whole table), as constants.
        rows, p2 = bakes["visible_rows"], bakes["visible_p2"]
        self.t["visible_x"] = mi.Float64(np.concatenate([-rows[:0:-1], rows]))
        self.t["visible_px"] = mi.Float64(np.concatenate([p2[:0:-1], p2]))
        s["visible_mass_end"] = float(bakes["visible_mass"][-1])
        s["visible_moment_end"] = float(bakes["visible_moment"][-1])
        s["visible_h_end"] = float(rows[-1] - rows[-2])
        # Constants of the base layer (`TwoScale::base_value`; the albedo
        # and k_d are the plugin's parameters, `Model.params`).
        n = max(abs(s["eta_re"]), 1e-3)
        f_dr = s["f_dr_int"]
        s["base_inv_n_sq"] = 1.0 / (n * n)
        s["base_a_f"] = (1.0 - f_dr) / (1.0 + f_dr)
        self.f, self.d = _Opaque(s, mi.Float), _Opaque(s, mi.Float64)
        # ln C as overlapping packets: packet j holds nodes j … j + 3 of the
        # flattened grid (so that a Catmull–Rom row is one packet gather).
        ln_c = np.ascontiguousarray(bakes["conv_ln_c"], dtype=np.float32).ravel()
        ln_c = np.concatenate([ln_c, np.zeros(3, np.float32)])
        self.conv_quads = _upload(np.lib.stride_tricks.sliding_window_view(ln_c, 4))
        self.diffraction = s["sigma_s"] > 0.0 and s["b"] > 0.0
        if self.diffraction and s["conv_baked"] == 0.0:
            raise ValueError("twoscale: this material's C is not baked (source other than T3b)")
        self.specialise(bakes)

    def specialise(self, bakes):
        """What the traced code leaves out (Python-level branches, as
        Mitsuba's own plugins): the lobe weights' columns that are 0 at every
        node of `bakes` (any model's, stacked), the compensation lobe when
        its scale is 0."""
        weights = np.asarray(bakes["direction_weights"])
        self.weight_columns = [k for k in range(4) if np.any(weights[..., k] > 0.0)]
        self.has_multiple = bool(np.any(np.asarray(bakes["multiple_scale"]) != 0.0))

    def _node_row(self, i, n):
        """Row `i` of a per-wavelength table of `n` rows (:class:`_NodeChannel`
        offsets it to its lane's model); one channel's own row here."""
        return i

    # -- the 1-D bakes -------------------------------------------------
    def direction_cell(self, cos):
        n = self.shapes["direction_rows"][0]
        i, frac = _cell_at(dr.sqrt(dr.maximum(cos, 0.0)) * float(n - 1), n)
        return self._node_row(i, n), frac

    def direction(self, cell, columns):
        """The direction bake's `columns` at `cell`, linear between its rows
        (`DirectionBake::at_cell`), read as packets of four columns."""
        i, frac = cell
        out = []
        for half in sorted({k // 4 for k in columns}):
            a = _gather4(self.t["direction_rows"], 2 * i + half)
            b = _gather4(self.t["direction_rows"], 2 * i + 2 + half)
            out += [(k, dr.fma(frac, b[k % 4] - a[k % 4], a[k % 4]))
                    for k in columns if k // 4 == half]
        values = dict(out)
        return [values[k] for k in columns]

    def g1(self, r, z):
        """`MaskingBake::g1`."""
        n = self.shapes["masking_g1"][0]
        a_num = self.f["masking_beta"] * r
        y = a_num / (a_num + z)
        i, frac = _cell_at(y * float(n - 1), n)
        value = _lerp_gather(self.t["masking_g1"], 1, 0, i, frac)
        return dr.select(z > 0.0, value, 0.0)

    # -- C over (u, θh) ------------------------------------------------
    def conv(self, sin_h, cos_h, u):
        """`ConvBake::at`."""
        return _c_of_ln(self.ln_conv(sin_h, cos_h, u))

    def ln_conv(self, sin_h, cos_h, u):
        """`ConvBake::ln_at`."""
        s, f = self.s, self.f
        n_u, n_s = self.shapes["conv_ln_c"]
        nodes_u, nodes_s = n_u - 2, n_s - 2
        u = dr.minimum(dr.maximum(u, 0.0), f["conv_big_b"])
        sec_h = 1.0 / dr.maximum(cos_h, s["conv_cos_h_min"])
        tan_h = dr.minimum(dr.maximum(sin_h, 0.0), 1.0) * sec_h
        x_u = (_log2_axis(1.0 + u / s["conv_u0"]) + u * f["conv_u_linear"]) * f["conv_u_scale"]
        v = u + 0.5
        nv = f["conv_ndf_quarter_width"] * v
        inv_w = dr.sqrt(16.0 + v * v / (1.0 / 64.0 + nv * nv))
        x_h = sec_h + tan_h * inv_w
        span = _log2_axis((1.0 + inv_w) * float(np.float32(1.0 / s["conv_cos_h_min"])))
        x_s = _log2_axis(x_h) * (float(nodes_s - 1) / span)
        ju, tu = _cell_at(x_u, nodes_u)
        ju = self._node_row(ju, n_u)
        ks, ts = _cell_at(x_s, nodes_s)
        wu, ws = _catmull_rom_weights(tu), _catmull_rom_weights(ts)
        ln_c = mi.Float(0.0)
        for a in range(4):
            # The four nodes (ks … ks + 3) of row ju + a in one packet.
            quad = _gather4(self.conv_quads, (ju + a) * n_s + ks)
            inner = mi.Float(0.0)
            for b in range(4):
                inner += ws[b] * quad[b]
            ln_c += wu[a] * inner
        return ln_c

    # -- the sampler's densities ---------------------------------------
    def lobe_weights(self, cos_i):
        """`DirectionBake::lobe_weights`: `[specular, diffraction, base, multiple]`,
        sum 1 (f64)."""
        columns = self.weight_columns
        if columns in ([], [0]):
            # The specular lobe alone (or no lobe): weights [1, 0, 0, 0] everywhere.
            return [mi.Float64(1.0)] + [mi.Float64(0.0)] * 3
        i, frac = self.direction_cell(mi.Float(cos_i))
        a = _gather4(self.t["direction_weights"], i)
        b = _gather4(self.t["direction_weights"], i + 1)
        # Columns that are 0 at every node contribute exact zeros.
        w = [mi.Float64(dr.maximum(dr.fma(frac, b[k] - a[k], a[k]), 0.0)) if k in columns
             else mi.Float64(0.0) for k in range(4)]
        total = sum(w[k] for k in columns)
        ok = total > 0.0
        return [dr.select(ok, w[0] / total, 1.0)] + [
            dr.select(ok, w[k] / total, 0.0) if k in columns else w[k] for k in range(1, 4)]

    def diffraction_pdf(self, wi, wo, geo):
        """`TwoScale::diffraction_pdf` where C is baked (the plugin requires
        it): the half-vector draw's `HaloBake::pdf`, f64."""
        return dr.select(geo["cos_d"] > 0.0, self.halo_pdf(wi, geo["sin_h"], geo["cos_h"], wo.z), 0.0)

    def _row_cell(self, wi):
        """`HaloBake::row_cell` at `u = B cos θi`: the row below and the
        fraction `(u − u_j)/(u_j+1 − u_j)` (f64)."""
        n_u = self.shapes["halo_u"][0]
        u = dr.clip(self.d["big_b"] * wi.z, 0.0, self.halo_u_top)
        j = _last_at_most(
            n_u - 1,
            lambda j: dr.gather(mi.Float64, self.t["halo_u"], self._node_row(j, n_u)) <= u, 6)
        row = self._node_row(j, n_u)
        u0 = dr.gather(mi.Float64, self.t["halo_u"], row)
        inv_du = dr.gather(mi.Float64, self.t["halo_inv_du"], row)
        return row, dr.clip((u - u0) * inv_du, 0.0, 1.0)

    def _halo_zeta(self, row, k):
        n_s = self.shapes["halo_zeta"][1]
        return mi.Float64(dr.gather(mi.Float, self.t["halo_zeta"], row * n_s + k))

    def _halo_cum(self, row, k):
        n_s = self.shapes["halo_zeta"][1]
        return dr.gather(mi.Float64, self.t["halo_cum"], row * n_s + k)

    def _halo_coef(self, row, k):
        """`[start, slope]` of row `row`'s cell `k` (f64)."""
        n_s = self.shapes["halo_zeta"][1]
        c = dr.gather(mi.Vector2f, self.t["halo_coef"], row * n_s + k)
        return mi.Float64(c.x), mi.Float64(c.y)

    @staticmethod
    def _azimuth(sin_i, cos_i, sin_h, cos_h):
        """`halo::Azimuth::new`: `(H, [A₂, A₁, A₀], F(H))` of the azimuth law
        `∝ (i·h)(cos θo)₊` and whether it exists (f64); `F(H)` from
        `x = cos H` without a sine or cosine."""
        a, b = sin_i * sin_h, cos_i * cos_h
        kappa = cos_i / (2.0 * cos_h)
        wide = b - a >= kappa
        exists = (cos_h > 0.0) & (wide | (b + a > kappa))
        x = dr.clip((kappa - b) / a, -1.0, 1.0)
        big_h = dr.select(wide, math.pi, _acos_approx(x))
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

    def _row_pdf(self, row, z):
        """`HaloBake::row_pdf`: `(start_k + slope_k (ζ − ζ_k)) / M_j`."""
        n_s = self.shapes["halo_zeta"][1]
        k = _last_at_most(n_s - 1, lambda k: self._halo_zeta(row, k) <= z, 8)
        start, slope = self._halo_coef(row, k)
        d = start + slope * (z - self._halo_zeta(row, k))
        inv_total = dr.gather(mi.Float64, self.t["halo_inv_total"], row)
        ok = z <= self._halo_zeta(row, n_s - 1)
        return dr.select(ok, dr.maximum(d, 0.0) * inv_total, 0.0)

    def halo_pdf(self, wi, sin_h, cos_h, cos_o):
        """`HaloBake::pdf`: `Σ_j w_j p_j(ζ) cos θo / (4 N(θh))`, f64."""
        sin_i = dr.minimum(dr.sqrt(wi.x * wi.x + wi.y * wi.y), 1.0)
        _, _, half, exists = self._azimuth(sin_i, wi.z, sin_h, cos_h)
        zeta = sin_h * sin_h / (1.0 + cos_h)
        j, t = self._row_cell(wi)
        p = dr.select(t < 1.0, (1.0 - t) * self._row_pdf(j, zeta), 0.0)
        p += dr.select(t > 0.0, t * self._row_pdf(j + 1, zeta), 0.0)
        return dr.select(exists, p * dr.maximum(cos_o, 0.0) / (8.0 * half), 0.0)

    def halo_sample(self, wi, pick, along):
        """`HaloBake::sample_h`: a half-vector (f64) and whether the row had mass."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        n_s = self.shapes["halo_zeta"][1]
        j, t = self._row_cell(wi)
        lower = pick < 1.0 - t
        row = dr.select(lower, j, j + 1)
        azimuth = dr.select(lower, pick / (1.0 - t), (pick - (1.0 - t)) / t)
        azimuth = dr.clip(azimuth, 0.0, below_one)
        total = self._halo_cum(row, n_s - 1)
        target = along * total
        k = _last_at_most(n_s - 1, lambda k: self._halo_cum(row, k) <= target, 8)
        rest = dr.maximum(target - self._halo_cum(row, k), 0.0)
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
        h = mi.Vector3d(sin_h * (cos_phi_i * cp - sin_phi_i * sp),
                        sin_h * (sin_phi_i * cp + cos_phi_i * sp), cos_h)
        return h, (total > 0.0) & exists

    @staticmethod
    def _solve_azimuth(coef, big_h, half, target):
        """`Azimuth::solve`: Newton's method in a shrinking bracket (a
        symbolic loop, each lane until a step is ≤ `_NEWTON_TOL`, at most 40 steps)."""
        psi = dr.select(half > 0.0, big_h * dr.clip(target / half, 0.0, 1.0), 0.0)
        return _newton_in_bracket(
            lambda psi: _Channel._azimuth_cdf(coef, psi) - target,
            lambda psi: (coef[0] * dr.cos(psi) + coef[1]) * dr.cos(psi) + coef[2],
            psi, mi.Float64(big_h), _NEWTON_TOL)

    # -- the visible-slope sampler (`VisibleSlopeBake`) ------------------
    def _visible_node(self, name, k):
        return dr.gather(mi.Float64, self.t[name], k)

    def _visible_locate(self, a, name, scale):
        """`visible::locate`: the cell `[a0, a1]` of the nodes `name` that
        holds `a ≥ 0` (from its axis position, corrected by one node where
        the f32 axis and the f64 nodes disagree), its index and the fraction
        in it. The four nodes around the axis position are gathered at once,
        so the correction costs no second dependent gather."""
        n = self.shapes[name][0]
        position = _log2_axis(1.0 + mi.Float(a) * self.f["visible_inv_sigma"]) * scale
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

    def _visible_phi(self, c, sn, j):
        """`Φ` at x̃ node `j`: `c ∫P2_tab − s ∫x̃ P2_tab` from `−r_max`."""
        return (c * self._visible_node("visible_mass", j)
                - sn * self._visible_node("visible_moment", j))

    def _visible_incidence(self, wi):
        """`VisibleSlopeBake::incidence` of the unit `wi` (f64, `wi.z > 0`):
        the stretched incidence `c, s, |i'|`, its unit tangential direction,
        the last cell `j_end` the visible marginal reaches, the visible
        length `τ_end` of it and `N_tab`."""
        beta, r_max = self.d["visible_beta"], self.d["visible_r_max"]
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
        phi_end = c * self.d["visible_mass_end"] - sn * self.d["visible_moment_end"]
        j_end = dr.select(reaches, j_mu, mi.UInt32(2 * rows_n - 3))
        tau_end = dr.select(reaches, mu - x0, self.d["visible_h_end"])
        norm = dr.select(reaches, self._visible_phi(c, sn, j_mu)
                         + self._visible_cell_integral(c, sn, x0, p0, k, mu - x0), phi_end)
        return types.SimpleNamespace(c=c, sn=sn, length=length, t0=t0, t1=t1, j_end=j_end,
                                     tau_end=tau_end, norm=norm)

    def visible_pdf(self, wi, wo):
        """`VisibleSlopeBake::pdf`: the specular lobe's solid-angle density, f64."""
        beta, r_max = self.d["visible_beta"], self.d["visible_r_max"]
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
            d0 = mi.Float64(dr.gather(mi.Float, self.t["visible_dens"], i * cols_n + k))
            d1 = mi.Float64(dr.gather(mi.Float, self.t["visible_dens"], (i + 1) * cols_n + k))
            return d0 + lam * (d1 - d0)

        p2 = blend("visible_p2", i, i + 1)
        kk, tt, _, _ = self._visible_locate(dr.abs(y), "visible_cols", self.f["visible_col_scale"])
        g0, g1 = dens(kk), dens(kk + 1)
        total = blend("visible_cum", i * cols_n + cols_n - 1, (i + 1) * cols_n + cols_n - 1)
        g = (g0 + tt * (g1 - g0)) / total
        # 1/cos⁴θh = (1 + |slope|²)² with the unstretched slope β (sx, sy).
        slope_sq = beta * beta * (sx * sx + sy * sy)
        sec4 = (1.0 + slope_sq) * (1.0 + slope_sq)
        value = p2 * g * sec4 / (8.0 * inc.norm * beta * beta * inc.length)
        return dr.select(valid, value, 0.0)

    def visible_sample(self, wi, u0, u1):
        """`VisibleSlopeBake::sample`: a visible EPD normal for the unit `wi`
        (f64) from two uniforms, and whether the tables gave mass."""
        beta = self.d["visible_beta"]
        cols_n = self.shapes["visible_cols"][0]
        x_nodes = self.shapes["visible_mass"][0]
        inc = self._visible_incidence(wi)
        c, sn = inc.c, inc.sn
        target = u0 * inc.norm
        # The last node j ≤ j_end with Φ_j ≤ target (Φ_0 = 0).
        j = _last_at_most(inc.j_end + 1, lambda j: self._visible_phi(c, sn, j) <= target,
                          (x_nodes - 2).bit_length())
        x0, p0 = self._visible_node("visible_x", j), self._visible_node("visible_px", j)
        x1 = self._visible_node("visible_x", j + 1)
        h = x1 - x0
        k = (self._visible_node("visible_px", j + 1) - p0) / h
        tau_max = dr.select(j == inc.j_end, inc.tau_end, h)
        rest = target - self._visible_phi(c, sn, j)
        x = x0 + self._solve_cell(c, sn, x0, p0, k, tau_max, rest)
        # The conditional at |x̃|: its row is the cell j itself, mirrored
        # where x̃ < 0 (`VisibleSlopeBake::row` of |x̃|, but without locating).
        rows_n = self.shapes["visible_rows"][0]
        negative = j < rows_n - 1
        i = dr.select(negative, rows_n - 2 - j, j - (rows_n - 1))
        a0, a1 = dr.select(negative, -x1, x0), dr.select(negative, -x0, x1)
        lam = dr.clip((dr.abs(x) - a0) / (a1 - a0), 0.0, 1.0)

        def cum(col):
            a0 = self._visible_node("visible_cum", i * cols_n + col)
            return a0 + lam * (self._visible_node("visible_cum", (i + 1) * cols_n + col) - a0)

        def dens(col):
            d0 = mi.Float64(dr.gather(mi.Float, self.t["visible_dens"], i * cols_n + col))
            d1 = mi.Float64(dr.gather(mi.Float, self.t["visible_dens"], (i + 1) * cols_n + col))
            return d0 + lam * (d1 - d0)

        signed = 2.0 * u1 - 1.0
        q = dr.abs(signed) * cum(cols_n - 1)
        kk = _last_at_most(cols_n - 1, lambda kc: cum(kc) <= q, (cols_n - 2).bit_length())
        y0 = self._visible_node("visible_cols", kk)
        w = self._visible_node("visible_cols", kk + 1) - y0
        g0, g1 = dens(kk), dens(kk + 1)
        r = dr.maximum(q - cum(kk), 0.0)
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
        return mi.Vector3d(-sx * inv, -sy * inv, inv), inc.norm > 0.0

    @staticmethod
    def _solve_cell(c, sn, x0, p0, k, tau_max, rest):
        """`visible::solve_cell`: Newton's method in a shrinking bracket (a
        symbolic loop, each lane until a step, or Newton's predicted error
        after it, is ≤ `_NEWTON_TOL` of the cell's scale, at most 40 steps)."""
        a = c - sn * x0

        def density(t):
            return (a - sn * t) * (p0 + k * t)

        # Start from the root without the cubic term: f0 t + b t²/2 = rest.
        f0 = density(0.0 * a)
        b = a * k - sn * p0
        disc = f0 * f0 + 2.0 * b * rest
        denom = f0 + dr.sqrt(dr.maximum(disc, 0.0))
        t = dr.select(denom > 0.0, dr.clip(2.0 * rest / denom, 0.0, tau_max), 0.5 * tau_max)
        tol = _NEWTON_TOL * (dr.abs(x0) + tau_max)
        return _newton_in_bracket(
            lambda t: _Channel._visible_cell_integral(c, sn, x0, p0, k, t) - rest, density,
            t, mi.Float64(tau_max), tol, lambda t: k * (a - sn * t) - sn * (p0 + k * t))

    def diffraction_sample(self, wi, u0, u1):
        """The diffraction lobe's direction where C is baked
        (`TwoScale::sample_diffraction`: a reflected half-vector of
        `halo_sample`) and whether it exists (f64)."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        m, ok = self.halo_sample(wi, dr.minimum(u1, below_one), u0)
        k = 2.0 * dr.dot(wi, m)
        return k * m - wi, ok & (k > 0.0)

    # -- the model -----------------------------------------------------
    def q_bar(self, fi, fo, along, across):
        """`QConstants::combine` (Q̄ from the factors `[a, Re U, Im U, Re W, Im W]`
        at θi and θo and the pair's `along = −(wi·wo)ₜ`, `across`), f32."""
        s = self.s
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
        if s["white"] != 0.0 or s["base"] == 0.0:
            return lambertian
        alpha = params["albedo"]
        t = (1.0 - f_i) * (1.0 - f_o)
        if s["base"] == 1.0:
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
        at_i = self.direction(self.direction_cell(cos_i), range(8))
        at_o = self.direction(self.direction_cell(cos_o), range(8))
        # A_spec and (1 − A)/σrel² from one exponential.
        if s["sigma_s"] > 0.0:
            r_i, r_o = at_i[5], at_o[5]
            ratio_sq = 0.5 * (r_i * r_i + r_o * r_o) if s["symmetrised"] else r_i * r_i
            sigma_rel_sq = f["sigma_s_sq"] * ratio_sq
        else:
            sigma_rel_sq = mi.Float(0.0)
        a_spec, one_minus_a_over = _exp_and_one_minus_over(f["x_scale"] * pair["cos_d_sq"],
                                                           sigma_rel_sq)
        fresnel_d = (mi.Float(1.0) if s["white"] else
                     self.direction(self.direction_cell(cos_d), [6])[0])
        specular = a_spec * fresnel_d * pair["rho_geo"]

        if self.diffraction:
            if s["white"]:
                q = mi.Float(1.0)
            elif s["has_q"]:
                q = dr.maximum(self.q_bar(at_i[:5], at_o[:5], pair["along"], pair["across"]), 0.0)
            else:
                q = mi.Float(0.0)
            if s["halo_incident"]:
                one_minus_a_over = _exp_and_one_minus_over(f["x_scale"] * cos_i * cos_i,
                                                           sigma_rel_sq)[1]
            if c_value is None:
                c_value = dr.maximum(self.conv(pair["sin_h"], pair["cos_h"], f["big_b"] * cos_d),
                                     0.0)
            g = pair["g"]
            diffraction = dr.select(g > 0.0, (q * g) * (f["halo_scale"] * one_minus_a_over)
                                    * c_value, 0.0) * params["halo_factor"]
        else:
            diffraction = mi.Float(0.0)
        base = self.base_value(at_i[6], at_o[6], cos_i, cos_o, params)
        # ρ_ms = F_ms (1 − E_s(μi)) (1 − E_s(μo)) / (π (1 − E_avg)), docs/model.md §2.11.
        multiple = (f["multiple_scale"] * at_i[7] * at_o[7] if self.has_multiple
                    else mi.Float(0.0))
        return (_finite_or_zero(specular), _finite_or_zero(diffraction), _finite_or_zero(base),
                _finite_or_zero(multiple))

    def node_terms(self, pair, params):
        """`spectral::NodeTerms::new`: (σrel²/σs², Q̄, F(θd), ρ_base + k_d/π
        + ρ_ms) of this model at a pair (:meth:`Model.pair`'s terms), f32."""
        s, f = self.s, self.f
        at_i = self.direction(self.direction_cell(pair["cos_i"]), range(8))
        at_o = self.direction(self.direction_cell(pair["cos_o"]), range(8))
        r_i, r_o = at_i[5], at_o[5]
        ratio_sq = 0.5 * (r_i * r_i + r_o * r_o) if s["symmetrised"] else r_i * r_i
        if s["white"]:
            q, fresnel_d = mi.Float(1.0), mi.Float(1.0)
        else:
            q = (dr.maximum(self.q_bar(at_i[:5], at_o[:5], pair["along"], pair["across"]), 0.0)
                 if s["has_q"] else mi.Float(0.0))
            fresnel_d = self.direction(self.direction_cell(pair["cos_d"]), [6])[0]
        base = self.base_value(at_i[6], at_o[6], pair["cos_i"], pair["cos_o"], params)
        multiple = (f["multiple_scale"] * at_i[7] * at_o[7] if self.has_multiple
                    else mi.Float(0.0))
        plain = _finite_or_zero(base) + _finite_or_zero(multiple)
        return ratio_sq, q, fresnel_d, plain


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
        self.channels = [_Channel(b) for b in bakes]
        first = self.channels[0].s
        self.p = dr.opaque(mi.Float, first["p"])
        self.epd_norm = dr.opaque(mi.Float, first["epd_norm"])
        self.epd_inv_beta_sq = dr.opaque(mi.Float, first["epd_inv_beta_sq"])
        self.height_correlated = first["height_correlated"] != 0.0
        self.channels_have_diffraction = any(ch.diffraction for ch in self.channels)
        self.diffraction_stack = _diffraction_stack(self.channels, bakes)

    def d(self, h):
        """`Epd::d`: `norm e^−(tan²θ/β²)^p / cos⁴θ`."""
        cos_sq = h.z * h.z
        inv_cos4 = 1.0 / (cos_sq * cos_sq)
        tan_sq = (h.x * h.x + h.y * h.y) / cos_sq
        y = dr.power(tan_sq * self.epd_inv_beta_sq, self.p)
        value = self.epd_norm * inv_cos4 * dr.exp(-y)
        return dr.select((h.z > 0.0) & (y < 104.0) & dr.isfinite(value), value, 0.0)

    def geometry(self, wi, wo):
        """The pair's geometry and D(h) (as `TwoScale::geometry`: directions
        and h in f64, D of h rounded to f32), and whether both directions
        are above the horizon."""
        wi, wo = mi.Vector3f(wi), mi.Vector3f(wo)
        valid = dr.all(dr.isfinite(wi)) & dr.all(dr.isfinite(wo))
        wi, wo = dr.normalize(mi.Vector3d(wi)), dr.normalize(mi.Vector3d(wo))
        valid &= (wi.z > 0.0) & (wo.z > 0.0)
        h = dr.normalize(wi + wo)
        return valid, {
            "wi": wi,
            "wo": wo,
            "cos_d": dr.clip(dr.dot(wi, h), 0.0, 1.0),
            "cos_h": dr.clip(h.z, 0.0, 1.0),
            "sin_h": dr.minimum(dr.sqrt(h.x * h.x + h.y * h.y), 1.0),
            "d": self.d(mi.Vector3f(h)),
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
        cos_i, cos_o, cos_d = mi.Float(geo["wi"].z), mi.Float(geo["wo"].z), mi.Float(geo["cos_d"])
        g = self.masking(geo)
        return {
            "cos_i": cos_i, "cos_o": cos_o, "cos_d": cos_d, "cos_d_sq": cos_d * cos_d,
            "g": g, "rho_geo": g * geo["d"] / (4.0 * cos_i * cos_o),
            "sin_h": mi.Float(geo["sin_h"]), "cos_h": mi.Float(geo["cos_h"]),
            "along": mi.Float(geo["along"]), "across": mi.Float(geo["across"]),
        }

    def eval(self, wi, wo):
        """ρ(wi, wo) per channel (sr⁻¹) as an ``mi.Color3f``: ``wi`` towards the
        light, ``wo`` towards the viewer (``Material.eval``'s convention); 0
        below the horizon."""
        valid, geo = self.geometry(wi, wo)
        pair = self.pair(geo)
        values = []
        for channel in self.channels:
            spec, diff, base, multiple = channel.lobes(pair, self.params)
            values.append(_finite_or_zero((spec + diff) + (base + multiple)))
        return dr.select(valid, mi.Color3f(*values), 0.0)

    def pdf(self, wi, wo):
        """`Material.pdf(wi, wo)` (``Rgb::pdf``): the mean over the channels of
        `Σ_k w_k(wi) pdf_k(wi, wo)`, as an ``mi.Float``; 0 below the horizon."""
        valid, geo = self.geometry(wi, wo)
        wi, wo = geo["wi"], geo["wo"]
        specular = self.channels[0].visible_pdf(wi, wo)
        base = wo.z / math.pi
        total = mi.Float64(0.0)
        for channel in self.channels:
            w = channel.lobe_weights(wi.z)
            value = dr.select(w[0] > 0.0, w[0] * specular, 0.0)
            if channel.diffraction:
                value += dr.select(w[1] > 0.0, w[1] * channel.diffraction_pdf(wi, wo, geo), 0.0)
            # The base and the compensation lobe share the cosine-weighted density.
            value += dr.select(w[2] + w[3] > 0.0, (w[2] + w[3]) * base, 0.0)
            total += mi.Float64(_finite_or_zero(mi.Float(value)))
        return dr.select(valid, _finite_or_zero(mi.Float(total / 3.0)), 0.0)

    def sample_direction(self, wi, u):
        """``Rgb::sample``'s direction for incidence `wi` and three uniforms
        `u` (an ``mi.Vector3f``): a channel picked with `u[0]`, its lobe with
        the rescaled `u[0]`, the lobe's direction from `u[1], u[2]`. Returns
        the direction (``mi.Vector3f``) and whether one was drawn."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        wi_f = mi.Vector3f(wi)
        valid = dr.all(dr.isfinite(wi_f))
        wi = dr.normalize(mi.Vector3d(wi_f))
        valid &= wi.z > 0.0
        pick = 3.0 * mi.Float64(dr.clip(u.x, 0.0, below_one))
        k = dr.minimum(mi.UInt32(pick), 2)
        rest = mi.Float(pick - mi.Float64(k))
        lobe_pick = mi.Float64(dr.clip(rest, 0.0, below_one))
        u1 = mi.Float64(dr.clip(u.y, 0.0, below_one))
        u2 = mi.Float64(dr.clip(u.z, 0.0, below_one))
        # The picked channel's lobe weights.
        weights = [ch.lobe_weights(wi.z) for ch in self.channels]
        w = [dr.select(k == 0, weights[0][n], dr.select(k == 1, weights[1][n], weights[2][n]))
             for n in range(4)]
        return _draw(self, [k == n for n in range(len(self.channels))], w, lobe_pick,
                     wi, u1, u2, valid)


def _draw(model, selected, w, pick, wi, u1, u2, valid):
    """`pick_lobe` of the weights `w` with `pick`, then `TwoScale::sample_lobe`'s
    direction from `u1, u2`: a visible normal of the shared specular bake, the
    diffraction law of the channel (model) where `selected[n]`, the cosine lobe
    for the base and the compensation lobe. Returns the direction
    (``mi.Vector3f``, `upper_unit(to_f32(o))`) and whether one was drawn."""
    cumulative, last, chosen = mi.Float64(0.0), mi.UInt32(0), mi.Int32(-1)
    for n in range(4):
        positive = w[n] > 0.0
        cumulative += dr.select(positive, w[n], 0.0)
        last = dr.select(positive, n, last)
        chosen = dr.select((chosen < 0) & positive & (pick < cumulative), n, chosen)
    lobe = dr.select(chosen < 0, last, mi.UInt32(chosen))
    m, ok = model.channels[0].visible_sample(wi, u1, u2)
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
        ob = mi.Vector3d(r * dr.cos(phi), r * dr.sin(phi), dr.sqrt(dr.maximum(1.0 - u1, 0.0)))
        o = dr.select(lobe >= 2, ob, o)
        ok = dr.select(lobe >= 2, True, ok)
    ok &= ~((lobe == 1) & ~model.channels_have_diffraction)
    o = mi.Vector3f(dr.normalize(mi.Vector3d(mi.Vector3f(o))))
    ok &= valid & (o.z > 0.0) & dr.all(dr.isfinite(o))
    return o, ok


class _NodeScalars:
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


class _NodeChannel(_Channel):
    """The 19 models of ``Material.spectral_bakes()`` as one channel: each
    quantity that differs between the models (``per_node``) uploaded once,
    stacked along a node axis; :meth:`at` gives the channel of a per-lane
    model `k` (its rows offset by `k` models, its scalars gathered at `k`),
    so that a lane reads the models it needs and no other."""

    # Read as Python floats (branches, literals), by `Model` from model 0
    # (D, G) or from the shared tables: one value for every model.
    SHARED = {"sigma_s", "b", "white", "has_q", "symmetrised", "halo_incident", "base",
              "conv_baked", "height_correlated", "conv_u0",
              "conv_cos_h_min", "masking_beta", "masking_g1", "beta", "p", "epd_norm",
              "epd_inv_beta_sq"}

    # The tables read through `_node_row`: stacked even where the models agree.
    ROWS = ("direction_rows", "direction_weights", "conv_ln_c", "radial_inv_m", "halo_u",
            "halo_inv_du", "halo_inv_total", "halo_zeta", "halo_coef", "halo_cum")

    def __init__(self, models, per_node, count):
        clash = sorted(n for n in per_node if n in self.SHARED or n.startswith("visible_"))
        if clash:
            raise ValueError(f"twoscale: the spectral models differ in {clash}")
        super().__init__({k: (v[0] if k in per_node else v) for k, v in models.items()})
        self.specialise(models)
        stacked = {k: models[k] for k in per_node}
        stacked.update({k: np.stack([models[k]] * count) for k in self.ROWS if k not in per_node})
        arrays = {k: v for k, v in stacked.items() if np.ndim(v) > 1}
        for name, v in arrays.items():
            self.t[name] = _upload(v)
        # As `_Channel`'s packets, over the stacked grids (a packet never
        # crosses a row, so never a model).
        ln_c = np.ascontiguousarray(arrays["conv_ln_c"], dtype=np.float32).ravel()
        ln_c = np.concatenate([ln_c, np.zeros(3, np.float32)])
        self.conv_quads = _upload(np.lib.stride_tricks.sliding_window_view(ln_c, 4))
        scalars = {k: np.asarray(v, np.float64) for k, v in stacked.items() if k not in arrays}
        if "eta_re" in scalars or "f_dr_int" in scalars:
            # The base layer's constants per model (as `_Channel`'s).
            n = np.maximum(np.abs(np.broadcast_to(models["eta_re"], count)), 1e-3)
            f_dr = np.broadcast_to(models["f_dr_int"], count).astype(np.float64)
            scalars["base_inv_n_sq"] = 1.0 / (n * n)
            scalars["base_a_f"] = (1.0 - f_dr) / (1.0 + f_dr)
        self.node_f = {k: mi.Float(v) for k, v in scalars.items()}
        self.node_d = {k: mi.Float64(v) for k, v in scalars.items()}
        self.halo_u_nodes = self.shapes["halo_u"][0]

    def at(self, k):
        """This stack at the per-lane model `k` (``mi.UInt32``)."""
        view = copy.copy(self)
        view.k = k
        view.f = _NodeScalars(self.f, self.node_f, mi.Float, k)
        view.d = _NodeScalars(self.d, self.node_d, mi.Float64, k)
        n_u = self.halo_u_nodes
        view.halo_u_top = dr.gather(mi.Float64, self.t["halo_u"], view._node_row(n_u - 1, n_u))
        return view

    def _node_row(self, i, n):
        return i + self.k * n


def _diffraction_stack(channels, bakes):
    """The channels' bakes as one :class:`_NodeChannel` (channel `k` at a
    lane's `k`), so that `_draw` runs one diffraction draw per lane, from its
    own channel, rather than one per channel; None with fewer than two
    channels, one without the lobe, or channels that differ in what
    `_NodeChannel` shares."""
    if len(channels) < 2 or not all(ch.diffraction for ch in channels):
        return None
    per_node = [k for k, v in bakes[0].items()
                if any(not np.array_equal(v, b[k]) for b in bakes[1:])]
    models = {k: (np.stack([b[k] for b in bakes]) if k in per_node else v)
              for k, v in bakes[0].items()}
    try:
        return _NodeChannel(models, per_node, len(bakes))
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
    stacked bakes, :class:`_NodeChannel`; C the lower one's only); ``pdf``
    and ``sample`` read the nearest model only."""

    def __init__(self, material: twoscale.Material, params=None):
        spectral = material.spectral_bakes()
        models, per_node = spectral["models"], set(spectral["per_node"])
        # The shared surface (geometry, G, the visible-slope sampler): model 0's.
        first = {k: (v[0] if k in per_node else v) for k, v in models.items()}
        super().__init__(material, params, [first])
        self.stack = _NodeChannel(models, per_node, len(spectral["wavelengths"]))
        self.nodes = [float(np.float32(x)) for x in spectral["wavelengths"]]
        self.node_table = mi.Float(spectral["wavelengths"])
        self.fresnel = _upload(np.asarray(spectral["fresnel"], np.float32))
        self.fresnel_shape = spectral["fresnel"].shape
        self.eta_first = float(np.float32(spectral["eta_first"]))
        self.eta_step = float(np.float32(spectral["eta_step"]))
        self.white = spectral["white"] != 0.0

    def clamped(self, lam):
        """λ (µm, f32) clamped to the models' range (NaN → the first)."""
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
        m, g = _cell_at((mi.Float(i) + frac) * (1.0 / ((n - 1) // (cols - 1))), cols)

        def row(r):
            a = dr.gather(mi.Float, self.fresnel, r * cols + m)
            b = dr.gather(mi.Float, self.fresnel, r * cols + m + 1)
            return a + g * (b - a)

        low, high = row(j), row(j + 1)
        return low + f * (high - low)

    def eval_spectral(self, wi, wo, lams):
        """ρ(wi, wo) at each wavelength of `lams` (µm; a sequence of
        ``mi.Float``), as a list of ``mi.Float`` (``Spectral::eval4``):
        each model's terms at the pair (:meth:`_Channel.node_terms`), then
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
            a_spec, one_minus_a_over = _exp_and_one_minus_over(x_scale * pair["cos_d_sq"],
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
                if s["halo_incident"]:
                    one_minus_a_over = _exp_and_one_minus_over(x_scale * cos_i * cos_i,
                                                               sigma_rel_sq)[1]
                halo = lower.f["halo_scale"] * ratio_sq * one_minus_a_over
                # C from the lower model's bake only, at u = b cos θd/λ.
                c_value = lower.conv(pair["sin_h"], pair["cos_h"], lower.f["big_b"] * ratio * cos_d)
                diffraction = dr.select(
                    g > 0.0, (q * g) * halo * dr.maximum(c_value, 0.0), 0.0
                ) * self.params["halo_factor"]
            else:
                diffraction = mi.Float(0.0)
            value = _finite_or_zero(specular) + _finite_or_zero(diffraction) + lerp(3)
            out.append(dr.select(valid, _finite_or_zero(dr.maximum(value, 0.0)), 0.0))
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
        specular = self.channels[0].visible_pdf(wi, wo)
        base = wo.z / math.pi
        w = node.lobe_weights(wi.z)
        value = dr.select(w[0] > 0.0, w[0] * specular, 0.0)
        if node.diffraction:
            value += dr.select(w[1] > 0.0, w[1] * node.diffraction_pdf(wi, wo, geo), 0.0)
        value += dr.select(w[2] + w[3] > 0.0, (w[2] + w[3]) * base, 0.0)
        return dr.select(valid, _finite_or_zero(mi.Float(value)), 0.0)

    def sample_spectral(self, wi, u, lam):
        """`Spectral::sample`'s direction: `TwoScale::sample_direction` of
        the sampler model nearest λ (the lobe picked with `u[0]`, its direction
        from `u[1], u[2]`). Returns the direction and whether one was drawn."""
        below_one = float(np.float32(1.0) - np.finfo(np.float32).eps / np.float32(2.0))
        wi_f = mi.Vector3f(wi)
        valid = dr.all(dr.isfinite(wi_f))
        wi = dr.normalize(mi.Vector3d(wi_f))
        valid &= wi.z > 0.0
        node = self.stack.at(self.nearest(lam))
        pick = mi.Float64(dr.clip(u.x, 0.0, below_one))
        u1 = mi.Float64(dr.clip(u.y, 0.0, below_one))
        u2 = mi.Float64(dr.clip(u.z, 0.0, below_one))
        # The nearest model as the one channel `_draw` reads (the visible
        # slopes are shared by the models).
        one = types.SimpleNamespace(channels=[node],
                                    channels_have_diffraction=self.channels_have_diffraction)
        return _draw(one, [mi.Bool(True)], node.lobe_weights(wi.z), pick, wi, u1, u2, valid)


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
        self.nodes = [shared[k] if k in shared else _Channel(b) for k, b in enumerate(models)]
        self.colour_nodes = integrated["surface"].shape[0]
        # R_kc a row per node of `√cos θd`, padded to whole packets of four.
        surface = np.asarray(integrated["surface"], np.float32).reshape(self.colour_nodes, -1)
        self.surface_packets = -(-surface.shape[1] // 4)
        self.surface = _upload(np.pad(surface, ((0, 0), (0, 4 * self.surface_packets
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
        a = [v for j in range(packets) for v in _gather4(self.surface, m * packets + j)]
        b = [v for j in range(packets) for v in _gather4(self.surface, (m + 1) * packets + j)]
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
            values.append(_c_of_ln(x))
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
        values = [_finite_or_zero(dr.maximum(x, 0.0)) for x in out]
        return dr.select(valid, mi.Color3f(*values), 0.0)


def rgb_model(material: twoscale.Material, params=None):
    """The Dr.Jit model of `material`'s RGB (its ``rgb_mode``):
    :class:`IntegratedModel` or :class:`Model` (the paper's wavelengths)."""
    if material.rgb_mode == "integrated":
        return IntegratedModel(material, params)
    return Model(material, params)


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
