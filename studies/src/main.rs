//! `studies`: the design studies behind the shipped tables. Each subcommand
//! reproduces the measurements of one record in `docs/design/`; it calls the
//! runtime and the generator (the reference, the tables' constants, the
//! lookup's weights) instead of copies of them.
//!
//! ```text
//! cargo run --release -p studies -- <subcommand> [options]
//! ```
//!
//! Deterministic (fixed seeds); the reference profiles run on rayon's
//! threads (`RAYON_NUM_THREADS` limits them).

mod brdf_instructions;
mod common;
mod rgb_integration;
mod t3_angle;
mod t3_axes;
mod t3_direct_cost;
mod t3_interp;
mod t3_node_cost;
mod t3_thresholds;
mod t4_band_limits;
mod t6_axes;

use clap::{Parser, Subcommand};
use common::Distribution;
use std::path::PathBuf;
use std::process::ExitCode;
use t3_angle::Angle;

/// Which of T3's axes (u, c, β, p) a string names (`u`, `c`, `b`, `p`).
fn parse_axes(s: &str) -> [bool; 4] {
    ['u', 'c', 'b', 'p'].map(|key| s.contains(key))
}

/// Four node counts (u, c, β, p) from `--nodes`.
fn parse_nodes(v: &[u32]) -> Result<[u32; 4], String> {
    <[u32; 4]>::try_from(v).map_err(|_| format!("--nodes takes four counts, got {v:?}"))
}

/// The workspace's materials file.
const DEFAULT_MATERIALS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");

#[derive(Parser)]
#[command(about = "Design studies behind the shipped tables (see docs/design/)")]
struct Cli {
    #[command(subcommand)]
    study: Study,
}

/// A T3 layout for the patch-mode studies: node counts, the u and c axes'
/// node placement and the normalised angles per node.
#[derive(clap::Args)]
struct Layout {
    /// Node counts of the axes u, c, β, p (0: the table's).
    #[arg(long, value_delimiter = ',', default_value = "0,0,0,0")]
    nodes: Vec<u32>,
    /// The u axis even in `ln(u + OFFSET)` (the table's: 0.1).
    #[arg(long)]
    u_offset: Option<f64>,
    /// The c axis even in `ln(c − 1) + LINEAR · c` (the table's: 0.5).
    #[arg(long)]
    c_linear: Option<f64>,
    /// The p axis even in `p^POWER` (the table's: −0.5; negative).
    #[arg(long, allow_hyphen_values = true)]
    p_power: Option<f64>,
    /// Normalised angles ξ per node (the table's: 32).
    #[arg(long)]
    xi: Option<usize>,
}

impl Layout {
    /// The parameter axes (and sets [`t3_angle::XI_COUNT`]).
    fn grid(&self) -> Result<[twoscale::tables::format::AxisHeader; 4], String> {
        if let Some(n) = self.xi {
            if n < 4 {
                return Err(format!("--xi {n}: at least 4"));
            }
            t3_angle::XI_COUNT.get_or_init(|| n);
        }
        parse_nodes(&self.nodes)
            .map(|n| common::axes_with(n, self.u_offset, self.c_linear, self.p_power))
    }
}

#[derive(Subcommand)]
enum Study {
    /// T3's normalised angle, ξ alone: each form's error on exact profiles
    /// with the parameters exact (docs/design/t3-normalised-angle.md).
    T3AngleForms {
        /// Profiles.
        #[arg(long, default_value_t = 80)]
        profiles: usize,
        /// Whose parameter points.
        #[arg(long, value_enum, default_value_t = Distribution::Brdf)]
        distribution: Distribution,
        /// Angles compared: `format1`, or `w_h,w_e,s_e,tau_f` (the runtime's
        /// angle with those weights); repeatable.
        #[arg(long = "angle", value_parser = Angle::parse,
              default_values = t3_angle::DEFAULT_ANGLES)]
        angles: Vec<Angle>,
    },
    /// T3's normalised angle: the NDF term's softening κ, ξ alone, on
    /// verify's and the BRDF check's points
    /// (docs/design/t3-normalised-angle.md). κ = 1 was chosen on format 1's
    /// angle (`--angle format1`); the default measures it in the shipped one.
    T3AngleSoftening {
        /// Profiles per distribution.
        #[arg(long, default_value_t = 60)]
        profiles: usize,
        /// The angle whose κ varies (`format1` or `w_h,w_e,s_e,tau_f`).
        #[arg(long, value_parser = Angle::parse, default_value = "0.5,0.5,2,3")]
        angle: Angle,
        /// The κ compared.
        #[arg(long, value_delimiter = ',', default_value = "0,0.5,1,2,4")]
        kappas: Vec<f64>,
    },
    /// T3's normalised angle with β and p interpolated as the lookup does
    /// (u, c exact), against ξ alone: predicts a table's error without
    /// building it (docs/design/t3-normalised-angle.md).
    T3AnglePatch {
        /// Profiles.
        #[arg(long, default_value_t = 80)]
        profiles: usize,
        /// Whose parameter points.
        #[arg(long, value_enum, default_value_t = Distribution::Verify)]
        distribution: Distribution,
        /// Angles compared (as for t3-angle-forms).
        #[arg(long = "angle", value_parser = Angle::parse,
              default_values = t3_angle::DEFAULT_ANGLES)]
        angles: Vec<Angle>,
        /// How the corners are combined (repeatable).
        #[arg(long = "blend", value_enum, default_values = ["xi"])]
        blends: Vec<t3_angle::Blend>,
        /// The axes interpolated (others exact): any of `u`, `c`, `b` (β), `p`.
        #[arg(long, default_value = "bp")]
        axes: String,
        /// `ln C̃`'s floor below `ln C̃(0)` for the residual blends.
        #[arg(long, default_value_t = 30.0)]
        residual_floor: f64,
        /// The table's layout.
        #[command(flatten)]
        layout: Layout,
        /// Profiles at these points (CSV `u,c,beta,p` with a header line)
        /// instead of the distribution's.
        #[arg(long)]
        points: Option<PathBuf>,
        /// Also print each profile's figures.
        #[arg(long)]
        per_profile: bool,
        /// Seed of the distribution's points (2017 with `--distribution
        /// verify --profiles 160`: `generator verify --table t3 --points
        /// 80000`'s profiles).
        #[arg(long, default_value_t = 61)]
        seed: u64,
    },
    /// T3's normalised angle at given points (CSV `u,c,beta,p,theta_h`, e.g.
    /// the BRDF check's): exact C and each angle's, as CSV on stdout
    /// (docs/design/t3-normalised-angle.md).
    T3AngleAtPoints {
        /// The points.
        file: PathBuf,
        /// The axes interpolated as in t3-angle-patch (`u`, `c`, `b`, `p`;
        /// empty: ξ alone).
        #[arg(long, default_value = "")]
        axes: String,
        /// How the corners are combined (repeatable).
        #[arg(long = "blend", value_enum, default_values = ["xi"])]
        blends: Vec<t3_angle::Blend>,
        /// The table's layout.
        #[command(flatten)]
        layout: Layout,
        /// Angles compared (as for t3-angle-forms).
        #[arg(long = "angle", value_parser = Angle::parse,
              default_values = t3_angle::DEFAULT_ANGLES)]
        angles: Vec<Angle>,
    },
    /// T3's parameter axes: node count and mapping of one axis, the others
    /// exact (docs/design/t3-grid-and-quantisation.md).
    T3Axis {
        /// The axis.
        #[arg(value_enum)]
        axis: t3_axes::Param,
        /// Random triples (one fixes the other parameters, two test).
        #[arg(long, default_value_t = 40)]
        triples: usize,
    },
    /// T3's interpolation across the parameters: Catmull–Rom or linear per
    /// axis, on the committed table (docs/design/t3-interpolation.md).
    T3CubicAxes {
        /// Verify profiles.
        #[arg(long, default_value_t = 60)]
        profiles: usize,
    },
    /// T3's interpolation: Catmull–Rom (shipped) against a not-a-knot
    /// B-spline on prefiltered coefficients, on the committed table's values
    /// (docs/design/t3-interpolation.md).
    T3Spline {
        /// Profiles.
        #[arg(long, default_value_t = 120)]
        profiles: usize,
        /// Seed of the points.
        #[arg(long, default_value_t = 99)]
        seed: u64,
        /// Whose parameter points.
        #[arg(long, value_enum, default_value_t = Distribution::Verify)]
        distribution: Distribution,
        /// Parameters snapped to their nearest nodes: any of `u`, `c`, `b`
        /// (β), `p`.
        #[arg(long, default_value = "")]
        snap: String,
    },
    /// Where the T3 build's time goes: the reference profile and fit of every
    /// `stride`-th node, timed on one thread, CSV on stdout, totals on stderr
    /// (docs/design/t3-build-speed.md).
    T3NodeCost {
        /// Time every `stride`-th node.
        #[arg(long, default_value_t = 61)]
        stride: usize,
        /// Only the nodes that the build tries by zonal harmonics (with
        /// `--stride 1`: the zonal-harmonic part of the whole build, moments
        /// shared as in the build).
        #[arg(long)]
        zh_only: bool,
    },
    /// The T3 build's direct quadrature: lobe evaluations and time of every
    /// `stride`-th direct node, all angles; saves or compares the values
    /// (docs/design/t3-build-speed.md).
    T3DirectCost {
        /// Every `stride`-th node (the direct ones among them).
        #[arg(long, default_value_t = 61)]
        stride: usize,
        /// Write the values (f64 bits) to this file.
        #[arg(long)]
        save: Option<PathBuf>,
        /// Compare the values with a file written by `--save`.
        #[arg(long)]
        compare: Option<PathBuf>,
    },
    /// The paper's thresholds for T3a's g (HP17 §4.4) read from the
    /// committed table (docs/design/t3-forms.md).
    T3Thresholds,
    /// Instructions per call of the BRDF's eval, pdf, sample and
    /// construction against the GGX baseline of benches/brdf.rs, counted by
    /// callgrind (docs/design/speed.md). Needs valgrind.
    BrdfInstructions {
        /// Calls per operation (construction: a thousandth, except with
        /// `--operation`, which runs exactly this many).
        #[arg(long, default_value_t = 10_000)]
        calls: usize,
        /// Run this operation only, without valgrind (what the report runs
        /// under callgrind).
        #[arg(long)]
        operation: Option<String>,
        /// Also write the table as markdown to this file
        /// (docs/figures/brdf-instructions.md).
        #[arg(long, conflicts_with = "operation")]
        markdown: Option<PathBuf>,
    },
    /// RGB by integration over the spectrum against the paper's three
    /// wavelengths, and few-wavelength candidates
    /// (docs/design/rgb-integration.md).
    RgbIntegration {
        /// Direction pairs per preset (half uniform, half sampled).
        #[arg(long, default_value_t = 4000)]
        pairs: usize,
        /// Seed of the pairs.
        #[arg(long, default_value_t = 26)]
        seed: u64,
        /// Also write the tables as markdown to this file
        /// (docs/figures/rgb-integration.md).
        #[arg(long)]
        markdown: Option<PathBuf>,
    },
    /// Wall time per call of the BRDF's operations and the GGX baselines,
    /// interleaved batches, minimum over rounds (docs/design/speed.md).
    BrdfTiming {
        /// Rounds (each times one batch of every operation).
        #[arg(long, default_value_t = 200)]
        rounds: usize,
        /// Calls per batch (construction: a thousandth).
        #[arg(long, default_value_t = 4096)]
        batch: usize,
    },
    /// T6's node counts and p mapping against its interpolated error and
    /// size, build times on stderr (docs/design/t6-albedo-axes.md).
    T6Axes {
        /// Random points (each measured for both maskings).
        #[arg(long, default_value_t = 20000)]
        points: usize,
        /// Layouts `ny,nz,np,power` (repeatable).
        #[arg(long = "layout", value_parser = t6_axes::parse_layout,
              default_values = ["40,56,10,-0.5", "40,48,13,-0.5", "36,48,14,-0.35", "32,44,14,-0.35", "36,40,16,-0.35"])]
        layouts: Vec<[f64; 4]>,
        /// Also write the table as markdown to this file
        /// (docs/figures/t6-axes.md).
        #[arg(long)]
        markdown: Option<PathBuf>,
    },
    /// T4's error against the band limit L
    /// (docs/design/t4-band-limits.md).
    T4BandLimits {
        /// Which BRDFs (one table, in this order).
        #[arg(value_enum, default_values = ["two-scale"])]
        subjects: Vec<t4_band_limits::Subject>,
        /// Materials file (for the two-scale presets).
        #[arg(long, default_value = DEFAULT_MATERIALS)]
        materials: PathBuf,
        /// Also write the table as markdown to this file
        /// (docs/figures/t4-band-limits.md).
        #[arg(long)]
        markdown: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let result = match Cli::parse().study {
        Study::T3AngleForms {
            profiles,
            distribution,
            angles,
        } => {
            t3_angle::forms(profiles, distribution, &angles);
            Ok(())
        }
        Study::T3AngleSoftening {
            profiles,
            angle,
            kappas,
        } => {
            t3_angle::softening(profiles, angle, &kappas);
            Ok(())
        }
        Study::T3AnglePatch {
            profiles,
            distribution,
            angles,
            blends,
            axes,
            residual_floor,
            layout,
            points,
            per_profile,
            seed,
        } => {
            t3_angle::RESIDUAL_FLOOR.get_or_init(|| residual_floor);
            let points = match points {
                Some(path) => common::read_points(&path),
                None => Ok(distribution.points(profiles, seed)),
            };
            points.and_then(|points| {
                layout.grid().map(|grid| {
                    t3_angle::patch(
                        &points,
                        &angles,
                        &blends,
                        parse_axes(&axes),
                        &grid,
                        per_profile,
                    )
                })
            })
        }
        Study::T3AngleAtPoints {
            file,
            axes,
            blends,
            layout,
            angles,
        } => layout.grid().and_then(|grid| {
            t3_angle::at_points(&file, &angles, &blends, parse_axes(&axes), &grid)
        }),
        Study::T3Axis { axis, triples } => {
            t3_axes::run(axis, triples);
            Ok(())
        }
        Study::T3CubicAxes { profiles } => {
            t3_interp::cubic_axes(profiles);
            Ok(())
        }
        Study::T3Spline {
            profiles,
            seed,
            distribution,
            snap,
        } => {
            t3_interp::spline(profiles, seed, distribution, &snap);
            Ok(())
        }
        Study::T3NodeCost { stride, zh_only } => {
            t3_node_cost::run(stride, zh_only);
            Ok(())
        }
        Study::T3DirectCost {
            stride,
            save,
            compare,
        } => t3_direct_cost::run(stride, save.as_deref(), compare.as_deref()),
        Study::T3Thresholds => {
            t3_thresholds::run();
            Ok(())
        }
        Study::T6Axes {
            points,
            layouts,
            markdown,
        } => t6_axes::run(&layouts, points, markdown.as_deref()),
        Study::T4BandLimits {
            subjects,
            materials,
            markdown,
        } => t4_band_limits::run(&subjects, &materials, markdown.as_deref()),
        Study::RgbIntegration {
            pairs,
            seed,
            markdown,
        } => rgb_integration::run(pairs, seed, markdown.as_deref()),
        Study::BrdfTiming { rounds, batch } => brdf_instructions::timing(rounds, batch),
        Study::BrdfInstructions {
            calls,
            operation,
            markdown,
        } => match operation {
            Some(op) => brdf_instructions::run_calls(&op, calls),
            None => brdf_instructions::report(calls, markdown.as_deref()),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
