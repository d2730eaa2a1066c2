//! The table file format: defined here, once, and used by the generator to write.
//!
//! A table file is a fixed-size [`Header`] followed by a 64-byte-aligned payload
//! of little-endian values. With [`ValueType::F32`] (every table but T3):
//!
//! ```text
//! offset 0                         Header (HEADER_SIZE bytes, #[repr(C)], read in place)
//! offset HEADER_SIZE .. 64k        zero padding
//! offset payload_offset            grid values (f32), row-major (last axis fastest), channels innermost
//!                                  then `aux_count` auxiliary f32 values (meaning fixed per table id)
//! end = payload_offset + payload_len   (nothing may follow)
//! ```
//!
//! With [`ValueType::U16`] (per-node quantised, T3), the payload is the nodes'
//! `(offset, step)` f32 pairs, then the aux f32 values, then the grid's u16
//! codes (row-major, channels innermost); see [`Quantised`]. Both sections
//! are viewed in place (`&[f32]`, `&[u16]`).
//!
//! Every field is validated by [`Table::from_bytes`]; any malformed input returns a
//! [`FormatError`] that says what is wrong, and no input can make it panic.
//! The checksum ([`checksum`], FNV-1a 64) covers every byte of the file except
//! the checksum field itself, so a flipped bit in the header or in the padding is
//! caught, not only one in the payload.
//!
//! Byte order: the format is little-endian and the crate reads it in place, so
//! the crate refuses to compile for big-endian targets (every renderer target we
//! know of — x86-64, AArch64, wasm32 — is little-endian).

use core::fmt;
use core::mem::{offset_of, size_of};
use zerocopy::{FromBytes, Immutable, IntoBytes, KnownLayout, TryFromBytes};

#[cfg(target_endian = "big")]
compile_error!(
    "twoscale table files are little-endian and read in place; big-endian targets are not supported"
);

/// The eight bytes every table file starts with.
pub const MAGIC: [u8; 8] = *b"TWOSCALE";
/// The format version this crate reads and writes.
///
/// * 1: eight generation parameters.
/// * 2: sixteen (T3's normalised angle gained its horizon and edge terms;
///   four slots spare).
/// * 3: T3's thirteenth parameter, the edge term's `(p′/p)^m` fade, is set
///   (`m = 2`); a format-2 reader would ignore it and misread T3. Older
///   versions are refused: rebuild them.
pub const FORMAT_VERSION: u32 = 3;
/// The largest number of axes a table may have (T3 is four-dimensional).
pub const MAX_AXES: usize = 4;
/// Number of table-specific generation parameters in the header.
pub const PARAM_COUNT: usize = 16;
/// Alignment of the payload, and of the start of the file in memory.
pub const PAYLOAD_ALIGN: usize = 64;
/// Size of [`Header`] in bytes.
pub const HEADER_SIZE: usize = size_of::<Header>();

/// Everything the runtime knows about one table, declared once (in
/// `table_ids!`'s invocation in `runtime/src/format.rs`) and read by every other place: the
/// readers, [`crate::TableSet`], the C API, the generator's registry, export
/// and inspect.
///
/// Tables are known by their **T-number** ([`number`](Self::number): T1 … T5,
/// in the docs, on the command line and in file names) and stored by their
/// **tag** ([`TableId::tag`]): tags are part of the file format and never
/// change, and they were given in the order the tables were added (T5 took
/// tag 3 before T3 existed; tag 5 is retired).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableDescriptor {
    /// The id (its discriminant is the tag stored in the file).
    pub id: TableId,
    /// The T-number the docs and the command line use (`3` for T3).
    pub number: u32,
    /// Short name `t<number>-<quantity>`: the file stem (`<stem>.tbl`) and
    /// the name on the command line. T4 has one file per material,
    /// `t4-<material>.tbl`; its stem names the kind.
    pub stem: &'static str,
    /// One-line description of the quantity.
    pub description: &'static str,
    /// Names of the axes, in storage order.
    pub axis_names: &'static [&'static str],
    /// Names of the generation parameters stored in [`Header::params`]
    /// (unused slots are zero and unnamed): the fields of the table's
    /// parameter struct ([`SmithG1Params`], [`SigmaRatioParams`],
    /// [`DiffuseFresnelParams`], [`ConvParams`], [`ShBrdfParams`], [`AlbedoParams`]).
    pub param_names: &'static [&'static str],
    /// How the runtime interpolates the payload; the reader refuses a file
    /// whose header says otherwise ([`Table::expecting`]).
    pub kernel: Kernel,
    /// How the payload is stored; the reader refuses a file whose header
    /// says otherwise ([`Table::expecting`]).
    pub value_type: ValueType,
    /// What the auxiliary values are (empty when the table has none).
    pub aux: &'static str,
    /// Whether [`crate::TableSet`] holds it (and the `embedded` feature
    /// compiles it in): every table the BRDF reads; not T4.
    pub in_set: bool,
}

/// Declares the table ids and their descriptors (the one place a table's
/// facts are written; ARCHITECTURE.md's "Adding a table").
macro_rules! table_ids {
    ($(
        $(#[$meta:meta])*
        $variant:ident = $tag:literal {
            number: $number:literal,
            stem: $stem:literal,
            description: $description:literal,
            axes: [$($axis:literal),+],
            params: $params:ident,
            kernel: $kernel:ident,
            value_type: $value_type:ident,
            aux: $aux:literal,
            in_set: $in_set:tt,
        }
    )+) => {
        /// Which quantity a table holds; its facts are its
        /// [`descriptor`](TableId::descriptor).
        #[derive(
            TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq, Eq, Hash,
        )]
        #[repr(u32)]
        pub enum TableId {
            $($(#[$meta])* $variant = $tag,)+
        }

        impl TableId {
            /// Every table id, in tag order.
            pub const ALL: [TableId; [$($tag),+].len()] = [$(TableId::$variant),+];

            /// Everything the runtime knows about the table.
            pub const fn descriptor(self) -> &'static TableDescriptor {
                match self {
                    $(TableId::$variant => &TableDescriptor {
                        id: TableId::$variant,
                        number: $number,
                        stem: $stem,
                        description: $description,
                        axis_names: &[$($axis),+],
                        param_names: $params::NAMES,
                        kernel: Kernel::$kernel,
                        value_type: ValueType::$value_type,
                        aux: $aux,
                        in_set: $in_set,
                    },)+
                }
            }
        }

        /// The committed files of the set's tables, compiled in (feature
        /// `embedded`). `tables` is a link to the workspace's `tables/` (the
        /// generator writes there); `cargo package` follows it, so a
        /// packaged crate carries the files.
        #[cfg(feature = "embedded")]
        pub(crate) fn embedded_bytes(id: TableId) -> Option<&'static [u8]> {
            match id {
                $(TableId::$variant => table_ids!(@embed $in_set, $stem),)+
            }
        }
    };
    (@embed true, $stem:literal) => {
        Some($crate::include_table!(concat!("../tables/", $stem, ".tbl")))
    };
    (@embed false, $stem:literal) => {
        None
    };
}

table_ids! {
    /// T1: Smith G1 of the EPD NDF over (p, ã = k_p·a); see [`crate::smith`].
    SmithG1 = 1 {
        number: 1,
        stem: "t1-smith-g1",
        description: "Smith G1 of the EPD NDF (HP17 36-38), axes p and k_p*beta*tan(theta); aux = k_p per p node",
        axes: ["p", "a_scaled"],
        params: SmithG1Params,
        kernel: Multilinear,
        value_type: F32,
        aux: "k_p = Gamma(3/(2p)) / (pi Gamma(1/p)) at each p node",
        in_set: true,
    }
    /// T2: σrel/σs of the K-correlation spectrum over (cos θi, B = b/λ, c);
    /// see [`crate::kcorr`].
    SigmaRatio = 2 {
        number: 2,
        stem: "t2-sigma-ratio",
        description: "sigma_rel/sigma_s of the K-correlation spectrum (HP17 17-19) divided by its closed form at normal incidence; cubic B-spline coefficients",
        axes: ["cos_theta_i", "B", "c"],
        params: SigmaRatioParams,
        kernel: CubicBSpline,
        value_type: F32,
        aux: "",
        in_set: true,
    }
    /// T5: internal diffuse Fresnel reflectance F_dr,int(η) of a dielectric
    /// over η; see [`crate::fresnel::DiffuseFresnelTable`].
    DiffuseFresnel = 3 {
        number: 5,
        stem: "t5-diffuse-fresnel",
        description: "internal diffuse Fresnel reflectance F_dr,int(eta) = 2 int_0^1 F(1/eta, mu) mu dmu of a dielectric (HP17 43, docs/model.md 2.6); cubic B-spline coefficients",
        axes: ["eta"],
        params: DiffuseFresnelParams,
        kernel: CubicBSpline,
        value_type: F32,
        aux: "",
        in_set: true,
    }
    /// T3: the convolution `C(θh; u, c, β, p)` of the diffraction lobe with
    /// the EPD NDF over (u, c, β, p): the paper's `s, g` (T3a) and `ln C` at
    /// 32 normalised angles (T3b) per node; see [`crate::conv`].
    Convolution = 4 {
        number: 3,
        stem: "t3-convolution",
        description: "convolution C(theta_h; u, c, beta, p) of the diffraction kernel with the EPD NDF (HP17 32-33, 39-41); channels: ln s, ln(g^2 + g_offset) of the paper's fit s*k(2g sin theta_h) (T3a), then ln C at evenly spaced values of the normalised angle xi (T3b); u16 codes per node; Catmull-Rom in the parameters and in xi",
        axes: ["u", "c", "beta", "p"],
        params: ConvParams,
        kernel: CatmullRom,
        value_type: U16,
        aux: "",
        in_set: true,
    }
    /// T6: the directional albedo `E(μ; β, p)` of the EPD microfacet lobe
    /// with F = 1, per masking mode; see [`crate::albedo`].
    Albedo = 7 {
        number: 6,
        stem: "t6-albedo",
        description: "directional albedo E(mu; beta, p) of the EPD microfacet lobe with F = 1 (docs/model.md 2.10); channels: separable, height-correlated masking; axes y = L/(1+L), L = ln(1+t), t = sigma tan(theta_i), sigma = s0/(1+s0^2), s0 = (1+k_p) beta, and z = (x-1)/(x+1), x = (k_p beta/width_centre)^width_exponent, and p; cubic B-spline coefficients",
        axes: ["incidence_y", "width_z", "p"],
        params: AlbedoParams,
        kernel: CubicBSpline,
        value_type: F32,
        aux: "",
        in_set: true,
    }
    /// T4: spherical-harmonic BRDF matrix of one material (\[WAT92\] §2,
    /// docs/model.md §2.9), one channel per RGB channel (at a wavelength, or
    /// integrated over the spectrum: aux `brdf_model`); see [`crate::sh`].
    ShBrdf = 6 {
        number: 4,
        stem: "t4-sh-brdf",
        description: "spherical-harmonic matrix of rho cos(theta_i) cos(theta_o) of one material (WAT92 2, docs/model.md 2.9): odd completion (l+m odd), packed upper triangles of the m-blocks; one channel per RGB channel (a wavelength, or integrated over the spectrum: aux brdf_model)",
        axes: ["coefficient"],
        params: ShBrdfParams,
        kernel: Multilinear,
        value_type: F32,
        aux: "",
        in_set: false,
    }
}

impl TableId {
    /// The tag stored in the file.
    pub const fn tag(self) -> u32 {
        self as u32
    }

    /// The id with this tag, if any.
    pub fn from_tag(tag: u32) -> Option<TableId> {
        Self::ALL.into_iter().find(|id| id.tag() == tag)
    }

    /// The T-number ([`TableDescriptor::number`]).
    pub const fn number(self) -> u32 {
        self.descriptor().number
    }

    /// The file stem and command-line name ([`TableDescriptor::stem`]).
    pub const fn name(self) -> &'static str {
        self.descriptor().stem
    }

    /// One-line description ([`TableDescriptor::description`]).
    pub const fn description(self) -> &'static str {
        self.descriptor().description
    }

    /// Names of the axes ([`TableDescriptor::axis_names`]).
    pub const fn axis_names(self) -> &'static [&'static str] {
        self.descriptor().axis_names
    }

    /// Names of the generation parameters ([`TableDescriptor::param_names`]).
    pub const fn param_names(self) -> &'static [&'static str] {
        self.descriptor().param_names
    }

    /// The file name, `<stem>.tbl`.
    #[cfg(feature = "std")]
    pub fn file_name(self) -> std::string::String {
        std::format!("{}.tbl", self.name())
    }
}

/// Implements a parameter struct's header slots: `NAMES`, `COUNT`,
/// `to_values` (what the generator writes) and `from_header` (what the
/// runtime reads), slot `k` holding the `k`-th listed field (a field of a
/// nested struct is written `outer.inner`; its name is `inner`).
macro_rules! header_slots {
    ($name:ident { $($first:ident $(. $rest:ident)?),+ $(,)? }) => {
        impl $name {
            /// The field names, in slot order (what `generator inspect` prints).
            pub const NAMES: &'static [&'static str] = &[$(header_slots!(@name $first $($rest)?)),+];
            /// Number of slots used.
            pub const COUNT: usize = Self::NAMES.len();

            /// The parameters in slot order (what the writer stores).
            pub fn to_values(&self) -> [f64; Self::COUNT] {
                [$(self.$first $(.$rest)?),+]
            }

            /// The parameters stored in `header`.
            pub fn from_header(header: &Header) -> Self {
                let mut slots = header.params.iter().copied();
                let mut out = Self::default();
                $(out.$first $(.$rest)? = slots.next().unwrap_or(0.0);)+
                out
            }
        }

        const _: () = assert!($name::COUNT <= PARAM_COUNT);
    };
    (@name $first:ident) => { stringify!($first) };
    (@name $first:ident $rest:ident) => { stringify!($rest) };
}

/// Defines a table's generation parameters as a struct of named `f64`
/// fields, stored in [`Header::params`] in field order: the one definition the
/// generator writes ([`to_values`](SmithG1Params::to_values)) and the runtime
/// reads ([`from_header`](SmithG1Params::from_header)).
macro_rules! header_params {
    ($(#[$meta:meta])* $name:ident { $($(#[$field_meta:meta])* $field:ident,)+ }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Default)]
        pub struct $name {
            $($(#[$field_meta])* pub $field: f64,)+
        }

        header_slots!($name { $($field),+ });
    };
}

header_params! {
    /// T1's generation parameters.
    SmithG1Params {
        /// Relative tolerance of the Λ quadrature.
        quadrature_rel_tol,
        /// Absolute tolerance of the Λ quadrature.
        quadrature_abs_tol,
    }
}

header_params! {
    /// T2's generation parameters.
    SigmaRatioParams {
        /// Relative tolerance of the σrel quadrature.
        quadrature_rel_tol,
        /// `c − 1` at which the node `c = 1` is computed (the limit c → 1).
        c_minus_1_at_first_node,
    }
}

header_params! {
    /// T5's generation parameters.
    DiffuseFresnelParams {
        /// Relative tolerance of the F_dr,int quadrature.
        quadrature_rel_tol,
        /// Absolute tolerance of the F_dr,int quadrature.
        quadrature_abs_tol,
    }
}

/// T3's generation parameters: its number of normalised angles, the
/// normalised angle's constants ([`AngleParams`](crate::conv::AngleParams),
/// docs/model.md §3), the T3a `g` offset and the value floor.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ConvParams {
    /// Number of normalised angles ξ (the `ln C` channels).
    pub angles: f64,
    /// The normalised angle's constants.
    pub angle: crate::conv::AngleParams,
    /// T3a stores `ln(g² + g_offset)`.
    pub g_offset: f64,
    /// `ln C` is stored at least at `ln(value_floor · peak)`.
    pub value_floor: f64,
}

// The slot order is format version 3's (the angle's fields are not
// contiguous: format 1 had five of them, the others came later); the
// edge term's fade `m` (slot 13) is what version 3 added.
header_slots!(ConvParams {
    angles,
    angle.tau_max,
    angle.kernel_scale_floor,
    angle.ndf_weight,
    angle.ndf_exponent_cap,
    g_offset,
    value_floor,
    angle.ndf_softening,
    angle.horizon_weight,
    angle.edge_weight,
    angle.edge_smoothing,
    angle.edge_fade_tan,
    angle.edge_softening_fade,
});

header_params! {
    /// T6's generation parameters.
    AlbedoParams {
        /// `γ_c` of the width coordinate (`crate::albedo::WIDTH_CENTRE`).
        width_centre,
        /// `κ` of the width coordinate (`crate::albedo::WIDTH_EXPONENT`).
        width_exponent,
        /// Gauss–Legendre points per piece of the node quadrature.
        quadrature_points,
        /// β at which the nodes of `z = −1` (β → 0) are computed.
        beta_at_first_node,
        /// β at which the nodes of `z = 1` (β → ∞) are computed.
        beta_at_last_node,
    }
}

header_params! {
    /// T4's generation parameters.
    ShBrdfParams {
        /// `L`, the largest degree stored.
        band_limit,
        /// `l_f` of the half-Gaussian band filter of \[WAT92\] §2.5: every
        /// coefficient `M_jk` is multiplied by `h(l_j) h(l_k)`,
        /// `h(l) = exp(−(l − l_f)² / (2 w²))` for `l > l_f`, 1 otherwise.
        filter_start,
        /// `w` of the band filter; 0 means no filter.
        filter_width,
        /// Wavelength of channel 0, µm (0 for an absent channel).
        lambda_0,
        /// Wavelength of channel 1, µm (0 for an absent channel).
        lambda_1,
        /// Wavelength of channel 2, µm (0 for an absent channel).
        lambda_2,
        /// `‖M − Mᵀ‖ / ‖M‖` before symmetrising, with the norm of (WAT92 27),
        /// `‖A‖ = Σ|A_jk| / J²`, over the whole matrix; the largest over the
        /// channels.
        asymmetry_rel,
        /// Gauss–Legendre nodes in `cos θ ∈ [0, 1]` of the projection.
        theta_nodes,
    }
}

impl ShBrdfParams {
    /// The wavelength of each channel, µm (0 for absent channels).
    pub fn wavelengths(&self) -> [f64; 3] {
        [self.lambda_0, self.lambda_1, self.lambda_2]
    }
}

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
    /// are the packed SH matrix (`crate::sh`).
    Multilinear = 1,
    /// Uniform cubic B-spline in the mapped coordinates: the payload holds the
    /// spline's coefficients, `nodes + 2` per axis (one beyond each end node),
    /// prefiltered by the generator so that the spline interpolates the samples.
    CubicBSpline = 2,
    /// The payload holds values at the nodes, `nodes` values per axis,
    /// blended with Catmull–Rom weights over nodes `i − 1 … i + 2` (quadratic
    /// in the first and last cell): T3 (`crate::conv`). Before this tag T3
    /// was written with tag 1, which misdescribed it; a reader that does not
    /// know tag 3 refuses the file ([`FormatError::UnknownKernel`]) rather
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

/// The file header, read in place (zero-copy) from the first [`HEADER_SIZE`] bytes.
///
/// zerocopy checks its size, its alignment and its enum tags; `#[repr(C)]`
/// without padding is enforced by the `IntoBytes` derive.
#[derive(TryFromBytes, IntoBytes, KnownLayout, Immutable, Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Header {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`FORMAT_VERSION`].
    pub format_version: u32,
    /// [`HEADER_SIZE`]; lets a reader reject a header of another layout.
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

const CHECKSUM_OFFSET: usize = offset_of!(Header, checksum);

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

/// What is wrong with a table file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FormatError {
    /// The buffer ends before the header or the payload does.
    Truncated {
        /// Bytes the header says the file has (or the header size).
        needed: u64,
        /// Bytes present.
        actual: u64,
    },
    /// Bytes follow the end of the payload.
    TrailingBytes {
        /// Bytes the header says the file has.
        expected: u64,
        /// Bytes present.
        actual: u64,
    },
    /// The file does not start with [`MAGIC`].
    WrongMagic {
        /// The first eight bytes.
        found: [u8; 8],
    },
    /// A format version this crate does not read.
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
    },
    /// The header size field disagrees with this crate's header layout.
    HeaderSize {
        /// Size in the file.
        found: u32,
    },
    /// The buffer does not start on a 64-byte boundary.
    Misaligned {
        /// Address of the buffer modulo 64.
        address_mod_64: usize,
    },
    /// An unknown table id tag.
    UnknownTableId(u32),
    /// An unknown value type tag.
    UnknownValueType(u32),
    /// An unknown interpolation kernel tag.
    UnknownKernel(u32),
    /// An unknown axis mapping tag.
    UnknownMapping {
        /// Axis index.
        axis: usize,
        /// The tag.
        tag: u32,
    },
    /// Axis count outside 1..=4.
    AxisCount(u32),
    /// An axis whose fields are inconsistent (see the reason).
    BadAxis {
        /// Axis index.
        axis: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// Some other header field is invalid (see the reason).
    BadHeader(&'static str),
    /// `payload_len` disagrees with node counts × channels + aux values.
    PayloadLength {
        /// Bytes implied by the node counts, channels and aux count.
        expected: u64,
        /// `payload_len` in the header.
        found: u64,
    },
    /// The checksum does not match the contents.
    ChecksumMismatch {
        /// Checksum in the header.
        stored: u64,
        /// Checksum of the bytes.
        computed: u64,
    },
    /// A payload value is NaN or infinite.
    NonFinite {
        /// Index of the value in the payload.
        index: usize,
    },
    /// The file is valid but holds another table than the one asked for.
    WrongTable {
        /// The table asked for.
        expected: TableId,
        /// The table in the file.
        found: TableId,
    },
    /// The file is valid but its kernel is not the one the runtime uses for
    /// this table ([`TableDescriptor::kernel`]).
    WrongKernel {
        /// The table.
        table: TableId,
        /// The kernel in the file.
        found: Kernel,
    },
    /// The file is valid but its values are not stored as the runtime reads
    /// them for this table ([`TableDescriptor::value_type`]).
    WrongValueType {
        /// The table.
        table: TableId,
        /// The value type in the file.
        found: ValueType,
    },
    /// The file is valid but its shape is not the one this table kind needs.
    Shape(&'static str),
}

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use FormatError::*;
        match *self {
            Truncated { needed, actual } => {
                write!(f, "truncated table file: {actual} bytes, needs {needed}")
            }
            TrailingBytes { expected, actual } => write!(
                f,
                "table file has {actual} bytes, but its header describes {expected}"
            ),
            WrongMagic { found } => write!(
                f,
                "not a twoscale table file: starts with {found:?}, expected {MAGIC:?}"
            ),
            UnsupportedVersion { found } => write!(
                f,
                "table format version {found} is not supported (this reader knows version {FORMAT_VERSION})"
            ),
            HeaderSize { found } => {
                write!(f, "header size field is {found}, expected {HEADER_SIZE}")
            }
            Misaligned { address_mod_64 } => write!(
                f,
                "table bytes must start on a {PAYLOAD_ALIGN}-byte boundary (address mod 64 = {address_mod_64}); use twoscale::AlignedBytes"
            ),
            UnknownTableId(tag) => write!(f, "unknown table id {tag}"),
            UnknownValueType(tag) => write!(f, "unknown value type {tag}"),
            UnknownKernel(tag) => write!(f, "unknown interpolation kernel {tag}"),
            UnknownMapping { axis, tag } => write!(f, "axis {axis}: unknown mapping {tag}"),
            AxisCount(n) => write!(f, "axis count {n} is outside 1..={MAX_AXES}"),
            BadAxis { axis, reason } => write!(f, "axis {axis}: {reason}"),
            BadHeader(reason) => write!(f, "invalid header: {reason}"),
            PayloadLength { expected, found } => write!(
                f,
                "payload length {found} bytes disagrees with the node counts, channels and aux count ({expected} bytes)"
            ),
            ChecksumMismatch { stored, computed } => write!(
                f,
                "checksum mismatch: header says {stored:#018x}, contents give {computed:#018x}"
            ),
            NonFinite { index } => write!(f, "payload value {index} is not finite"),
            WrongTable { expected, found } => write!(
                f,
                "expected table {}, found {}",
                expected.name(),
                found.name()
            ),
            WrongKernel { table, found } => write!(
                f,
                "{} is interpolated with kernel {:?}, the file says {found:?}; rebuild it with this generator",
                table.name(),
                table.descriptor().kernel
            ),
            WrongValueType { table, found } => write!(
                f,
                "{} is stored as {:?}, the file holds {found:?}; rebuild it with this generator",
                table.name(),
                table.descriptor().value_type
            ),
            Shape(reason) => write!(f, "unexpected table shape: {reason}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for FormatError {}

/// FNV-1a 64 of `bytes`, continuing from `state` (start with [`FNV_OFFSET`]).
pub const fn fnv1a(mut state: u64, bytes: &[u8]) -> u64 {
    let mut i = 0;
    while i < bytes.len() {
        state ^= bytes[i] as u64;
        state = state.wrapping_mul(0x0000_0100_0000_01b3);
        i += 1;
    }
    state
}

/// FNV-1a 64 offset basis.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The checksum of a whole file image: FNV-1a 64 of every byte except the eight
/// bytes of [`Header::checksum`]. `file.len()` must be at least [`HEADER_SIZE`].
pub fn checksum(file: &[u8]) -> u64 {
    let (before, rest) = file.split_at(CHECKSUM_OFFSET.min(file.len()));
    let after = rest.get(8..).unwrap_or(&[]);
    fnv1a(fnv1a(FNV_OFFSET, before), after)
}

/// Bytes with 64-byte alignment, for embedding a table with `include_bytes!`:
///
/// ```ignore
/// static G1: &twoscale::AlignedBytes<[u8]> =
///     &twoscale::AlignedBytes(*include_bytes!("../tables/t1-smith-g1.tbl"));
/// ```
///
/// (the [`include_table!`](crate::include_table) macro writes exactly this).
/// `include_bytes!` alone only guarantees 1-byte alignment, and a table must be
/// viewable in place as `&[f32]`.
#[repr(C, align(64))]
pub struct AlignedBytes<B: ?Sized>(pub B);

impl<B: AsRef<[u8]> + ?Sized> AlignedBytes<B> {
    /// The wrapped bytes.
    pub fn bytes(&self) -> &[u8] {
        self.0.as_ref()
    }
}

/// Embeds a table file in the binary with the 64-byte alignment it needs, and
/// evaluates to a `&'static [u8]` ready for `Table::from_bytes` or a typed table.
///
/// ```ignore
/// let bytes: &'static [u8] = twoscale::include_table!("../tables/t1-smith-g1.tbl");
/// ```
#[macro_export]
macro_rules! include_table {
    ($path:expr) => {{
        static TABLE: &$crate::AlignedBytes<[u8]> = &$crate::AlignedBytes(*include_bytes!($path));
        &TABLE.0
    }};
}

/// A validated table file viewed in place: its header, grid and aux values.
#[derive(Clone, Copy, Debug)]
pub struct Table<'a> {
    header: &'a Header,
    grid: &'a [f32],
    aux: &'a [f32],
    quantised: Option<Quantised<'a>>,
}

impl<'a> Table<'a> {
    /// Validates `bytes` as a table file and views it in place. Checks, in order:
    /// header size, alignment, magic, version, header size, enum tags, axes, payload
    /// offset and length, trailing bytes, checksum, and that every value is finite.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let actual = bytes.len() as u64;
        let head = bytes.get(..HEADER_SIZE).ok_or(FormatError::Truncated {
            needed: HEADER_SIZE as u64,
            actual,
        })?;
        let address_mod_64 = bytes.as_ptr() as usize % PAYLOAD_ALIGN;
        if address_mod_64 != 0 {
            return Err(FormatError::Misaligned { address_mod_64 });
        }
        if head[..8] != MAGIC {
            let mut found = [0; 8];
            found.copy_from_slice(&head[..8]);
            return Err(FormatError::WrongMagic { found });
        }
        let version = read_u32(head, offset_of!(Header, format_version));
        if version != FORMAT_VERSION {
            return Err(FormatError::UnsupportedVersion { found: version });
        }
        let header_size = read_u32(head, offset_of!(Header, header_size));
        if header_size as usize != HEADER_SIZE {
            return Err(FormatError::HeaderSize { found: header_size });
        }
        let header = Header::try_ref_from_bytes(head).map_err(|_| diagnose_tags(head))?;
        validate_header(header)?;

        let offset = header.payload_offset;
        let end = offset
            .checked_add(header.payload_len)
            .ok_or(FormatError::BadHeader("payload offset + length overflows"))?;
        if end > actual {
            return Err(FormatError::Truncated {
                needed: end,
                actual,
            });
        }
        if end < actual {
            return Err(FormatError::TrailingBytes {
                expected: end,
                actual,
            });
        }
        let computed = checksum(bytes);
        if computed != header.checksum {
            return Err(FormatError::ChecksumMismatch {
                stored: header.checksum,
                computed,
            });
        }
        // Bounds and alignment were checked above, so these cannot fail; map the
        // impossible case to an error rather than panic.
        let payload = bytes
            .get(offset as usize..end as usize)
            .ok_or(FormatError::BadHeader("payload out of bounds"))?;
        // The f32 part: everything (F32), or the scales and aux (U16).
        let (floats, codes) = match header.value_type {
            ValueType::F32 => (payload, &[][..]),
            ValueType::U16 => {
                let nodes = header.grid_values().unwrap_or(0) as usize;
                let float_bytes = (2 * nodes + header.aux_count as usize) * 4;
                payload
                    .split_at_checked(float_bytes)
                    .ok_or(FormatError::BadHeader("payload shorter than its scales"))?
            }
        };
        let values = <[f32]>::ref_from_bytes(floats)
            .map_err(|_| FormatError::BadHeader("payload is not a whole number of aligned f32"))?;
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(FormatError::NonFinite { index });
        }
        let split = values.len() - header.aux_count as usize;
        let (head_values, aux) = values.split_at(split);
        let (grid, quantised) = match header.value_type {
            ValueType::F32 => (head_values, None),
            ValueType::U16 => {
                // Every decoded value must be finite too, like an f32 table's.
                if head_values
                    .chunks_exact(2)
                    .any(|pair| !(pair[1] >= 0.0 && (pair[0] + 65535.0 * pair[1]).is_finite()))
                {
                    return Err(FormatError::BadHeader(
                        "a quantisation step is negative or decodes beyond f32",
                    ));
                }
                let codes = <[u16]>::ref_from_bytes(codes)
                    .map_err(|_| FormatError::BadHeader("codes are not whole aligned u16"))?;
                let quantised = Quantised {
                    scales: head_values,
                    codes,
                    channels: header.channels as usize,
                };
                (&[][..], Some(quantised))
            }
        };
        Ok(Table {
            header,
            grid,
            aux,
            quantised,
        })
    }

    /// Like [`Table::from_bytes`], and also checks the table id.
    pub fn from_bytes_expecting(bytes: &'a [u8], expected: TableId) -> Result<Self, FormatError> {
        Self::from_bytes(bytes)?.expecting(expected)
    }

    /// The table itself if it holds `expected`, else [`FormatError::WrongTable`].
    /// Also checks that the file's kernel and value type are the ones its
    /// [`TableDescriptor`] says the runtime uses.
    pub fn expecting(self, expected: TableId) -> Result<Self, FormatError> {
        if self.header.table_id != expected {
            return Err(FormatError::WrongTable {
                expected,
                found: self.header.table_id,
            });
        }
        let descriptor = expected.descriptor();
        if self.header.kernel != descriptor.kernel {
            return Err(FormatError::WrongKernel {
                table: expected,
                found: self.header.kernel,
            });
        }
        if self.header.value_type != descriptor.value_type {
            return Err(FormatError::WrongValueType {
                table: expected,
                found: self.header.value_type,
            });
        }
        Ok(self)
    }

    /// The header.
    pub fn header(&self) -> &'a Header {
        self.header
    }

    /// The grid values of a [`ValueType::F32`] table, row-major, channels
    /// innermost (empty for a [`ValueType::U16`] table: see
    /// [`Table::quantised`]).
    pub fn grid(&self) -> &'a [f32] {
        self.grid
    }

    /// The grid of a [`ValueType::U16`] table (`None` for f32 tables).
    pub fn quantised(&self) -> Option<Quantised<'a>> {
        self.quantised
    }

    /// The auxiliary values (meaning fixed per table id).
    pub fn aux(&self) -> &'a [f32] {
        self.aux
    }
}

fn read_u32(head: &[u8], offset: usize) -> u32 {
    let mut word = [0u8; 4];
    if let Some(src) = head.get(offset..offset + 4) {
        word.copy_from_slice(src);
    }
    u32::from_le_bytes(word)
}

/// zerocopy rejected the header: find which enum tag is invalid.
fn diagnose_tags(head: &[u8]) -> FormatError {
    let table_tag = read_u32(head, offset_of!(Header, table_id));
    if TableId::from_tag(table_tag).is_none() {
        return FormatError::UnknownTableId(table_tag);
    }
    let value_tag = read_u32(head, offset_of!(Header, value_type));
    if ValueType::from_tag(value_tag).is_none() {
        return FormatError::UnknownValueType(value_tag);
    }
    let kernel_tag = read_u32(head, offset_of!(Header, kernel));
    if Kernel::from_tag(kernel_tag).is_none() {
        return FormatError::UnknownKernel(kernel_tag);
    }
    for axis in 0..MAX_AXES {
        let at = offset_of!(Header, axes)
            + axis * size_of::<AxisHeader>()
            + offset_of!(AxisHeader, mapping);
        let tag = read_u32(head, at);
        if Mapping::from_tag(tag).is_none() {
            return FormatError::UnknownMapping { axis, tag };
        }
    }
    FormatError::BadHeader("header rejected by layout validation")
}

/// Checks the fields of a header whose tags are already known to be valid.
pub fn validate_header(header: &Header) -> Result<(), FormatError> {
    let count = header.axis_count;
    if count == 0 || count as usize > MAX_AXES {
        return Err(FormatError::AxisCount(count));
    }
    for (axis, a) in header.axes.iter().enumerate() {
        if axis >= count as usize {
            if *a != AxisHeader::UNUSED {
                return Err(FormatError::BadAxis {
                    axis,
                    reason: "unused axis slot is not zeroed",
                });
            }
            continue;
        }
        validate_axis(axis, a)?;
    }
    if header.channels == 0 {
        return Err(FormatError::BadHeader("channel count is zero"));
    }
    if header.params.iter().any(|p| !p.is_finite()) {
        return Err(FormatError::BadHeader(
            "a generation parameter is not finite",
        ));
    }
    let names = header.table_id.param_names().len();
    if header.params[names.min(PARAM_COUNT)..]
        .iter()
        .any(|&p| p != 0.0)
    {
        return Err(FormatError::BadHeader(
            "an unnamed generation parameter is not zero",
        ));
    }
    if !header.generator_version.is_ascii() {
        return Err(FormatError::BadHeader("generator version is not ASCII"));
    }
    if !header.payload_offset.is_multiple_of(PAYLOAD_ALIGN as u64)
        || header.payload_offset < HEADER_SIZE as u64
    {
        return Err(FormatError::BadHeader(
            "payload offset is not a multiple of 64 past the header",
        ));
    }
    let expected = payload_bytes(header).ok_or(FormatError::BadHeader("node counts overflow"))?;
    if expected != header.payload_len {
        return Err(FormatError::PayloadLength {
            expected,
            found: header.payload_len,
        });
    }
    Ok(())
}

/// Payload bytes implied by the node counts, channels, aux count and value
/// type (`None` on overflow).
fn payload_bytes(header: &Header) -> Option<u64> {
    let nodes = header.grid_values()?;
    let values = nodes.checked_mul(u64::from(header.channels))?;
    let aux = u64::from(header.aux_count);
    match header.value_type {
        ValueType::F32 => values.checked_add(aux)?.checked_mul(4),
        ValueType::U16 => nodes
            .checked_mul(2)?
            .checked_add(aux)?
            .checked_mul(4)?
            .checked_add(values.checked_mul(2)?),
    }
}

fn validate_axis(axis: usize, a: &AxisHeader) -> Result<(), FormatError> {
    let bad = |reason| Err(FormatError::BadAxis { axis, reason });
    if a.nodes < 2 {
        return bad("fewer than 2 nodes");
    }
    if !(a.lo.is_finite() && a.hi.is_finite() && a.param.is_finite() && a.param2.is_finite()) {
        return bad("non-finite domain or parameter");
    }
    if a.lo >= a.hi {
        return bad("domain is empty (lo >= hi)");
    }
    if a.mapping != Mapping::LogOffset && a.param2 != 0.0 {
        return bad("only the log-offset mapping takes a second parameter");
    }
    match a.mapping {
        Mapping::Uniform if a.param != 0.0 => bad("uniform mapping takes no parameter"),
        Mapping::Log if a.param != 0.0 => bad("log mapping takes no parameter"),
        Mapping::Log if a.lo <= 0.0 => bad("log mapping needs lo > 0"),
        Mapping::LogOffset if a.lo + a.param <= 0.0 => {
            bad("log-offset mapping needs lo + param > 0")
        }
        Mapping::LogOffset if a.param2 < 0.0 => bad("log-offset mapping needs param2 >= 0"),
        Mapping::Power if a.param == 0.0 => bad("power mapping needs a non-zero exponent"),
        Mapping::Power if a.lo <= 0.0 => bad("power mapping needs lo > 0"),
        _ => Ok(()),
    }
}

/// Writing table files (used by the generator).
#[cfg(feature = "std")]
pub mod write {
    use super::*;
    use std::io::Write;
    use std::path::Path;

    /// Everything a table file holds, before encoding.
    #[derive(Clone, Debug)]
    pub struct TableSpec<'v> {
        /// What the table holds.
        pub table_id: TableId,
        /// Values per node.
        pub channels: u32,
        /// The interpolation kernel (B-spline grids hold prefiltered coefficients).
        pub kernel: Kernel,
        /// How `grid` is stored: as is ([`ValueType::F32`]) or quantised per
        /// node by [`quantise_node`] ([`ValueType::U16`]).
        pub value_type: ValueType,
        /// Used axes, in storage order.
        pub axes: &'v [AxisHeader],
        /// Generation parameters, in the order of [`TableId::param_names`]
        /// (the table's parameter struct's `to_values()`, e.g. [`ConvParams::to_values`]).
        pub params: &'v [f64],
        /// Grid values, row-major, channels innermost.
        pub grid: &'v [f32],
        /// Auxiliary values.
        pub aux: &'v [f32],
        /// Generator version (at most 16 ASCII bytes).
        pub generator_version: &'v str,
    }

    /// Encodes a table into the bytes of a file, and validates them by reading
    /// them back (an encoder bug can never write a file the reader rejects).
    pub fn encode(spec: &TableSpec<'_>) -> Result<Vec<u8>, FormatError> {
        if spec.axes.is_empty() || spec.axes.len() > MAX_AXES {
            return Err(FormatError::AxisCount(spec.axes.len() as u32));
        }
        if spec.params.len() != spec.table_id.param_names().len() {
            return Err(FormatError::BadHeader(
                "parameter count disagrees with the table's parameter names",
            ));
        }
        let version = spec.generator_version.as_bytes();
        if version.len() > 16 {
            return Err(FormatError::BadHeader(
                "generator version longer than 16 bytes",
            ));
        }
        let mut axes = [AxisHeader::UNUSED; MAX_AXES];
        axes[..spec.axes.len()].copy_from_slice(spec.axes);
        let mut params = [0.0; PARAM_COUNT];
        params[..spec.params.len()].copy_from_slice(spec.params);
        let mut generator_version = [0u8; 16];
        generator_version[..version.len()].copy_from_slice(version);
        let payload_offset = HEADER_SIZE.next_multiple_of(PAYLOAD_ALIGN);
        let channels = spec.channels as usize;
        if channels == 0 || !spec.grid.len().is_multiple_of(channels) {
            return Err(FormatError::BadHeader(
                "grid length is not a multiple of the channel count",
            ));
        }
        // The f32 values and (U16) the codes, in payload order.
        let (floats, codes): (Vec<f32>, Vec<u16>) = match spec.value_type {
            ValueType::F32 => (spec.grid.iter().chain(spec.aux).copied().collect(), vec![]),
            ValueType::U16 => {
                let nodes = spec.grid.len() / channels;
                let mut scales = Vec::with_capacity(2 * nodes + spec.aux.len());
                let mut codes = vec![0u16; spec.grid.len()];
                for (values, node_codes) in spec
                    .grid
                    .chunks_exact(channels)
                    .zip(codes.chunks_exact_mut(channels))
                {
                    scales.extend_from_slice(&quantise_node(values, node_codes));
                }
                scales.extend_from_slice(spec.aux);
                (scales, codes)
            }
        };
        let payload_len = floats.len() * 4 + codes.len() * 2;
        let mut header = Header {
            magic: MAGIC,
            format_version: FORMAT_VERSION,
            header_size: HEADER_SIZE as u32,
            table_id: spec.table_id,
            value_type: spec.value_type,
            channels: spec.channels,
            axis_count: spec.axes.len() as u32,
            axes,
            aux_count: spec.aux.len() as u32,
            kernel: spec.kernel,
            generator_version,
            params,
            payload_offset: payload_offset as u64,
            payload_len: payload_len as u64,
            checksum: 0,
        };
        validate_header(&header)?;
        let mut file = Vec::with_capacity(payload_offset + payload_len);
        file.extend_from_slice(header.as_bytes());
        file.resize(payload_offset, 0);
        for v in &floats {
            file.extend_from_slice(&v.to_le_bytes());
        }
        for q in &codes {
            file.extend_from_slice(&q.to_le_bytes());
        }
        header.checksum = checksum(&file);
        file[..HEADER_SIZE].copy_from_slice(header.as_bytes());
        // Read it back through the validating reader (from an aligned copy).
        let aligned = crate::format::aligned_copy(&file);
        Table::from_bytes(aligned.bytes())?;
        Ok(file)
    }

    /// Writes `bytes` to `path` atomically: to a temporary file in the same
    /// directory, flushed to disk, then renamed over `path`.
    ///
    /// Table files are memory-mapped by readers, and a mapped file that is
    /// truncated or rewritten in place makes every process that maps it crash
    /// with SIGBUS (or silently see mixed contents). A rename replaces the
    /// directory entry and leaves any old mapping on the old inode intact, so
    /// never rewrite a table file in place: always go through this function.
    pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        let name = path
            .file_name()
            .ok_or_else(|| std::io::Error::other("table path has no file name"))?;
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.tmp", std::process::id()));
        let tmp = dir.join(tmp_name);
        let result = (|| {
            let mut file = std::fs::File::create(&tmp)?;
            file.write_all(bytes)?;
            file.sync_all()?;
            std::fs::rename(&tmp, path)
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }
}

/// A 64-byte-aligned heap copy of `bytes` (for tests and for reading a file
/// into memory instead of mapping it).
#[cfg(feature = "std")]
pub fn aligned_copy(bytes: &[u8]) -> AlignedBuf {
    let mut blocks = vec![Block([0; 64]); bytes.len().div_ceil(64)];
    for (block, chunk) in blocks.iter_mut().zip(bytes.chunks(64)) {
        block.0[..chunk.len()].copy_from_slice(chunk);
    }
    AlignedBuf {
        blocks,
        len: bytes.len(),
    }
}

#[cfg(feature = "std")]
#[derive(Clone, Copy, FromBytes, IntoBytes, KnownLayout, Immutable)]
#[repr(C, align(64))]
struct Block([u8; 64]);

/// An owned, 64-byte-aligned byte buffer (see [`aligned_copy`]).
#[cfg(feature = "std")]
#[derive(Clone)]
pub struct AlignedBuf {
    blocks: Vec<Block>,
    len: usize,
}

#[cfg(feature = "std")]
impl AlignedBuf {
    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.blocks.as_bytes()[..self.len]
    }

    /// The bytes, mutably (for corruption tests).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        let len = self.len;
        &mut self.blocks.as_mut_bytes()[..len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quantising a node's decoded values gives back its bits (the
    /// exporters' round trip), on 20 000 random nodes shaped like T3's
    /// (34 values, offsets up to ±50, ranges from 2% of the magnitude to 50).
    #[test]
    fn quantise_node_is_idempotent() {
        let mut rng = crate::test_rng::Lcg(3);
        let mut next = || rng.next();
        for _ in 0..20_000 {
            let lo = 100.0 * next() - 50.0;
            // Codes round-trip where the step exceeds the f32 spacing of the
            // values: ranges ≥ 2% of the largest magnitude (T3's are larger).
            let range = 0.02 * (f64::abs(lo) + 1.0) + 50.0 * next() * next();
            let values: Vec<f32> = (0..34).map(|_| (lo + range * next()) as f32).collect();
            let mut codes = [0u16; 34];
            let [offset, step] = quantise_node(&values, &mut codes);
            let decoded: Vec<f32> = codes
                .iter()
                .map(|&q| offset + f32::from(q) * step)
                .collect();
            let mut again = [0u16; 34];
            let scale = quantise_node(&decoded, &mut again);
            assert_eq!(
                scale.map(f32::to_bits),
                [offset, step].map(f32::to_bits),
                "{values:?}"
            );
            assert_eq!(again, codes);
        }
    }

    /// Every descriptor: its id's tag round-trips, it is its id's, its stem
    /// starts with its T-number, stems, T-numbers and tags are each
    /// unique, its axes fit the header, its parameter names fit the header's
    /// slots, and every table of the set is embedded.
    #[test]
    fn every_descriptor_is_consistent() {
        for id in TableId::ALL {
            let d = id.descriptor();
            assert_eq!(d.id, id);
            assert_eq!(TableId::from_tag(id.tag()), Some(id));
            assert!(
                d.stem.starts_with(&format!("t{}-", d.number)),
                "{id:?}: {}",
                d.stem
            );
            assert!((1..=MAX_AXES).contains(&d.axis_names.len()), "{id:?}");
            assert!(d.param_names.len() <= PARAM_COUNT, "{id:?}");
            #[cfg(feature = "embedded")]
            assert_eq!(embedded_bytes(id).is_some(), d.in_set, "{id:?}");
            for other in TableId::ALL {
                if other != id {
                    let o = other.descriptor();
                    assert_ne!(o.number, d.number);
                    assert_ne!(o.stem, d.stem);
                    assert_ne!(other.tag(), id.tag());
                }
            }
        }
    }

    /// A table whose header names another kernel than its descriptor's is
    /// refused: T3 written with kernel 1 (`Multilinear`, what T3 files said
    /// before tag 3) names the kernel it needs.
    #[cfg(all(feature = "embedded", feature = "std"))]
    #[test]
    fn a_table_with_another_kernel_is_refused() {
        let t3 = embedded_bytes(TableId::Convolution).unwrap_or(&[]);
        let mut file = aligned_copy(t3);
        let at = offset_of!(Header, kernel);
        file.bytes_mut()[at..at + 4].copy_from_slice(&(Kernel::Multilinear as u32).to_le_bytes());
        let sum = checksum(file.bytes());
        file.bytes_mut()[CHECKSUM_OFFSET..CHECKSUM_OFFSET + 8].copy_from_slice(&sum.to_le_bytes());
        let table = Table::from_bytes(file.bytes()).expect("still a valid file");
        let error = table.expecting(TableId::Convolution).err();
        assert_eq!(
            error,
            Some(FormatError::WrongKernel {
                table: TableId::Convolution,
                found: Kernel::Multilinear,
            })
        );
        let message = std::format!("{}", error.unwrap_or(FormatError::Shape("")));
        assert!(message.contains("CatmullRom"), "{message}");
        assert!(crate::conv::ConvTable::from_bytes(file.bytes()).is_err());
    }

    /// T3's parameters nest its angle constants: slot order is format 3's
    /// (angles, τ_max, u_floor, λ, Y, g_offset, value_floor, κ, w_h, w_e,
    /// s_e, τ_f, m) and a header round-trips.
    #[test]
    fn conv_params_keep_their_slots() {
        let values: [f64; 13] = core::array::from_fn(|k| k as f64 + 1.0);
        let params = {
            let mut slots = values.iter().copied();
            let mut next = || slots.next().unwrap_or(0.0);
            ConvParams {
                angles: next(),
                angle: crate::conv::AngleParams {
                    tau_max: next(),
                    kernel_scale_floor: next(),
                    ndf_weight: next(),
                    ndf_exponent_cap: next(),
                    ..Default::default()
                },
                g_offset: next(),
                value_floor: next(),
            }
        };
        let params = ConvParams {
            angle: crate::conv::AngleParams {
                ndf_softening: 8.0,
                horizon_weight: 9.0,
                edge_weight: 10.0,
                edge_smoothing: 11.0,
                edge_fade_tan: 12.0,
                edge_softening_fade: 13.0,
                ..params.angle
            },
            ..params
        };
        assert_eq!(params.to_values(), values);
        assert_eq!(
            ConvParams::NAMES,
            [
                "angles",
                "tau_max",
                "kernel_scale_floor",
                "ndf_weight",
                "ndf_exponent_cap",
                "g_offset",
                "value_floor",
                "ndf_softening",
                "horizon_weight",
                "edge_weight",
                "edge_smoothing",
                "edge_fade_tan",
                "edge_softening_fade",
            ]
        );
        #[cfg(feature = "embedded")]
        {
            let bytes = embedded_bytes(TableId::Convolution).unwrap_or(&[]);
            let header = Table::from_bytes(bytes).expect("the committed T3").header();
            let params = ConvParams::from_header(header);
            assert_eq!(params.to_values()[..], header.params[..ConvParams::COUNT]);
            assert_eq!(params.angle.edge_softening_fade, header.params[12]);
        }
    }
}
