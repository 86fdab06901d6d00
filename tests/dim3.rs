//! The shared scenario tests, run in 3D.

pub use sinew::dim3 as dim;
/// The scene harness in the same dimension.
pub use sinew_scenes::dim3 as scenes;

/// A revolute joint about the axis normal to the x-y plane (dimension-specific constructor).
pub fn planar_revolute() -> sinew::dim3::rapier::dynamics::RevoluteJointBuilder {
    sinew::dim3::rapier::dynamics::RevoluteJointBuilder::new(sinew::dim3::math::Vector::Z)
}

#[path = "shared/mod.rs"]
mod shared;

#[path = "only3d/rotation.rs"]
mod rotation;

#[path = "only3d/shapes.rs"]
mod shapes_3d;
