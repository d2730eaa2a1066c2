//! [`ConvBake`]: `ln C(θh; u)` for one material and wavelength.

use super::cell_at;
use crate::bake::BakeVisitor;
use crate::math;
use crate::tables::convolution::ConvSlice;
use crate::tables::convolution::catmull_rom_weights;
use zerocopy::FromZeros;
/// `u` nodes of [`ConvBake`].
pub const CONV_U_NODES: usize = 33;
/// `sin θh` nodes of [`ConvBake`].
pub const CONV_S_NODES: usize = 130;
/// [`CONV_U_NODES`] and [`CONV_S_NODES`] with a ghost node at each end.
const PADDED_U: usize = CONV_U_NODES + 2;
const PADDED_S: usize = CONV_S_NODES + 2;
/// `u₀` of the `u` mapping (as T3's `ln(u + 0.1)`).
const U0: f32 = 0.1;
/// `u₁` of the `u` mapping's linear part.
const U1: f32 = 1.0;
/// The linear part spans at most this many times the logarithmic part.
const LINEAR_SHARE: f32 = 2.0;

/// The `u` axis of [`ConvBake`]: `log₂(1 + u/u₀) + a u` (with
/// [`math::log2_axis`]), `a = min(1/u₁, 2 log₂(1 + B/u₀)/B)`: logarithmic at
/// small `u`, where T3's own nodes are dense, linear at large `u`, where the
/// profile keeps narrowing; for large `B` the linear part is capped at twice
/// the logarithmic one so that small `u` keeps its rows.
#[inline]
pub(crate) fn u_axis(u: f32, linear: f32) -> f32 {
    math::log2_axis(1.0 + u / U0) + u * linear
}
/// Smallest `cos θh` of [`ConvBake`]'s angle axis.
const COS_H_MIN: f64 = 1e-3;
/// Floor of the stored `ln C` relative to its maximum (C below
/// `e^−70 C_max` ≈ 4e-31 C_max is stored as that).
const LN_C_RANGE: f32 = 70.0;

/// `ln C` for one material and wavelength over `(u, sin θh)` (module
/// documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct ConvBake {
    /// `B`, the largest `u`.
    big_b: f32,
    /// `(CONV_U_NODES − 1) / u_axis(B)`.
    u_scale: f32,
    /// The slope of `u_axis`'s linear part.
    u_linear: f32,
    /// A quarter of the NDF's core width (the floor of [`ConvBake::inv_width`]'s `w`).
    ndf_quarter_width: f32,
    /// `ln C` row-major `[u][θh]` with one ghost node on each side of both
    /// axes (linear extrapolation), so that every cell has four taps.
    ln_c: [f32; PADDED_U * PADDED_S],
    /// `1/w(u)` of each row (its θh nodes are [`row_tans`] of it).
    pub(crate) row_inv_w: [f32; CONV_U_NODES],
    /// The `u` of each row.
    pub(crate) row_u: [f32; CONV_U_NODES],
}

/// The `tan θh` nodes of a row with `1/w = inv_w`: `x = (1 + sin θ / w)/cos θ`
/// even in [`math::log2_axis`] from 1 to [`angle_span`], inverted as
/// `tan θ = tan(A − B)` with `tan A = w x`, `tan B = w/√(1 + w²(x² − 1))`;
/// in f32, as the slice's angle is evaluated (module documentation).
pub(crate) fn row_tans(inv_w: f32) -> [f32; CONV_S_NODES] {
    let w = 1.0 / f64::from(inv_w);
    let s_span = f64::from(angle_span(inv_w));
    let mut tans = [0.0f32; CONV_S_NODES];
    for (k, tan) in tans.iter_mut().enumerate() {
        let x = math::exp2_axis(k as f64 / (CONV_S_NODES - 1) as f64 * s_span).max(1.0);
        let tan_a = w * x;
        let tan_b = w / math::sqrt(1.0 + w * w * (x * x - 1.0));
        *tan = ((tan_a - tan_b) / (1.0 + tan_a * tan_b)) as f32;
    }
    tans
}

impl ConvBake {
    /// Tabulates `slice` in place for `u ∈ [0, B]` (its normalised angle
    /// evaluated in f32 at the nodes); `beta`, `p` give the NDF's core width.
    /// `false` (and `self` left as it was) when `B` is not positive and finite.
    pub fn init(&mut self, slice: &ConvSlice<'_>, big_b: f32, beta: f32, p: f32) -> bool {
        self.init_from(
            |u, tans, row| slice.ln_profile_at_tans(u, tans, row),
            big_b,
            beta,
            p,
        )
    }

    /// [`ConvBake::init`] from any source of rows: `rows(u, tans, out)`
    /// writes `ln C − ln s` at each `tan θh` of `tans` into `out` and
    /// returns the factor `s` (`None`: the row is 0).
    pub fn init_from(
        &mut self,
        mut rows: impl FnMut(f32, &[f32], &mut [f32]) -> Option<f32>,
        big_b: f32,
        beta: f32,
        p: f32,
    ) -> bool {
        if !(big_b > 0.0 && big_b.is_finite()) {
            return false;
        }
        let linear = (1.0 / U1).min(LINEAR_SHARE * math::log2_axis(1.0 + big_b / U0) / big_b);
        let u_span = u_axis(big_b, linear);
        // The NDF's core: where D has fallen by 10% (tan θ = β 0.1^(1/2p)).
        let ndf_width = beta * math::powff(0.1, 0.5 / p);
        let bake = self;
        bake.big_b = big_b;
        bake.u_scale = (CONV_U_NODES - 1) as f32 / u_span;
        bake.u_linear = linear;
        bake.ndf_quarter_width = 0.25 * ndf_width;
        let mut top = f32::MIN;
        for j in 0..CONV_U_NODES {
            let x_u = j as f64 / (CONV_U_NODES - 1) as f64 * f64::from(u_span);
            // u_axis⁻¹(x_u) by bisection on [0, B] (u_axis increases).
            let (mut lo, mut hi) = (0.0f32, big_b);
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if f64::from(u_axis(mid, linear)) < x_u {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let u = 0.5 * (lo + hi);
            let u = if j + 1 == CONV_U_NODES { big_b } else { u };
            let inv_w = bake.inv_width(u);
            bake.row_inv_w[j] = inv_w;
            bake.row_u[j] = u;
            let tans = row_tans(inv_w);
            let row = &mut bake.ln_c[(j + 1) * PADDED_S + 1..(j + 1) * PADDED_S + 1 + CONV_S_NODES];
            // ln C = ln s + the profile (s = 1 inside T3's u range).
            match rows(u, &tans, row) {
                Some(factor) if factor > 0.0 => {
                    let ln_factor = math::lnf(factor);
                    for v in row.iter_mut() {
                        *v += ln_factor;
                        top = top.max(*v);
                    }
                }
                _ => row.iter_mut().for_each(|v| *v = f32::MIN),
            }
        }
        let ln_c = &mut bake.ln_c;
        let floor = if top > f32::MIN {
            top - LN_C_RANGE
        } else {
            0.0
        };
        for v in ln_c.iter_mut() {
            *v = v.max(floor);
        }
        // Ghost nodes: along θh in the real rows, then along u in every column.
        for j in 1..=CONV_U_NODES {
            let row = &mut ln_c[j * PADDED_S..(j + 1) * PADDED_S];
            row[0] = 2.0 * row[1] - row[2];
            row[PADDED_S - 1] = 2.0 * row[PADDED_S - 2] - row[PADDED_S - 3];
        }
        for k in 0..PADDED_S {
            let at = |j: usize| j * PADDED_S + k;
            ln_c[at(0)] = 2.0 * ln_c[at(1)] - ln_c[at(2)];
            ln_c[at(PADDED_U - 1)] = 2.0 * ln_c[at(PADDED_U - 2)] - ln_c[at(PADDED_U - 3)];
        }
        true
    }

    /// The bake of [`ConvBake::init`] in new storage (`None` when `init` is `false`).
    #[cfg(test)]
    pub fn new(slice: &ConvSlice<'_>, big_b: f32, beta: f32, p: f32) -> Option<Self> {
        let mut bake = Self::new_zeroed();
        bake.init(slice, big_b, beta, p).then_some(bake)
    }

    /// `1/w(u)`: `w` is about a quarter of the lobe's core width at `u`, the
    /// kernel's `1/(2u)` or the NDF's, whichever is wider, and at most ¼:
    /// `1/w² = 16 + 1/(k² + n²)` with `k = ⅛/(u + ½)`, `n` the NDF's quarter
    /// width. Smooth in `u`, so that rows at equal `x` interpolate well.
    #[inline]
    fn inv_width(&self, u: f32) -> f32 {
        // 1/(k² + n²) = v²/(1/64 + n² v²) with v = u + ½: one division.
        let v = u + 0.5;
        let nv = self.ndf_quarter_width * v;
        math::sqrtf(16.0 + v * v / (1.0 / 64.0 + nv * nv))
    }

    /// The rows' axis: `(linear, scale)` with row `j` at `u_axis(u, linear) · scale = j`.
    pub(crate) fn u_axis_constants(&self) -> (f32, f32) {
        (self.u_linear, self.u_scale)
    }

    /// Hands the axes' constants and the padded `ln C` grid to `v`
    /// (`conv_ln_c` `[35, 132]`, ghost nodes included; `conv_*` scalars,
    /// and the axes' constants `conv_u0`, `conv_cos_h_min`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.scalar("conv_big_b", f64::from(self.big_b));
        v.scalar("conv_u_scale", f64::from(self.u_scale));
        v.scalar("conv_u_linear", f64::from(self.u_linear));
        v.scalar("conv_ndf_quarter_width", f64::from(self.ndf_quarter_width));
        v.scalar("conv_u0", f64::from(U0));
        v.scalar("conv_cos_h_min", COS_H_MIN);
        v.array("conv_ln_c", &[PADDED_U, PADDED_S], &self.ln_c);
    }

    /// `C` at `sin θh`, `cos θh` (in [0, 1]) and `u ∈ [0, B]` (clamped).
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn at(&self, sin_h: f32, cos_h: f32, u: f32) -> f32 {
        c_of_ln(self.ln_at(sin_h, cos_h, u))
    }

    /// `ln C` of [`ConvBake::at`] (finite: the bake's floor bounds it below).
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn ln_at(&self, sin_h: f32, cos_h: f32, u: f32) -> f32 {
        let u = u.max(0.0).min(self.big_b);
        // 1/cos θh and tan θh do not wait for `w(u)`: only a multiply-add does.
        let sec_h = 1.0 / cos_h.max(COS_H_MIN as f32);
        let tan_h = sin_h.max(0.0).min(1.0) * sec_h;
        let x_u = u_axis(u, self.u_linear) * self.u_scale;
        let inv_w = self.inv_width(u);
        let x_h = sec_h + tan_h * inv_w;
        let x_s = math::log2_axis(x_h) * ((CONV_S_NODES - 1) as f32 / angle_span(inv_w));
        let (ju, wu) = catmull_rom(x_u, CONV_U_NODES);
        let (ks, ws) = catmull_rom(x_s, CONV_S_NODES);
        // ju ≤ CONV_U_NODES − 2 and ks ≤ CONV_S_NODES − 2: the 4 × 4 taps
        // lie in the padded grid.
        let mut ln_c = 0.0f32;
        for (a, wa) in wu.iter().enumerate() {
            let row = &self.ln_c[(ju + a) * PADDED_S..][..PADDED_S];
            let taps = &row[ks..ks + 4];
            ln_c += wa * (taps[0] * ws[0] + taps[1] * ws[1] + taps[2] * ws[2] + taps[3] * ws[3]);
        }
        ln_c
    }
}

/// `C = e^ln C` of [`ConvBake::ln_at`], 0 where it is not finite.
///
/// Mirrored in python/twoscale/drjit/lookups.py.
#[inline]
pub(crate) fn c_of_ln(ln_c: f32) -> f32 {
    // e^x is 0 in f32 below x ≈ −103.3.
    if !(ln_c > -104.0) {
        return 0.0;
    }
    let value = math::expf(ln_c);
    if value.is_finite() { value } else { 0.0 }
}

/// The θh axis's value at `cos θh = 10⁻³` (its last node) for `1/w`.
#[inline]
pub(crate) fn angle_span(inv_w: f32) -> f32 {
    math::log2_axis((1.0 + inv_w) * (1.0 / COS_H_MIN) as f32)
}

/// The first of the four padded node indices (the cell's index, as the
/// padding shifts nodes by one) and the Catmull–Rom weights at position `x`
/// (in nodes, clamped to `[0, n − 1]`).
#[inline]
fn catmull_rom(x: f32, n: usize) -> (usize, [f32; 4]) {
    let (i, t) = cell_at(x.max(0.0), n);
    (i, catmull_rom_weights(t))
}
