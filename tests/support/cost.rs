//! The BRDF cost workload shared by `benches/brdf.rs` (criterion) and
//! `studies brdf-instructions` (instruction counts under callgrind): the
//! two-scale model of HP17's nickel geometry at 0.526 µm, the GGX baseline
//! it is compared with, and the same pseudo-random inputs for both
//! (docs/design/speed.md).

use twoscale::Complex;
use twoscale::brdf::{Rgb, TwoScale};
use twoscale::materials::{HP17_NICKEL_SURFACE, PRESETS};
use twoscale::{Convolution, TableSet};

/// Inputs per batch.
pub const BATCH: usize = 1024;
/// Wavelength of the one-wavelength model (µm).
pub const LAMBDA: f32 = 0.526;
/// A nickel-like index at [`LAMBDA`].
pub const NICKEL_LIKE: Complex = Complex::new(1.98, 3.74);
/// The preset of the RGB rows.
pub const RGB_PRESET: &str = "gold-hp17-geometry";

/// A GGX Cook–Torrance conductor in f32, as a renderer would write it:
/// `F(η, i·h) D(h) G1(i) G1(o) / (4 cos θi cos θo)` with
/// `D = α² / (π cos⁴θh (α² + tan²θh)²)`, `G1 = 2 / (1 + √(1 + α² tan²θ))`
/// and the same complex Fresnel as the two-scale model.
pub struct Ggx {
    /// GGX roughness α.
    pub alpha: f32,
    /// Complex index of the conductor.
    pub eta: Complex,
}

impl Ggx {
    #[inline]
    pub fn g1(&self, w: [f32; 3]) -> f32 {
        let z2 = w[2] * w[2];
        let tan2 = (1.0 - z2).max(0.0) / z2;
        2.0 / (1.0 + libm::sqrtf(1.0 + self.alpha * self.alpha * tan2))
    }

    /// `cos θd` and `D G1(i) G1(o) / (4 cos θi cos θo)`, or `None` below
    /// the horizon.
    #[inline]
    pub fn cos_d_and_dg(&self, i: [f32; 3], o: [f32; 3]) -> Option<(f32, f32)> {
        if !(i[2] > 0.0 && o[2] > 0.0) {
            return None;
        }
        let s = [i[0] + o[0], i[1] + o[1], i[2] + o[2]];
        let inv = 1.0 / libm::sqrtf(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        let h = s.map(|x| x * inv);
        let cos_d = (i[0] * h[0] + i[1] * h[1] + i[2] * h[2]).clamp(0.0, 1.0);
        let a2 = self.alpha * self.alpha;
        let c2 = h[2] * h[2];
        let t = a2 * c2 + (1.0 - c2);
        let d = a2 / (core::f32::consts::PI * t * t);
        Some((cos_d, d * self.g1(i) * self.g1(o) / (4.0 * i[2] * o[2])))
    }

    #[inline]
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.cos_d_and_dg(i, o) {
            Some((cos_d, dg)) => twoscale::model::fresnel::fresnel(self.eta, cos_d) * dg,
            None => 0.0,
        }
    }

    /// The RGB GGX conductor: D and G once, Fresnel per channel.
    #[inline]
    pub fn eval_rgb(&self, etas: &[Complex; 3], i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        match self.cos_d_and_dg(i, o) {
            Some((cos_d, dg)) => etas.map(|eta| twoscale::model::fresnel::fresnel(eta, cos_d) * dg),
            None => [0.0; 3],
        }
    }

    /// Samples a visible normal (Heitz 2018, "Sampling the GGX Distribution
    /// of Visible Normals", JCGT 7(4)), reflects `i` about it, and returns
    /// the direction, its pdf `D_i(h) / (4 i·h)` and the eval there.
    #[inline]
    pub fn sample_eval(&self, i: [f32; 3], u: [f32; 2]) -> Option<([f32; 3], f32, f32)> {
        let a = self.alpha;
        let vh = [a * i[0], a * i[1], i[2]];
        let l = libm::sqrtf(vh[0] * vh[0] + vh[1] * vh[1] + vh[2] * vh[2]);
        let vh = vh.map(|x| x / l);
        let lensq = vh[0] * vh[0] + vh[1] * vh[1];
        let t1 = if lensq > 0.0 {
            let inv = 1.0 / libm::sqrtf(lensq);
            [-vh[1] * inv, vh[0] * inv, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let t2 = [
            vh[1] * t1[2] - vh[2] * t1[1],
            vh[2] * t1[0] - vh[0] * t1[2],
            vh[0] * t1[1] - vh[1] * t1[0],
        ];
        let r = libm::sqrtf(u[0]);
        let phi = 2.0 * core::f32::consts::PI * u[1];
        let p1 = r * libm::cosf(phi);
        let s = 0.5 * (1.0 + vh[2]);
        let p2 = (1.0 - s) * libm::sqrtf((1.0 - p1 * p1).max(0.0)) + s * r * libm::sinf(phi);
        let p3 = libm::sqrtf((1.0 - p1 * p1 - p2 * p2).max(0.0));
        let nh = [0, 1, 2].map(|k| p1 * t1[k] + p2 * t2[k] + p3 * vh[k]);
        let m = [a * nh[0], a * nh[1], nh[2].max(0.0)];
        let lm = libm::sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        let m = m.map(|x| x / lm);
        let k = 2.0 * (i[0] * m[0] + i[1] * m[1] + i[2] * m[2]);
        let o = [k * m[0] - i[0], k * m[1] - i[1], k * m[2] - i[2]];
        if o[2] <= 0.0 || o[2].is_nan() {
            return None;
        }
        let a2 = a * a;
        let c2 = m[2] * m[2];
        let t = a2 * c2 + (1.0 - c2);
        let d = a2 / (core::f32::consts::PI * t * t);
        let pdf = self.g1(i) * d / (4.0 * i[2]);
        Some((o, pdf, self.eval(i, o)))
    }
}

/// A direction uniform over the upper hemisphere.
fn direction(rng: &mut generator::rng::SplitMix64) -> [f32; 3] {
    let z = rng.uniform();
    let r = (1.0 - z * z).sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform();
    [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
}

/// The inputs of every cost measurement: `pairs` for eval and pdf,
/// `uniforms` (a direction and three uniforms) for sample.
pub struct Inputs {
    pub pairs: Vec<([f32; 3], [f32; 3])>,
    pub uniforms: Vec<([f32; 3], [f32; 3])>,
}

impl Inputs {
    /// [`BATCH`] of each, from a fixed seed.
    pub fn new() -> Self {
        let mut rng = generator::rng::SplitMix64::new(17);
        let pairs = (0..BATCH)
            .map(|_| (direction(&mut rng), direction(&mut rng)))
            .collect();
        let uniforms = (0..BATCH)
            .map(|_| {
                let u = [0, 1, 2].map(|_| rng.uniform() as f32);
                (direction(&mut rng), u)
            })
            .collect();
        Inputs { pairs, uniforms }
    }
}

impl Default for Inputs {
    fn default() -> Self {
        Self::new()
    }
}

/// The measured one-wavelength model with `conv` as its source of C.
pub fn nickel<'a>(set: &'a TableSet<'a>, conv: &'a (dyn Convolution + Sync)) -> TwoScale<'a> {
    TwoScale::conductor(
        &set.brdf_tables_with(conv),
        HP17_NICKEL_SURFACE,
        LAMBDA,
        NICKEL_LIKE,
    )
}

/// The GGX baseline with the nickel geometry's roughness (α = β).
pub fn ggx() -> Ggx {
    Ggx {
        alpha: HP17_NICKEL_SURFACE.beta,
        eta: NICKEL_LIKE,
    }
}

/// The RGB preset of the RGB rows and its three indices.
pub fn rgb_preset<'a>(set: &'a TableSet<'a>) -> (Rgb<'a>, [Complex; 3]) {
    let model = set.material(RGB_PRESET).expect("preset");
    let eta = PRESETS
        .iter()
        .find(|(n, _)| *n == RGB_PRESET)
        .map(|(_, m)| m.eta_rgb)
        .expect("preset");
    (model, eta)
}
