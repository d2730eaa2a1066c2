//! Unit tests of the parent module.

use super::integrated::ColourBake;
use super::*;
use crate::bake::halo::HaloBake;
use crate::bake::visible::VisibleSlopeBake;
use crate::bake::{ConvBake, DirectionBake, LobeWeightNodes, MaskingBake, RadialNormBake};
use core::mem::size_of;

/// `size_of::<T>()` in KB (1000 bytes), rounded, as the doc comments state it.
fn kb<T>() -> usize {
    (size_of::<T>() + 500) / 1000
}

/// The sizes the doc comments of the bakes and models state.
#[test]
fn stated_sizes_are_the_types() {
    assert_eq!(kb::<ChannelBake>(), 141);
    assert_eq!(kb::<VisibleSlopeBake>(), 55);
    assert_eq!(kb::<HaloBake>(), 48);
    assert_eq!(kb::<ConvBake>(), 19);
    assert_eq!(kb::<DirectionBake>(), 12);
    assert_eq!(kb::<MaskingBake>(), 4);
    assert_eq!(kb::<RadialNormBake>(), 2);
    assert_eq!(kb::<LobeWeightNodes>(), 4);
    assert_eq!(kb::<ColourBake>(), 6);
    assert_eq!(kb::<TwoScale<'static>>(), 141);
    assert_eq!(kb::<Rgb<'static>>(), 424);
    assert_eq!(kb::<IntegratedRgb<'static>>(), 1137);
    assert!(size_of::<TwoScale<'static, std::boxed::Box<ChannelBake>>>() < 400);
}
