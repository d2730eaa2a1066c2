//! Models are built in place: every preset, RGB and one wavelength, with T3b
//! (C baked) and T3a (C read directly), is constructed on a thread whose
//! stack is 64 KiB, and gives the same values as the by-value constructors;
//! storage reused for another material ([`Rgb::new_in`]) holds nothing of
//! the previous one.

use twoscale::TableSet;
use twoscale::brdf::{ChannelBake, Rgb, TwoScale};
use twoscale::material::{Options, RGB_WAVELENGTHS};
use twoscale::materials::PRESETS;

/// The stack of the construction thread.
const STACK: usize = 64 << 10;

const PAIRS: [([f32; 3], [f32; 3]); 3] = [
    ([0.6, 0.1, 0.8], [-0.55, -0.05, 0.83]),
    ([0.0, 0.0, 1.0], [0.3, 0.2, 0.93]),
    ([0.9, 0.0, 0.436], [-0.88, 0.1, 0.465]),
];

/// `f` run on a thread with a [`STACK`]-byte stack.
fn on_small_stack<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(STACK)
            .spawn_scoped(scope, f)
            .expect("spawn")
            .join()
            .expect("construction on a 64 KiB stack")
    })
}

#[test]
fn construction_fits_a_64_kib_stack() {
    let set = TableSet::embedded();
    let fit = set.convolution.fit();
    let sources = [set.brdf_tables(), set.brdf_tables_with(&fit)];
    // Built on the small stack, evaluated here against the by-value models.
    let built = on_small_stack(|| {
        let mut models = Vec::new();
        for tables in &sources {
            for (name, material) in PRESETS {
                let rgb = Rgb::boxed(tables, &material, Options::default());
                let channels = [0, 1, 2].map(|k| {
                    TwoScale::boxed(
                        tables,
                        material.layer,
                        RGB_WAVELENGTHS[k],
                        material.eta_rgb[k],
                        Options::default(),
                    )
                });
                let values =
                    PAIRS.map(|(i, o)| (rgb.eval(i, o), channels.each_ref().map(|c| c.eval(i, o))));
                models.push((name, values));
            }
        }
        models
    });
    let mut k = 0;
    for tables in &sources {
        for (name, material) in PRESETS {
            let rgb = Rgb::new(tables, &material, Options::default());
            for (pair, (i, o)) in PAIRS.iter().enumerate() {
                let (boxed_rgb, boxed_channels) = built[k].1[pair];
                assert_eq!(built[k].0, name);
                assert_eq!(boxed_rgb, rgb.eval(*i, *o), "{name}");
                assert_eq!(boxed_channels, boxed_rgb, "{name}: channels against RGB");
            }
            k += 1;
        }
    }
}

#[test]
fn reused_storage_keeps_nothing_of_the_previous_material() {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    // Every preset rebuilt into the storage of every other one.
    for (_, first) in PRESETS {
        let mut model = Rgb::boxed(&tables, &first, Options::default());
        for (name, material) in PRESETS {
            model = Rgb::new_in(model.into_bakes(), &tables, &material, Options::default());
            let fresh = Rgb::new(&tables, &material, Options::default());
            for (i, o) in PAIRS {
                assert_eq!(model.eval(i, o), fresh.eval(i, o), "{name}");
                assert_eq!(model.pdf(i, o), fresh.pdf(i, o), "{name}");
                assert_eq!(
                    model.sample(i, [0.3, 0.6, 0.2]),
                    fresh.sample(i, [0.3, 0.6, 0.2]),
                    "{name}"
                );
            }
        }
    }
    // Caller-provided storage.
    let mut storage = [(); 3].map(|_| ChannelBake::boxed());
    let [a, b, c] = &mut storage;
    let (name, material) = PRESETS[0];
    let model = Rgb::new_in(
        [&mut **a, &mut **b, &mut **c],
        &tables,
        &material,
        Options::default(),
    );
    let fresh = Rgb::new(&tables, &material, Options::default());
    for (i, o) in PAIRS {
        assert_eq!(model.eval(i, o), fresh.eval(i, o), "{name}");
    }
}
