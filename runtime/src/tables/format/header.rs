//! The header ([`Header`], read in place) and the enums it is made of; the
//! per-node quantisation of u16 tables ([`quantise_node`], [`Quantised`]).

use super::MAX_AXES;
use super::PARAM_COUNT;
use super::TableId;
use core::fmt;
use core::mem::offset_of;
use zerocopy::Immutable;
use zerocopy::IntoBytes;
use zerocopy::KnownLayout;
use zerocopy::TryFromBytes;
/// Type of the stored grid values. `f16` is not offered: its round-trip error
/// (4.9e-4 relative) exceeds the accuracy targets, and on T3's `ln C` (values
/// up to ~40) it would be ~2e-2 absolute, i.e. 2% on `C`.
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum ValueType {
    /// IEEE 754 binary32, little-endian.
    F32 = 1,
    /// Per-node quantised: node `n`'s values are `offset_n + q · step_n` for
    /// u16 codes `q`, with `step_n = (max − min) / 65535` over the node's
    /// channels ([`quantise_node`]). The rounding error is at most
    /// `step_n / 2` (plus f32 rounding of the decode), i.e. 7.6e-6 of the
    /// node's value range: in the shipped T3 (node ranges up to 44: `ln C`
    /// and the fit channels) ≤ 3.4e-4 in `ln C`, 0.034% on `C`, at half the
    /// bytes of f32. The reader checks
    /// that every step is ≥ 0 and every decodable value finite. See
    /// [`Quantised`].
    U16 = 2,
}

impl ValueType {
    /// Every value type, in tag order.
    pub const ALL: [ValueType; 2] = [ValueType::F32, ValueType::U16];

    /// The value type with this tag, if any.
    pub fn from_tag(tag: u32) -> Option<ValueType> {
        Self::ALL.into_iter().find(|v| *v as u32 == tag)
    }
}

/// Quantises one node's values for [`ValueType::U16`]: returns
/// `[offset, step]` and writes the codes, so that
/// `offset + code · step` is within `step / 2` of each value (before f32
/// rounding). `offset` is the minimum, `step = (max − min) / 65535`
/// rounded to the smallest f32 whose decoded maximum reaches the maximum
/// (0 for a constant node, whose codes are all 0), so that quantising the
/// decoded values gives the same bits (the codes too, where the step exceeds
/// the f32 spacing of the values). Deterministic: the same values always
/// give the same bits. `codes` must be as long as `values` (extra entries of
/// either are ignored).
pub fn quantise_node(values: &[f32], codes: &mut [u16]) -> [f32; 2] {
    let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if !(lo.is_finite() && hi.is_finite()) {
        codes.iter_mut().for_each(|c| *c = 0);
        return [0.0, 0.0];
    }
    // The smallest f32 step whose decoded maximum `lo + 65535 step` (f32, as
    // `Quantised::value` decodes) reaches `hi`: decoding and quantising
    // again then gives the same step, so the node's bits round-trip (the
    // exporters rely on it). Within an ulp or two of `(hi − lo)/65535`.
    let mut step = ((f64::from(hi) - f64::from(lo)) / 65535.0) as f32;
    if step > 0.0 && step.is_finite() {
        let top = |s: f32| lo + 65535.0 * s;
        for _ in 0..64 {
            if top(step) >= hi {
                break;
            }
            step = f32::from_bits(step.to_bits() + 1);
        }
        for _ in 0..64 {
            let down = f32::from_bits(step.to_bits() - 1);
            if down > 0.0 && top(down) >= hi {
                step = down;
            } else {
                break;
            }
        }
    }
    for (code, &v) in codes.iter_mut().zip(values) {
        *code = if step > 0.0 {
            let q = (f64::from(v) - f64::from(lo)) / f64::from(step);
            // round half up; q ∈ [0, 65535 + rounding]
            crate::math::floor(q + 0.5).clamp(0.0, 65535.0) as u16
        } else {
            0
        };
    }
    [lo, step]
}

/// The grid of a [`ValueType::U16`] table, viewed in place: per node an
/// `(offset, step)` pair and `channels` u16 codes.
#[derive(Clone, Copy, Debug)]
pub struct Quantised<'a> {
    /// `[offset_0, step_0, offset_1, step_1, …]`, one pair per node.
    pub scales: &'a [f32],
    /// The codes, row-major (last axis fastest), channels innermost.
    pub codes: &'a [u16],
    /// Values per node.
    pub channels: usize,
}

impl Quantised<'_> {
    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.scales.len() / 2
    }

    /// Value `channel` of node `node` (0 outside the grid).
    #[inline]
    pub fn value(&self, node: usize, channel: usize) -> f32 {
        let (Some(&offset), Some(&step)) =
            (self.scales.get(2 * node), self.scales.get(2 * node + 1))
        else {
            return 0.0;
        };
        match self.codes.get(node * self.channels + channel) {
            Some(&q) if channel < self.channels => offset + f32::from(q) * step,
            _ => 0.0,
        }
    }
}

/// How the payload is interpolated, which also fixes what it holds.
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Kernel {
    /// The payload holds values at the nodes (not spline coefficients),
    /// `nodes` values per axis, blended n-linearly (`interp::Grid`, T1); T4's
    /// are the packed SH matrix (`crate::tables::sh_brdf`).
    Multilinear = 1,
    /// Uniform cubic B-spline in the mapped coordinates: the payload holds the
    /// spline's coefficients, `nodes + 2` per axis (one beyond each end node),
    /// prefiltered by the generator so that the spline interpolates the samples.
    CubicBSpline = 2,
    /// The payload holds values at the nodes, `nodes` values per axis,
    /// blended with Catmull–Rom weights over nodes `i − 1 … i + 2` (quadratic
    /// in the first and last cell): T3 (`crate::tables::convolution`). Before this tag T3
    /// was written with tag 1, which misdescribed it; a reader that does not
    /// know tag 3 refuses the file ([`FormatError::UnknownKernel`](super::FormatError::UnknownKernel)) rather
    /// than misread it, so the format version is unchanged.
    CatmullRom = 3,
}

impl Kernel {
    /// Every kernel, in tag order.
    pub const ALL: [Kernel; 3] = [
        Kernel::Multilinear,
        Kernel::CubicBSpline,
        Kernel::CatmullRom,
    ];

    /// The kernel with this tag, if any.
    pub fn from_tag(tag: u32) -> Option<Kernel> {
        Self::ALL.into_iter().find(|k| *k as u32 == tag)
    }

    /// Stored values along an axis of `nodes` nodes.
    pub const fn stored_per_axis(self, nodes: u32) -> u64 {
        match self {
            Kernel::Multilinear | Kernel::CatmullRom => nodes as u64,
            Kernel::CubicBSpline => nodes as u64 + 2,
        }
    }
}

/// How an axis maps a physical value `x` to the coordinate `c(x)` in which its
/// nodes are evenly spaced. Interpolation is linear in `c`. The numeric tags are
/// part of the file format; `param` is the mapping's parameter in [`AxisHeader`].
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Mapping {
    /// `c = x`.
    Uniform = 1,
    /// `c = ln x` (requires `lo > 0`).
    Log = 2,
    /// `c = ln(x + param) + param2·x`, `lo + param > 0`, `param2 ≥ 0`:
    /// logarithmic for `x ≫ param`, linear near `−param`; the optional linear
    /// term spreads the nodes again where the logarithm has crowded them out.
    LogOffset = 3,
    /// `c = x^param`, `param ≠ 0` (requires `lo > 0`); a negative exponent puts
    /// more nodes at small `x`.
    Power = 4,
}

impl Mapping {
    /// Every mapping, in tag order.
    pub const ALL: [Mapping; 4] = [
        Mapping::Uniform,
        Mapping::Log,
        Mapping::LogOffset,
        Mapping::Power,
    ];

    /// The mapping with this tag, if any.
    pub fn from_tag(tag: u32) -> Option<Mapping> {
        Self::ALL.into_iter().find(|m| *m as u32 == tag)
    }

    /// Human-readable form, e.g. `ln(x + 0.01)`.
    pub fn describe(self, param: f64, param2: f64) -> MappingDisplay {
        MappingDisplay {
            mapping: self,
            param,
            param2,
        }
    }
}

/// Display helper of [`Mapping::describe`].
pub struct MappingDisplay {
    mapping: Mapping,
    param: f64,
    param2: f64,
}

impl fmt::Display for MappingDisplay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sign = if self.param < 0.0 { '-' } else { '+' };
        let offset = self.param.abs();
        match self.mapping {
            Mapping::Uniform => write!(f, "x"),
            Mapping::Log => write!(f, "ln(x)"),
            Mapping::LogOffset if self.param2 != 0.0 => {
                write!(f, "ln(x {sign} {offset}) + {}·x", self.param2)
            }
            Mapping::LogOffset => write!(f, "ln(x {sign} {offset})"),
            Mapping::Power => write!(f, "x^{}", self.param),
        }
    }
}

/// One axis of a table, as stored: `nodes` values of the physical variable from
/// `lo` to `hi`, evenly spaced in the coordinate of `mapping`.
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct AxisHeader {
    /// Number of nodes (≥ 2 for a used axis, 0 for an unused slot).
    pub nodes: u32,
    /// The coordinate mapping.
    pub mapping: Mapping,
    /// First node, physical units.
    pub lo: f64,
    /// Last node, physical units.
    pub hi: f64,
    /// Parameter of the mapping (see [`Mapping`]); 0 when it has none.
    pub param: f64,
    /// Second parameter of the mapping (see [`Mapping`]); 0 when it has none.
    pub param2: f64,
}

impl AxisHeader {
    /// The header of an unused axis slot.
    pub const UNUSED: AxisHeader = AxisHeader {
        nodes: 0,
        mapping: Mapping::Uniform,
        lo: 0.0,
        hi: 0.0,
        param: 0.0,
        param2: 0.0,
    };
}

/// The file header, read in place (zero-copy) from the first [`HEADER_SIZE`](super::HEADER_SIZE) bytes.
///
/// zerocopy checks its size, its alignment and its enum tags; `#[repr(C)]`
/// without padding is enforced by the `IntoBytes` derive.
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Header {
    /// [`MAGIC`](super::MAGIC).
    pub magic: [u8; 8],
    /// [`FORMAT_VERSION`](super::FORMAT_VERSION).
    pub format_version: u32,
    /// [`HEADER_SIZE`](super::HEADER_SIZE); lets a reader reject a header of another layout.
    pub header_size: u32,
    /// What the table holds.
    pub table_id: TableId,
    /// Type of the stored values.
    pub value_type: ValueType,
    /// Values per grid node.
    pub channels: u32,
    /// Number of used axes (1..=[`MAX_AXES`]); the slots after them are unused.
    pub axis_count: u32,
    /// The axes, in storage order (the last varies fastest).
    pub axes: [AxisHeader; MAX_AXES],
    /// Number of auxiliary `f32` values (after the grid; for [`ValueType::U16`]
    /// after the node scales, before the codes). Meaning fixed per table id.
    pub aux_count: u32,
    /// How the grid is interpolated (and so how many values each axis stores).
    pub kernel: Kernel,
    /// Version of the generator that wrote the file, ASCII, NUL-padded.
    pub generator_version: [u8; 16],
    /// Generation parameters (names in [`TableId::param_names`]); unused slots zero.
    pub params: [f64; PARAM_COUNT],
    /// Byte offset of the payload from the start of the file (a multiple of 64).
    pub payload_offset: u64,
    /// Payload length in bytes (grid, aux and, for [`ValueType::U16`], scales).
    pub payload_len: u64,
    /// FNV-1a 64 of every byte of the file except this field.
    pub checksum: u64,
}

pub(super) const CHECKSUM_OFFSET: usize = offset_of!(Header, checksum);

impl Header {
    /// The used axes.
    pub fn used_axes(&self) -> &[AxisHeader] {
        let n = (self.axis_count as usize).min(MAX_AXES);
        &self.axes[..n]
    }

    /// The generator version as text (invalid UTF-8 shows as `?`).
    pub fn generator_version_str(&self) -> &str {
        let end = self
            .generator_version
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(self.generator_version.len());
        core::str::from_utf8(&self.generator_version[..end]).unwrap_or("?")
    }

    /// Number of stored grid values per channel (product over the used axes of
    /// the values the kernel stores per axis), `None` on overflow.
    pub fn grid_values(&self) -> Option<u64> {
        self.used_axes().iter().try_fold(1u64, |acc, axis| {
            acc.checked_mul(self.kernel.stored_per_axis(axis.nodes))
        })
    }
}
