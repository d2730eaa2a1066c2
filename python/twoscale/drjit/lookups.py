"""The bake lookups (runtime/src/bake/: `cell_at`, `DirectionBake`,
`MaskingBake`, `ConvBake`) in Dr.Jit, and :class:`Bakes`, a channel's
constants and bakes uploaded once (the names are the bake schema's,
``twoscale.Material.bakes()``)."""

import drjit as dr
import mitsuba as mi
import numpy as np

from .math import log2_axis


#: The lobes in the order of the port's weight lists and lobe numbers
#: (`brdf::Lobe`'s): each the name of a `direction_weights` column.
LOBES = ("specular", "diffraction", "base", "multiple")

#: Q̄'s factors (`QFactors`): `direction_rows` columns.
Q_FACTORS = ("q_a", "q_u_re", "q_u_im", "q_w_re", "q_w_im")


def cell_at(t, n):
    """`bake::cell_at`: the cell `i ∈ [0, n − 2]` and fraction of position `t ≥ 0`."""
    t = dr.minimum(dr.maximum(t, 0.0), float(n - 1))
    i = dr.clip(mi.Int32(dr.floor(t)), 0, n - 2)
    return mi.UInt32(i), t - mi.Float(i)


def lerp_gather(table, width, column, i, frac):
    """Linear interpolation of column `column` of a row-major table of `width`."""
    a = dr.gather(mi.Float, table, i * width + column)
    b = dr.gather(mi.Float, table, (i + 1) * width + column)
    return dr.fma(frac, b - a, a)


def sampler_tables(bakes):
    """`bakes` with the samplers' cumulative tables in the form the f32
    draws read (computed in f64, then rounded once): ``halo_cum`` and
    ``visible_cum`` (and the visible marginal's ``visible_mass``,
    ``visible_moment``) as `[cum, total − cum]` along their last axis, so
    that a draw with `u ≥ ½` measures its rest from the end (`(total −
    cum_k) − (1 − u) total`, small numbers near the end): the difference it
    takes has the f32 rounding of the mass beyond the cell, not of the
    total."""
    out = dict(bakes)
    for name in ("halo_cum", "visible_cum", "visible_mass", "visible_moment"):
        cum = np.asarray(bakes[name], np.float64)
        out[name] = np.concatenate([cum, cum[..., -1:] - cum], axis=-1)
    # `Φ` of the whole table, and from the last cell's left node to the end.
    mass, moment = np.asarray(bakes["visible_mass"]), np.asarray(bakes["visible_moment"])
    out["visible_mass_end"], out["visible_moment_end"] = float(mass[-1]), float(moment[-1])
    out["visible_mass_last"] = float(mass[-1] - mass[-2])
    out["visible_moment_last"] = float(moment[-1] - moment[-2])
    return out


def upload(values):
    """A bake as an f32 Dr.Jit array (``mi.Float``; f64 tables rounded once)
    over a copy of `values` aligned to 64 bytes. Dr.Jit maps a NumPy
    array's memory rather than copying it, and gathers a packet
    (:func:`gather4`) as one load only from an aligned table: elsewhere it
    falls back to four gathers."""
    values = np.ascontiguousarray(values, dtype=np.float32).ravel()
    buf = np.empty(values.nbytes + 64, np.uint8)
    start = -buf.ctypes.data % 64
    out = buf[start:start + values.nbytes].view(values.dtype)
    out[:] = values
    return mi.Float(out)


def gather4(table, k):
    """Floats `4k … 4k + 3` of `table`, one packet gather."""
    return dr.gather(mi.Vector4f, table, k)


def catmull_rom_weights(t):
    """`convolution::catmull_rom_weights`."""
    t2 = t * t
    t3 = t2 * t
    return (
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    )


class Opaque:
    """A material's constants as opaque Dr.Jit scalars of one type (made on
    first use): kernel inputs rather than literals, so that materials of the
    same structure share compiled kernels."""

    def __init__(self, values, dtype):
        self.values, self.dtype, self.cache = values, dtype, {}

    def __getitem__(self, name):
        if name not in self.cache:
            self.cache[name] = dr.opaque(self.dtype, self.values[name])
        return self.cache[name]


def c_of_ln(ln_c):
    """`bake::c_of_ln`: `e^ln C`, 0 below −104 or where not finite."""
    value = dr.exp(ln_c)
    return dr.select((ln_c > -104.0) & dr.isfinite(value), value, 0.0)


class Bakes:
    """One channel's constants (Python floats, and the names of the base
    layer's kind and the options), bakes (Dr.Jit arrays) and the bakes'
    columns by name (``columns``: array name → column name → index)."""

    def __init__(self, bakes):
        bakes = sampler_tables(bakes)
        self.columns = {name: {c: k for k, c in enumerate(names)}
                        for name, names in bakes["columns"].items()}
        self.s = {k: (v if isinstance(v, str) else float(v)) for k, v in bakes.items()
                  if not isinstance(v, (np.ndarray, dict))}
        self.shapes = {k: v.shape for k, v in bakes.items() if isinstance(v, np.ndarray)}
        self.t = {k: upload(v) for k, v in bakes.items() if isinstance(v, np.ndarray)}
        s = self.s
        self.r_max = float(bakes["visible_rows"][-1])
        self.halo_u_top = float(bakes["halo_u"][-1])
        s["visible_r_max"] = self.r_max
        # The marginal's x̃ nodes −r_max … 0 … r_max and P2_tab there
        # (`VisibleSlopeBake::x_node`, `p_node`).
        rows, p2 = bakes["visible_rows"], bakes["visible_p2"]
        self.t["visible_x"] = upload(np.concatenate([-rows[:0:-1], rows]))
        self.t["visible_px"] = upload(np.concatenate([p2[:0:-1], p2]))
        s["visible_h_end"] = float(rows[-1] - rows[-2])
        # Constants of the base layer (`TwoScale::base_value`; the albedo
        # and k_d are the plugin's parameters, `Model.params`).
        n = max(abs(s["eta_re"]), 1e-3)
        f_dr = s["f_dr_int"]
        s["base_inv_n_sq"] = 1.0 / (n * n)
        s["base_a_f"] = (1.0 - f_dr) / (1.0 + f_dr)
        # f32 constants (the samplers' too: visible.py, halo.py).
        self.f = Opaque(s, mi.Float)
        # ln C as overlapping packets: packet j holds nodes j … j + 3 of the
        # flattened grid (so that a Catmull–Rom row is one packet gather).
        ln_c = np.ascontiguousarray(bakes["conv_ln_c"], dtype=np.float32).ravel()
        ln_c = np.concatenate([ln_c, np.zeros(3, np.float32)])
        self.conv_quads = upload(np.lib.stride_tricks.sliding_window_view(ln_c, 4))
        self.diffraction = s["sigma_s"] > 0.0 and s["b"] > 0.0
        if self.diffraction and s["conv_baked"] == 0.0:
            raise ValueError("twoscale: this material's C is not baked (source other than T3b)")
        self.specialise(bakes)

    def specialise(self, bakes):
        """What the traced code leaves out (Python-level branches, as
        Mitsuba's own plugins): the lobes (numbers in :data:`LOBES`) whose
        weight is 0 at every node of `bakes` (any model's, stacked), the
        compensation lobe when its scale is 0."""
        weights = np.asarray(bakes["direction_weights"])
        self.weight_index = [self.columns["direction_weights"][name] for name in LOBES]
        self.weight_columns = [n for n, k in enumerate(self.weight_index)
                               if np.any(weights[..., k] > 0.0)]
        self.has_multiple = bool(np.any(np.asarray(bakes["multiple_scale"]) != 0.0))

    def _node_row(self, i, n):
        """Row `i` of a per-wavelength table of `n` rows (:class:`NodeChannel`
        offsets it to its lane's model); one channel's own row here."""
        return i

    # -- the 1-D bakes -------------------------------------------------
    def direction_cell(self, cos):
        """`DirectionCell::new`: the row and fraction of `cos θ` (clamped to [0, 1])."""
        n = self.shapes["direction_rows"][0]
        i, frac = cell_at(dr.sqrt(dr.maximum(cos, 0.0)) * float(n - 1), n)
        return self._node_row(i, n), frac

    def direction_values(self, cos):
        """`DirectionBake::at`: the row at `cos θ`, a dict by column name."""
        names = list(self.columns["direction_rows"])
        values = self.direction(self.direction_cell(cos), [self.columns["direction_rows"][n]
                                                           for n in names])
        return dict(zip(names, values))

    def direction_fresnel(self, cos):
        """`DirectionBake::fresnel_at`: F at `cos θ` alone."""
        return self.direction(self.direction_cell(cos), [self.columns["direction_rows"]["fresnel"]])[0]

    def direction(self, cell, columns):
        """The direction bake's `columns` at `cell`, linear between its rows
        (`DirectionBake::at_cell`), read as packets of four columns."""
        i, frac = cell
        out = []
        for half in sorted({k // 4 for k in columns}):
            a = gather4(self.t["direction_rows"], 2 * i + half)
            b = gather4(self.t["direction_rows"], 2 * i + 2 + half)
            out += [(k, dr.fma(frac, b[k % 4] - a[k % 4], a[k % 4]))
                    for k in columns if k // 4 == half]
        values = dict(out)
        return [values[k] for k in columns]

    def g1(self, r, z):
        """`MaskingBake::g1`."""
        n = self.shapes["masking_g1"][0]
        a_num = self.f["masking_beta"] * r
        y = a_num / (a_num + z)
        i, frac = cell_at(y * float(n - 1), n)
        value = lerp_gather(self.t["masking_g1"], 1, 0, i, frac)
        return dr.select(z > 0.0, value, 0.0)

    # -- C over (u, θh) ------------------------------------------------
    def conv(self, sin_h, cos_h, u):
        """`ConvBake::at`."""
        return c_of_ln(self.ln_conv(sin_h, cos_h, u))

    def ln_conv(self, sin_h, cos_h, u):
        """`ConvBake::ln_at`."""
        s, f = self.s, self.f
        n_u, n_s = self.shapes["conv_ln_c"]
        nodes_u, nodes_s = n_u - 2, n_s - 2
        u = dr.minimum(dr.maximum(u, 0.0), f["conv_big_b"])
        sec_h = 1.0 / dr.maximum(cos_h, s["conv_cos_h_min"])
        tan_h = dr.minimum(dr.maximum(sin_h, 0.0), 1.0) * sec_h
        x_u = (log2_axis(1.0 + u / s["conv_u0"]) + u * f["conv_u_linear"]) * f["conv_u_scale"]
        v = u + 0.5
        nv = f["conv_ndf_quarter_width"] * v
        inv_w = dr.sqrt(16.0 + v * v / (1.0 / 64.0 + nv * nv))
        x_h = sec_h + tan_h * inv_w
        span = log2_axis((1.0 + inv_w) * float(np.float32(1.0 / s["conv_cos_h_min"])))
        x_s = log2_axis(x_h) * (float(nodes_s - 1) / span)
        ju, tu = cell_at(x_u, nodes_u)
        ju = self._node_row(ju, n_u)
        ks, ts = cell_at(x_s, nodes_s)
        wu, ws = catmull_rom_weights(tu), catmull_rom_weights(ts)
        ln_c = mi.Float(0.0)
        for a in range(4):
            # The four nodes (ks … ks + 3) of row ju + a in one packet.
            quad = gather4(self.conv_quads, (ju + a) * n_s + ks)
            inner = mi.Float(0.0)
            for b in range(4):
                inner += ws[b] * quad[b]
            ln_c += wu[a] * inner
        return ln_c
