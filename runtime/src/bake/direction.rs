//! [`DirectionBake`]: one direction's quantities at one wavelength over `cos θ`.

use super::cell;
use super::cell_at;
use crate::bake::BakeVisitor;
use crate::math;
use crate::math::Complex;
use crate::model::fresnel::QConstants;
use crate::model::fresnel::QFactors;
use crate::model::fresnel::fresnel;
use crate::tables::albedo::AVERAGE_NODES;
use crate::tables::sigma_ratio::SigmaRatioTable;
use zerocopy::FromZeros;
/// Nodes of [`DirectionBake`]: those of `E_avg`'s rule ([`crate::tables::albedo::AlbedoColumn::average`]).
pub(crate) const MU_NODES: usize = AVERAGE_NODES;

/// One direction's quantities at one wavelength (module documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct DirectionBake {
    /// `[a, Re U, Im U, Re W, Im W, σrel/σs, F, 1 − E_s]` per node: what `eval`
    /// reads, in one row (`1 − E_s(μ)`, the white albedo the compensation lobe puts back, 0
    /// when it is off).
    rows: [[f32; ROW]; MU_NODES],
    /// `[w_spec, w_diff, w_base, w_ms]` per node: what the sampler and `pdf` read.
    weights: [[f32; 4]; MU_NODES],
}

/// Values per [`DirectionBake`] row.
const ROW: usize = 8;

/// The row's columns: Q̄'s five factors ([`QFactors`]) from `Q`, then
/// σrel/σs, F and `1 − E_s`.
const Q: usize = 0;
const SIGMA_RATIO: usize = 5;
const FRESNEL: usize = 6;
const LOST: usize = 7;

/// The names of a [`DirectionBake`] row's columns (`direction_rows`, given
/// to [`BakeVisitor::columns`]; ports read the columns by these).
pub(crate) const ROW_COLUMNS: [&str; ROW] = {
    let mut names = [""; ROW];
    let q = ["q_a", "q_u_re", "q_u_im", "q_w_re", "q_w_im"];
    let mut k = 0;
    while k < q.len() {
        names[Q + k] = q[k];
        k += 1;
    }
    names[SIGMA_RATIO] = "sigma_ratio";
    names[FRESNEL] = "fresnel";
    names[LOST] = "lost";
    names
};

/// The names of the lobe weights' columns (`direction_weights`), in
/// `brdf::Lobe`'s order.
pub(crate) const WEIGHT_COLUMNS: [&str; 4] = ["specular", "diffraction", "base", "multiple"];

/// A `cos θ`'s place on [`DirectionBake`]'s axis (the same for every
/// wavelength, so [`crate::brdf::Rgb`] finds it once for its three channels).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DirectionCell {
    index: usize,
    fraction: f32,
}

impl DirectionCell {
    /// The cell of `cos θ` (clamped to [0, 1]).
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn new(cos: f32) -> Self {
        let (index, fraction) = cell(math::sqrtf(cos.max(0.0)), MU_NODES);
        DirectionCell { index, fraction }
    }

    /// The cell and fraction of the same `cos θ` on an axis of `N` nodes of
    /// `√cos θ` (`MU_NODES − 1` a multiple of `N − 1`).
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline]
    pub fn coarser<const N: usize>(self) -> (usize, f32) {
        let step = ((MU_NODES - 1) / (N - 1)) as f32;
        cell_at((self.index as f32 + self.fraction) * (1.0 / step), N)
    }
}

/// Interpolated [`DirectionBake`] row at one `cos θ`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DirectionValues {
    /// `[a, Re U, Im U, Re W, Im W, σrel/σs, F, 1 − E_s]`.
    pub v: [f32; ROW],
}

impl DirectionValues {
    /// F(η, cos θ).
    #[inline]
    pub fn fresnel(&self) -> f64 {
        f64::from(self.v[FRESNEL])
    }

    /// The factors of Q̄.
    #[inline]
    pub fn q_factors(&self) -> QFactors {
        let v = &self.v;
        [v[Q], v[Q + 1], v[Q + 2], v[Q + 3], v[Q + 4]].map(f64::from)
    }

    /// σrel/σs.
    #[inline]
    pub fn sigma_ratio(&self) -> f64 {
        f64::from(self.v[SIGMA_RATIO])
    }

    /// `1 − E_s(μ)`, the light single scattering loses (0 unless the
    /// compensation lobe is on).
    #[inline]
    pub fn lost(&self) -> f64 {
        f64::from(self.v[LOST])
    }
}

/// The lobe weights of [`DirectionBake`] at its nodes, as computed by
/// [`DirectionBake::lobe_weight_nodes`] (4 KB).
pub(crate) struct LobeWeightNodes([[f32; 4]; MU_NODES]);

impl DirectionBake {
    /// Tabulates in place F and Q̄'s factors of `eta` (when `q` is given) and
    /// σrel/σs of the spectrum `(B, c)` from T2; the lobe weights are
    /// cleared (set them with [`DirectionBake::set_lobe_weights`]), and so is
    /// `1 − E_s` (set it with [`DirectionBake::set_albedo`]).
    pub fn init(
        &mut self,
        eta: Complex,
        q: Option<&QConstants>,
        sigma_ratio: &SigmaRatioTable<'_>,
        big_b: f32,
        c: f32,
    ) {
        let mut cosines = [0.0f32; MU_NODES];
        for (k, (row, cos_f32)) in self.rows.iter_mut().zip(cosines.iter_mut()).enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            let cos = x * x;
            *cos_f32 = cos as f32;
            let factors = q.map(|q| q.factors(cos)).unwrap_or([0.0; 5]);
            for (slot, value) in row[Q..Q + 5].iter_mut().zip(factors) {
                *slot = value as f32;
            }
            row[FRESNEL] = fresnel(eta, cos as f32);
            row[LOST] = 0.0;
        }
        let mut ratios = [0.0f32; MU_NODES];
        sigma_ratio.sigma_ratio_cos_many(&cosines, big_b, c, &mut ratios);
        for (row, ratio) in self.rows.iter_mut().zip(ratios) {
            row[SIGMA_RATIO] = ratio;
        }
        self.weights = [[0.0f32; 4]; MU_NODES];
    }

    /// The bake of [`DirectionBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(
        eta: Complex,
        q: Option<&QConstants>,
        sigma_ratio: &SigmaRatioTable<'_>,
        big_b: f32,
        c: f32,
    ) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(eta, q, sigma_ratio, big_b, c);
        bake
    }

    /// Stores `1 − E_s(μ)` at the nodes from `albedo(μ)` (clamped to
    /// [0, 1]) and returns `E_avg = 2 ∫₀¹ E μ dμ` of the stored values as
    /// `eval` interpolates them (linear in `√μ`,
    /// [`crate::math::cosine_weighted_mean`]), so that the compensation lobe
    /// `∝ (1 − E_s(μi)) (1 − E_s(μo)) / (1 − E_avg)` integrates exactly.
    pub fn set_albedo(&mut self, albedo: impl Fn(f64) -> f32) -> f64 {
        for (k, row) in self.rows.iter_mut().enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            row[LOST] = 1.0 - albedo(x * x).max(0.0).min(1.0);
        }
        1.0 - crate::math::cosine_weighted_mean(MU_NODES, |k| self.rows[k][LOST])
    }

    /// The lobe weights `weights(values at cos θ, cos θ)` at the nodes, for
    /// [`DirectionBake::set_lobe_weights`].
    pub fn lobe_weight_nodes(
        &self,
        weights: impl Fn(&DirectionValues, f64) -> [f64; 4],
    ) -> LobeWeightNodes {
        let mut nodes = [[0.0f32; 4]; MU_NODES];
        for (k, node) in nodes.iter_mut().enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            let cos = x * x;
            let w = weights(&self.at(cos as f32), cos);
            for (slot, value) in node.iter_mut().zip(w) {
                *slot = value as f32;
            }
        }
        LobeWeightNodes(nodes)
    }

    /// Stores the lobe weights tabulated by [`DirectionBake::lobe_weight_nodes`].
    pub fn set_lobe_weights(&mut self, nodes: &LobeWeightNodes) {
        self.weights = nodes.0;
    }

    /// F alone at a cell.
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn fresnel_at(&self, at: DirectionCell) -> f32 {
        let (a, b) = (
            self.rows[at.index][FRESNEL],
            self.rows[at.index + 1][FRESNEL],
        );
        a + at.fraction * (b - a)
    }

    /// The values at `cos θ` (clamped to [0, 1]).
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn at(&self, cos: f32) -> DirectionValues {
        self.at_cell(DirectionCell::new(cos))
    }

    /// The values at a cell.
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn at_cell(&self, at: DirectionCell) -> DirectionValues {
        let (a, b) = (&self.rows[at.index], &self.rows[at.index + 1]);
        let mut v = [0.0f32; ROW];
        for k in 0..ROW {
            v[k] = a[k] + at.fraction * (b[k] - a[k]);
        }
        DirectionValues { v }
    }

    /// Hands the node rows and lobe weights to `v` (`direction_rows`
    /// `[257, 8]`, columns [`ROW_COLUMNS`]; `direction_weights` `[257, 4]`,
    /// columns [`WEIGHT_COLUMNS`]; nodes even in `√cos θ`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.array("direction_rows", &[MU_NODES, ROW], self.rows.as_flattened());
        v.columns("direction_rows", &ROW_COLUMNS);
        v.array(
            "direction_weights",
            &[MU_NODES, 4],
            self.weights.as_flattened(),
        );
        v.columns("direction_weights", &WEIGHT_COLUMNS);
    }

    /// The sampler's lobe weights `[specular, diffraction, base, multiple]`
    /// (sum 1) at `cos θ` (clamped to [0, 1]).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    #[inline]
    pub fn lobe_weights(&self, cos: f32) -> [f64; 4] {
        let at = DirectionCell::new(cos);
        let (a, b) = (&self.weights[at.index], &self.weights[at.index + 1]);
        let w = [0, 1, 2, 3].map(|k| f64::from(a[k] + at.fraction * (b[k] - a[k])).max(0.0));
        let total = w[0] + w[1] + w[2] + w[3];
        if total > 0.0 {
            w.map(|x| x / total)
        } else {
            [1.0, 0.0, 0.0, 0.0]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{ROW_COLUMNS, WEIGHT_COLUMNS};

    /// Every column of the bakes a port reads by name has one, unique.
    #[test]
    fn every_column_has_its_own_name() {
        for names in [&ROW_COLUMNS[..], &WEIGHT_COLUMNS[..]] {
            for (k, name) in names.iter().enumerate() {
                assert!(!name.is_empty(), "column {k} has no name");
                assert!(!names[..k].contains(name), "{name} names two columns");
            }
        }
    }
}
