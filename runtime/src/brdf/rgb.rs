//! [`Rgb`]: the model at the paper's three wavelengths, the channels sharing
//! each evaluation's geometry.

use super::ChannelBake;
use super::Tables;
use super::TwoScale;
use super::construct::NodeBakes;
use super::construct::SurfaceBakes;
use super::eval::Geometry;
use super::finite_or_zero;
use super::sample::share_lobe_weights;
use crate::material::{Material, Options, RGB_WAVELENGTHS};
use crate::math::BELOW_ONE;
use core::borrow::{Borrow, BorrowMut};

/// The model at the three [`RGB_WAVELENGTHS`], one complex index per channel.
/// The channels share the geometry, D and G of each evaluation (they must
/// share the surface, as [`Rgb::new`] makes them). The bakes are held as `B`,
/// as [`TwoScale`]'s: by value ([`Rgb::new`], 424 KB), boxed (`Rgb::boxed`)
/// or in caller-provided storage ([`Rgb::new_in`]).
#[derive(Clone)]
pub struct Rgb<'a, B = ChannelBake> {
    /// The red, green and blue channels.
    pub channels: [TwoScale<'a, B>; 3],
}

/// A sampled direction of the RGB model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbSample {
    /// The outgoing direction (unit vector, `z > 0`).
    pub o: [f32; 3],
    /// [`Rgb::pdf`] at `o`.
    pub pdf: f32,
    /// ρ(i, o) per channel (sr⁻¹).
    pub value: [f32; 3],
}

impl<'a> Rgb<'a> {
    /// The three channels of `material` at [`RGB_WAVELENGTHS`]. The value is
    /// 424 KB: on small stacks use `Rgb::boxed` or [`Rgb::new_in`].
    pub fn new(tables: &Tables<'a>, material: &Material, options: Options) -> Self {
        let bakes = [
            ChannelBake::zeroed(),
            ChannelBake::zeroed(),
            ChannelBake::zeroed(),
        ];
        Self::new_in(bakes, tables, material, options)
    }
}

#[cfg(feature = "std")]
impl<'a> Rgb<'a, std::boxed::Box<ChannelBake>> {
    /// [`Rgb::new`] with the bakes on the heap (`ChannelBake::boxed`,
    /// filled in place): construction runs on a 64 KiB stack.
    pub fn boxed(tables: &Tables<'a>, material: &Material, options: Options) -> Self {
        let bakes = [
            ChannelBake::boxed(),
            ChannelBake::boxed(),
            ChannelBake::boxed(),
        ];
        Self::new_in(bakes, tables, material, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>> Rgb<'a, B> {
    /// [`Rgb::new`] baking into the storage `bakes` in place (see
    /// [`TwoScale::new_in`]).
    pub fn new_in(
        bakes: [B; 3],
        tables: &Tables<'a>,
        material: &Material,
        options: Options,
    ) -> Self {
        // G1, the visible-slope tables and C's slice do not depend on the wavelength.
        let shared = SurfaceBakes::new(tables, material.layer.surface);
        let [r, g, b] = bakes;
        let layer = material.layer;
        let (l, eta) = (RGB_WAVELENGTHS, material.eta_rgb);
        // An array literal rather than `bakes.map`: built in place, not in a
        // temporary of the channels' size on the stack.
        let mut channels = [
            TwoScale::around(r, tables, &shared, layer, l[0], eta[0], options),
            TwoScale::around(g, tables, &shared, layer, l[1], eta[1], options),
            TwoScale::around(b, tables, &shared, layer, l[2], eta[2], options),
        ];
        let (first, rest) = channels.split_at_mut(1);
        let first = first[0].bake.borrow_mut();
        shared.bake_into(tables, first);
        for channel in rest {
            let bake = channel.bake.borrow_mut();
            bake.masking.clone_from(&first.masking);
            bake.visible.clone_from(&first.visible);
        }
        for (channel, eta) in channels.iter_mut().zip(material.eta_rgb) {
            channel.bake_wavelength(tables, &shared, eta, NodeBakes::ALL);
        }
        let [r, g, b] = &mut channels;
        share_lobe_weights([r, g, b]);
        Rgb { channels }
    }

    /// The storage of the bakes, to rebuild another model in ([`Rgb::new_in`]).
    pub fn into_bakes(self) -> [B; 3] {
        self.channels.map(TwoScale::into_bake)
    }
}

impl<B: Borrow<ChannelBake>> Rgb<'_, B> {
    /// ρ(i, o) per channel.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        match self.channels[0].pair(i, o) {
            Some(pair) => self.channels.each_ref().map(|ch| ch.lobes(&pair).total()),
            None => [0.0; 3],
        }
    }

    /// The density of [`Rgb::sample`]: the mean of the channels' pdfs (one
    /// channel's sampler is picked uniformly; the channels' lobe weights are
    /// shared, `share_lobe_weights`).
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.channels[0].geometry(i, o) {
            Some(geometry) => finite_or_zero(self.pdf_at(&geometry)),
            None => 0.0,
        }
    }

    /// [`Rgb::pdf`] at a pair's geometry.
    pub(super) fn pdf_at(&self, geometry: &Geometry) -> f64 {
        // The channels share the surface, hence the specular density.
        let specular = self.channels[0].specular_pdf(geometry);
        let sum: f64 = self
            .channels
            .iter()
            .map(|ch| f64::from(finite_or_zero(ch.pdf_with_specular(geometry, specular))))
            .sum();
        sum / 3.0
    }

    /// Picks a channel's sampler with `u[0]` (uniformly; `u[0]` is rescaled
    /// and reused to pick the lobe), samples it, and returns the direction,
    /// the mixture density [`Rgb::pdf`] and the three values.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<RgbSample> {
        let pick = 3.0 * f64::from(u[0].max(0.0).min(BELOW_ONE));
        let k = (pick as usize).min(2);
        let rest = (pick - k as f64) as f32;
        let (o, _) = self.channels[k].sample_direction(i, [rest, u[1], u[2]])?;
        // pdf(i, o) and eval(i, o) from one geometry.
        let geometry = self.channels[0].geometry(i, o)?;
        let pdf = finite_or_zero(self.pdf_at(&geometry));
        if !(pdf > 0.0) {
            return None;
        }
        let pair = self.channels[0].with_masking(geometry);
        Some(RgbSample {
            o,
            pdf,
            value: self.channels.each_ref().map(|ch| ch.lobes(&pair).total()),
        })
    }
}
