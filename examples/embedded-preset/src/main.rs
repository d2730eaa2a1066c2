//! Evaluates the `gold-rough` preset from the embedded tables and prints ρ
//! per linear-sRGB channel (the integral over the spectrum, as C, Python
//! and Mitsuba give it) at a few pairs of directions.

use twoscale::brdf::{ChannelBake, IntegratedRgb};

/// The preset's model: `TableSet::material` (bakes on the heap, `twoscale`'s
/// feature `std`), or without that feature `TableSet::material_in` with
/// storage this program allocates.
fn gold<'a>(tables: &'a twoscale::TableSet<'static>) -> IntegratedRgb<'a, Box<ChannelBake>> {
    #[cfg(feature = "std")]
    let model = tables.material("gold-rough");
    #[cfg(not(feature = "std"))]
    let model = tables.material_in(
        "gold-rough",
        core::array::from_fn(|_| Box::new(ChannelBake::zeroed())),
    );
    match model {
        Ok(model) => model,
        Err(error) => {
            eprintln!("{error}");
            std::process::exit(1);
        }
    }
}

fn main() {
    let tables = twoscale::TableSet::embedded();
    let gold = gold(&tables);
    println!("gold-rough, ρ (sr⁻¹) in linear sRGB; i towards the light, o towards the viewer");
    for (theta_i, theta_o) in [(0.0f32, 0.0f32), (0.5, 0.5), (0.5, 0.8), (1.2, 1.2)] {
        let i = [theta_i.sin(), 0.0, theta_i.cos()];
        let o = [-theta_o.sin(), 0.0, theta_o.cos()];
        let [r, g, b] = gold.eval(i, o);
        println!("θi = {theta_i:.2} rad, θo = {theta_o:.2} rad (plane of incidence): {r:.5} {g:.5} {b:.5}");
    }
}
