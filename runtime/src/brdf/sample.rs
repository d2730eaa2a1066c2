//! Sampling: the lobe weights, `sample` and its `pdf` (docs/model.md §2.7).

use super::ChannelBake;
use super::Lobe;
use super::Sample;
use super::TwoScale;
use super::dot;
use super::eval::Geometry;
use super::finite_or_zero;
use super::to_f32;
use crate::bake::DirectionValues;
use crate::bake::visible::VisibleIncidence;
use crate::material::BaseLayer;
use crate::math::{self, BELOW_ONE, upper_unit};
use core::borrow::{Borrow, BorrowMut};
use core::f64::consts::PI;

/// The albedo estimates of the lobes at one incidence, for
/// [`TwoScale::weights_at`].
#[derive(Clone, Copy, Debug)]
pub(super) struct LobeEnergies {
    /// `E(μ; β, p)` of T6 (F = 1, no A).
    pub(super) specular: f64,
    /// `∫ ρ_CTD cos θo dωo`.
    pub(super) halo: f64,
}

/// Incidences of [`TwoScale::halo_albedo_nodes`] (every 32nd node of the
/// direction bake's 257).
const HALO_ALBEDO_NODES: usize = 9;

/// Lattice points per incidence, and the lattice's generator (Fibonacci).
const HALO_ALBEDO_POINTS: usize = 34;

const HALO_ALBEDO_STRIDE: usize = 21;

/// The diffraction lobe's smallest share of the estimated albedo.
const HALO_FLOOR: f64 = 1e-3;

/// The halo albedo between [`HALO_ALBEDO_NODES`], linear in `√cos θi`.
pub(super) fn halo_albedo_at(nodes: &[f64; HALO_ALBEDO_NODES], cos: f64) -> f64 {
    let x = math::sqrt(cos.max(0.0).min(1.0)) * (HALO_ALBEDO_NODES - 1) as f64;
    let k = (x as usize).min(HALO_ALBEDO_NODES - 2);
    let t = x - k as f64;
    nodes[k] + t * (nodes[k + 1] - nodes[k])
}

/// The lobe weights of three channels whose samplers are mixed with equal
/// probability under one density ([`Rgb::pdf`]), set in each channel's
/// table. With `s_cl` a channel's own weights (its lobes'
/// albedo shares, [`TwoScale::lobe_weights`]), the mixture picks lobe `l` with
///
/// ```text
/// π_l ∝ (min_c s_cl + max_c s_cl) / 2,     Σ_l π_l = 1
/// ```
///
/// and the halo's `π_h` is split over the channels' halo draws (whose shapes
/// differ) as their own shares, channel `c`'s weights being
///
/// ```text
/// w_ch = min(1, 3 π_h s_ch / Σ_c' s_c'h),   w_cl = π_l (1 − w_ch)/(1 − π_h)  (l ≠ h)
/// ```
///
/// so that `(1/3) Σ_c w_cl = π_l`. For lobes apart, a channel's relative
/// variance is at least `Σ_l s_cl²/π_l − 1`; with two lobes that is
/// `(s_c − π)²/(π (1 − π))`, whose largest over the channels is smallest at
/// the mid-range `π = (min s_c + max s_c)/2`. Each channel's own weights
/// (the mixture `π_l = mean_c s_cl`) sent the lobe carrying most of the
/// energy in one channel too few samples (docs/design/halo-sampling.md;
/// not applied to `IntegratedRgb`'s sampler nodes, where it raised the
/// presets' largest variance by up to 10%).
pub(super) fn share_lobe_weights<B: BorrowMut<ChannelBake>>(channels: [&mut TwoScale<'_, B>; 3]) {
    let nodes = {
        let own = |cos: f64| channels.each_ref().map(|ch| ch.weights(cos));
        let shared = |c: usize, cos: f64| shared_lobe_weights(own(cos))[c];
        [0, 1, 2].map(|c| {
            channels[c]
                .bake()
                .direction
                .lobe_weight_nodes(|_, cos| shared(c, cos))
        })
    };
    for (channel, nodes) in channels.into_iter().zip(&nodes) {
        channel.bake.borrow_mut().direction.set_lobe_weights(nodes);
    }
}

/// [`share_lobe_weights`] at one incidence: the channels' weights from
/// their own (normalised) weights `s`.
fn shared_lobe_weights(s: [[f64; 4]; 3]) -> [[f64; 4]; 3] {
    let mut pi = [0usize, 1, 2, 3].map(|l| {
        let (lo, hi) = s.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
            (lo.min(w[l]), hi.max(w[l]))
        });
        0.5 * (lo + hi)
    });
    let total: f64 = pi.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return s;
    }
    pi = pi.map(|x| x / total);
    let halo: f64 = s.iter().map(|w| w[1]).sum();
    let rest = 1.0 - pi[1];
    s.map(|w| {
        let h = if halo > 0.0 {
            (3.0 * pi[1] * w[1] / halo).min(1.0)
        } else {
            0.0
        };
        let k = if rest > 0.0 { (1.0 - h) / rest } else { 0.0 };
        [pi[0] * k, h, pi[2] * k, pi[3] * k]
    })
}

/// The lobe whose cumulative-weight interval holds `pick ∈ [0, 1)`; rounding
/// past the last interval falls on the last lobe of positive weight.
///
/// Mirrored in python/twoscale/drjit/lobes.py.
fn pick_lobe(pick: f64, w: [f64; 4]) -> Lobe {
    const LOBES: [Lobe; 4] = [
        Lobe::Specular,
        Lobe::Diffraction,
        Lobe::Base,
        Lobe::Multiple,
    ];
    let mut cumulative = 0.0;
    let mut last = Lobe::Specular;
    for (k, lobe) in LOBES.into_iter().enumerate() {
        if w[k] > 0.0 {
            cumulative += w[k];
            last = lobe;
            if pick < cumulative {
                return lobe;
            }
        }
    }
    last
}

impl<'a, B: Borrow<ChannelBake>> TwoScale<'a, B> {
    /// The lobe-selection probabilities `[specular, diffraction, base,
    /// multiple]` for incidence `i` (sum 1; all 0 for `i` below the horizon),
    /// proportional to estimates of the lobes' directional albedos at θi
    /// (docs/design/halo-sampling.md):
    ///
    /// ```text
    /// E_s  = A(θi) F(η, cos θi) E(μ; β, p)      A(θi) = exp(−(4π σrel(θi) cos θi / λ)²) (HP17 25),
    ///                                           E of T6 (F = 1), F = 1 with white colour terms
    /// E_d  = ∫ ρ_CTD cos θo dωo                  by the diffraction lobe's own sampler, 34 lattice
    ///                                           points at 9 incidences, linear in √cos θi between
    /// E_b  = base albedo estimate: plastic (1 − F(θi)) ρd (1 − F_dr,int)/(1 − ρd F_dr,int)
    ///        (its exact albedo), subsurface (1 − F(θi)) α, plus k_d
    /// E_ms = F_ms (1 − E_w(μi)), the compensation lobe's albedo (0 when off), E_w the white
    ///        albedo of docs/model.md §2.11 (T6's E plus the halo's deficit)
    /// w    ∝ [E_s, max(E_d, 10⁻³ ΣE), E_b, E_ms]  (E_d's floor only where the lobe exists)
    /// ```
    ///
    /// When every estimate is 0 (η = 1 and no base) the split
    /// `[A, 1 − A, 0, 0]` is used. The weights are tabulated with the material
    /// (linear in `√cos θi` between 257 nodes): `sample` and `pdf` read the
    /// same table, so the weights add no error to the pdf.
    pub fn lobe_weights(&self, i: [f32; 3]) -> [f32; 4] {
        let Some(wi) = upper_unit(i) else {
            return [0.0; 4];
        };
        self.weights(wi[2]).map(|w| w as f32)
    }

    /// The lobe weights at `cos θi`, from the direction bake's table of
    /// [`TwoScale::weights_at`].
    fn weights(&self, cos_i: f64) -> [f64; 4] {
        self.bake().direction.lobe_weights(cos_i as f32)
    }

    /// The diffraction lobe's directional albedo at [`HALO_ALBEDO_NODES`]
    /// incidences even in `√cos θi`, estimated with its own sampler on a
    /// rank-1 lattice of [`HALO_ALBEDO_POINTS`] points (deterministic;
    /// zeros without a diffraction lobe). Needs the bakes but not the
    /// lobe weights.
    pub(super) fn halo_albedo_nodes(&self) -> [f64; HALO_ALBEDO_NODES] {
        let mut out = [0.0; HALO_ALBEDO_NODES];
        if !self.has_lobes().0 {
            return out;
        }
        let n = HALO_ALBEDO_POINTS;
        for (k, slot) in out.iter_mut().enumerate().skip(1) {
            let x = k as f64 / (HALO_ALBEDO_NODES - 1) as f64;
            let cos = x * x;
            let i = [
                math::sqrt((1.0 - cos * cos).max(0.0)) as f32,
                0.0,
                cos as f32,
            ];
            let mut sum = 0.0;
            for j in 0..n {
                let u0 = (j as f64 + 0.5) / n as f64;
                let u1 = ((j * HALO_ALBEDO_STRIDE) as f64 + 0.5) / n as f64;
                let u = [u0 as f32, (u1 - math::floor(u1)) as f32];
                let Some(o) = self.sample_lobe(Lobe::Diffraction, i, u) else {
                    continue;
                };
                let Some(geometry) = self.geometry(i, o) else {
                    continue;
                };
                let pdf = self.diffraction_pdf(&geometry);
                if pdf > 0.0 {
                    let value = f64::from(self.lobes(&self.with_masking(geometry)).diffraction);
                    sum += value * geometry.wo[2] / pdf;
                }
            }
            let e = sum / n as f64;
            *slot = if e.is_finite() { e } else { 0.0 };
        }
        out
    }

    /// The lobe weights (see [`TwoScale::lobe_weights`]) with F from `at_i`
    /// and the lobes' albedo estimates `e`.
    pub(super) fn weights_at(
        &self,
        at_i: &DirectionValues,
        cos_i: f64,
        e: LobeEnergies,
    ) -> [f64; 4] {
        let sigma_rel = f64::from(self.surface.sigma_s) * at_i.sigma_ratio();
        let t = self.x_scale * cos_i * cos_i * sigma_rel * sigma_rel;
        let a = math::exp(-t);
        let e_s = a * self.fresnel_of(at_i) * e.specular;
        let mut e_b = self.lambertian;
        if !self.white() {
            let into = 1.0 - at_i.fresnel();
            e_b += match self.base {
                BaseLayer::Conductor => 0.0,
                BaseLayer::Plastic { albedo } => {
                    let rho_d = f64::from(albedo);
                    into * rho_d * (1.0 - self.f_dr_int) / (1.0 - rho_d * self.f_dr_int)
                }
                BaseLayer::Subsurface { albedo } => into * f64::from(albedo),
            };
        }
        let mut e_d = e.halo.max(0.0);
        if self.has_lobes().0 {
            e_d = e_d.max(HALO_FLOOR * (e_s + e_d + e_b));
        }
        // ∫ ρ_ms cos θo dωo = F_ms (1 − E_s(μi)): π (1 − E_avg) cancels.
        let e_ms = self.multiple_colour * at_i.lost();
        let w = [e_s, e_d, e_b, e_ms];
        let total = w[0] + w[1] + w[2] + w[3];
        if total > 0.0 && total.is_finite() {
            w.map(|x| x / total)
        } else {
            [a, 1.0 - a, 0.0, 0.0]
        }
    }

    /// The solid-angle density over `o` of [`TwoScale::sample`] for incidence
    /// `i`: `Σ_k w_k(i) pdf_k(i, o)` with the weights of
    /// [`TwoScale::lobe_weights`] and the lobe densities of
    /// [`TwoScale::pdf_lobe`]. 0 below the horizon.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.geometry(i, o) {
            Some(geometry) => finite_or_zero(self.pdf_at(&geometry)),
            None => 0.0,
        }
    }

    /// [`TwoScale::pdf`] at a pair's geometry.
    pub(super) fn pdf_at(&self, geometry: &Geometry) -> f64 {
        self.pdf_with_specular(geometry, self.specular_pdf(geometry))
    }

    /// The specular lobe's density at a pair (wavelength independent).
    #[inline]
    pub(super) fn specular_pdf(&self, geometry: &Geometry) -> f64 {
        self.bake().visible.pdf(geometry.wi, geometry.wo)
    }

    /// [`TwoScale::pdf_at`] given the specular lobe's density `specular`
    /// (which [`Rgb`] computes once for its channels).
    pub(super) fn pdf_with_specular(&self, geometry: &Geometry, specular: f64) -> f64 {
        self.pdf_with(geometry, &self.weights(geometry.wi[2]), specular)
    }

    /// [`TwoScale::pdf_at`] given the lobe weights `w` at θi and the
    /// specular lobe's density `specular` (which [`TwoScale::sample`] has from
    /// its draw).
    fn pdf_with(&self, geometry: &Geometry, w: &[f64; 4], specular: f64) -> f64 {
        let mut total = 0.0;
        if w[0] > 0.0 {
            total += w[0] * specular;
        }
        if w[1] > 0.0 {
            total += w[1] * self.lobe_pdf(Lobe::Diffraction, geometry);
        }
        // The base and the compensation lobe share the cosine-weighted density.
        let diffuse = w[2] + w[3];
        if diffuse > 0.0 {
            total += diffuse * self.lobe_pdf(Lobe::Base, geometry);
        }
        total
    }

    /// The solid-angle density of [`TwoScale::sample_lobe`] for one lobe:
    ///
    /// * specular: the density of reflecting `i` about a visible EPD normal
    ///   (the tabulated `D_vis`, `crate::bake::visible`: `P2_tab g_tab / (8 N_tab β²
    ///   |i'| cos⁴θh)`, docs/model.md §2.1), 0 where `i·h ≤ 0`;
    /// * diffraction: the half-vector draw's where C is baked, else the
    ///   spectrum's. The spectrum's
    ///   (HP17 51-55): with `d = o_p + i_p` (the tangential parts;
    ///   `|d| = λ f`), `B = b/λ`, `s = sin θi`,
    ///   `M = 1 − (1 + B²(1 + s)²)^(−(c−1)/2)` and `φmax(|d|)` of (HP17 53),
    ///   `pdf = (c−1) B² (1 + B²|d|²)^(−(c+1)/2) / (2 M φmax) · cos θo`; the
    ///   half-vector draw's `Σ_j w_j p_j(ζ) cos θo / (4 N(θh))` (`crate::bake::halo`);
    /// * base and multiple: `cos θo / π`.
    ///
    /// 0 below the horizon or where the lobe cannot produce `o`.
    pub fn pdf_lobe(&self, lobe: Lobe, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.geometry(i, o) {
            Some(geometry) => finite_or_zero(self.lobe_pdf(lobe, &geometry)),
            None => 0.0,
        }
    }

    /// [`TwoScale::pdf_lobe`] at a pair's geometry.
    fn lobe_pdf(&self, lobe: Lobe, geometry: &Geometry) -> f64 {
        let wo = geometry.wo;
        match lobe {
            Lobe::Specular => self.specular_pdf(geometry),
            Lobe::Diffraction => self.diffraction_pdf(geometry),
            Lobe::Base | Lobe::Multiple => wo[2] / PI,
        }
    }

    /// `(B, s, 1/M)` of the diffraction sampler (M of HP17 52 from the
    /// bake), or `None` when the spectrum is degenerate (σs = 0 or b = 0) or
    /// M is not positive.
    fn diffraction_setup(&self, wi: [f64; 3]) -> Option<(f64, f64, f64)> {
        if !(self.surface.sigma_s > 0.0 && self.big_b > 0.0) {
            return None;
        }
        let sin_i = math::sqrt(wi[0] * wi[0] + wi[1] * wi[1]).min(1.0);
        let inv_m = self.bake().radial_norm.inv_m(sin_i);
        if !(inv_m > 0.0) {
            return None;
        }
        Some((self.big_b, sin_i, inv_m))
    }

    /// φmax of (HP17 53) for `r = λ f`: the half-width of the arc of
    /// directions of `d` around `i_p` that keeps `o_p = d − i_p` in the unit disc.
    fn phi_max(r: f64, sin_i: f64) -> f64 {
        if r + sin_i <= 1.0 {
            return PI;
        }
        let x = (r * r + sin_i * sin_i - 1.0) / (2.0 * r * sin_i);
        math::acos_approx(x.max(-1.0).min(1.0))
    }

    /// The diffraction lobe's density: the half-vector draw of [`HaloBake`],
    /// `p(h) / (4 i·h)`, when the C bake is there; else the spectrum's draw.
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    fn diffraction_pdf(&self, geometry: &Geometry) -> f64 {
        let Geometry {
            wi,
            wo,
            cos_d,
            cos_h,
            sin_h,
            ..
        } = *geometry;
        match self.bake().halo() {
            Some(halo) if cos_d > 0.0 => halo.pdf(wi, self.big_b * wi[2], sin_h, cos_h, wo[2]),
            Some(_) => 0.0,
            None => self.spectrum_pdf(wi, wo),
        }
    }

    /// The density of the spectrum's draw (HP17 51-55).
    fn spectrum_pdf(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let Some((b, sin_i, inv_m)) = self.diffraction_setup(wi) else {
            return 0.0;
        };
        let (dx, dy) = (wo[0] + wi[0], wo[1] + wi[1]);
        let r = math::sqrt(dx * dx + dy * dy);
        if r > 1.0 + sin_i {
            return 0.0;
        }
        let phi_max = Self::phi_max(r, sin_i);
        if !(phi_max > 0.0) {
            return 0.0;
        }
        let c = f64::from(self.surface.c);
        let density =
            (c - 1.0) * b * b * math::pow_positive(1.0 + b * b * r * r, -0.5 * (c + 1.0)) * inv_m
                / (2.0 * phi_max);
        density * wo[2]
    }

    /// Samples `o` from one lobe with the uniforms `u` (clamped to [0, 1));
    /// `None` when `i` is below the horizon, the lobe is degenerate, or the
    /// direction falls at or below the horizon. Its density is
    /// [`TwoScale::pdf_lobe`].
    ///
    /// * specular: `m` a visible normal of the EPD (the tabulated visible-slope
    ///   sampler of docs/model.md §2.1, `u` its two uniforms), `o = 2(i·m)m − i`;
    /// * diffraction: the half-vector draw of `crate::bake::halo` reflected where C
    ///   is baked, else the spectrum's draw
    ///   (HP17 51-55): `r = λ f = √((1 − M u₀)^(−2/(c−1)) − 1) / B`,
    ///   `ψ = (2u₁ − 1) φmax(r)`, `d = r (cos(φi + ψ), sin(φi + ψ))`,
    ///   `o_p = d − i_p`. (HP17 54-55) write the same arc as `φf = φi + π ± φmax`
    ///   with `o_p = −i_p + λ f`; the arc that keeps `o_p` in the disc is
    ///   centred on `+i_p` as written here (at ψ = 0, `o_p` moves from the
    ///   mirror direction towards `i`'s side);
    /// * base and multiple: cosine-weighted hemisphere.
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    pub fn sample_lobe(&self, lobe: Lobe, i: [f32; 3], u: [f32; 2]) -> Option<[f32; 3]> {
        let wi = upper_unit(i)?;
        let visible = match lobe {
            Lobe::Specular => Some(self.bake().visible.incidence(wi)),
            _ => None,
        };
        self.draw_lobe(lobe, wi, visible.as_ref(), u)
    }

    /// [`TwoScale::sample_lobe`] for the unit incidence `wi`, with the
    /// visible-normal sampler's incidence `visible` (needed for the specular
    /// lobe only).
    fn draw_lobe(
        &self,
        lobe: Lobe,
        wi: [f64; 3],
        visible: Option<&VisibleIncidence>,
        u: [f32; 2],
    ) -> Option<[f32; 3]> {
        let u = u.map(|x| f64::from(x.max(0.0).min(BELOW_ONE)));
        let o = match lobe {
            Lobe::Specular => {
                let m = self.bake().visible.sample_at(visible?, u)?;
                let k = 2.0 * dot(wi, m);
                [k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]]
            }
            Lobe::Diffraction => self.sample_diffraction(wi, u)?,
            Lobe::Base | Lobe::Multiple => {
                let r = math::sqrt(u[0]);
                let phi = 2.0 * PI * u[1];
                [
                    r * math::cos(phi),
                    r * math::sin(phi),
                    math::sqrt((1.0 - u[0]).max(0.0)),
                ]
            }
        };
        let o = upper_unit(to_f32(o))?;
        Some(to_f32(o))
    }

    /// The diffraction lobe's draw: a half-vector from [`HaloBake`] (`u[1]`
    /// picks its row and then the azimuth, `u[0]` gives θh) reflected, when
    /// the C bake is there; else the spectrum's.
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    fn sample_diffraction(&self, wi: [f64; 3], u: [f64; 2]) -> Option<[f64; 3]> {
        let Some(halo) = self.bake().halo() else {
            return self.sample_spectrum(wi, u);
        };
        let m = halo.sample_h(wi, self.big_b * wi[2], u[1], u[0])?;
        let k = 2.0 * dot(wi, m);
        if !(k > 0.0) {
            return None;
        }
        Some([k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]])
    }

    /// The spectrum's draw (HP17 51-55; [`TwoScale::sample_lobe`]).
    fn sample_spectrum(&self, wi: [f64; 3], u: [f64; 2]) -> Option<[f64; 3]> {
        let (b, sin_i, inv_m) = self.diffraction_setup(wi)?;
        let m = 1.0 / inv_m;
        let c = f64::from(self.surface.c);
        let t = -2.0 / (c - 1.0) * f64::from(math::ln_1pf((-m * u[0]) as f32)); // (HP17 51)
        let r = (math::sqrt(f64::from(math::exp_m1f(t as f32)).max(0.0)) / b).min(1.0 + sin_i);
        let psi = (2.0 * u[1] - 1.0) * Self::phi_max(r, sin_i); // (HP17 53-54)
        let (cos_phi_i, sin_phi_i) = if sin_i > 0.0 {
            (wi[0] / sin_i, wi[1] / sin_i)
        } else {
            (1.0, 0.0)
        };
        let (cp, sp) = (math::cos(psi), math::sin(psi));
        let dir = [
            cos_phi_i * cp - sin_phi_i * sp,
            sin_phi_i * cp + cos_phi_i * sp,
        ];
        let ox = r * dir[0] - wi[0]; // (HP17 55)
        let oy = r * dir[1] - wi[1];
        let z2 = 1.0 - ox * ox - oy * oy;
        if !(z2 > 0.0) {
            return None;
        }
        Some([ox, oy, math::sqrt(z2)])
    }

    /// Samples an outgoing direction for incidence `i` from three uniforms:
    /// `u[0]` picks the lobe with the weights of [`TwoScale::lobe_weights`]
    /// (and is rescaled), `u[1], u[2]` drive [`TwoScale::sample_lobe`].
    /// Returns the direction, [`TwoScale::pdf`] there (> 0) and ρ there;
    /// `None` when nothing can be sampled (see `sample_lobe`). The specular
    /// lobe draws visible normals from the material's tabulated visible-slope
    /// density, which `pdf` evaluates (docs/model.md §2.1).
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<Sample> {
        let wi = upper_unit(i)?;
        // The lobe weights and the visible-normal sampler's incidence serve
        // the draw and the pdf: the same values `pdf(i, o)` computes from `i`.
        let w = self.weights(wi[2]);
        let lobe = pick_lobe(f64::from(u[0].max(0.0).min(BELOW_ONE)), w);
        let visible = (w[0] > 0.0).then(|| self.bake().visible.incidence(wi));
        let o = self.draw_lobe(lobe, wi, visible.as_ref(), [u[1], u[2]])?;
        // pdf(i, o) and eval(i, o) from one geometry.
        let geometry = self.geometry(i, o)?;
        let specular = match &visible {
            Some(inc) => self.bake().visible.pdf_at(inc, geometry.wi, geometry.wo),
            None => 0.0,
        };
        let pdf = finite_or_zero(self.pdf_with(&geometry, &w, specular));
        if !(pdf > 0.0) {
            return None;
        }
        Some(Sample {
            o,
            pdf,
            value: self.lobes(&self.with_masking(geometry)).total(),
            lobe,
        })
    }

    /// The direction and lobe of [`TwoScale::sample`].
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub(super) fn sample_direction(&self, i: [f32; 3], u: [f32; 3]) -> Option<([f32; 3], Lobe)> {
        let wi = upper_unit(i)?;
        let w = self.weights(wi[2]);
        let pick = f64::from(u[0].max(0.0).min(BELOW_ONE));
        let lobe = pick_lobe(pick, w);
        Some((self.sample_lobe(lobe, i, [u[1], u[2]])?, lobe))
    }
}
