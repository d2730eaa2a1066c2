//! Each table's named generation parameters, stored in the header's
//! parameter slots.

use super::Header;
use super::PARAM_COUNT;
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
/// normalised angle's constants ([`AngleParams`],
/// docs/model.md §3), the T3a `g` offset and the value floor.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ConvParams {
    /// Number of normalised angles ξ (the `ln C` channels).
    pub angles: f64,
    /// The normalised angle's constants.
    pub angle: AngleParams,
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

/// The constants of the normalised angle ([`crate::tables::convolution`]'s documentation),
/// stored in the header as [`ConvParams::angle`].
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AngleParams {
    /// `τ_max`: the largest `tan θh` represented (`ξ = 1`).
    pub tau_max: f64,
    /// `u_floor`: `u_e = √(u² + u_floor²)`.
    pub kernel_scale_floor: f64,
    /// `λ`: weight of the NDF term.
    pub ndf_weight: f64,
    /// `Y`: where the NDF term saturates.
    pub ndf_exponent_cap: f64,
    /// `κ`: softening of the NDF exponent where the kernel is wider than the
    /// NDF (`2p → 2p / (1 + κ p / (2 u_e β))`; 0 = none).
    pub ndf_softening: f64,
    /// `w_h`: weight of the horizon term `½ ln(1 + τ²) = −ln cos θh`.
    pub horizon_weight: f64,
    /// `w_e`: weight of the edge term.
    pub edge_weight: f64,
    /// `s_e`: the edge term's onset is smoothed over `δ = s_e / (2 u_e)`
    /// (in units of the kernel's width).
    pub edge_smoothing: f64,
    /// `τ_f`: the edge term fades out for edges near the horizon, by
    /// `1 / (1 + (tan θe / τ_f)²)`.
    pub edge_fade_tan: f64,
    /// `m`: the edge term also fades where the kernel is wider than the
    /// NDF (where `C` has no edge), by `(p′/p)^m` (0: no such fade).
    pub edge_softening_fade: f64,
}

impl ConvParams {
    /// T3's header parameters: `angles` normalised angles with constants
    /// `angle`, the T3a `g` offset and the value floor.
    pub fn new(angles: usize, angle: &AngleParams, g_offset: f64, value_floor: f64) -> Self {
        ConvParams {
            angles: angles as f64,
            angle: *angle,
            g_offset,
            value_floor,
        }
    }
}

header_params! {
    /// T6's generation parameters.
    AlbedoParams {
        /// `γ_c` of the width coordinate (`crate::tables::albedo::WIDTH_CENTRE`).
        width_centre,
        /// `κ` of the width coordinate (`crate::tables::albedo::WIDTH_EXPONENT`).
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
