//! The shared scenario tests, run in 2D, plus the 2D-only checks of Cooper & Maddock's
//! figures.

pub use sinew::dim2 as dim;

#[path = "shared/mod.rs"]
mod shared;

#[path = "only2d/cooper.rs"]
mod cooper;
