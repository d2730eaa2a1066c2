//! Each table's descriptor ([`TableDescriptor`]), declared once by `table_ids!`.

use super::AlbedoParams;
use super::ConvParams;
use super::DiffuseFresnelParams;
use super::Kernel;
use super::ShBrdfParams;
use super::SigmaRatioParams;
use super::SmithG1Params;
use super::ValueType;
use zerocopy::Immutable;
use zerocopy::IntoBytes;
use zerocopy::KnownLayout;
use zerocopy::TryFromBytes;
/// Everything the runtime knows about one table, declared once (in
/// `table_ids!`'s invocation in `runtime/src/tables/format/`) and read by every other place: the
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
    /// Names of the generation parameters stored in [`Header::params`](super::Header::params)
    /// (unused slots are zero and unnamed): the fields of the table's
    /// parameter struct ([`SmithG1Params`], [`SigmaRatioParams`],
    /// [`DiffuseFresnelParams`], [`ConvParams`], [`ShBrdfParams`], [`AlbedoParams`]).
    pub param_names: &'static [&'static str],
    /// How the runtime interpolates the payload; the reader refuses a file
    /// whose header says otherwise ([`Table::expecting`](super::Table::expecting)).
    pub kernel: Kernel,
    /// How the payload is stored; the reader refuses a file whose header
    /// says otherwise ([`Table::expecting`](super::Table::expecting)).
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
        Some($crate::include_table!(concat!("../../../tables/", $stem, ".tbl")))
    };
    (@embed false, $stem:literal) => {
        None
    };
}

table_ids! {
    /// T1: Smith G1 of the EPD NDF over (p, ã = k_p·a); see [`crate::tables::smith_g1`].
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
    /// see [`crate::tables::sigma_ratio`].
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
    /// over η; see [`crate::tables::diffuse_fresnel::DiffuseFresnelTable`].
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
    /// 32 normalised angles (T3b) per node; see [`crate::tables::convolution`].
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
    /// with F = 1, per masking mode; see [`crate::tables::albedo`].
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
    /// integrated over the spectrum: aux `brdf_model`); see [`crate::tables::sh_brdf`].
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
