//! The scenes in 3D, over [`sinew::dim3`].

use sinew::dim3 as lib;

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;

/// Level geometry whose construction differs per dimension.
pub(crate) mod level {
    use sinew::dim3::math::{Real, Vector};
    use sinew::dim3::rapier::geometry::ColliderBuilder;

    /// An open square bowl as a trimesh: a floor `width` wide at height 0 and four walls
    /// sloping out at 45° up to `height`, normals inwards.
    pub fn bowl(width: Real, height: Real) -> ColliderBuilder {
        let (a, b) = (0.5 * width, 0.5 * width + height);
        let mut vertices = Vec::new();
        for (h, r) in [(0.0, a), (height, b)] {
            for (x, z) in [(-r, -r), (r, -r), (r, r), (-r, r)] {
                vertices.push(Vector::new(x, h, z));
            }
        }
        // Floor (0..4), counter-clockwise seen from above; then each wall from floor edge
        // (i, i+1) to rim edge (4+i, 4+i+1), facing the inside.
        let mut indices = vec![[0, 2, 1], [0, 3, 2]];
        for i in 0..4u32 {
            let j = (i + 1) % 4;
            indices.push([i, j, 4 + j]);
            indices.push([i, 4 + j, 4 + i]);
        }
        ColliderBuilder::trimesh(vertices, indices).expect("a valid bowl")
    }

    /// A ramp as a trimesh as wide (across z) as `run`, at least 1 m: from height
    /// `length·sin a` at `x = −length·cos a` down to the origin at slope `angle` (radians), then
    /// on along the floor to `x = run`; normals up.
    pub fn ramp(length: Real, angle: Real, run: Real) -> ColliderBuilder {
        let (x0, y0, w) = (
            -length * angle.cos(),
            length * angle.sin(),
            0.5 * run.max(1.0),
        );
        let vertices = vec![
            Vector::new(x0, y0, -w),
            Vector::new(x0, y0, w),
            Vector::new(0.0, 0.0, -w),
            Vector::new(0.0, 0.0, w),
            Vector::new(run, 0.0, -w),
            Vector::new(run, 0.0, w),
        ];
        let indices = vec![[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]];
        ColliderBuilder::trimesh(vertices, indices).expect("a valid ramp")
    }
}
