//! Tests written once for both dimensions: `crate::dim` is `sinew::dim2` or `sinew::dim3`.

mod auto;
mod bones;
mod cantilever;
mod contact;
mod deformation_damping;
mod determinism;
mod elements;
mod embedding;
mod energy;
mod errors;
mod fall;
mod faults;
mod gas;
mod impact;
mod implicit;
// The recorded hashes hold for this platform's arithmetic in a default build.
#[cfg(all(
    target_arch = "x86_64",
    not(feature = "parallel"),
    not(feature = "enhanced-determinism")
))]
mod golden;
mod held;
mod io;
mod io_props;
mod levels;
mod mesh;
mod metrics;
mod parallel;
mod pinch;
mod pipeline;
mod plasticity;
mod poisson;
mod properties;
mod query;
mod scenes;
mod self_contact;
mod shapes;
mod sleep;
mod snapshot;
mod soft;
mod support;
mod tear;
mod tower;
mod validation;
mod vibration;
