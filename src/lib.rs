//! # sinew
//!
//! Deformable meshes that live beside a [rapier](https://rapier.rs) rigid-body world:
//! soft tissue bound to bones, soft objects that fall, bounce and get crushed by rapier
//! colliders.
//!
//! The crate compiles one source tree twice, like rapier itself: [`dim2`] (triangles and
//! quads, beside `rapier2d`) and [`dim3`] (tetrahedra and hexahedra, beside `rapier3d`).
//! Each dimension has the same API:
//!
//! * [`dim3::Mesh`] — rest topology, validation and boundary extraction, with lattice
//!   generators ([`dim3::Mesh::cuboid`], [`dim3::Mesh::from_shape`] for any parry shape),
//!   2D polygons triangulated ([`dim2::Mesh::polygon`]), and mesh files: Gmsh, TetGen /
//!   Triangle and legacy VTK readers and writers ([`dim3::mesh::io`]).
//! * [`dim3::ElementModel`] — the five element force laws: damped springs, springs to the
//!   centroid, nonlinear springs (Cooper & Maddock 1999 eq. 1, 3, 4), the edge-repulsion
//!   element (ibid. eq. 5) and the shape-based element (rest shape rotated about the cell
//!   centroid).
//! * [`dim3::DeformableBuilder`] → [`dim3::Deformable`] stored in a [`dim3::DeformableSet`],
//!   stepped by [`dim3::DeformablePipeline::step`] before rapier's `PhysicsPipeline::step`, or
//!   all bundled in a [`dim3::DeformableWorld`].
//!
//! ```
//! use sinew::dim3::{DeformableBuilder, DeformableWorld, ElementModel, Material};
//! use sinew::dim3::math::Vector;
//! use sinew::dim3::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
//!
//! let mut world = DeformableWorld::new();
//! world.physics.insert(RigidBodyBuilder::fixed(), ColliderBuilder::cuboid(5.0, 0.1, 5.0));
//! let jelly = DeformableBuilder::cuboid(Vector::splat(0.5), [3, 3, 3])
//!     .model(ElementModel::EdgeRepulsion)
//!     .material(Material { density: 100.0, young_modulus: 1e4, ..Default::default() })
//!     .translation(Vector::new(0.0, 1.0, 0.0))
//!     .build()
//!     .expect("a valid lattice");
//! let jelly = world.insert(jelly);
//! for _ in 0..10 {
//!     world.step();
//! }
//! assert!(world.deformables[jelly].positions().iter().all(|p| p.is_finite()));
//! ```
//!
//! Cargo features: `dim2` and `dim3` (default), `rerun` (logging to the Rerun viewer), `parallel`: element forces of
//! large bodies on rayon's threads, with rapier's own `parallel` (the same bits whatever the
//! number of threads, see [`dim3::model`]), `serde`:
//! snapshots of a running world that continue bit for bit (see [`dim3::snapshot`]), and
//! `enhanced-determinism`: rapier's, for the same results across platforms.
//!
//! The design — the element models, the phases of a step, the rules of coupling with rapier
//! and of contact, and which file owns what — is
//! [`docs/ARCHITECTURE.md`](../docs/ARCHITECTURE.md) in the repository.
//!
//! A step is deterministic: the same inputs give the same state, bit for bit (wall-clock
//! timings go into the reports only).
#![warn(missing_docs)]
#![deny(unsafe_code)]
// `src/shared/` is mounted twice on purpose, once per dimension (docs/ARCHITECTURE.md §2).
#![allow(clippy::duplicate_mod)]

#[cfg(feature = "dim2")]
pub mod dim2;
#[cfg(feature = "dim3")]
pub mod dim3;

// The README's example is compiled and run as a doctest.
#[cfg(all(doctest, feature = "dim3"))]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
