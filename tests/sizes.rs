//! The sizes that docs/design/ states, to the precision it states them: a
//! record that gives a size either reads it from a generated file
//! (docs/accuracy.md gives every table file's length) or is held to it
//! here, so a layout change that moves a size fails until the records say
//! the new one.

use std::mem::size_of;
use twoscale::brdf::{ChannelBake, FresnelBake, Rgb};
use twoscale::tables::convolution::FIT_CHANNELS;
use twoscale::tables::format::{HEADER_SIZE, Table, aligned_copy};

/// `bytes` in kB (10³ bytes), rounded as the records round them.
fn kb(bytes: usize) -> usize {
    (bytes + 500) / 1000
}

/// `bytes` in KiB (2¹⁰ bytes), rounded.
fn kib(bytes: usize) -> usize {
    (bytes + 512) / 1024
}

#[test]
fn a_channel_bake_and_an_rgb_model_are_the_stated_sizes() {
    // halo-sampling.md, per-material-bake.md, in-place-construction.md,
    // rgb-integration.md: "ChannelBake 141 KB", "Rgb 424 KB by value".
    assert_eq!(kb(size_of::<ChannelBake>()), 141, "ChannelBake");
    assert_eq!(kb(size_of::<Rgb<'static>>()), 424, "Rgb by value");
}

#[test]
fn the_spectral_fresnel_table_is_the_stated_size() {
    // rgb-integration.md: "FresnelBake 123 KiB".
    assert_eq!(kib(size_of::<FresnelBake>()), 123);
}

#[test]
fn t3s_length_is_the_layout_formula() {
    // t3-accuracy-candidates.md sizes candidate layouts by
    // `nu · nc · nβ · np · (12 + 2 nξ) + 384` bytes: per node an f32 offset
    // and step and a u16 code per channel (nξ angles and T3a's two fit
    // channels), after a 384-byte header (t3-grid-and-quantisation.md:
    // 28 × 10 × 12 × 12 nodes, 32 angles).
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tables/t3-convolution.tbl"
    ))
    .expect("tables/t3-convolution.tbl");
    let buf = aligned_copy(&bytes);
    let table = Table::from_bytes(buf.bytes()).expect("a valid T3");
    let header = table.header();
    let nodes: Vec<u32> = header.used_axes().iter().map(|a| a.nodes).collect();
    assert_eq!(nodes, [28, 10, 12, 12]);
    let xi = header.channels as usize - FIT_CHANNELS;
    assert_eq!(xi, 32);
    let count: usize = nodes.iter().map(|&n| n as usize).product();
    assert_eq!(bytes.len(), count * (12 + 2 * xi) + 384);
    // The 384 bytes are the header and its padding to the 64-byte payload.
    assert_eq!(header.payload_offset, 384);
    assert!(HEADER_SIZE as u64 <= header.payload_offset);
}
