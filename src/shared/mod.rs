// Everything below is written once and compiled twice, by `dim2.rs` and `dim3.rs`. It reaches
// the dimension only through `super::math` and `super::rapier`; a per-dimension difference is
// a function or a constant in `math`, never a `cfg`.

#[cfg(feature = "rerun")]
use super::render;
use super::{math, rapier};

mod attach;
mod body;
mod contact;
mod coupling;
mod embedding;
mod error;
mod events;
mod integrator;
mod material;
pub mod mesh;
pub mod model;
mod pipeline;
mod query;
#[cfg(feature = "rerun")]
pub mod recorder;
mod report;
mod set;
pub mod snapshot;
mod threads;
mod world;

pub use attach::{AttachError, Attachment};
pub use body::{ChamberState, Deformable, DeformableBuilder};
pub use contact::ContactPoint;
pub use embedding::Embedding;
pub use error::BuildError;
pub use events::{
    ChannelEventCollector, DeformableContactEvent, DeformableEventHandler, DeformableTearEvent,
};
pub use integrator::{Integrator, AUTO_GLOBAL_ITERATIONS, AUTO_SUBSTEPS, GLOBAL_SUBSTEPS};
pub use material::{FlowIn, Gas, Material, Plasticity, Stiffness, Tearing};
pub use mesh::{CellKind, Mesh, MeshWarning};
pub use model::{ElementModel, RotationFit, ShapeDamping};
pub use pipeline::{DeformablePipeline, PipelineSettings, RigidSets};
pub use query::{DeformableHit, DeformableQueryFilter};
#[cfg(feature = "rerun")]
pub use recorder::{ColorField, RecorderError, RecorderOptions, RerunRecorder};
pub use report::{DeformableReport, StepReport};
pub use set::{DeformableHandle, DeformableSet};
pub use world::DeformableWorld;
