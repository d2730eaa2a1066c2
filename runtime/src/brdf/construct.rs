//! Construction: what [`TwoScale`] bakes once per material and wavelength,
//! and the bakes handed to ports ([`TwoScale::visit_bakes`]).

use super::ChannelBake;
use super::Tables;
use super::TwoScale;
use super::eval::halo_attenuation;
use super::eval::masking_g;
use super::eval::q_bar;
use super::eval::sigma_ratio_sq;
use super::exp_and_one_minus_over;
use super::sample::LobeEnergies;
use super::sample::halo_albedo_at;
use super::to_f32;
use crate::bake::BakeVisitor;
use crate::material::{
    BaseLayer, ColourTerms, HaloWeight, Layer, Masking, MultipleScattering, Options, SigmaRelMode,
    Surface,
};
use crate::math::{self, Complex};
use crate::model::epd::Epd;
use crate::model::fresnel::{QConstants, fresnel_average};
use crate::tables::convolution::ConvSlice;
use crate::validate::Named;
use core::borrow::{Borrow, BorrowMut};
use core::f64::consts::PI;
use zerocopy::FromZeros;

/// What [`TwoScale::new`] derives from the surface alone, independent of the
/// wavelength: made once for the three channels of [`Rgb`] (G1 and the
/// visible-slope tables are baked once, into the first channel, and copied).
pub(super) struct SurfaceBakes<'a> {
    pub(super) ndf: Epd<'a>,
    /// Sanitised surface (β, p as the EPD clamps them; σs = 0 when c ≤ 1).
    pub(super) surface: Surface,
    /// T3b's material slice when there is diffraction and the source of C
    /// offers one.
    pub(super) slice: Option<ConvSlice<'a>>,
}

impl<'a> SurfaceBakes<'a> {
    /// Sanitises `s` (as [`TwoScale::new`] documents) and blends C's
    /// material slice.
    pub(super) fn new(tables: &Tables<'a>, s: Surface) -> Self {
        let nonneg = |x: f32| if x > 0.0 { x.min(f32::MAX) } else { 0.0 };
        let c_ok = s.c > 1.0;
        let ndf = Epd::new(s.beta, s.p, &tables.smith);
        let surface = Surface {
            beta: ndf.beta(),
            p: ndf.p(),
            sigma_s: if c_ok { nonneg(s.sigma_s) } else { 0.0 },
            b: nonneg(s.b),
            c: if c_ok { s.c.min(1e6) } else { 2.0 },
        };
        let slice = if surface.sigma_s > 0.0 {
            tables
                .convolution
                .material_slice(surface.c, surface.beta, surface.p)
        } else {
            None
        };
        SurfaceBakes {
            ndf,
            surface,
            slice,
        }
    }

    /// Bakes G1 and the sampler's visible-slope tables into `bake`.
    pub(super) fn bake_into(&self, tables: &Tables<'a>, bake: &mut ChannelBake) {
        let (beta, p) = (self.ndf.beta(), self.ndf.p());
        bake.masking.init(beta, &tables.smith.shape(p));
        bake.visible.init(beta, p);
    }
}

impl<'a> TwoScale<'a> {
    /// The model for `layer` at wavelength `lambda` (µm) and index `eta`.
    /// Construct once per material and wavelength: it bakes the tables of
    /// [`ChannelBake`] (cost: `cargo bench --bench brdf -- construct`). The
    /// value is 141 KB: on small stacks use `TwoScale::boxed` or
    /// [`TwoScale::new_in`].
    ///
    /// Sanitising: β and p as [`Epd::new`]; σs, b negative or NaN → 0; c NaN
    /// or ≤ 1 → no diffraction (σs = 0); λ NaN or ≤ 0 → 0.526 µm, λ clamped to
    /// [0.01, 100] µm; albedos and `k_d` clamped to [0, 1].
    pub fn new(
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        Self::new_in(ChannelBake::zeroed(), tables, layer, lambda, eta, options)
    }

    /// A conductor (no base layer, no Lambertian term) with the default options.
    pub fn conductor(tables: &Tables<'a>, surface: Surface, lambda: f32, eta: Complex) -> Self {
        let layer = Layer {
            surface,
            base: BaseLayer::Conductor,
            lambertian: 0.0,
        };
        Self::new(tables, layer, lambda, eta, Options::default())
    }
}

#[cfg(feature = "std")]
impl<'a> TwoScale<'a, std::boxed::Box<ChannelBake>> {
    /// [`TwoScale::new`] with the bakes on the heap (`ChannelBake::boxed`,
    /// filled in place): the value is a few hundred bytes, and construction
    /// runs on a 64 KiB stack.
    pub fn boxed(
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        Self::new_in(ChannelBake::boxed(), tables, layer, lambda, eta, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>> TwoScale<'a, B> {
    /// [`TwoScale::new`] baking into the storage `bake` in place (whatever
    /// it held is overwritten): a zeroed [`ChannelBake`], a box, a `&mut`
    /// to caller-provided storage, or [`TwoScale::into_bake`] of a model to
    /// rebuild.
    pub fn new_in(
        bake: B,
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        let shared = SurfaceBakes::new(tables, layer.surface);
        let mut model = Self::around(bake, tables, &shared, layer, lambda, eta, options);
        shared.bake_into(tables, model.bake.borrow_mut());
        model.bake_wavelength(tables, &shared, eta, NodeBakes::ALL);
        model
    }

    /// The model's parameters for `layer` at `lambda` and `eta` around the
    /// storage `bake`, not yet baked (`shared` must come from the same
    /// tables and surface).
    pub(super) fn around(
        bake: B,
        tables: &Tables<'a>,
        shared: &SurfaceBakes<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        let (ndf, surface) = (shared.ndf, shared.surface);
        let lambda = math::sanitised_wavelength(lambda);
        let unit = |x: f32| f64::from(x.max(0.0).min(1.0));
        let base = match layer.base {
            BaseLayer::Conductor => BaseLayer::Conductor,
            BaseLayer::Plastic { albedo } => BaseLayer::Plastic {
                albedo: unit(albedo) as f32,
            },
            BaseLayer::Subsurface { albedo } => BaseLayer::Subsurface {
                albedo: unit(albedo) as f32,
            },
        };
        let f_dr_int = match base {
            BaseLayer::Conductor => 0.0,
            _ => f64::from(tables.diffuse_fresnel.f_dr_int(eta.re)),
        };
        let sigma_s = f64::from(surface.sigma_s);
        let b = f64::from(surface.b);
        TwoScale {
            x_scale: (4.0 * PI / lambda) * (4.0 * PI / lambda),
            sigma_s_sq: sigma_s * sigma_s,
            halo_scale: (f64::from(surface.c) - 1.0) * sigma_s * sigma_s * b * b
                / (2.0 * PI * lambda * lambda),
            ndf,
            q: QConstants::new(eta),
            conv: tables.convolution,
            surface,
            lambda,
            big_b: b / lambda,
            base,
            f_dr_int,
            eta_re: f64::from(eta.re),
            lambertian: unit(layer.lambertian),
            multiple_scale: 0.0,
            multiple_colour: 0.0,
            options,
            bake,
        }
    }

    /// Bakes, in place, what depends on the wavelength: the direction bake
    /// and its lobe weights, `1/M` and C (G1 and the visible-slope tables are
    /// [`SurfaceBakes::bake_into`]'s).
    pub(super) fn bake_wavelength(
        &mut self,
        tables: &Tables<'a>,
        shared: &SurfaceBakes<'a>,
        eta: Complex,
        what: NodeBakes,
    ) {
        let (surface, big_b, q) = (self.surface, self.big_b, self.q);
        let white = self.white();
        let sigma_s = f64::from(surface.sigma_s);
        let bake = self.bake.borrow_mut();
        bake.direction.init(
            eta,
            q.as_ref(),
            &tables.sigma_ratio,
            big_b as f32,
            surface.c,
        );
        // Read only when there is diffraction (`diffraction_setup`).
        if sigma_s > 0.0 && big_b > 0.0 {
            bake.radial_norm.init(big_b, f64::from(surface.c));
        } else {
            bake.radial_norm.clear();
        }
        if what.conv {
            let (c, beta, p) = (surface.c, surface.beta, surface.p);
            let source = tables.convolution;
            bake.conv_baked = match &shared.slice {
                Some(slice) => bake.conv.init(slice, big_b as f32, beta, p),
                // A source without a slice that bakes: sampled at the nodes.
                None if sigma_s > 0.0 && source.bakes_profiles() => bake.conv.init_from(
                    |u, tans, row| {
                        source.ln_profile(u, c, beta, p, tans, row);
                        Some(1.0)
                    },
                    big_b as f32,
                    beta,
                    p,
                ),
                None => false,
            };
        }
        bake.halo_baked = bake.conv_baked && what.halo_sampler;
        if !bake.halo_baked {
            // Not read (`ChannelBake::halo`); zeroed so that exports are
            // the same whatever the storage held.
            bake.halo.zero();
        } else {
            let (x_scale, sigma_s_sq, options) = (self.x_scale, self.sigma_s_sq, self.options);
            let (direction, masking) = (&bake.direction, &bake.masking);
            // The halo's factors besides C and the projections: Q̄ G (1 − A)/σrel².
            let g1 =
                |z: f64| f64::from(masking.g1(math::sqrt((1.0 - z * z).max(0.0)) as f32, z as f32));
            // The incidence's values, computed once per row.
            let row = core::cell::Cell::new((f64::NAN, direction.at(1.0), 1.0));
            let weight = |cos_i: f64, cos_d: f64, cos_o: f64, along: f64, across: f64| {
                if row.get().0 != cos_i {
                    row.set((cos_i, direction.at(cos_i as f32), g1(cos_i)));
                }
                let (_, at_i, g1_i) = row.get();
                let at_o = direction.at(cos_o as f32);
                let q = q_bar(q.as_ref(), white, &at_i, &at_o, along, across);
                let sigma_rel_sq = sigma_s_sq * sigma_ratio_sq(options.sigma_rel, &at_i, &at_o);
                let printed = exp_and_one_minus_over(x_scale * cos_d * cos_d, sigma_rel_sq).1;
                let halo =
                    halo_attenuation(options.halo_weight, printed, x_scale, cos_i, sigma_rel_sq);
                q * halo * masking_g(options.masking, g1_i, g1(cos_o))
            };
            bake.halo.init(&bake.conv, &weight);
        }
        let specular = tables
            .albedo
            .column(surface.beta, surface.p, self.options.masking);
        (self.multiple_colour, self.multiple_scale) = match self.options.multiple_scattering {
            MultipleScattering::None => (0.0, 0.0),
            MultipleScattering::KullaConty => {
                // The halo's share of the white albedo (0 without diffraction).
                let mut deficit = [0.0f64; DEFICIT_NODES];
                if sigma_s > 0.0 && big_b > 0.0 {
                    for (j, value) in deficit.iter_mut().enumerate() {
                        let x = j as f64 / (DEFICIT_NODES - 1) as f64;
                        *value = self.halo_deficit((x * x).max(DEFICIT_MIN_COS));
                    }
                }
                let deficit_at = |cos: f64| {
                    let t = math::sqrt(cos.max(0.0).min(1.0)) * (DEFICIT_NODES - 1) as f64;
                    let k = (t as usize).min(DEFICIT_NODES - 2);
                    let f = t - k as f64;
                    deficit[k] + f * (deficit[k + 1] - deficit[k])
                };
                let e_avg =
                    self.bake.borrow_mut().direction.set_albedo(|cos| {
                        (f64::from(specular.albedo(cos)) + deficit_at(cos)) as f32
                    });
                let f_avg = if self.options.colour == ColourTerms::White {
                    1.0
                } else {
                    fresnel_average(eta)
                };
                compensation(e_avg, f_avg)
            }
        };
        let halo = self.halo_albedo_nodes();
        let weights = self.bake().direction.lobe_weight_nodes(|at, cos| {
            let energies = LobeEnergies {
                specular: f64::from(specular.albedo(cos)),
                halo: halo_albedo_at(&halo, cos),
            };
            self.weights_at(at, cos, energies)
        });
        self.bake.borrow_mut().direction.set_lobe_weights(&weights);
    }

    /// The halo's change to the surface's white albedo at `cos θi`
    /// (docs/model.md §2.11):
    ///
    /// ```text
    /// Δ(μ) = ∫ [(A_spec(θd) − 1) ρ_CT + ρ_CTD]_{F = Q̄ = 1} cos θo dωo
    /// ```
    ///
    /// so that `E(μ) + Δ(μ)` is the white albedo of the specular peak and
    /// the halo together (E of T6). In polar coordinates `(α, φ)` around the
    /// mirror direction, `α = e^t` from `10⁻³ w` to π (`w` the narrower of
    /// the NDF's width β and the halo's `λ/2b`) by 4-point Gauss–Legendre on
    /// [`DEFICIT_PANELS`] panels of t, φ by the trapezoid rule on
    /// [`DEFICIT_AZIMUTHS`] points; both terms come from the same nodes.
    fn halo_deficit(&self, cos_i: f64) -> f64 {
        let sin_i = math::sqrt((1.0 - cos_i * cos_i).max(0.0));
        let i = [sin_i as f32, 0.0, cos_i as f32];
        // The mirror direction r and two unit vectors orthogonal to it.
        let r = [-sin_i, 0.0, cos_i];
        let e1 = [cos_i, 0.0, sin_i];
        let e2 = [0.0, 1.0, 0.0];
        let halo_width = 0.5 * self.lambda / f64::from(self.surface.b).max(1e-6);
        let width = f64::from(self.surface.beta)
            .min(halo_width)
            .max(1e-4)
            .min(1.0);
        let (t0, t1) = (math::ln(1e-3 * width), math::ln(PI));
        let h = (t1 - t0) / DEFICIT_PANELS as f64;
        let mut total = 0.0;
        for k in 0..DEFICIT_PANELS {
            let mid = t0 + (k as f64 + 0.5) * h;
            for (x, weight) in math::GAUSS_LEGENDRE_4 {
                for t in [mid - 0.5 * h * x, mid + 0.5 * h * x] {
                    let alpha = math::exp(t);
                    let (sa, ca) = (math::sin(alpha), math::cos(alpha));
                    // The integrand is even in φ (i lies in the xz-plane): the
                    // trapezoid rule over [0, π], ends halved, doubled.
                    let half = DEFICIT_AZIMUTHS / 2;
                    let mut ring = 0.0;
                    for m in 0..=half {
                        let phi = PI * m as f64 / half as f64;
                        let (sp, cp) = (math::sin(phi), math::cos(phi));
                        let o = [0, 1, 2].map(|c| ca * r[c] + sa * (cp * e1[c] + sp * e2[c]));
                        if !(o[2] > 0.0) {
                            continue;
                        }
                        let Some(pair) = self.pair(i, to_f32(o)) else {
                            continue;
                        };
                        let terms = self.surface_terms(&pair, true);
                        let value = (terms.a_spec - 1.0) * terms.rho_ct + terms.diffraction;
                        if value.is_finite() {
                            let end = if m == 0 || m == half { 0.5 } else { 1.0 };
                            ring += end * value * o[2];
                        }
                    }
                    total += 0.5 * h * weight * ring * (2.0 * PI / half as f64) * sa * alpha;
                }
            }
        }
        total
    }

    /// The storage of the bakes, to rebuild another model in
    /// ([`TwoScale::new_in`]).
    pub fn into_bake(self) -> B {
        self.bake
    }
}

/// What [`TwoScale::bake_wavelength`] bakes besides the direction bake:
/// a model on its own bakes everything; models that serve only the eval of
/// a model over λ between its sampler models skip the halo sampler (their
/// own halo draws come from the spectrum, HP17 51–55) and may take C from
/// a model at a shorter wavelength (whose bake covers their `u` range).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct NodeBakes {
    /// Bake C (else the caller has copied a bake covering `[0, B]` in).
    pub(super) conv: bool,
    /// Bake the halo sampler ([`HaloBake`]) from C.
    pub(super) halo_sampler: bool,
}

impl NodeBakes {
    /// Everything.
    pub(super) const ALL: NodeBakes = NodeBakes {
        conv: true,
        halo_sampler: true,
    };
}

/// Nodes of [`TwoScale::halo_deficit`] over `√cos θi` (linear between).
const DEFICIT_NODES: usize = 17;

/// The smallest `cos θi` at which the deficit is computed (the first node's).
const DEFICIT_MIN_COS: f64 = 1e-4;

/// Panels of [`TwoScale::halo_deficit`]'s rule in `ln α`.
const DEFICIT_PANELS: usize = 16;

/// Azimuths of [`TwoScale::halo_deficit`]'s rule.
const DEFICIT_AZIMUTHS: usize = 32;

/// `(F_ms, F_ms / (π (1 − E_avg)))` of the compensation lobe
/// (docs/model.md §2.11) for the albedo average `E_avg` and the Fresnel
/// average `F_avg`:
///
/// ```text
/// F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg))
/// ```
///
/// (the light that leaves after k ≥ 2 bounces, `Σ F_avg^k E_avg (1 − E_avg)^(k−1)`,
/// over its value at `F_avg = 1`, `1 − E_avg`). `(0, 0)` when
/// `1 − E_avg ≤ 1e-6` (nothing to put back).
fn compensation(e_avg: f64, f_avg: f64) -> (f64, f64) {
    let lost = 1.0 - e_avg;
    if !(lost > 1e-6) {
        return (0.0, 0.0);
    }
    let f_ms = f_avg * f_avg * e_avg / (1.0 - f_avg * lost);
    if !f_ms.is_finite() {
        return (0.0, 0.0);
    }
    (f_ms, f_ms / (PI * lost))
}

impl<'a, B: Borrow<ChannelBake>> TwoScale<'a, B> {
    /// Hands the model's constants and bakes to `v` (names in the
    /// visitor's calls; layouts as [`crate::bake`] documents; the base
    /// layer's kind and the options `masking`, `sigma_rel`, `halo_weight`
    /// and `colour` by their [`Named`] spelling), for ports of `eval` and
    /// `pdf` (the Python package's `Material.bakes()`).
    #[doc(hidden)]
    pub fn visit_bakes(&self, v: &mut dyn BakeVisitor) {
        let s = &self.surface;
        for (name, value) in [
            ("beta", s.beta),
            ("p", s.p),
            ("sigma_s", s.sigma_s),
            ("b", s.b),
            ("c", s.c),
        ] {
            v.scalar(name, f64::from(value));
        }
        let (norm, inv_beta_sq) = self.ndf.d_constants();
        v.scalar("epd_norm", f64::from(norm));
        v.scalar("epd_inv_beta_sq", f64::from(inv_beta_sq));
        let (e_norm_sqr, eta_sq) = self.q.map_or((0.0, [0.0; 2]), |q| q.combine_constants());
        v.scalar("has_q", if self.q.is_some() { 1.0 } else { 0.0 });
        v.scalar("q_e_norm_sqr", e_norm_sqr);
        v.scalar("q_eta_sq_re", eta_sq[0]);
        v.scalar("q_eta_sq_im", eta_sq[1]);
        let albedo = match self.base {
            BaseLayer::Conductor => 0.0,
            BaseLayer::Plastic { albedo } | BaseLayer::Subsurface { albedo } => f64::from(albedo),
        };
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        let o = &self.options;
        for (name, value) in [
            ("base", self.base.kind().name()),
            (Masking::OPTION, o.masking.name()),
            (SigmaRelMode::OPTION, o.sigma_rel.name()),
            (HaloWeight::OPTION, o.halo_weight.name()),
            (ColourTerms::OPTION, o.colour.name()),
        ] {
            v.named(name, value);
        }
        for (name, value) in [
            ("lambda", self.lambda),
            ("big_b", self.big_b),
            ("x_scale", self.x_scale),
            ("sigma_s_sq", self.sigma_s_sq),
            ("halo_scale", self.halo_scale),
            ("f_dr_int", self.f_dr_int),
            ("eta_re", self.eta_re),
            ("lambertian", self.lambertian),
            ("multiple_scale", self.multiple_scale),
            ("albedo", albedo),
            ("conv_baked", flag(self.bake().conv_baked)),
        ] {
            v.scalar(name, value);
        }
        let bake = self.bake();
        bake.direction.visit(v);
        bake.masking.visit(v);
        bake.radial_norm.visit(v);
        bake.conv.visit(v);
        bake.halo.visit(v);
        bake.visible.visit(v);
    }
}
