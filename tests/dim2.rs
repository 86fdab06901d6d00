//! The shared scenario tests, run in 2D, plus the 2D-only checks of Cooper & Maddock's
//! figures.

pub use sinew::dim2 as dim;
/// The scene harness in the same dimension.
pub use sinew_scenes::dim2 as scenes;

/// A revolute joint about the axis normal to the x-y plane (dimension-specific constructor).
pub fn planar_revolute() -> sinew::dim2::rapier::dynamics::RevoluteJointBuilder {
    sinew::dim2::rapier::dynamics::RevoluteJointBuilder::new()
}

#[path = "shared/mod.rs"]
mod shared;

#[path = "only2d/cooper.rs"]
mod cooper;

#[path = "only2d/cantilever.rs"]
mod cantilever;

#[path = "only2d/polygon.rs"]
mod polygon;
