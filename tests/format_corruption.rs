//! Corrupts the real, committed table files in every way the format can be
//! damaged and checks that the reader returns the right typed error — and never
//! panics or accepts the damage.

use std::mem::offset_of;
use twoscale::tables::format::{
    AxisHeader, FORMAT_VERSION, FormatError, HEADER_SIZE, Header, TableId, aligned_copy, checksum,
};
use twoscale::{SmithG1Table, Table};

fn original(id: TableId) -> Vec<u8> {
    suite::read_table(id).bytes().to_vec()
}

/// Reads `bytes` (copied to an aligned buffer) and returns the error, failing
/// the test if the reader accepts them.
fn reject(bytes: &[u8], what: &str) -> FormatError {
    let buf = aligned_copy(bytes);
    match Table::from_bytes(buf.bytes()) {
        Ok(_) => panic!("{what}: corrupted file was accepted"),
        Err(e) => e,
    }
}

/// Rewrites the checksum so that the corruption under test is the only fault.
fn reseal(bytes: &mut [u8]) {
    let sum = checksum(bytes);
    let at = offset_of!(Header, checksum);
    bytes[at..at + 8].copy_from_slice(&sum.to_le_bytes());
}

fn put_u32(bytes: &mut [u8], at: usize, value: u32) {
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

fn put_f64(bytes: &mut [u8], at: usize, value: f64) {
    bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
}

fn axis_field(axis: usize, field: usize) -> usize {
    offset_of!(Header, axes) + axis * size_of::<AxisHeader>() + field
}

#[test]
fn committed_tables_are_valid() {
    for id in TableId::ALL {
        let buf = suite::read_table(id);
        Table::from_bytes_expecting(buf.bytes(), id).unwrap();
    }
    SmithG1Table::from_bytes(suite::read_table(TableId::SmithG1).bytes()).unwrap();
}

#[test]
fn truncation_at_every_header_offset_and_across_the_payload() {
    for id in TableId::ALL {
        let bytes = original(id);
        let len = bytes.len();
        let mut offsets: Vec<usize> = (0..HEADER_SIZE + 128).collect();
        offsets.extend((HEADER_SIZE + 128..len).step_by(len / 997 + 1));
        offsets.push(len - 1);
        for cut in offsets {
            match reject(&bytes[..cut], "truncation") {
                FormatError::Truncated { actual, .. } => assert_eq!(actual, cut as u64),
                other => panic!("cut at {cut}: expected Truncated, got {other}"),
            }
        }
    }
}

#[test]
fn every_bit_of_the_header_is_protected() {
    for id in TableId::ALL {
        let bytes = original(id);
        for byte in 0..HEADER_SIZE {
            for bit in 0..8 {
                let mut bad = bytes.clone();
                bad[byte] ^= 1 << bit;
                // Any error will do; the point is that none is accepted and none panics.
                reject(&bad, &format!("{} header byte {byte} bit {bit}", id.name()));
            }
        }
    }
}

#[test]
fn random_payload_bit_flips_fail_the_checksum() {
    let mut rng = generator::rng::SplitMix64::new(99);
    for id in TableId::ALL {
        let bytes = original(id);
        let payload = bytemuck_payload_offset(&bytes);
        for _ in 0..2000 {
            let mut bad = bytes.clone();
            let at = payload + (rng.next_u64() as usize) % (bytes.len() - payload);
            bad[at] ^= 1 << (rng.next_u64() % 8);
            match reject(&bad, "payload flip") {
                FormatError::ChecksumMismatch { .. } => {}
                other => panic!("flip at {at}: expected ChecksumMismatch, got {other}"),
            }
        }
    }
}

fn bytemuck_payload_offset(bytes: &[u8]) -> usize {
    let at = offset_of!(Header, payload_offset);
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize
}

/// Each header field set to a bad value (checksum resealed) gives its own error.
#[test]
fn each_bad_field_gets_its_own_error() {
    let bytes = original(TableId::SmithG1);
    let case = |what: &str, edit: &dyn Fn(&mut Vec<u8>), seal: bool| -> FormatError {
        let mut bad = bytes.clone();
        edit(&mut bad);
        if seal {
            reseal(&mut bad);
        }
        reject(&bad, what)
    };
    use FormatError::*;
    assert!(matches!(
        case("magic", &|b| b[0] = b'X', false),
        WrongMagic { .. }
    ));
    assert!(matches!(
        case(
            "version",
            &|b| put_u32(b, offset_of!(Header, format_version), FORMAT_VERSION + 1),
            false
        ),
        UnsupportedVersion { found } if found == FORMAT_VERSION + 1
    ));
    // A file of the previous version (eight generation parameters) is refused.
    assert!(matches!(
        case(
            "old version",
            &|b| put_u32(b, offset_of!(Header, format_version), FORMAT_VERSION - 1),
            false
        ),
        UnsupportedVersion { found } if found == FORMAT_VERSION - 1
    ));
    assert!(matches!(
        case(
            "header size",
            &|b| put_u32(b, offset_of!(Header, header_size), 64),
            false
        ),
        HeaderSize { found: 64 }
    ));
    assert!(matches!(
        case(
            "table id",
            &|b| put_u32(b, offset_of!(Header, table_id), 77),
            true
        ),
        UnknownTableId(77)
    ));
    assert!(matches!(
        case(
            "value type",
            &|b| put_u32(b, offset_of!(Header, value_type), 7),
            true
        ),
        UnknownValueType(7)
    ));
    assert!(matches!(
        case(
            "mapping",
            &|b| put_u32(b, axis_field(1, offset_of!(AxisHeader, mapping)), 9),
            true
        ),
        UnknownMapping { axis: 1, tag: 9 }
    ));
    assert!(matches!(
        case(
            "axis count 0",
            &|b| put_u32(b, offset_of!(Header, axis_count), 0),
            true
        ),
        AxisCount(0)
    ));
    assert!(matches!(
        case(
            "axis count 5",
            &|b| put_u32(b, offset_of!(Header, axis_count), 5),
            true
        ),
        AxisCount(5)
    ));
    assert!(matches!(
        case(
            "one node",
            &|b| put_u32(b, axis_field(0, offset_of!(AxisHeader, nodes)), 1),
            true
        ),
        BadAxis { axis: 0, .. }
    ));
    assert!(matches!(
        case(
            "node count vs payload",
            &|b| put_u32(b, axis_field(0, offset_of!(AxisHeader, nodes)), 63),
            true
        ),
        PayloadLength { .. }
    ));
    assert!(matches!(
        case(
            "empty domain",
            &|b| put_f64(b, axis_field(0, offset_of!(AxisHeader, hi)), 0.1),
            true
        ),
        BadAxis { axis: 0, .. }
    ));
    assert!(matches!(
        case(
            "NaN domain",
            &|b| put_f64(b, axis_field(1, offset_of!(AxisHeader, lo)), f64::NAN),
            true
        ),
        BadAxis { axis: 1, .. }
    ));
    assert!(matches!(
        case(
            "NaN parameter",
            &|b| put_f64(b, offset_of!(Header, params), f64::NAN),
            true
        ),
        BadHeader(_)
    ));
    assert!(matches!(
        case(
            "unused axis slot",
            &|b| put_u32(b, axis_field(3, 0), 7),
            true
        ),
        BadAxis { axis: 3, .. }
    ));
    assert!(matches!(
        case(
            "misaligned payload offset",
            &|b| put_u32(b, offset_of!(Header, payload_offset), 100),
            true
        ),
        BadHeader(_)
    ));
    assert!(matches!(
        case(
            "aux count",
            &|b| put_u32(b, offset_of!(Header, aux_count), 1),
            true
        ),
        PayloadLength { .. }
    ));
    assert!(matches!(
        case("checksum", &|b| b[offset_of!(Header, checksum)] ^= 1, false),
        ChecksumMismatch { .. }
    ));
    let payload = bytemuck_payload_offset(&bytes);
    assert!(matches!(
        case(
            "NaN value",
            &|b| b[payload..payload + 4].copy_from_slice(&f32::NAN.to_le_bytes()),
            true
        ),
        NonFinite { index: 0 }
    ));
    assert!(matches!(
        case("trailing bytes", &|b| b.extend_from_slice(&[0; 4]), true),
        TrailingBytes { .. }
    ));
}

#[test]
fn misaligned_and_wrong_table_are_reported() {
    let bytes = original(TableId::SmithG1);
    let mut shifted = vec![0u8; bytes.len() + 64];
    let buf_start = shifted.as_ptr() as usize;
    let skip = (64 - buf_start % 64) % 64 + 1; // lands 1 byte past a 64-byte boundary
    shifted[skip..skip + bytes.len()].copy_from_slice(&bytes);
    assert!(matches!(
        Table::from_bytes(&shifted[skip..skip + bytes.len()]),
        Err(FormatError::Misaligned { address_mod_64: 1 })
    ));
    assert!(matches!(
        Table::from_bytes(&[]),
        Err(FormatError::Truncated { .. })
    ));
}

/// A G1 value outside [0, 1] passes the generic checks (finite, checksum) but
/// not T1's shape check.
#[test]
fn t1_rejects_impossible_values() {
    let mut bytes = original(TableId::SmithG1);
    let payload = bytemuck_payload_offset(&bytes);
    bytes[payload..payload + 4].copy_from_slice(&1.5f32.to_le_bytes());
    reseal(&mut bytes);
    let buf = aligned_copy(&bytes);
    assert!(Table::from_bytes(buf.bytes()).is_ok());
    assert!(matches!(
        SmithG1Table::from_bytes(buf.bytes()),
        Err(FormatError::Shape(_))
    ));
}

/// A per-node quantised (`ValueType::U16`) table decodes every value within
/// half its node's step (plus f32 rounding of the decode), keeps its codes and
/// scales where the reader expects them, and is refused (with an error, not a
/// panic) by readers that need f32 values, and when its payload is cut.
#[test]
fn u16_tables_round_trip_within_half_a_step() {
    use twoscale::tables::format::write::{TableSpec, encode};
    use twoscale::tables::format::{Kernel, Mapping, ValueType};
    let axis = |nodes| AxisHeader {
        nodes,
        mapping: Mapping::Uniform,
        lo: 0.0,
        hi: 1.0,
        param: 0.0,
        param2: 0.0,
    };
    let axes = [axis(5), axis(7)];
    let channels = 9;
    let mut rng = generator::rng::SplitMix64::new(3);
    // Node ranges from 0 (a constant node) to ~60, values of either sign.
    let grid: Vec<f32> = (0..35)
        .flat_map(|node| {
            let spread = if node == 4 {
                0.0
            } else {
                rng.uniform_in(0.0, 60.0)
            };
            let centre = rng.uniform_in(-40.0, 10.0);
            (0..channels)
                .map(|_| (centre + spread * rng.uniform_in(-0.5, 0.5)) as f32)
                .collect::<Vec<_>>()
        })
        .collect();
    let aux = [1.5f32, -2.0];
    let bytes = encode(&TableSpec {
        table_id: TableId::SmithG1,
        channels,
        kernel: Kernel::Multilinear,
        value_type: ValueType::U16,
        axes: &axes,
        params: &vec![0.0; TableId::SmithG1.param_names().len()],
        grid: &grid,
        aux: &aux,
        generator_version: "test",
    })
    .unwrap();
    // Scales and aux as f32, codes as u16: 35·2·4 + 2·4 + 35·9·2 bytes.
    let buf = aligned_copy(&bytes);
    let table = Table::from_bytes(buf.bytes()).unwrap();
    assert_eq!(table.header().payload_len, 35 * 8 + 8 + 35 * 9 * 2);
    assert_eq!(table.aux(), &aux);
    assert!(table.grid().is_empty());
    let q = table.quantised().unwrap();
    assert_eq!(q.nodes(), 35);
    let mut worst = 0.0f64;
    for node in 0..35 {
        let step = f64::from(q.scales[2 * node + 1]);
        for k in 0..channels as usize {
            let want = f64::from(grid[node * channels as usize + k]);
            let got = f64::from(q.value(node, k));
            // half a step, and a few f32 ulps of values up to ~70
            let bound = 0.5 * step + 3.0 * 70.0 * f64::from(f32::EPSILON);
            worst = worst.max((got - want).abs() / bound);
        }
        if node == 4 {
            assert_eq!(step, 0.0, "a constant node has step 0");
        }
    }
    assert!(worst <= 1.0, "worst error / bound = {worst}");
    assert_eq!(q.value(35, 0), 0.0, "outside the grid");
    // An f32 reader refuses it with an error.
    assert!(SmithG1Table::from_bytes(buf.bytes()).is_err());
    // A step that decodes beyond f32 (resealed, so only that is wrong).
    let mut huge = bytes.clone();
    let at = table.header().payload_offset as usize + 4; // node 0's step
    huge[at..at + 4].copy_from_slice(&f32::MAX.to_le_bytes());
    reseal(&mut huge);
    assert!(matches!(
        reject(&huge, "huge step"),
        FormatError::BadHeader(_)
    ));
    // Cut codes: the payload length no longer matches.
    let mut cut = bytes.clone();
    cut.truncate(bytes.len() - 2);
    assert!(matches!(
        reject(&cut, "cut codes"),
        FormatError::Truncated { .. }
    ));
}
