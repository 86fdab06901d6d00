//! Tests written once for both dimensions: `crate::dim` is `sinew::dim2` or `sinew::dim3`.

mod bones;
mod cantilever;
mod contact;
mod determinism;
mod elements;
mod errors;
mod fall;
mod faults;
mod golden;
mod io;
mod io_props;
mod mesh;
mod metrics;
mod parallel;
mod pipeline;
mod properties;
mod scenes;
mod shapes;
mod sleep;
mod snapshot;
mod support;
mod validation;
