//! The model's linear-sRGB reflectance by integration over the spectrum
//! (docs/design/rgb-integration.md, docs/model.md §2.12):
//!
//! ```text
//! ρ_c(i,o) = ∫ ρ(i,o,λ) w_c(λ) dλ                       (w_c: crate::spectrum::colour)
//!          ≈ Σ_k [ρ_s + ρ_CTD](λ_k) R_kc(cos θd) + [ρ_base + ρ_ms](λ_k) P_kc
//! R_kc(μ)  = Σ_j hat_k(λ_j) W_c,j F(η(λ_j), μ) / F(η(λ_k), μ)
//! P_kc     = Σ_j hat_k(λ_j) W_c,j
//! ```
//!
//! `λ_k` are [`INTEGRATED_WAVELENGTHS`] (8, 0.38 to 0.72 µm),
//! `hat_k` their hat functions (held beyond the ends), `W_c,j` the CIE 5 nm
//! weights of [`crate::spectrum::colour`]. The surface lobes are divided by F(θd) at
//! their wavelength and integrated against F: a metal's colour, which
//! changes fast with λ (gold's edge at 0.47–0.55 µm), is integrated at the
//! 85 CIE wavelengths; what is left is smooth in λ and interpolated from
//! the 8. `R_kc` is tabulated per material over `√cos θd` (65 nodes,
//! linear). White colour terms (F ≡ 1) make `R = P`. C is read at 4 of the
//! 8 wavelengths ([`CONV_NODES`]) and `ln C` at the others is the cubic
//! through those in `u = b cos θd/λ` ([`CONV_WEIGHTS`]). A channel that
//! comes out negative (a spectrum outside the sRGB gamut) is clamped to 0.

use super::construct::{NodeBakes, SurfaceBakes};
use super::eval::{Geometry, Pair};
use super::{BakeVisitor, ChannelBake, RgbSample, Tables, TwoScale, finite_or_zero};
use crate::bake::c_of_ln;
use crate::material::{ColourTerms, HaloWeight, Options, SigmaRelMode};
use crate::math::{self, BELOW_ONE};
use crate::model::fresnel::fresnel;
use crate::spectrum::colour::{self, SRGB_WEIGHTS, WAVELENGTH_COUNT};
use crate::spectrum::optical::SpectralMaterial;
use core::borrow::{Borrow, BorrowMut};

/// Number of wavelengths the integrated model evaluates.
pub const INTEGRATED_COUNT: usize = 8;

/// The wavelengths of [`IntegratedRgb`], µm: 0.38 to 0.72, about 0.05
/// apart (the spacing and range that met the accuracy target of
/// docs/design/rgb-integration.md; [0.40, 0.70] and nodes denser around
/// gold's edge did worse).
pub const INTEGRATED_WAVELENGTHS: [f32; INTEGRATED_COUNT] =
    [0.38, 0.43, 0.47, 0.52, 0.57, 0.62, 0.67, 0.72];

/// The nodes whose samplers [`IntegratedRgb::sample`] mixes: near the
/// paper's red, green and blue (0.62, 0.52, 0.43 µm).
const SAMPLER_NODES: [usize; 3] = [5, 3, 1];

/// The models whose C [`IntegratedRgb::eval`] looks up (0.38, 0.47, 0.62,
/// 0.72 µm); the others take `ln C` from the cubic through these
/// ([`CONV_WEIGHTS`]; docs/design/rgb-integration.md).
const CONV_NODES: [usize; 4] = [0, 2, 5, 7];

/// `ln C_k = Σ_j CONV_WEIGHTS[k][j] ln C_{CONV_NODES[j]}`: the Lagrange
/// weights of the cubic through the [`CONV_NODES`] in `u = b cos θd/λ`.
/// `u_k ∝ 1/λ_k` at every pair, so the weights are constants; the rows of
/// the `CONV_NODES` themselves are unit vectors.
const CONV_WEIGHTS: [[f32; 4]; INTEGRATED_COUNT] = conv_weights();

/// [`CONV_WEIGHTS`] transposed, `[j][k]`: the f32 path's lanes.
const CONV_LANES: [[f32; INTEGRATED_COUNT]; 4] = {
    let mut out = [[0.0; INTEGRATED_COUNT]; 4];
    let mut k = 0;
    while k < INTEGRATED_COUNT {
        let mut j = 0;
        while j < 4 {
            out[j][k] = CONV_WEIGHTS[k][j];
            j += 1;
        }
        k += 1;
    }
    out
};

const fn conv_weights() -> [[f32; 4]; INTEGRATED_COUNT] {
    const fn x(k: usize) -> f64 {
        1.0 / INTEGRATED_WAVELENGTHS[k] as f64
    }
    let mut out = [[0.0; 4]; INTEGRATED_COUNT];
    let mut k = 0;
    while k < INTEGRATED_COUNT {
        let mut j = 0;
        while j < 4 {
            let mut w = 1.0;
            let mut m = 0;
            while m < 4 {
                if m != j {
                    let (xj, xm) = (x(CONV_NODES[j]), x(CONV_NODES[m]));
                    w *= (x(k) - xm) / (xj - xm);
                }
                m += 1;
            }
            out[k][j] = w as f32;
            j += 1;
        }
        k += 1;
    }
    out
}

/// `√cos θd` nodes of [`ColourBake`].
const COLOUR_NODES: usize = 65;

/// `hat_k(λ) = 1 − f`, `hat_{k+1}(λ) = f`: the hats' cell of `lambda` (µm),
/// held at the end nodes beyond them.
fn hat_cell(lambda: f32) -> (usize, f64) {
    let w = INTEGRATED_WAVELENGTHS;
    let l = f64::from(lambda);
    let mut k = 0;
    while k + 2 < INTEGRATED_COUNT && l > f64::from(w[k + 1]) {
        k += 1;
    }
    let (a, b) = (f64::from(w[k]), f64::from(w[k + 1]));
    (k, ((l - a) / (b - a)).max(0.0).min(1.0))
}

/// `R_kc` over `√cos θd` and `P_kc` (module documentation): 6 KB.
#[derive(Clone)]
pub(super) struct ColourBake {
    /// `R_kc` per node as `[c][k]`: a channel's 8 weights side by side, as
    /// the lanes of [`IntegratedRgb::eval`]'s f32 path read them.
    surface: [[[f32; INTEGRATED_COUNT]; 3]; COLOUR_NODES],
    plain: [[f32; 3]; INTEGRATED_COUNT],
}

impl ColourBake {
    /// The weights of `material`'s index; `white`: F ≡ 1.
    pub(super) fn new(material: &SpectralMaterial<'_>, white: bool) -> ColourBake {
        let mut plain = [[0.0f64; 3]; INTEGRATED_COUNT];
        let cells: [(usize, f64); WAVELENGTH_COUNT] =
            core::array::from_fn(|j| hat_cell(colour::wavelength(j)));
        for (j, &(k, f)) in cells.iter().enumerate() {
            for c in 0..3 {
                let w = f64::from(SRGB_WEIGHTS[j][c]);
                plain[k][c] += (1.0 - f) * w;
                plain[k + 1][c] += f * w;
            }
        }
        let plain_f32 = plain.map(|row| row.map(|x| x as f32));
        let mut surface = [plain_f32; COLOUR_NODES];
        if !white {
            let eta_j: [_; WAVELENGTH_COUNT] =
                core::array::from_fn(|j| material.eta.at(colour::wavelength(j)));
            let eta_k = INTEGRATED_WAVELENGTHS.map(|l| material.eta.at(l));
            for (m, row) in surface.iter_mut().enumerate() {
                let x = m as f32 / (COLOUR_NODES - 1) as f32;
                let cos = x * x;
                let mut t = [[0.0f64; 3]; INTEGRATED_COUNT];
                for (j, &(k, f)) in cells.iter().enumerate() {
                    let fj = f64::from(fresnel(eta_j[j], cos));
                    for c in 0..3 {
                        let w = f64::from(SRGB_WEIGHTS[j][c]) * fj;
                        t[k][c] += (1.0 - f) * w;
                        t[k + 1][c] += f * w;
                    }
                }
                for k in 0..INTEGRATED_COUNT {
                    let fk = f64::from(fresnel(eta_k[k], cos));
                    if fk > 0.0 {
                        row[k] = t[k].map(|v| (v / fk) as f32);
                    }
                }
            }
        }
        ColourBake {
            surface: surface.map(|row| core::array::from_fn(|c| row.map(|r| r[c]))),
            plain: plain_f32,
        }
    }

    /// `R_kc` at `cos θd`, linear in `√cos θd` between nodes.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline]
    fn surface_at(&self, cos_d: f64) -> [[f32; INTEGRATED_COUNT]; 3] {
        let t = math::sqrt(cos_d.max(0.0).min(1.0)) * (COLOUR_NODES - 1) as f64;
        let m = (math::floor(t) as usize).min(COLOUR_NODES - 2);
        let f = (t - m as f64) as f32;
        let (a, b) = (&self.surface[m], &self.surface[m + 1]);
        // Plain loops: `array::from_fn`'s closures do not vectorise.
        let mut out = [[0.0; INTEGRATED_COUNT]; 3];
        for c in 0..3 {
            for k in 0..INTEGRATED_COUNT {
                out[c][k] = a[c][k] + f * (b[c][k] - a[c][k]);
            }
        }
        out
    }
}

/// The models of `material` at `wavelengths`, with `η(λ_k)`, baked into
/// `bakes` in place; G1 and the visible-slope tables (wavelength
/// independent) are baked once and copied. Only the models `samplers`
/// lists bake the halo sampler (the others draw the halo from the
/// spectrum); with `share_conv`, a model not in `samplers` takes C from the
/// model before it, which must be at a shorter wavelength (its bake covers
/// `u ≤ b/λ_{k−1}`, hence `b/λ_k`).
pub(super) fn models_at<'a, B: BorrowMut<ChannelBake>, const N: usize>(
    bakes: [B; N],
    tables: &Tables<'a>,
    material: &SpectralMaterial<'_>,
    options: Options,
    wavelengths: &[f32; N],
    samplers: &[usize],
    share_conv: bool,
) -> [TwoScale<'a, B>; N] {
    let shared = SurfaceBakes::new(tables, material.layer.surface);
    let mut k = 0;
    let mut nodes = bakes.map(|bake| {
        let lambda = wavelengths[k];
        k += 1;
        TwoScale::around(
            bake,
            tables,
            &shared,
            material.layer,
            lambda,
            material.eta.at(lambda),
            options,
        )
    });
    let (first, rest) = nodes.split_at_mut(1);
    let first = first[0].bake.borrow_mut();
    shared.bake_into(tables, first);
    for node in rest {
        let bake = node.bake.borrow_mut();
        bake.masking.clone_from(&first.masking);
        bake.visible.clone_from(&first.visible);
    }
    for k in 0..N {
        let sampler = samplers.contains(&k);
        let what = NodeBakes {
            conv: sampler || !share_conv || k == 0,
            halo_sampler: sampler,
        };
        let (before, rest) = nodes.split_at_mut(k);
        let node = &mut rest[0];
        if !what.conv {
            debug_assert!(wavelengths[k - 1] <= wavelengths[k]);
            let (from, to) = (before[k - 1].bake(), node.bake.borrow_mut());
            to.conv.clone_from(&from.conv);
            to.conv_baked = from.conv_baked;
        }
        node.bake_wavelength(tables, &shared, material.eta.at(wavelengths[k]), what);
    }
    nodes
}

/// The models' constants that [`IntegratedRgb::eval`]'s f32 path reads, one
/// lane per model: `(4π/λ_k)²`, `σs²`, `(c−1) σs² b² / (2π λ_k²)`,
/// `|η_k² − 1|²/2` (0 without an index) and `η_k²`.
#[derive(Clone, Copy)]
struct Lanes {
    x_scale: [f32; INTEGRATED_COUNT],
    sigma_s_sq: [f32; INTEGRATED_COUNT],
    halo_scale: [f32; INTEGRATED_COUNT],
    half_e: [f32; INTEGRATED_COUNT],
    eta_sq: [[f32; 2]; INTEGRATED_COUNT],
    symmetrised: bool,
}

impl Lanes {
    /// The constants of `nodes`, or `None` where the f32 path does not
    /// apply: a base or compensation lobe (`diffuse`), white colour terms,
    /// or the halo weighted at θi ([`HaloWeight::Incident`]).
    fn new<B: Borrow<ChannelBake>>(
        nodes: &[TwoScale<'_, B>; INTEGRATED_COUNT],
        diffuse: bool,
    ) -> Option<Lanes> {
        let options = nodes[0].options;
        if diffuse
            || options.colour == ColourTerms::White
            || options.halo_weight != HaloWeight::Printed
        {
            return None;
        }
        let constants = nodes
            .each_ref()
            .map(|node| node.q.map(|q| q.combine_constants()));
        Some(Lanes {
            x_scale: nodes.each_ref().map(|node| node.x_scale as f32),
            sigma_s_sq: nodes.each_ref().map(|node| node.sigma_s_sq as f32),
            halo_scale: nodes.each_ref().map(|node| node.halo_scale as f32),
            half_e: constants.map(|c| c.map_or(0.0, |(e, _)| (0.5 * e) as f32)),
            eta_sq: constants.map(|c| c.map_or([0.0; 2], |(_, eta_sq)| eta_sq.map(|x| x as f32))),
            symmetrised: options.sigma_rel == SigmaRelMode::Symmetrised,
        })
    }
}

/// The two-scale BRDF in linear sRGB by integration over the spectrum
/// (module documentation): one [`TwoScale`] per wavelength of
/// [`INTEGRATED_WAVELENGTHS`] sharing the surface's bakes, and the colour
/// weights. The bakes are held as `B` as [`super::Rgb`]'s: boxed
/// (`IntegratedRgb::boxed`, feature `std`) or in caller-provided storage
/// ([`IntegratedRgb::new_in`]); 1 137 KB by value (8 models of 141 KB, the colour weights 6 KB).
#[derive(Clone)]
pub struct IntegratedRgb<'a, B = ChannelBake> {
    nodes: [TwoScale<'a, B>; INTEGRATED_COUNT],
    colour: ColourBake,
    /// Whether the models have a base lobe, `k_d` or the compensation lobe
    /// (else their `ρ_base + ρ_ms` is 0 and is not evaluated).
    diffuse: bool,
    /// Whether the surface has a diffraction lobe (σs > 0, b > 0).
    halo: bool,
    /// The constants of `eval`'s f32 path, where it applies.
    lanes: Option<Lanes>,
}

#[cfg(feature = "std")]
impl<'a> IntegratedRgb<'a, std::boxed::Box<ChannelBake>> {
    /// [`IntegratedRgb::new_in`] with the bakes on the heap.
    pub fn boxed(tables: &Tables<'a>, material: &SpectralMaterial<'_>, options: Options) -> Self {
        let bakes = core::array::from_fn(|_| ChannelBake::boxed());
        Self::new_in(bakes, tables, material, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>> IntegratedRgb<'a, B> {
    /// The model of `material` baked into the storage `bakes` in place (see
    /// [`TwoScale::new_in`]; sanitised as [`TwoScale::new`]): the models at
    /// [`INTEGRATED_WAVELENGTHS`] with `η(λ_k)`, and the colour weights of
    /// `η` at the CIE wavelengths.
    pub fn new_in(
        bakes: [B; INTEGRATED_COUNT],
        tables: &Tables<'a>,
        material: &SpectralMaterial<'_>,
        options: Options,
    ) -> Self {
        let nodes = models_at(
            bakes,
            tables,
            material,
            options,
            &INTEGRATED_WAVELENGTHS,
            &SAMPLER_NODES,
            false,
        );
        let colour = ColourBake::new(material, options.colour == ColourTerms::White);
        let diffuse = nodes.iter().any(|node| node.has_lobes().1);
        let halo = nodes[0].has_lobes().0;
        let lanes = Lanes::new(&nodes, diffuse);
        IntegratedRgb {
            nodes,
            colour,
            diffuse,
            halo,
            lanes,
        }
    }
}

impl<B: Borrow<ChannelBake>> IntegratedRgb<'_, B> {
    /// The one-wavelength models, at [`INTEGRATED_WAVELENGTHS`].
    pub fn nodes(&self) -> &[TwoScale<'_, B>; INTEGRATED_COUNT] {
        &self.nodes
    }

    /// Hands the colour weights to `v`, for ports of [`IntegratedRgb::eval`]
    /// and [`IntegratedRgb::sample`] (the Python package's
    /// `Material.integrated_bakes()`): `wavelengths` ([`INTEGRATED_WAVELENGTHS`],
    /// µm), `surface` (`R_kc` at the `√cos θd` nodes, `[nodes, 8, 3]`),
    /// `plain` (`P_kc`, `[8, 3]`) and `sampler_nodes` (the nodes whose
    /// samplers [`IntegratedRgb::sample`] mixes, as numbers), `conv_nodes`
    /// (the models whose C `eval` reads, as numbers) and `conv_weights`
    /// (`[8, 4]`: `ln C` at each model over those; module documentation). Each node's bakes are its [`TwoScale::visit_bakes`].
    #[doc(hidden)]
    pub fn visit_colour(&self, v: &mut dyn BakeVisitor) {
        v.array("wavelengths", &[INTEGRATED_COUNT], &INTEGRATED_WAVELENGTHS);
        // Stored `[c][k]` per node; handed over `[k][c]`.
        let surface: [[[f32; 3]; INTEGRATED_COUNT]; COLOUR_NODES] = self
            .colour
            .surface
            .map(|row| core::array::from_fn(|k| row.map(|r| r[k])));
        v.array(
            "surface",
            &[COLOUR_NODES, INTEGRATED_COUNT, 3],
            surface.as_flattened().as_flattened(),
        );
        v.array(
            "plain",
            &[INTEGRATED_COUNT, 3],
            self.colour.plain.as_flattened(),
        );
        v.array(
            "sampler_nodes",
            &[SAMPLER_NODES.len()],
            &SAMPLER_NODES.map(|k| k as f32),
        );
        v.array(
            "conv_nodes",
            &[CONV_NODES.len()],
            &CONV_NODES.map(|k| k as f32),
        );
        v.array(
            "conv_weights",
            &[INTEGRATED_COUNT, CONV_NODES.len()],
            CONV_WEIGHTS.as_flattened(),
        );
    }

    /// `ln C` at the [`CONV_NODES`]' wavelengths, when they are baked.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline(always)]
    fn ln_conv(&self, geometry: &Geometry) -> Option<[f32; 4]> {
        let mut ln = [0.0; 4];
        for (value, &k) in ln.iter_mut().zip(&CONV_NODES) {
            let node = &self.nodes[k];
            let u = (node.big_b * geometry.cos_d) as f32;
            *value = node.ln_conv_at(geometry.sin_h, geometry.cos_h, u)?;
        }
        Some(ln)
    }

    /// ρ(i, o) per linear-sRGB channel (module documentation; C read at 4
    /// of the wavelengths and interpolated at the others). Conductors with
    /// physical colour terms and the printed halo weight (every metal
    /// preset) take an f32 path whose arithmetic over the 8 models
    /// vectorises (`eval_lanes`: the same terms, e^x to 1e-7), the others
    /// the terms in f64 (`eval_terms`).
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        let Some(pair) = self.nodes[0].pair(i, o) else {
            return [0.0; 3];
        };
        if let Some(lanes) = &self.lanes
            && let Some(value) = self.eval_lanes(lanes, &pair)
        {
            return value;
        }
        self.eval_terms(&pair)
    }

    /// [`IntegratedRgb::eval`] in f32, one lane per model, with the models'
    /// direction-bake rows gathered first, so that the arithmetic over the
    /// 8 models vectorises: per model
    /// `ρ_k = A_k F_k D G / (4 cos θi cos θo) + Q̄_k G (1 − A_k)/σrel,k² ·
    /// (c−1) σs² b² / (2π λ_k²) · C_k` (HP17 24-33, as
    /// [`TwoScale::surface_terms_with`]), `A_k = e^(−t)`,
    /// `t = (4π cos θd/λ_k)² σrel,k²`, `(1 − e^(−t))/t` by its series to
    /// `t⁴` below `t = 0.05` (truncation below 5e-10), Q̄ as
    /// `QConstants::combine`, `e^x` by [`math::exp_lanef`]; then
    /// `ρ_c = Σ_k ρ_k R_kc(cos θd)`. `None` where the halo needs C and C is
    /// not baked (the T3a source).
    #[inline(always)]
    fn eval_lanes(&self, lanes: &Lanes, pair: &Pair) -> Option<[f32; 3]> {
        const N: usize = INTEGRATED_COUNT;
        let g = &pair.geometry;
        let ln_c = if self.halo && pair.g > 0.0 {
            Some(self.ln_conv(g)?)
        } else {
            None
        };
        // The rows at cos θi and cos θo and F at cos θd, per model.
        let mut sigma = [0.0f32; N];
        let mut f_d = [0.0f32; N];
        let mut q_i = [[0.0f32; N]; 5];
        let mut q_o = [[0.0f32; N]; 5];
        for (k, node) in self.nodes.iter().enumerate() {
            let bake = &node.bake().direction;
            let (at_i, at_o) = (bake.at_cell(pair.cells[0]), bake.at_cell(pair.cells[1]));
            let r_i = at_i.sigma_ratio() as f32;
            sigma[k] = if lanes.symmetrised {
                let r_o = at_o.sigma_ratio() as f32;
                0.5 * (r_i * r_i + r_o * r_o)
            } else {
                r_i * r_i
            };
            f_d[k] = bake.fresnel_at(pair.cells[2]);
            let (fi, fo) = (at_i.q_factors(), at_o.q_factors());
            for m in 0..5 {
                q_i[m][k] = fi[m] as f32;
                q_o[m][k] = fo[m] as f32;
            }
        }
        let mut conv = [0.0f32; N];
        if let Some(ln) = ln_c {
            let w = &CONV_LANES;
            for k in 0..N {
                let x = w[0][k] * ln[0] + w[1][k] * ln[1] + w[2][k] * ln[2] + w[3][k] * ln[3];
                // c_of_ln's threshold: e^x is 0 in f32 below −103.3.
                conv[k] = if x > -104.0 { math::exp_lanef(x) } else { 0.0 };
            }
        }
        let (cos_i, cos_o) = (g.wi[2], g.wo[2]);
        let specular = (pair.g / (4.0 * cos_i * cos_o) * pair.d) as f32;
        let halo_g = pair.g as f32;
        let cos_d_sq = (g.cos_d * g.cos_d) as f32;
        // Q̄'s angles as QConstants::combine takes them.
        let s_sq = pair.along * pair.along + pair.across * pair.across;
        let (along, across, inv_s_sq) = if s_sq > 0.0 {
            (pair.along as f32, pair.across as f32, (1.0 / s_sq) as f32)
        } else {
            (1.0, 0.0, 1.0)
        };
        let s_sq = s_sq as f32;
        let mut rho = [0.0f32; N];
        for k in 0..N {
            let x = lanes.x_scale[k] * cos_d_sq;
            let sigma_rel_sq = lanes.sigma_s_sq[k] * sigma[k];
            let t = x * sigma_rel_sq;
            let a = math::exp_lanef(-t);
            let series = 1.0 - 0.5 * t * (1.0 - t / 3.0 * (1.0 - 0.25 * t * (1.0 - 0.2 * t)));
            let one_minus_a_over = x * if t < 0.05 { series } else { (1.0 - a) / t };
            // Q̄ (QConstants::combine).
            let (ai, uir, uii, wir, wii) = (q_i[0][k], q_i[1][k], q_i[2][k], q_i[3][k], q_i[4][k]);
            let (ao, uor, uoi, wor, woi) = (q_o[0][k], q_o[1][k], q_o[2][k], q_o[3][k], q_o[4][k]);
            let [er, ei] = lanes.eta_sq[k];
            let (uu_re, uu_im) = (uir * uor - uii * uoi, uir * uoi + uii * uor);
            let (ww_re, ww_im) = (wir * wor - wii * woi, wir * woi + wii * wor);
            let pp_re = uu_re * along - (er * ww_re - ei * ww_im) * s_sq;
            let pp_im = uu_im * along - (er * ww_im + ei * ww_re) * s_sq;
            let q = ai * ao * (along * along)
                + (ai * (uor * uor + uoi * uoi) + (uir * uir + uii * uii) * ao) * (across * across)
                + (pp_re * pp_re + pp_im * pp_im);
            let q_bar = (lanes.half_e[k] * q * inv_s_sq).max(0.0);
            let value = a * f_d[k] * specular
                + q_bar * halo_g * lanes.halo_scale[k] * one_minus_a_over * conv[k];
            rho[k] = if value.is_finite() { value } else { 0.0 };
        }
        let r = self.colour.surface_at(g.cos_d);
        let mut out = [0.0f32; 3];
        for k in 0..N {
            for c in 0..3 {
                out[c] += rho[k] * r[c][k];
            }
        }
        Some(out.map(|x| if x.is_finite() && x > 0.0 { x } else { 0.0 }))
    }

    /// [`IntegratedRgb::eval`] term by term in f64 (every material).
    fn eval_terms(&self, pair: &Pair) -> [f32; 3] {
        let g = &pair.geometry;
        let ln_c = if self.halo && pair.g > 0.0 {
            self.ln_conv(g)
        } else {
            None
        };
        let r = self.colour.surface_at(g.cos_d);
        let mut out = [0.0f64; 3];
        let (cos_i, cos_o) = (g.wi[2], g.wo[2]);
        for (k, node) in self.nodes.iter().enumerate() {
            let conv = || match ln_c {
                Some(ln) => {
                    let w = &CONV_WEIGHTS[k];
                    let x = w[0] * ln[0] + w[1] * ln[1] + w[2] * ln[2] + w[3] * ln[3];
                    f64::from(c_of_ln(x))
                }
                None => node.conv_at(g.sin_h, g.cos_h, (node.big_b * g.cos_d) as f32),
            };
            // `TwoScale::lobes` in f64, without rounding each lobe to f32.
            let t = node.surface_terms_with(pair, node.white(), conv);
            let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
            let surface = finite(t.a_spec * t.rho_ct + t.diffraction);
            if self.diffuse {
                // The compensation lobe's colour is F_avg's, per node: plain weights.
                let base = finite(
                    node.base_value(&t.at_i, &t.at_o, cos_i, cos_o)
                        + node.multiple_value(&t.at_i, &t.at_o),
                );
                for c in 0..3 {
                    out[c] +=
                        surface * f64::from(r[c][k]) + base * f64::from(self.colour.plain[k][c]);
                }
            } else {
                for c in 0..3 {
                    out[c] += surface * f64::from(r[c][k]);
                }
            }
        }
        out.map(|x| finite_or_zero(x.max(0.0)))
    }

    /// The density of [`IntegratedRgb::sample`]: the mean of the pdfs of
    /// the models nearest the paper's red, green and blue.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.nodes[0].geometry(i, o) {
            Some(geometry) => finite_or_zero(self.pdf_at(&geometry)),
            None => 0.0,
        }
    }

    pub(super) fn pdf_at(&self, geometry: &Geometry) -> f64 {
        // The nodes share the surface, hence the specular density.
        let specular = self.nodes[0].specular_pdf(geometry);
        let sum: f64 = SAMPLER_NODES
            .iter()
            .map(|&k| {
                f64::from(finite_or_zero(
                    self.nodes[k].pdf_with_specular(geometry, specular),
                ))
            })
            .sum();
        sum / SAMPLER_NODES.len() as f64
    }

    /// Picks one of three models' samplers with `u[0]` (uniformly; `u[0]`
    /// is rescaled and reused to pick the lobe), samples it, and returns
    /// the direction, [`IntegratedRgb::pdf`] and [`IntegratedRgb::eval`] there.
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<RgbSample> {
        let n = SAMPLER_NODES.len();
        let pick = n as f64 * f64::from(u[0].max(0.0).min(BELOW_ONE));
        let k = (pick as usize).min(n - 1);
        let rest = (pick - k as f64) as f32;
        let (o, _) = self.nodes[SAMPLER_NODES[k]].sample_direction(i, [rest, u[1], u[2]])?;
        let geometry = self.nodes[0].geometry(i, o)?;
        let pdf = finite_or_zero(self.pdf_at(&geometry));
        if !(pdf > 0.0) {
            return None;
        }
        Some(RgbSample {
            o,
            pdf,
            value: self.eval(i, o),
        })
    }
}

/// The RGB model of [`RgbMode`](crate::material::RgbMode): [`super::Rgb`] or [`IntegratedRgb`].
#[derive(Clone)]
#[allow(clippy::large_enum_variant)] // one per material, boxed by the front ends
pub enum RgbModel<'a, B = ChannelBake> {
    /// [`RgbMode::PaperWavelengths`](crate::material::RgbMode::PaperWavelengths).
    PaperWavelengths(super::Rgb<'a, B>),
    /// [`RgbMode::Integrated`](crate::material::RgbMode::Integrated).
    Integrated(IntegratedRgb<'a, B>),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TableSet;
    use crate::materials::SPECTRAL_PRESETS;

    /// A direction of the upper hemisphere, uniform in `cos θ` (grazing
    /// included) and φ.
    fn direction(rng: &mut crate::test_rng::Lcg) -> [f32; 3] {
        let (z, phi) = (
            rng.next().max(1e-4),
            2.0 * core::f64::consts::PI * rng.next(),
        );
        let s = (1.0 - z * z).sqrt();
        [(s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32]
    }

    /// The f32 path is the f64 terms' sum: on every metal preset (which
    /// takes it) and with σrel symmetrised, within 1e-5 relative per
    /// channel where the channel exceeds 1e-6 of its peak, at 4000 pairs
    /// (half of them around the mirror direction, where the halo is).
    #[test]
    fn lanes_equal_the_f64_terms() {
        let set = TableSet::embedded();
        let tables = set.brdf_tables();
        let mut worst = (0.0f64, "");
        let symmetrised = Options {
            sigma_rel: SigmaRelMode::Symmetrised,
            ..Options::default()
        };
        let mut lanes_taken = 0;
        for preset in SPECTRAL_PRESETS {
            for options in [Options::default(), symmetrised] {
                let bakes = core::array::from_fn(|_| std::boxed::Box::new(ChannelBake::zeroed()));
                let model = IntegratedRgb::new_in(bakes, &tables, &preset.material, options);
                let Some(lanes) = &model.lanes else {
                    continue;
                };
                lanes_taken += 1;
                let mut rng = crate::test_rng::Lcg(43);
                let mut values = std::vec::Vec::new();
                for k in 0..4000 {
                    let i = direction(&mut rng);
                    let o = if k % 2 == 0 {
                        direction(&mut rng)
                    } else {
                        let d = 0.3 * rng.next() as f32;
                        let phi = 2.0 * core::f32::consts::PI * rng.next() as f32;
                        let o = [-i[0] + d * phi.cos(), -i[1] + d * phi.sin(), i[2]];
                        let n = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
                        o.map(|x| x / n)
                    };
                    let Some(pair) = model.nodes[0].pair(i, o) else {
                        continue;
                    };
                    let fast = model.eval_lanes(lanes, &pair).expect("C is baked");
                    values.push((fast, model.eval_terms(&pair)));
                }
                let peak = values.iter().fold([0.0f32; 3], |m, (_, r)| {
                    core::array::from_fn(|c| m[c].max(r[c]))
                });
                for (fast, reference) in &values {
                    for c in 0..3 {
                        let r = f64::from(reference[c]);
                        if r > 1e-6 * f64::from(peak[c]) {
                            let e = (f64::from(fast[c]) / r - 1.0).abs();
                            if e > worst.0 {
                                worst = (e, preset.name);
                            }
                        }
                    }
                }
            }
        }
        std::eprintln!(
            "lanes against f64 terms: worst {:.2e} ({})",
            worst.0,
            worst.1
        );
        assert!(lanes_taken >= 18, "{lanes_taken} models took the f32 path");
        assert!(worst.0 <= 1e-5, "{worst:?}");
    }
}
