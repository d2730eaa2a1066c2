//! A `no_std` consumer of the runtime: embeds T1 and T5, looks up G1 and
//! F_dr,int, samples the EPD and evaluates Fresnel and Q̄, with no standard
//! library linked.
#![no_std]

use twoscale::model::epd::Epd;
use twoscale::{Complex, DiffuseFresnelTable, SmithG1Table};

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

static T5: &twoscale::AlignedBytes<[u8]> =
    &twoscale::AlignedBytes(*include_bytes!("../../../tables/t5-diffuse-fresnel.tbl"));

/// F_dr,int(η) from the embedded T5, or −1 if the table does not validate.
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_f_dr_int(eta: f32) -> f32 {
    match DiffuseFresnelTable::from_bytes(T5.bytes()) {
        Ok(table) => table.f_dr_int(eta),
        Err(_) => -1.0,
    }
}

/// Unpolarised Fresnel reflectance of n + ik at incidence cos θ.
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_fresnel(n: f32, k: f32, cos_theta: f32) -> f32 {
    twoscale::model::fresnel::fresnel(Complex::new(n, k), cos_theta)
}

/// Q̄ of n + ik for incidence i = (sin θi, 0, cos θi) and o = (ox, oy, oz).
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_q_bar(n: f32, k: f32, cos_i: f32, ox: f32, oy: f32, oz: f32) -> f32 {
    let sin_i = twoscale::math::sqrtf((1.0 - cos_i * cos_i).max(0.0));
    twoscale::model::fresnel::q_bar(Complex::new(n, k), [sin_i, 0.0, cos_i], [ox, oy, oz])
}

/// ρ of the `gold-rough` preset from the embedded table set (feature
/// `embedded`, no std) at the green wavelength, or −1 for an unknown preset.
#[unsafe(no_mangle)]
pub extern "C" fn twoscale_gold_rough_green(ix: f32, iy: f32, iz: f32, ox: f32, oy: f32, oz: f32) -> f32 {
    match twoscale::TableSet::embedded().material("gold-rough") {
        Ok(model) => model.eval([ix, iy, iz], [ox, oy, oz])[1],
        Err(_) => -1.0,
    }
}
