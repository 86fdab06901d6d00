//! The shared scenario tests, run in 2D, plus the 2D-only checks of Cooper & Maddock's
//! figures.

pub use sinew::dim2 as dim;
/// The scene harness in the same dimension.
pub use sinew_scenes::dim2 as scenes;

/// A revolute joint about the axis normal to the x-y plane (dimension-specific constructor).
pub fn planar_revolute() -> sinew::dim2::rapier::dynamics::RevoluteJointBuilder {
    sinew::dim2::rapier::dynamics::RevoluteJointBuilder::new()
}

/// Level geometry whose construction differs per dimension (issue 14's floors).
pub mod levels {
    use sinew::dim2::math::{Real, Vector};
    use sinew::dim2::rapier::geometry::ColliderBuilder;

    /// An open surface at height 0 over `[-half, half]`: a polyline of `cells` segments whose
    /// normals point up (`flip`: down); `fix_internal_edges` has no 2D counterpart.
    pub fn open_floor(
        cells: usize,
        half: Real,
        flip: bool,
        _fix_internal_edges: bool,
    ) -> ColliderBuilder {
        let at = |i: usize| -half + 2.0 * half * i as Real / cells as Real;
        let vertices = (0..=cells).map(|i| Vector::new(at(i), 0.0)).collect();
        let indices = (0..cells as u32)
            .map(|i| if flip { [i + 1, i] } else { [i, i + 1] })
            .collect();
        ColliderBuilder::polyline(vertices, Some(indices))
    }

    /// A closed slab `[-half, half]` made of two triangles (a 2D trimesh is solid).
    pub fn closed_box(half: Vector) -> ColliderBuilder {
        let (x, y) = (half.x, half.y);
        let vertices = vec![
            Vector::new(-x, -y),
            Vector::new(x, -y),
            Vector::new(x, y),
            Vector::new(-x, y),
        ];
        ColliderBuilder::trimesh(vertices, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    /// A flat heightfield at height 0 over `[-half, half]`, `cells` cells.
    pub fn heightfield(cells: usize, half: Real) -> ColliderBuilder {
        ColliderBuilder::heightfield(vec![0.0; cells + 1], Vector::new(2.0 * half, 1.0))
    }
}

#[path = "shared/mod.rs"]
mod shared;

#[path = "only2d/cooper.rs"]
mod cooper;

#[path = "only2d/cantilever.rs"]
mod cantilever;

#[path = "only2d/polygon.rs"]
mod polygon;
