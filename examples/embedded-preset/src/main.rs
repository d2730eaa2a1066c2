//! Evaluates the `gold-rough` preset from the embedded tables and prints ρ
//! per RGB channel at a few pairs of directions.

fn main() {
    let tables = twoscale::TableSet::embedded();
    let gold = match tables.material("gold-rough") {
        Ok(model) => model,
        Err(error) => {
            eprintln!("{error}");
            std::process::exit(1);
        }
    };
    println!("gold-rough, ρ (sr⁻¹) at 0.645, 0.526, 0.444 µm; i towards the light, o towards the viewer");
    for (theta_i, theta_o) in [(0.0f32, 0.0f32), (0.5, 0.5), (0.5, 0.8), (1.2, 1.2)] {
        let i = [theta_i.sin(), 0.0, theta_i.cos()];
        let o = [-theta_o.sin(), 0.0, theta_o.cos()];
        let [r, g, b] = gold.eval(i, o);
        println!("θi = {theta_i:.2} rad, θo = {theta_o:.2} rad (plane of incidence): {r:.5} {g:.5} {b:.5}");
    }
}
