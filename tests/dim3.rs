//! The shared scenario tests, run in 3D.

pub use sinew::dim3 as dim;
/// The scene harness in the same dimension.
pub use sinew_scenes::dim3 as scenes;

/// A revolute joint about the axis normal to the x-y plane (dimension-specific constructor).
pub fn planar_revolute() -> sinew::dim3::rapier::dynamics::RevoluteJointBuilder {
    sinew::dim3::rapier::dynamics::RevoluteJointBuilder::new(sinew::dim3::math::Vector::Z)
}

/// Level geometry whose construction differs per dimension (issue 14's floors).
pub mod levels {
    use sinew::dim3::math::{Real, Vector};
    use sinew::dim3::rapier::geometry::{ColliderBuilder, TriMeshFlags};
    use sinew::dim3::rapier::parry::utils::Array2;

    /// An open surface at height 0 over `[-half, half]²`, `cells` × `cells` quads split in
    /// triangles whose normals point up (`flip`: down), optionally with
    /// `FIX_INTERNAL_EDGES`.
    pub fn open_floor(
        cells: usize,
        half: Real,
        flip: bool,
        fix_internal_edges: bool,
    ) -> ColliderBuilder {
        let n = cells + 1;
        let at = |i: usize| -half + 2.0 * half * i as Real / cells as Real;
        let vertices = (0..n * n)
            .map(|k| Vector::new(at(k % n), 0.0, at(k / n)))
            .collect();
        let mut indices = Vec::new();
        for j in 0..cells {
            for i in 0..cells {
                let v = |di: usize, dj: usize| ((j + dj) * n + i + di) as u32;
                // Counter-clockwise seen from above: normal +y.
                let (a, b, c, d) = (v(0, 0), v(1, 0), v(1, 1), v(0, 1));
                for t in [[a, c, b], [a, d, c]] {
                    indices.push(if flip { [t[0], t[2], t[1]] } else { t });
                }
            }
        }
        let flags = if fix_internal_edges {
            TriMeshFlags::FIX_INTERNAL_EDGES
        } else {
            TriMeshFlags::empty()
        };
        ColliderBuilder::trimesh_with_flags(vertices, indices, flags).unwrap()
    }

    /// A closed box surface `[-half, half]` (a trimesh with an inside).
    pub fn closed_box(half: Vector) -> ColliderBuilder {
        let (vertices, indices) = sinew::dim3::rapier::parry::shape::Cuboid::new(half).to_trimesh();
        ColliderBuilder::trimesh(vertices, indices).unwrap()
    }

    /// A flat heightfield at height 0 over `[-half, half]²`, `cells` × `cells`.
    pub fn heightfield(cells: usize, half: Real) -> ColliderBuilder {
        let heights = Array2::repeat(cells + 1, cells + 1, 0.0);
        ColliderBuilder::heightfield(heights, Vector::new(2.0 * half, 1.0, 2.0 * half))
    }
}

#[path = "shared/mod.rs"]
mod shared;

#[path = "only3d/rotation.rs"]
mod rotation;

#[path = "only3d/shapes.rs"]
mod shapes_3d;

#[path = "only3d/surface.rs"]
mod surface;

#[path = "only3d/stuffing.rs"]
mod stuffing;

#[path = "only3d/gripper.rs"]
mod gripper;
