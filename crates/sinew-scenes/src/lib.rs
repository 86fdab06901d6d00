//! # sinew-scenes
//!
//! The scene harness of [sinew](https://docs.rs/sinew): the papers' scenes (a fall and bounce,
//! Cooper & Maddock's limb, a crush, a manipulator's strikes, a dt sweep, a rotation-error
//! run, a cantilever), each runnable with any of sinew's element models or with rapier 0.36's
//! own soft bodies on the same mesh and material ([`dim3::Subject`]), each returning a
//! [`record::Record`] measured from node positions alone. The examples, the tests and the
//! benches of sinew share it, so that they all measure the same thing.
//!
//! It is also for users' own integration tests: [`dim3::testing::DropTest`] drops their mesh
//! and material into their world of colliders and returns the record (apex, rest,
//! penetration, inverted cells, energy) as plain data to assert on.
//!
//! The crate compiles one source tree twice, like sinew: [`dim2`] and [`dim3`]. Feature `fem`
//! adds rapier's implicit FEM soft bodies as two more peers.
#![warn(missing_docs)]
#![deny(unsafe_code)]
// `src/shared/` is mounted twice on purpose, once per dimension.
#![allow(clippy::duplicate_mod)]

pub mod beam;
#[cfg(feature = "dim2")]
pub mod dim2;
#[cfg(feature = "dim3")]
pub mod dim3;
pub mod record;
pub mod reference;

/// `a` within `rel` of `b`, relatively (the closed-form tests of `beam` and `reference`).
#[cfg(test)]
fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}
