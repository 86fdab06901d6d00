//! The shared scenario tests, run in 3D.

pub use sinew::dim3 as dim;

#[path = "shared/mod.rs"]
mod shared;
