//! A `no_std` consumer of the runtime: embeds T1, looks up G1 and samples the
//! EPD, with no standard library linked.
#![no_std]

use twoscale::epd::Epd;
use twoscale::SmithG1Table;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

static T1: &twoscale::AlignedBytes<[u8]> =
    &twoscale::AlignedBytes(*include_bytes!("../../../tables/t1-smith-g1.tbl"));

/// Smith G1 from the embedded table, or −1 if the table does not validate.
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_g1(p: f32, a: f32) -> f32 {
    match SmithG1Table::from_bytes(T1.bytes()) {
        Ok(table) => table.g1(p, a),
        Err(_) => -1.0,
    }
}

/// cos θm of an EPD sample, or −1 if the table does not validate.
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_sample_cos(beta: f32, p: f32, u0: f32, u1: f32) -> f32 {
    match SmithG1Table::from_bytes(T1.bytes()) {
        Ok(table) => Epd::new(beta, p, &table).sample([u0, u1])[2],
        Err(_) => -1.0,
    }
}
