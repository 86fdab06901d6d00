//! The scenes in 2D, over [`sinew::dim2`].

use sinew::dim2 as lib;

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;
