//! Unit tests of the parent module.

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
    let at = core::mem::offset_of!(Header, kernel);
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
    assert!(crate::tables::convolution::ConvTable::from_bytes(file.bytes()).is_err());
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
            angle: crate::tables::format::AngleParams {
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
        angle: crate::tables::format::AngleParams {
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
