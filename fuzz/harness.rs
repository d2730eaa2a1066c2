//! The table-loader fuzz harness, shared by the libFuzzer target
//! (`fuzz/fuzz_targets/table_loader.rs`) and the stable-Rust replay test
//! (`tests/fuzz_regressions.rs`).
//!
//! Random bytes almost never pass a table's header checks and checksum, so
//! the input is a mutation of a real table: byte 0 picks the table (T1, T2,
//! T3, T5 of the embedded set, or a shipped T4), byte 1 holds flags, and the
//! rest is a list of 5-byte patches (a little-endian u32 position, a byte to
//! XOR there). Flags: bit 0 recomputes the checksum after patching (so the
//! checks past it are reached), bit 1 truncates the file to `len · ((flags >>
//! 3) & 15) / 16`, bit 2 confines the patches to the header, bit 7 also
//! loads the file into a `TableSet::from_bytes` (with the other three tables
//! intact) and evaluates, samples and takes the pdf of a preset with it (tens
//! of ms under ASan, hence optional). The patched bytes go through the
//! table's typed reader and the generic `Table::from_bytes`; whatever loads
//! is looked up at finite inputs, which must give finite values.

use twoscale::material::Options;
use twoscale::tables::format::{HEADER_SIZE, Header, aligned_copy, checksum};
use twoscale::{
    ConvTable, Convolution, DiffuseFresnelTable, ShBrdfTable, SigmaRatioTable, SmithG1Table, Table,
    TableSet,
};

/// A shipped T4 (the smallest).
static T4: &[u8] = include_bytes!("../tables/t4-gold-rough.tbl");

/// Finite inputs of the lookups: extremes, zero, signs, in-range values.
const INPUTS: [f32; 10] = [-1e30, -1.0, 0.0, 1e-30, 0.05, 0.5, 1.0, 2.5, 40.0, 3e38];

/// Runs one fuzz input (see the module documentation); true if the mutated
/// table loaded (so that its lookups were checked).
pub fn run(data: &[u8]) -> bool {
    let [selector, flags, patches @ ..] = data else {
        return false;
    };
    let set = TableSet::embedded_bytes();
    let which = usize::from(*selector % 5);
    let original: &[u8] = [
        set.smith,
        set.sigma_ratio,
        set.convolution,
        set.diffuse_fresnel,
        T4,
    ][which];
    let mut bytes = original.to_vec();
    let span = if flags & 4 != 0 {
        HEADER_SIZE.min(bytes.len())
    } else {
        bytes.len()
    };
    for patch in patches.chunks_exact(5) {
        let position = u32::from_le_bytes([patch[0], patch[1], patch[2], patch[3]]) as usize;
        bytes[position % span] ^= patch[4];
    }
    if flags & 2 != 0 {
        bytes.truncate(bytes.len() * usize::from((flags >> 3) & 15) / 16);
    }
    if flags & 1 != 0 && bytes.len() >= HEADER_SIZE {
        let at = core::mem::offset_of!(Header, checksum);
        let sum = checksum(&bytes);
        bytes[at..at + 8].copy_from_slice(&sum.to_le_bytes());
    }
    let copy = aligned_copy(&bytes);
    let file = copy.bytes();

    let _ = Table::from_bytes(file).map(|t| (t.header().channels, t.grid().len(), t.aux().len()));
    let loaded = match which {
        0 => {
            let table = SmithG1Table::from_bytes(file);
            if let Ok(t) = &table {
                for p in INPUTS {
                    for a in INPUTS {
                        finite(t.g1(p, a), "g1", &[p, a]);
                        finite(t.lambda(p, a), "lambda", &[p, a]);
                    }
                }
            }
            table.is_ok()
        }
        1 => {
            let table = SigmaRatioTable::from_bytes(file);
            if let Ok(t) = &table {
                for x in INPUTS {
                    for b in INPUTS {
                        for c in INPUTS {
                            finite(t.sigma_ratio_cos(x, b, c), "sigma_ratio", &[x, b, c]);
                        }
                    }
                }
            }
            table.is_ok()
        }
        2 => {
            let table = ConvTable::from_bytes(file);
            if let Ok(t) = &table {
                for s in [0.0f32, 1e-4, 0.3, 1.0] {
                    let cos = (1.0 - s * s).sqrt();
                    for u in INPUTS {
                        for beta in [1e-30, 0.01, 0.3, 3e38] {
                            for (c, p) in [(1.5, 1.0), (-1.0, 0.0), (40.0, 5.0), (2.0, 0.5)] {
                                let args = [s, u, c, beta, p];
                                let v = t.convolution_sin_cos(s, cos, u, c, beta, p);
                                finite(v, "C (T3b)", &args);
                                let v = t.fit().convolution_sin_cos(s, cos, u, c, beta, p);
                                finite(v, "C (T3a)", &args);
                            }
                        }
                    }
                }
            }
            table.is_ok()
        }
        3 => {
            let table = DiffuseFresnelTable::from_bytes(file);
            if let Ok(t) = &table {
                for eta in INPUTS {
                    finite(t.f_dr_int(eta), "f_dr_int", &[eta]);
                }
            }
            table.is_ok()
        }
        _ => {
            let table = ShBrdfTable::from_bytes(file);
            if let Ok(t) = &table {
                for channel in 0..t.channels() {
                    for z in [-0.5, 0.0, 0.3, 1.0] {
                        let (i, o) = ([0.4, 0.1, z], [-0.2, 0.5, 0.7]);
                        finite(t.eval(channel, i, o), "sh eval", &[z]);
                    }
                }
            }
            table.is_ok()
        }
    };
    if which < 4 && flags & 0x80 != 0 {
        let mut set_bytes = set;
        let slot = [
            &mut set_bytes.smith,
            &mut set_bytes.sigma_ratio,
            &mut set_bytes.convolution,
            &mut set_bytes.diffuse_fresnel,
        ];
        let slot = slot.into_iter().nth(which);
        if let Some(slot) = slot {
            *slot = file;
        }
        if let Ok(tables) = TableSet::from_bytes(set_bytes) {
            let presets = twoscale::materials::PRESETS;
            evaluate(
                &tables,
                &presets[usize::from(*selector / 5) % presets.len()].1,
            );
        }
    }
    loaded
}

/// `material` from the set, evaluated and sampled.
fn evaluate(tables: &TableSet<'_>, material: &twoscale::material::Material) {
    let model = tables.rgb(material, Options::default());
    for (i, o) in [
        ([0.6, 0.1, 0.8], [-0.55, -0.05, 0.83]),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
        ([1.0, 0.0, 1e-6], [-1.0, 0.0, 1e-6]),
    ] {
        for v in model.eval(i, o) {
            finite(v, "rgb eval", &[i[2], o[2]]);
        }
        finite(model.pdf(i, o), "rgb pdf", &[i[2], o[2]]);
        if let Some(s) = model.sample(i, [0.3, 0.7, 0.2]) {
            finite(s.pdf, "rgb sample pdf", &[i[2]]);
        }
    }
}

fn finite(v: f32, what: &str, args: &[f32]) {
    assert!(
        v.is_finite(),
        "{what}{args:?} = {v} from a table that loaded"
    );
}
