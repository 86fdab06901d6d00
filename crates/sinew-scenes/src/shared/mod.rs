//! Ready-made scenes (`docs/ARCHITECTURE.md` §10), shared by the examples, the tests and the benches so
//! that they all measure the same thing — and run rapier's own soft bodies through the very
//! same scenes, on the same mesh and material, as peers ([`Subject::Rapier`]).
//!
//! Every scene returns [`Record`]s (one row per run). What a scene measures is computed from
//! node positions alone, in the same way for every subject: a cell is inverted when its signed
//! volume is ≤ 0, penetration is the depth of the lowest node below the ground's top, the
//! shape error is the largest node distance from the rest shape moved by the best rigid fit.
//!
//! | scene | what fails | `first_failure` |
//! |---|---|---|
//! | [`FallScene`] | nothing should | — |
//! | [`LimbScene`] | an element inverts as the joint bends | bone angle, degrees |
//! | [`CrushScene`] | an element inverts or the box reaches the ground | the smallest such mass, kg |
//! | [`ManipulatorScene`] | an element stays inverted after a strike | strike number |
//! | [`dt_sweep`] | the fall explodes, leaves an element inverted or sinks | the smallest such dt, ms |
//! | [`RotationErrorScene`] | (accuracy) spurious angular acceleration of the rotation fit | — |
//! | [`CantileverScene`] | (accuracy) static sag against Euler–Bernoulli; fails only if it does not settle | — |
//! | [`StackScene`], [`PileScene`], [`SqueezeScene`] | a cell inverts, or bodies rest inside each other by over 1 % of their size | — |
//! | [`VibrationScene`] | (accuracy) a free bar's first axial frequency and decay; fails if it explodes, inverts or does not ring | — |
//! | [`TowerScene`] | a cell inverts, or bodies rest inside each other by over 1 % of their size | — |
//! | [`PinchScene`] | the box slips over 5 cm, goes over 1 cm into the ground, or a cell inverts | — |
//! | [`RollScene`] | a cell inverts (or the ball blows up) | — |
//! | [`FoldScene`] | the surface passes into itself (over 1 % of a cell) or a cell inverts | — |
//! | [`DentScene`] | a cell inverts, the box goes through the plate, or no dent of 1 mm stays | — |
//! | [`BendScene`] | a cell inverts, or the bend the bar keeps is over 15 % from an elastic–perfectly-plastic beam's | — |
//! | [`TearScene`] | a cell inverts (rapier's: up to its first tear), it never tears or tears over 10 % from the tear strain, it does not end in two pieces, or they still move over 0.1 m/s | — |
//! | [`BalloonScene`] | a cell inverts, the plates never squeeze the cavity, `pV` strays over 2 % (sinew) or the cavity ends over 1 % from its inflated volume | — |

pub mod advise;
mod ball;
mod balloon;
mod bend;
mod cantilever;
mod crush;
mod dent;
mod fall;
mod fall_reference;
mod flock;
mod fold;
mod limb;
mod manipulator;
pub mod metrics;
mod pinch;
mod roll;
mod rotation_error;
mod sim;
mod stretch;
mod subject;
mod tear;
pub mod testing;
mod vibration;

pub use crate::beam::{euler_bernoulli_tip_sag, sag_error};
pub use crate::record::{Record, Spread};
pub use advise::{advise, Advice, Bounds, Candidate, Trial};
pub use ball::BallScene;
pub use balloon::BalloonScene;
pub use bend::BendScene;
pub use cantilever::{CantileverScene, SETTLED_WOBBLE};
pub use crush::{CrushScene, CRUSH_MASSES};
pub use dent::DentScene;
pub use fall::{dt_sweep, FallScene, DT_SWEEP_MS};
pub use fall_reference::{FallReference, ReferenceRun, FALL_REFERENCE_PATH};
pub use flock::{PileScene, SqueezeScene, StackScene, TowerScene};
pub use fold::FoldScene;
pub use limb::LimbScene;
pub use manipulator::ManipulatorScene;
pub use pinch::PinchScene;
pub use roll::RollScene;
pub use rotation_error::{spurious_acceleration, RotationErrorScene};
pub use sim::{Sim, RAPIER_SKIN};
pub use stretch::StretchScene;
pub use subject::{RapierModel, Subject};
pub use tear::TearScene;
pub use vibration::{Ring, VibrationScene};
