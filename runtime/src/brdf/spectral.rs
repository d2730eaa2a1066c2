//! The model at any wavelength of [0.36, 0.83] µm from one construction
//! (docs/model.md §2.12): models at [`SPECTRAL_WAVELENGTHS`] sharing the
//! surface's bakes; at λ between the models k and k + 1 (hat weights), the
//! surface lobes are evaluated at λ itself with what is slow in λ
//! interpolated between the two models:
//!
//! ```text
//! ρ(i,o,λ) ≈ A_spec(λ) F(η(λ), θd) D G / (4 cos θi cos θo)
//!          + Q̄(λ) G (1 − A(λ))/σrel²(λ) (c−1) σs² b² / (2π λ²) C(θh; b cos θd/λ)
//!          + Σ_k hat_k(λ) [ρ_base + ρ_ms](λ_k)
//! Q̄(λ)     = F(η(λ), θd) Σ_k hat_k(λ) Q̄(λ_k)/F(η(λ_k), θd),   σrel²(λ) = σs² Σ_k hat_k(λ) (σrel/σs)²(λ_k)
//! ```
//!
//! As for [`super::IntegratedRgb`], a metal's fast colour is in F, which is
//! read at λ per call from a per-material table ([`FresnelBake`]: the closed
//! form on a grid of λ and √cos θd, bilinear); Q̄/F and σrel
//! are smooth in λ. C depends on λ only
//! through `u`, and model k's bake covers `[0, b/λ_k] ⊇ [0, b/λ]`: one C
//! lookup per wavelength. `sample` and `pdf` at λ are those of the model
//! nearest λ among every other one (`SAMPLER_NODES`, 0.04–0.07 µm apart).
//! Only these bake C and the halo sampler; each model between them takes C
//! from the one before it (a bake at a shorter λ covers a longer λ's u).

use super::eval::{Pair, halo_attenuation, q_bar};
use super::integrated::models_at;
use super::{
    BakeVisitor, ChannelBake, Sample, Tables, TwoScale, exp_and_one_minus_over, finite_or_zero,
};
use crate::bake::DirectionCell;
use crate::material::{ColourTerms, Options};
use crate::model::fresnel::fresnel;
use crate::spectrum::optical::SpectralMaterial;
use crate::validate::Named;
use core::borrow::{Borrow, BorrowMut};
use zerocopy::FromZeros;

/// Number of wavelengths of [`Spectral`].
pub const SPECTRAL_COUNT: usize = 19;

/// The wavelengths of [`Spectral`]'s models, µm: [0.36, 0.83], 0.02 apart
/// over 0.44–0.64 (the metals' absorption edges: gold, copper), 0.03–0.04
/// beyond (docs/model.md §2.12).
pub const SPECTRAL_WAVELENGTHS: [f32; SPECTRAL_COUNT] = [
    0.36, 0.40, 0.44, 0.46, 0.48, 0.50, 0.52, 0.54, 0.56, 0.58, 0.60, 0.62, 0.64, 0.67, 0.70, 0.73,
    0.76, 0.795, 0.83,
];

/// The models whose samplers [`Spectral::sample`] uses: every other one,
/// the first and the last included (an odd count, so that `nearest`'s
/// `e + 2` exists).
const SAMPLER_NODES: [usize; SPECTRAL_COUNT.div_ceil(2)] = {
    let mut nodes = [0; SPECTRAL_COUNT.div_ceil(2)];
    let mut j = 0;
    while j < nodes.len() {
        nodes[j] = 2 * j;
        j += 1;
    }
    nodes
};
const _: () = assert!(SPECTRAL_COUNT % 2 == 1);

/// λ nodes of [`FresnelBake`], 1 nm apart (finer than the measured
/// indices' rows: η linear in λ every 5 nm cost a rough gold up to 1% of ρ
/// at 0.496 µm).
const ETA_NODES: usize = 471;
/// First node and spacing of [`FresnelBake`]'s λ axis, µm.
const ETA_FIRST: f32 = 0.36;
const ETA_STEP: f32 = 0.001;
/// `√cos θ` nodes of [`FresnelBake`] (linear in `√cos θ`: within 4.0e-4 of
/// the closed form for the metal presets, 1.1e-3 for the dielectric ones;
/// test `fresnel_bake_is_within_its_stated_error`).
const FRESNEL_COS_NODES: usize = 65;

/// F(η(λ), cos θ) of one material on a grid of λ 1 nm apart from 0.36 µm
/// and of `√cos θ` from 0 to 1 (the closed form `fresnel::fresnel`), read
/// bilinearly by [`Spectral`], and η at those λ: 123 KiB, held as
/// [`Spectral`]'s `T` (boxed, or caller-provided storage).
#[derive(Clone, Debug, FromZeros)]
pub struct FresnelBake {
    /// η = (n, k) at the λ nodes (the table's source, for ports).
    eta: [[f32; 2]; ETA_NODES],
    rows: [[f32; FRESNEL_COS_NODES]; ETA_NODES],
}

impl FresnelBake {
    /// Empty storage on the heap, allocated zeroed (feature `std`).
    #[cfg(feature = "std")]
    pub fn boxed() -> std::boxed::Box<FresnelBake> {
        FresnelBake::new_box_zeroed().unwrap_or_else(|_| {
            std::alloc::handle_alloc_error(core::alloc::Layout::new::<FresnelBake>())
        })
    }

    /// Fills the table for `material`'s index.
    fn init(&mut self, material: &SpectralMaterial<'_>) {
        for (j, row) in self.rows.iter_mut().enumerate() {
            let eta = material.eta.at(ETA_FIRST + ETA_STEP * j as f32);
            self.eta[j] = [eta.re, eta.im];
            for (m, slot) in row.iter_mut().enumerate() {
                let mu = m as f32 / (FRESNEL_COS_NODES - 1) as f32;
                *slot = fresnel(eta, mu * mu);
            }
        }
    }

    /// The λ row below `lambda` (clamped to the table) and the fraction
    /// towards the next.
    #[inline]
    fn row(lambda: f32) -> (usize, f32) {
        let t = (lambda - ETA_FIRST) / ETA_STEP;
        // ⌊t⌋ for t ≥ 0 (`as` truncates; NaN → 0).
        let j = (t.max(0.0) as usize).min(ETA_NODES - 2);
        (j, (t - j as f32).max(0.0).min(1.0))
    }

    /// F at `lambda` (clamped to the table) and at the `cos θ` of `cell`,
    /// bilinear.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline]
    fn at(&self, lambda: f32, cell: DirectionCell) -> f32 {
        let (j, f) = Self::row(lambda);
        let (m, g) = cell.coarser::<FRESNEL_COS_NODES>();
        let (a, b) = (&self.rows[j], &self.rows[j + 1]);
        let low = a[m] + g * (a[m + 1] - a[m]);
        let high = b[m] + g * (b[m + 1] - b[m]);
        low + f * (high - low)
    }
}

/// Width of the bins of [`CELL_START`], µm.
const CELL_BIN: f32 = 0.01;
/// Bins of [`CELL_START`] over [0.36, 0.83] µm.
const CELL_BINS: usize = 48;

/// Per 0.01 µm bin from 0.36 µm, a model index at or below the hats' cell
/// of every λ in the bin: the number of inner nodes below the bin's start
/// less one, so that rounding of the bin index cannot overshoot; the nodes
/// are ≥ 0.02 µm apart, so [`cell`] steps at most twice from it.
const CELL_START: [u8; CELL_BINS] = {
    let mut start = [0u8; CELL_BINS];
    let mut j = 0;
    while j < CELL_BINS {
        let edge = SPECTRAL_WAVELENGTHS[0] + CELL_BIN * j as f32;
        let mut below = 0u8;
        let mut m = 1;
        while m + 1 < SPECTRAL_COUNT {
            if SPECTRAL_WAVELENGTHS[m] < edge {
                below += 1;
            }
            m += 1;
        }
        start[j] = below.saturating_sub(1);
        j += 1;
    }
    start
};

/// The hats' cell of `lambda` (clamped to [0.36, 0.83] µm) on
/// [`SPECTRAL_WAVELENGTHS`] (held at the ends): `(k, f)` with
/// `hat_k = 1 − f`, `hat_{k+1} = f`. The search starts at [`CELL_START`]'s
/// bin of λ.
///
/// Mirrored in python/twoscale/drjit/models.py.
#[inline]
fn cell(lambda: f32) -> (usize, f32) {
    let nodes = &SPECTRAL_WAVELENGTHS;
    // NaN and λ below the first node → bin 0 (`as` saturates).
    let bin = (((lambda - nodes[0]) * (1.0 / CELL_BIN)) as usize).min(CELL_BINS - 1);
    let mut k = usize::from(CELL_START[bin]);
    while k + 2 < nodes.len() && lambda > nodes[k + 1] {
        k += 1;
    }
    let (a, b) = (nodes[k], nodes[k + 1]);
    let f = (lambda - a) / (b - a);
    // NaN → 0.
    (k, if f > 0.0 { f.min(1.0) } else { 0.0 })
}

/// What [`Spectral`] reads of one model at a pair of directions.
#[derive(Clone, Copy, Default)]
struct NodeTerms {
    /// `σrel²/σs²`.
    ratio_sq: f64,
    /// Q̄ (1 for white colour terms, 0 for η = 1).
    q: f64,
    /// F(θd) from the model's direction bake (1 for white colour terms).
    fresnel: f64,
    /// `ρ_base + k_d/π + ρ_ms`.
    plain: f64,
}

impl NodeTerms {
    /// The terms of `node` at `pair`; `plain` 0 unless `diffuse` (the
    /// models have a base lobe, `k_d` or the compensation lobe).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    pub(super) fn new<B: Borrow<ChannelBake>>(
        node: &TwoScale<'_, B>,
        pair: &Pair,
        white: bool,
        diffuse: bool,
    ) -> Self {
        let direction = &node.bake().direction;
        let (at_i, at_o) = (
            direction.at_cell(pair.cells[0]),
            direction.at_cell(pair.cells[1]),
        );
        let (cos_i, cos_o) = (pair.geometry.wi[2], pair.geometry.wo[2]);
        let q = q_bar(
            node.q.as_ref(),
            white,
            &at_i,
            &at_o,
            pair.along,
            pair.across,
        );
        let plain = if diffuse {
            let multiple = node.multiple_value(&at_i, &at_o);
            f64::from(finite_or_zero(node.base_value(&at_i, &at_o, cos_i, cos_o)))
                + f64::from(finite_or_zero(multiple))
        } else {
            0.0
        };
        NodeTerms {
            ratio_sq: node.sigma_ratio_sq(&at_i, &at_o),
            q,
            fresnel: node.fresnel_at(pair.cells[2]),
            plain,
        }
    }
}

/// The two-scale BRDF at any wavelength of [0.36, 0.83] µm (module
/// documentation); wavelengths outside are clamped to it. The bakes are held
/// as `B` as [`TwoScale`]'s and the table of F as `T`: boxed
/// (`Spectral::boxed`, feature `std`) or in caller-provided storage
/// ([`Spectral::new_in`]); [`SPECTRAL_COUNT`] bakes and one [`FresnelBake`].
#[derive(Clone)]
pub struct Spectral<'a, B = ChannelBake, T = FresnelBake> {
    nodes: [TwoScale<'a, B>; SPECTRAL_COUNT],
    /// F(η(λ), cos θ).
    fresnel: T,
    white: bool,
    /// Whether the models have a base lobe, `k_d` or the compensation lobe
    /// (else their `ρ_base + ρ_ms` is 0 and is not evaluated).
    diffuse: bool,
}

/// [`Spectral`] with its bakes on the heap ([`Spectral::boxed`]).
#[cfg(feature = "std")]
pub type BoxedSpectral<'a> =
    Spectral<'a, std::boxed::Box<ChannelBake>, std::boxed::Box<FresnelBake>>;

#[cfg(feature = "std")]
impl<'a> BoxedSpectral<'a> {
    /// [`Spectral::new_in`] with the bakes on the heap.
    pub fn boxed(tables: &Tables<'a>, material: &SpectralMaterial<'_>, options: Options) -> Self {
        let bakes = core::array::from_fn(|_| ChannelBake::boxed());
        Self::new_in(bakes, FresnelBake::boxed(), tables, material, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>, T: BorrowMut<FresnelBake>> Spectral<'a, B, T> {
    /// The model of `material` baked into `bakes` and `fresnel` in place
    /// (see [`TwoScale::new_in`]; sanitised as [`TwoScale::new`]).
    pub fn new_in(
        bakes: [B; SPECTRAL_COUNT],
        mut fresnel: T,
        tables: &Tables<'a>,
        material: &SpectralMaterial<'_>,
        options: Options,
    ) -> Self {
        let nodes = models_at(
            bakes,
            tables,
            material,
            options,
            &SPECTRAL_WAVELENGTHS,
            &SAMPLER_NODES,
            true,
        );
        let white = options.colour == ColourTerms::White;
        fresnel.borrow_mut().init(material);
        Spectral {
            diffuse: nodes.iter().any(|node| node.has_lobes().1),
            nodes,
            fresnel,
            white,
        }
    }
}

impl<B: Borrow<ChannelBake>, T: Borrow<FresnelBake>> Spectral<'_, B, T> {
    /// The one-wavelength models, at [`SPECTRAL_WAVELENGTHS`].
    pub fn nodes(&self) -> &[TwoScale<'_, B>; SPECTRAL_COUNT] {
        &self.nodes
    }

    /// Hands the spectral constants to `v` for ports of [`Spectral::eval`]
    /// (the Python package's `Material.spectral_bakes()`): `wavelengths`
    /// ([`SPECTRAL_WAVELENGTHS`], µm), `fresnel` ([`FresnelBake`],
    /// `[ETA_NODES, FRESNEL_COS_NODES]`: λ every `eta_step` µm from
    /// `eta_first`, `√cos θ` from 0 to 1), `eta` (`[ETA_NODES, 2]`: n, k at
    /// those λ, columns `n`, `k`) and `colour` ([`ColourTerms`]' name). Each model's bakes are its node's
    /// [`TwoScale::visit_bakes`].
    #[doc(hidden)]
    pub fn visit_index(&self, v: &mut dyn BakeVisitor) {
        v.array("wavelengths", &[SPECTRAL_COUNT], &SPECTRAL_WAVELENGTHS);
        let bake = self.fresnel.borrow();
        let shape = [ETA_NODES, FRESNEL_COS_NODES];
        v.array("fresnel", &shape, bake.rows.as_flattened());
        v.array("eta", &[ETA_NODES, 2], bake.eta.as_flattened());
        v.columns("eta", &["n", "k"]);
        v.scalar("eta_first", f64::from(ETA_FIRST));
        v.scalar("eta_step", f64::from(ETA_STEP));
        let colour = if self.white {
            ColourTerms::White
        } else {
            ColourTerms::Physical
        };
        v.named(ColourTerms::OPTION, colour.name());
    }

    /// λ clamped to [0.36, 0.83] µm (NaN → 0.36).
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline]
    fn clamped(lambda: f32) -> f32 {
        let (lo, hi) = (
            SPECTRAL_WAVELENGTHS[0],
            SPECTRAL_WAVELENGTHS[SPECTRAL_COUNT - 1],
        );
        if lambda > lo { lambda.min(hi) } else { lo }
    }

    /// ρ(i, o) at `lambda` µm (module documentation). 0 below the horizon.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3], lambda: f32) -> f32 {
        match self.nodes[0].pair(i, o) {
            Some(pair) => self.finish(&pair, self.start(&pair, lambda)),
            None => 0.0,
        }
    }

    /// `eval`'s ρ at a wavelength [`Spectral::start`]ed (not `eval4`'s
    /// passes, which made the one wavelength slower).
    #[inline(always)]
    fn finish(&self, pair: &Pair, (lambda, fl, (k, f)): (f32, f64, (usize, f64))) -> f32 {
        let (a, b) = self.terms(pair, k);
        self.at_lambda(pair, lambda, fl, (k, f), &a, &b)
    }

    /// ρ(i, o) at four wavelengths (µm), as spectral renderers carry them:
    /// the pair's geometry, D and G once, then three passes over the
    /// wavelengths, so that the four wavelengths' table reads overlap:
    /// `Spectral::start` (F), `Spectral::terms`, `Spectral::at_lambda`.
    /// (Plain loops: `array::map`'s closures here were not inlined;
    /// docs/design/rgb-integration.md.)
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn eval4(&self, i: [f32; 3], o: [f32; 3], lambdas: [f32; 4]) -> [f32; 4] {
        let Some(pair) = self.nodes[0].pair(i, o) else {
            return [0.0; 4];
        };
        let mut started = [(0.0, 0.0, (0, 0.0)); 4];
        for (s, &lambda) in started.iter_mut().zip(&lambdas) {
            *s = self.start(&pair, lambda);
        }
        let mut terms = [(NodeTerms::default(), NodeTerms::default()); 4];
        for (t, &(_, _, (k, _))) in terms.iter_mut().zip(&started) {
            *t = self.terms(&pair, k);
        }
        let mut out = [0.0; 4];
        for ((o, &(lambda, fl, kf)), (a, b)) in out.iter_mut().zip(&started).zip(&terms) {
            *o = self.at_lambda(&pair, lambda, fl, kf, a, b);
        }
        out
    }

    /// What comes first at `lambda`: λ clamped, its models' cell `(k, f)`
    /// and F(η(λ), θd).
    #[inline(always)]
    fn start(&self, pair: &Pair, lambda: f32) -> (f32, f64, (usize, f64)) {
        let lambda = Self::clamped(lambda);
        let (k, f) = cell(lambda);
        let fl = self.fresnel_at(lambda, pair.cells[2]);
        (lambda, fl, (k, f64::from(f)))
    }

    /// The terms of the models `k` and `k + 1` ([`NodeTerms`]; not shared
    /// between wavelengths: a renderer's wavelengths rarely share a model,
    /// and a cache cost more than it saved).
    #[inline(always)]
    fn terms(&self, pair: &Pair, k: usize) -> (NodeTerms, NodeTerms) {
        (
            NodeTerms::new(&self.nodes[k], pair, self.white, self.diffuse),
            NodeTerms::new(&self.nodes[k + 1], pair, self.white, self.diffuse),
        )
    }

    /// F(η(λ), θd) at `lambda` (clamped) and the cell of `cos θd`
    /// ([`FresnelBake`]), or 1 for white colour terms.
    #[inline]
    pub(super) fn fresnel_at(&self, lambda: f32, cos_d: DirectionCell) -> f64 {
        if self.white {
            1.0
        } else {
            f64::from(self.fresnel.borrow().at(lambda, cos_d))
        }
    }

    /// ρ at `lambda` (clamped) between the models `k` and `k + 1` (terms `a`,
    /// `b`, fraction `f`; `fl` = [`Spectral::fresnel_at`] λ; docs/model.md
    /// §2.12): the surface lobes at λ itself
    /// (F(θd) of η(λ), A_spec, (1 − A)/σrel² and the halo's constant at λ, C
    /// at `u = b cos θd/λ` from model `k`'s bake, which covers `[0, b/λ_k]`),
    /// σrel/σs and Q̄/F(θd) linear in λ between the models; the base lobes
    /// linear in λ.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    fn at_lambda(
        &self,
        pair: &Pair,
        lambda: f32,
        fl: f64,
        (k, f): (usize, f64),
        a: &NodeTerms,
        b: &NodeTerms,
    ) -> f32 {
        let lerp = |x: f64, y: f64| (1.0 - f) * x + f * y;
        let node = &self.nodes[k];
        let geometry = &pair.geometry;
        let (cos_i, cos_o, cos_d) = (geometry.wi[2], geometry.wo[2], geometry.cos_d);
        // λ_k/λ: B, the exponents' (4π/λ)² and the halo's 1/λ² from model k's.
        let ratio = node.lambda / f64::from(lambda);
        let x_scale = node.x_scale * ratio * ratio;
        let s = &node.surface;
        let sigma_rel_sq = if s.sigma_s > 0.0 {
            node.sigma_s_sq * lerp(a.ratio_sq, b.ratio_sq)
        } else {
            0.0
        };
        // A_spec = exp(−x σrel²), x = (4π cos θd / λ)²                (HP17 25)
        let (a_spec, one_minus_a_over) =
            exp_and_one_minus_over(x_scale * cos_d * cos_d, sigma_rel_sq);
        // ρ_CT = F D G / (4 cos θi cos θo)                              (HP17 26)
        let specular = a_spec * fl * pair.g / (4.0 * cos_i * cos_o) * pair.d;
        // ρ_CTD = Q̄ G (1 − A)/σrel² (c−1) σs² b² / (2π λ²) C(θh; b cos θd/λ)   (HP17 32-33)
        let diffraction = if s.sigma_s > 0.0 && s.b > 0.0 && pair.g > 0.0 {
            let q = if self.white {
                1.0
            } else if a.fresnel > 0.0 && b.fresnel > 0.0 {
                fl * lerp(a.q / a.fresnel, b.q / b.fresnel)
            } else {
                lerp(a.q, b.q)
            };
            let halo = node.halo_scale
                * ratio
                * ratio
                * halo_attenuation(
                    node.options.halo_weight,
                    one_minus_a_over,
                    x_scale,
                    cos_i,
                    sigma_rel_sq,
                );
            let u = (node.big_b * ratio * cos_d) as f32;
            q * pair.g * halo * node.conv_at(geometry.sin_h, geometry.cos_h, u)
        } else {
            0.0
        };
        let value = f64::from(finite_or_zero(specular))
            + f64::from(finite_or_zero(diffraction))
            + lerp(a.plain, b.plain);
        finite_or_zero(value.max(0.0))
    }

    /// The model whose sampler serves `lambda`: the nearest of
    /// [`SAMPLER_NODES`] (the even ones), the lower on a tie.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    fn nearest(&self, lambda: f32) -> &TwoScale<'_, B> {
        let lambda = Self::clamped(lambda);
        // The even nodes around λ: `e` at or below the hats' cell, `e + 2`.
        let e = cell(lambda).0 & !1;
        let w = &SPECTRAL_WAVELENGTHS;
        &self.nodes[if lambda + lambda <= w[e] + w[e + 2] {
            e
        } else {
            e + 2
        }]
    }

    /// The density of [`Spectral::sample`] at `lambda`.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3], lambda: f32) -> f32 {
        self.nearest(lambda).pdf(i, o)
    }

    /// Samples an outgoing direction for the (hero) wavelength `lambda`
    /// with the sampler of the nearest sampler model; the value is
    /// [`Spectral::eval`] at `lambda`.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn sample(&self, i: [f32; 3], u: [f32; 3], lambda: f32) -> Option<Sample> {
        let node = self.nearest(lambda);
        let (o, lobe) = node.sample_direction(i, u)?;
        let pdf = finite_or_zero(node.pdf_at(&node.geometry(i, o)?));
        if !(pdf > 0.0) {
            return None;
        }
        Some(Sample {
            o,
            pdf,
            value: self.eval(i, o, lambda),
            lobe,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::SPECTRAL_PRESETS;
    use crate::math::Complex;
    use crate::test_rng::Lcg;

    /// [`FresnelBake`] against the closed form, at 20 000 random (λ, cos θ)
    /// per preset: at η linear between the 1 nm nodes (the table's own
    /// error, its linear interpolation in √cos θ) within 4.5e-4 relative for
    /// the metals and 2e-3 for the dielectrics (Brewster's minimum of F);
    /// at the material's own η(λ) within 1.2e-3 (the measured rows' kinks
    /// between two 1 nm nodes add up to 1.1e-3 for gold at 0.4714 µm).
    #[test]
    fn fresnel_bake_is_within_its_stated_error() {
        let mut rng = Lcg(41);
        let mut bake = FresnelBake::new_zeroed();
        for preset in &SPECTRAL_PRESETS {
            let material = &preset.material;
            bake.init(material);
            let (mut own, mut measured) = (0.0f64, 0.0f64);
            for _ in 0..20_000 {
                let lambda = (0.36 + 0.47 * rng.next()) as f32;
                let cos = rng.next() as f32;
                let table = f64::from(bake.at(lambda, DirectionCell::new(cos)));
                let (j, f) = FresnelBake::row(lambda);
                let [a, b] = [bake.eta[j], bake.eta[j + 1]];
                let linear = Complex::new(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
                let relative = |eta: Complex| (table / f64::from(fresnel(eta, cos)) - 1.0).abs();
                own = own.max(relative(linear));
                measured = measured.max(relative(material.eta.at(lambda)));
            }
            let dielectric = material.eta.at(0.5).im == 0.0;
            let bound = if dielectric { 2e-3 } else { 4.5e-4 };
            std::eprintln!("{}: {own:.2e} ({measured:.2e} at η(λ))", preset.name);
            assert!(
                own < bound && measured < 1.2e-3,
                "{}: {own:e} {measured:e}",
                preset.name
            );
        }
    }
}
