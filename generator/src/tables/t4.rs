//! T4: the spherical-harmonic BRDF matrix of each material of the materials
//! file ([WAT92] §2, SPEC §2.9), one file `t4-<material>.tbl` per material,
//! one channel per wavelength. Layout and conventions: `twoscale::sh`;
//! projection: [`crate::sh`].
//!
//! **Stand-in.** The two-scale f64 reference BRDF (SPEC §2.5) is not written
//! yet; [`material_brdf`] returns the Beckmann Cook–Torrance stand-in of
//! [`crate::analytic::StandIn`] (no diffraction; `p`, σs, b, c unused), and
//! the files record it (`brdf_model = 2`). Plugging in the two-scale
//! reference means changing [`material_brdf`] (and [`MODEL`]) only.

use indicatif::ProgressBar;
use rayon::prelude::*;
use twoscale::format::write::{TableSpec, encode};
use twoscale::format::{AxisHeader, Kernel, Mapping};
use twoscale::sh::{AUX_NAMES, ProjectedModel, coefficient_count};
use twoscale::{ShBrdfTable, TableId};

use super::{Accuracy, BuildError, GENERATOR_VERSION, TableKind};
use crate::analytic::{BeckmannCt, StandIn};
use crate::materials::{Base, Material, Materials};
use crate::reference::fresnel::{self, Complex64};
use crate::rng::SplitMix64;
use crate::sh::{IsotropicBrdf, default_quadrature, project};

/// What the T4 files currently project (see the module docs).
pub const MODEL: ProjectedModel = ProjectedModel::BeckmannStandIn;

/// Verification target: `max |f_SH − f| / max f` over the random pairs, with
/// `f = ρ cos θi cos θo` (what the matrix represents; dividing by the cosines
/// magnifies any error near grazing, [WAT92] §5). The maximum is always at
/// grazing incidence and exitance near the mirror azimuth, where the specular
/// peak is narrower in `Δφ` than any band limit can follow (measured with
/// the stand-in: 0.43 nickel L = 48, 0.12 rough aluminium L = 16, 0.40 rough
/// plastic L = 16; p99 1.3%, 2.1%, 4.0%). The target, 0.5, only catches a
/// broken table; the p99 and median are the figures to read (README, T4).
pub const TARGET_MAX_REL_F_ERROR: f64 = 0.5;

/// The BRDF of `material` at `channel` that T4 projects. **The one place to
/// change** when the two-scale reference (`generator::reference::brdf`)
/// exists: return it here (it must be isotropic and even in `φo − φi`) and
/// set [`MODEL`] to [`ProjectedModel::TwoScale`].
pub fn material_brdf(
    material: &Material,
    channel: usize,
    _wavelength: f64,
) -> Result<Box<dyn IsotropicBrdf>, BuildError> {
    let eta = Complex64::new(material.n[channel], material.k[channel]);
    let base_factor = match &material.base {
        Base::Conductor => 0.0,
        Base::Plastic { albedo } => {
            let n = material.n[channel];
            let f_dr = fresnel::diffuse_internal(n).map_err(|source| BuildError::Quadrature {
                at: format!("T4 {} F_dr,int(η = {n})", material.name),
                source,
            })?;
            let rho_d = albedo[channel];
            rho_d / (std::f64::consts::PI * n * n * (1.0 - rho_d * f_dr))
        }
    };
    Ok(Box::new(StandIn {
        lobe: BeckmannCt {
            alpha: material.beta,
            eta: Some(eta),
        },
        base_factor,
    }))
}

/// The T4 builder of one material.
pub struct ShBrdf {
    /// The material.
    pub material: Material,
    /// The wavelengths of the channels, µm.
    pub wavelengths: Vec<f64>,
}

impl ShBrdf {
    /// One builder per material of the file.
    pub fn all(materials: &Materials) -> Vec<ShBrdf> {
        materials
            .materials
            .iter()
            .map(|m| ShBrdf {
                material: m.clone(),
                wavelengths: materials.wavelengths.clone(),
            })
            .collect()
    }

    fn aux(&self, phi_nodes: usize) -> Vec<f32> {
        let m = &self.material;
        let base_albedo = match &m.base {
            Base::Conductor => 0.0,
            Base::Plastic { albedo } => albedo.iter().sum::<f64>() / albedo.len() as f64,
        };
        let mut aux = vec![
            MODEL.code() as f32,
            phi_nodes as f32,
            m.beta as f32,
            m.p as f32,
            m.sigma_s as f32,
            m.b as f32,
            m.c as f32,
            base_albedo as f32,
        ];
        for c in 0..3 {
            aux.push(m.n.get(c).copied().unwrap_or(0.0) as f32);
            aux.push(m.k.get(c).copied().unwrap_or(0.0) as f32);
        }
        debug_assert_eq!(aux.len(), AUX_NAMES.len());
        aux
    }
}

impl TableKind for ShBrdf {
    fn id(&self) -> TableId {
        TableId::ShBrdf
    }

    fn file_stem(&self) -> String {
        format!("t4-{}", self.material.name)
    }

    fn work_items(&self) -> u64 {
        (default_quadrature(self.material.band_limit).theta_nodes * self.wavelengths.len()) as u64
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let m = &self.material;
        let l = m.band_limit;
        let quadrature = default_quadrature(l);
        let channels = self.wavelengths.len();
        let count = coefficient_count(l);
        let mut grid = vec![0.0f32; count * channels];
        let mut asymmetry: f64 = 0.0;
        for (c, &lambda) in self.wavelengths.iter().enumerate() {
            let brdf = material_brdf(m, c, lambda)?;
            let projection = project(brdf.as_ref(), l, quadrature, Some(progress));
            let (diff, norm) = projection.asymmetry();
            asymmetry = asymmetry.max(if norm > 0.0 { diff / norm } else { 0.0 });
            for (k, v) in projection.packed(m.filter).into_iter().enumerate() {
                grid[k * channels + c] = v as f32;
            }
        }
        let mut params = vec![
            l as f64,
            m.filter.map_or(0.0, |f| f.start),
            m.filter.map_or(0.0, |f| f.width),
        ];
        params.extend((0..3).map(|c| self.wavelengths.get(c).copied().unwrap_or(0.0)));
        params.push(asymmetry);
        params.push(quadrature.theta_nodes as f64);
        let axis = AxisHeader {
            nodes: count as u32,
            mapping: Mapping::Uniform,
            lo: 0.0,
            hi: (count - 1) as f64,
            param: 0.0,
            param2: 0.0,
        };
        Ok(encode(&TableSpec {
            table_id: TableId::ShBrdf,
            channels: channels as u32,
            kernel: Kernel::Multilinear,
            axes: &[axis],
            params: &params,
            grid: &grid,
            aux: &self.aux(quadrature.phi_nodes()),
            generator_version: GENERATOR_VERSION,
        })?)
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = ShBrdfTable::from_bytes(bytes)?;
        let mut out = Vec::new();
        let pairs = verification_pairs(points, seed);
        for (c, &lambda) in self.wavelengths.iter().enumerate() {
            let brdf = material_brdf(&self.material, c, lambda)?;
            let values: Vec<(f64, f64, String)> = pairs
                .par_iter()
                .map(|&(wi, wo)| {
                    let cc = wi[2] * wo[2];
                    let exact = brdf.eval(wi, wo) * cc;
                    let got = f64::from(table.eval(c, narrow(wi), narrow(wo))) * cc;
                    let at = format!(
                        "θi {:.1}°, θo {:.1}°, Δφ {:.1}°",
                        wi[2].acos().to_degrees(),
                        wo[2].acos().to_degrees(),
                        wo[1].atan2(wo[0]).to_degrees()
                    );
                    (exact, got, at)
                })
                .collect();
            let peak = values.iter().fold(0.0f64, |m, v| m.max(v.0.abs()));
            let errors = values
                .into_iter()
                .map(|(exact, got, at)| ((got - exact).abs() / peak, at))
                .collect();
            out.push(Accuracy::from_errors(
                &format!("λ{c} |f_SH-f|/max f, L={}", table.band_limit()),
                TARGET_MAX_REL_F_ERROR,
                errors,
            ));
        }
        Ok(out)
    }
}

fn narrow(d: [f64; 3]) -> [f32; 3] {
    [d[0] as f32, d[1] as f32, d[2] as f32]
}

/// Random pairs of directions, uniform in solid angle on the upper
/// hemisphere (`cos θ ≥ 1e-3`), `wi` in the xz-plane (isotropy), rounded to
/// f32 as the runtime takes them.
pub fn verification_pairs(points: usize, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
    let mut rng = SplitMix64::new(seed);
    let round = |v: f64| f64::from(v as f32);
    (0..points)
        .map(|_| {
            let zi = round(rng.uniform_in(1e-3, 1.0));
            let zo = round(rng.uniform_in(1e-3, 1.0));
            let phi = rng.uniform_in(0.0, 2.0 * std::f64::consts::PI);
            let (si, so) = ((1.0 - zi * zi).sqrt(), (1.0 - zo * zo).sqrt());
            let wi = [round(si), 0.0, zi];
            let wo = [round(so * phi.cos()), round(so * phi.sin()), zo];
            (normalise(wi), normalise(wo))
        })
        .collect()
}

fn normalise(d: [f64; 3]) -> [f64; 3] {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / len, d[1] / len, d[2] / len]
}
