//! Tests written once for both dimensions: `crate::dim` is `sinew::dim2` or `sinew::dim3`.

mod bones;
mod cantilever;
mod contact;
mod determinism;
mod elements;
mod errors;
mod fall;
mod mesh;
mod metrics;
mod parallel;
mod pipeline;
mod scenes;
mod sleep;
mod snapshot;
mod support;
