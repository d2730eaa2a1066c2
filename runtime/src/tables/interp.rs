//! Axis mappings and the grid interpolator [`Grid`] of T1 (bilinear), T2
//! (tricubic B-spline) and T5 (cubic B-spline). T3 uses [`Axis`] from here
//! with its own Catmull–Rom blend (`crate::tables::convolution`); T4 is read by `crate::tables::sh_brdf`.
//!
//! An [`Axis`] turns a physical value `x` into a position between two nodes:
//! a cell index `i` and a fraction `t ∈ [0, 1]`, by mapping `x` to the coordinate
//! `c(x)` of its [`Mapping`] (in which the nodes are evenly spaced). Values
//! outside `[lo, hi]` clamp to the end nodes; NaN clamps to `lo`. A [`Grid`]
//! combines up to four axes with a value slice and, depending on its
//! [`Kernel`]:
//! - multilinear: blends its `2^D` corner values with the product weights
//!   `Π (t_d or 1 − t_d)`;
//! - cubic B-spline: blends `4^D` coefficients with the product of the uniform
//!   cubic B-spline weights `(1−t)³/6, (3t³−6t²+4)/6, (−3t³+3t²+3t+1)/6, t³/6`
//!   on coefficients `i … i+3` of each axis (coefficient `j` sits at node `j − 1`).

use crate::math;
use crate::tables::format::{AxisHeader, FormatError, Header, Kernel, MAX_AXES, Mapping};

/// One axis of a grid, ready for lookups.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    mapping: Mapping,
    param: f32,
    param2: f32,
    lo: f32,
    hi: f32,
    /// `c(lo)`.
    c_lo: f32,
    /// Cells per unit of coordinate: `(nodes − 1) / (c(hi) − c(lo))`.
    scale: f32,
    /// Number of cells, `nodes − 1` (≥ 1).
    cells: u32,
}

impl Axis {
    /// Builds an axis from its header. Fails if the mapped domain is degenerate
    /// in `f32` (the header validation already checked the `f64` fields).
    pub fn new(header: &AxisHeader) -> Result<Axis, FormatError> {
        let cells = header.nodes.saturating_sub(1);
        let mapping = header.mapping;
        let param = header.param as f32;
        let param2 = header.param2 as f32;
        let c_lo = coordinate(mapping, param, param2, header.lo as f32);
        let c_hi = coordinate(mapping, param, param2, header.hi as f32);
        let scale = cells as f32 / (c_hi - c_lo);
        if cells == 0
            || !c_lo.is_finite()
            || !c_hi.is_finite()
            || !scale.is_finite()
            || scale == 0.0
        {
            return Err(FormatError::BadAxis {
                axis: 0,
                reason: "mapped domain is degenerate in f32",
            });
        }
        Ok(Axis {
            mapping,
            param,
            param2,
            lo: header.lo as f32,
            hi: header.hi as f32,
            c_lo,
            scale,
            cells,
        })
    }

    /// [`Axis::new`] for axis `d` of a table: a [`FormatError::BadAxis`]
    /// names that axis.
    pub fn numbered(d: usize, header: &AxisHeader) -> Result<Axis, FormatError> {
        Axis::new(header).map_err(|e| match e {
            FormatError::BadAxis { reason, .. } => FormatError::BadAxis { axis: d, reason },
            other => other,
        })
    }

    /// First node (physical units).
    pub fn lo(&self) -> f32 {
        self.lo
    }

    /// Last node (physical units).
    pub fn hi(&self) -> f32 {
        self.hi
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.cells as usize + 1
    }

    /// The cell containing `x` and the fraction across it, `(i, t)` with
    /// `0 ≤ i < nodes − 1`, `t ∈ [0, 1]`. Clamps outside `[lo, hi]`; NaN → `lo`.
    #[inline]
    pub fn locate(&self, x: f32) -> (usize, f32) {
        // `max`/`min` of f32 return the non-NaN operand, so NaN becomes lo.
        let x = x.max(self.lo).min(self.hi);
        let position =
            (coordinate(self.mapping, self.param, self.param2, x) - self.c_lo) * self.scale;
        self.split(position)
    }

    /// Splits a fractional node position into `(cell, fraction)`, clamped.
    #[inline]
    fn split(&self, position: f32) -> (usize, f32) {
        let last = self.cells as f32;
        // Rounding in `coordinate` can put the end points slightly outside.
        let position = position.max(0.0).min(last);
        let cell = (math::floorf(position) as u32).min(self.cells - 1);
        (cell as usize, position - cell as f32)
    }

    /// The physical value of node `i` (f64, as the generator computes it).
    pub fn node(header: &AxisHeader, i: usize) -> f64 {
        node_value(header, i)
    }
}

/// `c(x)` of a mapping, in f32 (lookups).
#[inline]
fn coordinate(mapping: Mapping, param: f32, param2: f32, x: f32) -> f32 {
    match mapping {
        Mapping::Uniform => x,
        Mapping::Log => math::lnf(x),
        Mapping::LogOffset => math::lnf(x + param) + param2 * x,
        Mapping::Power => math::powff(x, param),
    }
}

/// `c(x)` of an axis's mapping, in f64 (node placement by the generator).
pub fn coordinate_f64(axis: &AxisHeader, x: f64) -> f64 {
    match axis.mapping {
        Mapping::Uniform => x,
        Mapping::Log => math::ln(x),
        Mapping::LogOffset => math::ln(x + axis.param) + axis.param2 * x,
        Mapping::Power => math::powf(x, axis.param),
    }
}

/// The inverse of [`coordinate_f64`]: `x(c)`. Closed form where there is one;
/// for the log-offset mapping with a linear term, bisection on `[lo, hi]`
/// (the mapping is increasing), to full f64 precision.
pub fn inverse_coordinate_f64(axis: &AxisHeader, c: f64) -> f64 {
    match axis.mapping {
        Mapping::Uniform => c,
        Mapping::Log => math::exp(c),
        Mapping::LogOffset if axis.param2 == 0.0 => math::exp(c) - axis.param,
        Mapping::LogOffset => {
            let (mut lo, mut hi) = (axis.lo, axis.hi);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if coordinate_f64(axis, mid) < c {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        }
        Mapping::Power => math::powf(c, 1.0 / axis.param),
    }
}

/// The physical value of node `i` of an axis. The end nodes are exactly `lo`
/// and `hi`; the others are the inverse mapping of evenly spaced coordinates.
pub fn node_value(header: &AxisHeader, i: usize) -> f64 {
    let cells = header.nodes.saturating_sub(1) as usize;
    if i == 0 {
        return header.lo;
    }
    if i >= cells {
        return header.hi;
    }
    let c_lo = coordinate_f64(header, header.lo);
    let c_hi = coordinate_f64(header, header.hi);
    let c = c_lo + (c_hi - c_lo) * (i as f64 / cells as f64);
    inverse_coordinate_f64(header, c)
}

/// An n-dimensional grid of values over up to [`MAX_AXES`] axes.
#[derive(Clone, Copy, Debug)]
pub struct Grid<'a> {
    axes: [Axis; MAX_AXES],
    /// Strides in values (channels included), per axis.
    strides: [usize; MAX_AXES],
    dims: usize,
    kernel: Kernel,
    values: &'a [f32],
}

impl<'a> Grid<'a> {
    /// A grid over `values` described by `header` (already validated, so the
    /// length agrees with the node counts).
    pub fn new(header: &Header, values: &'a [f32]) -> Result<Grid<'a>, FormatError> {
        let used = header.used_axes();
        let placeholder = Axis {
            mapping: Mapping::Uniform,
            param: 0.0,
            param2: 0.0,
            lo: 0.0,
            hi: 1.0,
            c_lo: 0.0,
            scale: 1.0,
            cells: 1,
        };
        let mut axes = [placeholder; MAX_AXES];
        for (d, a) in used.iter().enumerate() {
            axes[d] = Axis::numbered(d, a)?;
        }
        if header.value_type != crate::tables::format::ValueType::F32 {
            return Err(FormatError::Shape(
                "this table must be stored as f32 (the file holds quantised values)",
            ));
        }
        let channels = header.channels as usize;
        let mut strides = [0; MAX_AXES];
        let mut stride = channels;
        let kernel = header.kernel;
        if kernel == Kernel::CatmullRom {
            return Err(FormatError::Shape(
                "a Catmull-Rom grid is read by its table's reader (crate::tables::convolution), not interp::Grid",
            ));
        }
        for d in (0..used.len()).rev() {
            strides[d] = stride;
            stride *= kernel.stored_per_axis(axes[d].cells + 1) as usize;
        }
        if stride != values.len() {
            return Err(FormatError::Shape("grid length disagrees with the axes"));
        }
        Ok(Grid {
            axes,
            strides,
            dims: used.len(),
            kernel,
            values,
        })
    }

    /// Number of axes.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// Axis `d` (`d < dims()`; larger `d` gives the last axis).
    pub fn axis(&self, d: usize) -> &Axis {
        &self.axes[d.min(self.dims.saturating_sub(1)).min(MAX_AXES - 1)]
    }

    /// The raw values.
    pub fn values(&self) -> &'a [f32] {
        self.values
    }

    /// The interpolation kernel.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Interpolation of channel `channel` at the physical point `x` with the
    /// grid's kernel. `D` must equal [`Grid::dims`] (typed tables guarantee
    /// it); out-of-domain coordinates clamp to the end nodes.
    #[inline]
    pub fn interpolate<const D: usize>(&self, x: [f32; D], channel: usize) -> f32 {
        let mut cells = [(0usize, 0.0f32); D];
        for d in 0..D {
            cells[d] = self.axes[d.min(MAX_AXES - 1)].locate(x[d]);
        }
        match self.kernel {
            // `Grid::new` refuses Catmull–Rom grids (T3 has its own reader).
            Kernel::Multilinear | Kernel::CatmullRom => self.blend(cells, channel),
            Kernel::CubicBSpline => self.blend_cubic(cells, channel),
        }
    }

    /// Cubic B-spline blend of the `4^D` coefficients around the cell given
    /// per axis as `(index, fraction)`: coefficients `i … i+3` of each axis.
    #[inline]
    pub fn blend_cubic<const D: usize>(&self, cells: [(usize, f32); D], channel: usize) -> f32 {
        let mut weights = [[0.0f32; 4]; D];
        let mut base = channel;
        for ((&(i, t), stride), w) in cells.iter().zip(&self.strides).zip(weights.iter_mut()) {
            base += i * stride;
            *w = bspline_weights(t);
        }
        let mut sum = 0.0f32;
        for corner in 0..(1usize << (2 * D)) {
            let mut weight = 1.0f32;
            let mut offset = base;
            for (d, (w, stride)) in weights.iter().zip(&self.strides).enumerate() {
                let k = (corner >> (2 * d)) & 3;
                weight *= w[k];
                offset += k * stride;
            }
            sum += weight * self.values.get(offset).copied().unwrap_or(0.0);
        }
        sum
    }

    /// The cubic B-spline coefficients of channel `channel` along axis 0,
    /// blended over the other axes at their cells `cells[1..]` (`cells[0]`
    /// is unused), into `out`; returns their count (0 when `out` is too
    /// short or the grid is not a B-spline). With
    /// [`Grid::interpolate_column`], the value of [`Grid::blend_cubic`] up to
    /// f32 rounding, for many points along axis 0 at one blend's cost.
    pub fn cubic_column<const D: usize>(
        &self,
        cells: [(usize, f32); D],
        channel: usize,
        out: &mut [f32],
    ) -> usize {
        let count = self.kernel.stored_per_axis(self.axes[0].cells + 1) as usize;
        if self.kernel != Kernel::CubicBSpline || D == 0 || D > MAX_AXES || count > out.len() {
            return 0;
        }
        let out = &mut out[..count];
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut weights = [[0.0f32; 4]; D];
        let mut base = channel;
        for ((&(i, t), stride), w) in cells
            .iter()
            .zip(&self.strides)
            .zip(weights.iter_mut())
            .skip(1)
        {
            base += i * stride;
            *w = bspline_weights(t);
        }
        for corner in 0..(1usize << (2 * (D - 1))) {
            let mut weight = 1.0f32;
            let mut offset = base;
            for (d, (w, stride)) in weights.iter().zip(&self.strides).enumerate().skip(1) {
                let k = (corner >> (2 * (d - 1))) & 3;
                weight *= w[k];
                offset += k * stride;
            }
            for (j, acc) in out.iter_mut().enumerate() {
                let value = self.values.get(offset + j * self.strides[0]);
                *acc += weight * value.copied().unwrap_or(0.0);
            }
        }
        count
    }

    /// The cubic B-spline along axis 0 through `column` (from
    /// [`Grid::cubic_column`]) at the physical coordinate `x` (clamped as
    /// [`Grid::interpolate`] clamps).
    #[inline]
    pub fn interpolate_column(&self, column: &[f32], x: f32) -> f32 {
        let (i, t) = self.axes[0].locate(x);
        let w = bspline_weights(t);
        let mut sum = 0.0f32;
        for (k, wk) in w.iter().enumerate() {
            sum += wk * column.get(i + k).copied().unwrap_or(0.0);
        }
        sum
    }

    /// n-linear blend of the `2^D` corners of the cell given per axis as
    /// `(index, fraction)` (from [`Axis::locate`]).
    #[inline]
    pub fn blend<const D: usize>(&self, cells: [(usize, f32); D], channel: usize) -> f32 {
        let mut base = channel;
        for (&(i, _), stride) in cells.iter().zip(&self.strides) {
            base += i * stride;
        }
        let mut sum = 0.0f32;
        for corner in 0..(1usize << D) {
            let mut weight = 1.0f32;
            let mut offset = base;
            for (d, (&(_, t), stride)) in cells.iter().zip(&self.strides).enumerate() {
                if corner >> d & 1 == 1 {
                    weight *= t;
                    offset += stride;
                } else {
                    weight *= 1.0 - t;
                }
            }
            sum += weight * self.values.get(offset).copied().unwrap_or(0.0);
        }
        sum
    }
}

/// The four uniform cubic B-spline weights at fraction `t ∈ [0, 1]` of a cell,
/// for the coefficients one before, at, after and two after the cell's start.
#[inline]
pub fn bspline_weights(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    [
        s * s * s / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tables::format::{AxisHeader, Header};

    fn axis(nodes: u32, mapping: Mapping, lo: f64, hi: f64, param: f64) -> AxisHeader {
        AxisHeader {
            nodes,
            mapping,
            lo,
            hi,
            param,
            param2: 0.0,
        }
    }

    fn header_with(axes: &[AxisHeader], channels: u32) -> Header {
        let mut all = [AxisHeader::UNUSED; MAX_AXES];
        all[..axes.len()].copy_from_slice(axes);
        Header {
            magic: crate::tables::format::MAGIC,
            format_version: crate::tables::format::FORMAT_VERSION,
            header_size: crate::tables::format::HEADER_SIZE as u32,
            table_id: crate::tables::format::TableId::SmithG1,
            value_type: crate::tables::format::ValueType::F32,
            channels,
            axis_count: axes.len() as u32,
            axes: all,
            aux_count: 0,
            kernel: Kernel::Multilinear,
            generator_version: [0; 16],
            params: [0.0; crate::tables::format::PARAM_COUNT],
            payload_offset: 0,
            payload_len: 0,
            checksum: 0,
        }
    }

    fn fill(axes: &[AxisHeader], f: impl Fn(&[f64]) -> f64) -> Vec<f32> {
        let total: usize = axes.iter().map(|a| a.nodes as usize).product();
        let mut out = Vec::with_capacity(total);
        let mut index = vec![0usize; axes.len()];
        for _ in 0..total {
            let x: Vec<f64> = index
                .iter()
                .zip(axes)
                .map(|(&i, a)| node_value(a, i))
                .collect();
            out.push(f(&x) as f32);
            for d in (0..axes.len()).rev() {
                index[d] += 1;
                if index[d] < axes[d].nodes as usize {
                    break;
                }
                index[d] = 0;
            }
        }
        out
    }

    /// Deterministic pseudo-random numbers in [0, 1) (SplitMix64).
    fn uniform(state: &mut u64) -> f64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn nodes_are_reproduced_exactly() {
        let axes = [
            axis(7, Mapping::Power, 0.2, 5.0, -0.5),
            axis(9, Mapping::LogOffset, 0.0, 100.0, 0.01),
        ];
        let values = fill(&axes, |x| x[0].sin() + x[1].sqrt());
        let header = header_with(&axes, 1);
        let grid = Grid::new(&header, &values).unwrap();
        for i in 0..7 {
            for j in 0..9 {
                let x = [
                    node_value(&axes[0], i) as f32,
                    node_value(&axes[1], j) as f32,
                ];
                let got = grid.interpolate(x, 0);
                let want = values[i * 9 + j];
                assert!(
                    (got - want).abs() <= 2e-6 * want.abs().max(1.0),
                    "{i},{j}: {got} vs {want}"
                );
            }
        }
    }

    /// A multilinear function of the mapped coordinates is reproduced exactly
    /// (to f32 rounding) everywhere, in 1 to 4 dimensions, with every mapping.
    #[test]
    fn multilinear_functions_are_exact() {
        let all = [
            axis(5, Mapping::Uniform, -1.0, 2.0, 0.0),
            axis(6, Mapping::Log, 0.1, 3000.0, 0.0),
            axis(4, Mapping::LogOffset, 0.0, 10.0, 0.5),
            axis(8, Mapping::Power, 0.2, 5.0, -0.5),
        ];
        for dims in 1..=4 {
            let axes = &all[..dims];
            let coef = [0.7, -1.3, 0.4, 2.1];
            // f = Π_d (1 + coef_d·c_d(x_d)): multilinear in the coordinates.
            let f = |x: &[f64]| -> f64 {
                x.iter()
                    .zip(axes)
                    .zip(coef)
                    .map(|((&x, a), k)| 1.0 + k * coordinate_f64(a, x))
                    .product()
            };
            let values = fill(axes, f);
            let header = header_with(axes, 1);
            let grid = Grid::new(&header, &values).unwrap();
            let mut state = 42u64;
            for _ in 0..2000 {
                let x: Vec<f64> = axes
                    .iter()
                    .map(|a| {
                        let c_lo = coordinate_f64(a, a.lo);
                        let c_hi = coordinate_f64(a, a.hi);
                        inverse_coordinate_f64(a, c_lo + (c_hi - c_lo) * uniform(&mut state))
                    })
                    .collect();
                let want = f(&x);
                let got = match dims {
                    1 => grid.interpolate([x[0] as f32], 0),
                    2 => grid.interpolate([x[0] as f32, x[1] as f32], 0),
                    3 => grid.interpolate([x[0] as f32, x[1] as f32, x[2] as f32], 0),
                    _ => grid.interpolate([x[0] as f32, x[1] as f32, x[2] as f32, x[3] as f32], 0),
                } as f64;
                // Scale of the function: the largest corner magnitude.
                let scale = values.iter().fold(0.0f32, |m, v| m.max(v.abs())) as f64;
                assert!(
                    (got - want).abs() <= 2e-5 * scale,
                    "dims {dims} at {x:?}: got {got}, want {want}"
                );
            }
        }
    }

    /// On a smooth function the error falls ~4x when the node count doubles
    /// (second-order convergence), per axis and together.
    #[test]
    fn convergence_is_second_order() {
        let f = |x: &[f64]| (1.3 * x[0]).sin() * (0.7 * x[1]).cos() + x[0] * x[1];
        let mut errors = Vec::new();
        for nodes in [9u32, 17, 33, 65] {
            let axes = [
                axis(nodes, Mapping::Uniform, 0.0, 3.0, 0.0),
                axis(nodes, Mapping::Uniform, -1.0, 2.0, 0.0),
            ];
            let values = fill(&axes, f);
            let header = header_with(&axes, 1);
            let grid = Grid::new(&header, &values).unwrap();
            let mut state = 7u64;
            let mut max = 0.0f64;
            for _ in 0..4000 {
                let x = [3.0 * uniform(&mut state), -1.0 + 3.0 * uniform(&mut state)];
                let got = grid.interpolate([x[0] as f32, x[1] as f32], 0) as f64;
                max = max.max((got - f(&x)).abs());
            }
            errors.push(max);
        }
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            assert!(
                (3.3..=4.8).contains(&ratio),
                "error ratio {ratio} in {errors:?}"
            );
        }
    }

    #[test]
    fn out_of_domain_clamps_and_nan_is_defined() {
        let axes = [axis(4, Mapping::Log, 0.1, 10.0, 0.0)];
        let values = fill(&axes, |x| x[0]);
        let header = header_with(&axes, 1);
        let grid = Grid::new(&header, &values).unwrap();
        let lo = grid.interpolate([0.1], 0);
        let hi = grid.interpolate([10.0], 0);
        assert_eq!(grid.interpolate([-5.0], 0), lo);
        assert_eq!(grid.interpolate([0.0], 0), lo);
        assert_eq!(grid.interpolate([f32::NAN], 0), lo);
        assert_eq!(grid.interpolate([f32::NEG_INFINITY], 0), lo);
        assert_eq!(grid.interpolate([1e30], 0), hi);
        assert_eq!(grid.interpolate([f32::INFINITY], 0), hi);
        assert!((hi - 10.0).abs() < 1e-5 && (lo - 0.1).abs() < 1e-6);
    }

    /// The B-spline kernel: weights form a partition of unity, and
    /// coefficients sampled from a function that is linear in each mapped
    /// coordinate (the B-spline's linear precision) reproduce it exactly.
    #[test]
    fn bspline_reproduces_multilinear_functions() {
        for i in 0..=100 {
            let w = bspline_weights(i as f32 / 100.0);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            assert!(w.iter().all(|&x| x >= 0.0));
        }
        let mut shifted = axis(6, Mapping::LogOffset, 0.0, 1.0, 0.003);
        shifted.param2 = 1.5;
        let axes = [
            shifted,
            axis(5, Mapping::Log, 0.05, 3000.0, 0.0),
            axis(4, Mapping::LogOffset, 1.0, 100.0, -0.8),
        ];
        let coef = [0.3, -0.7, 1.1];
        // Coefficient j of an axis sits at coordinate c_lo + (j − 1)·h.
        let coordinate_of = |a: &AxisHeader, j: usize| {
            let (c_lo, c_hi) = (coordinate_f64(a, a.lo), coordinate_f64(a, a.hi));
            c_lo + (c_hi - c_lo) * (j as f64 - 1.0) / f64::from(a.nodes - 1)
        };
        let mut values = Vec::new();
        for i in 0..axes[0].nodes as usize + 2 {
            for j in 0..axes[1].nodes as usize + 2 {
                for k in 0..axes[2].nodes as usize + 2 {
                    let c = [
                        coordinate_of(&axes[0], i),
                        coordinate_of(&axes[1], j),
                        coordinate_of(&axes[2], k),
                    ];
                    values.push(
                        (1.0 + coef[0] * c[0]) * (1.0 + coef[1] * c[1]) * (1.0 + coef[2] * c[2]),
                    );
                }
            }
        }
        let values: Vec<f32> = values.into_iter().map(|v| v as f32).collect();
        let mut header = header_with(&axes, 1);
        header.kernel = Kernel::CubicBSpline;
        let grid = Grid::new(&header, &values).unwrap();
        let mut state = 5u64;
        for _ in 0..3000 {
            let x: Vec<f64> = axes
                .iter()
                .map(|a| {
                    let (c_lo, c_hi) = (coordinate_f64(a, a.lo), coordinate_f64(a, a.hi));
                    inverse_coordinate_f64(a, c_lo + (c_hi - c_lo) * uniform(&mut state))
                })
                .collect();
            let c: Vec<f64> = x
                .iter()
                .zip(&axes)
                .map(|(&x, a)| coordinate_f64(a, x))
                .collect();
            let want = (1.0 + coef[0] * c[0]) * (1.0 + coef[1] * c[1]) * (1.0 + coef[2] * c[2]);
            let got = grid.interpolate([x[0] as f32, x[1] as f32, x[2] as f32], 0) as f64;
            assert!(
                (got - want).abs() < 1e-4 * want.abs().max(1.0),
                "{x:?}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn log_offset_linear_mapping_inverts() {
        let mut a = axis(72, Mapping::LogOffset, 0.0, 1.0, 0.003);
        a.param2 = 1.5;
        for i in 0..72 {
            let x = node_value(&a, i);
            assert!((0.0..=1.0).contains(&x));
            if i > 0 {
                assert!(x > node_value(&a, i - 1));
            }
        }
        let c = coordinate_f64(&a, 0.37);
        assert!((inverse_coordinate_f64(&a, c) - 0.37).abs() < 1e-14);
    }

    #[test]
    fn channels_are_interleaved() {
        let axes = [axis(3, Mapping::Uniform, 0.0, 2.0, 0.0)];
        let values = [0.0, 10.0, 1.0, 11.0, 2.0, 12.0];
        let header = header_with(&axes, 2);
        let grid = Grid::new(&header, &values).unwrap();
        assert_eq!(grid.interpolate([1.5], 0), 1.5);
        assert_eq!(grid.interpolate([1.5], 1), 11.5);
    }
}
