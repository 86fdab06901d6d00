//! The scenes in 3D, over [`sinew::dim3`].

use sinew::dim3 as lib;

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;
