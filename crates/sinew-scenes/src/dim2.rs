//! The scenes in 2D, over [`sinew::dim2`].

use sinew::dim2 as lib;

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;

/// Level geometry whose construction differs per dimension.
pub(crate) mod level {
    use sinew::dim2::math::{Real, Vector};
    use sinew::dim2::rapier::geometry::ColliderBuilder;

    /// An open bowl as a polyline: a floor `width` wide at height 0 and two walls sloping out
    /// at 45° up to `height`.
    pub fn bowl(width: Real, height: Real) -> ColliderBuilder {
        let (a, b) = (0.5 * width, 0.5 * width + height);
        let vertices = vec![
            Vector::new(-b, height),
            Vector::new(-a, 0.0),
            Vector::new(a, 0.0),
            Vector::new(b, height),
        ];
        ColliderBuilder::polyline(vertices, None)
    }

    /// A ramp as a polyline: from `(−length·cos a, length·sin a)` down to the origin at slope
    /// `angle` (radians), then on along the floor to `run`.
    pub fn ramp(length: Real, angle: Real, run: Real) -> ColliderBuilder {
        let top = Vector::new(-length * angle.cos(), length * angle.sin());
        ColliderBuilder::polyline(vec![top, Vector::ZERO, Vector::new(run, 0.0)], None)
    }
}
