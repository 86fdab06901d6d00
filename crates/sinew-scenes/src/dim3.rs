//! The scenes in 3D, over [`sinew::dim3`].

use sinew::dim3 as lib;

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;

pub mod gripper;

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

/// Shapes and measures for tetrahedral meshes of users' surfaces (the stuffing tests and the
/// `meshing` example).
pub mod meshing {
    use sinew::dim3::math::{Real, Vector};
    use sinew::dim3::{Mesh, Surface};

    /// A torus of radii `big` and `small` about the y axis, `n` × `m` flat quads.
    pub fn torus(big: Real, small: Real, n: usize, m: usize) -> Surface {
        let tau = std::f64::consts::TAU as Real;
        let mut v = Vec::new();
        for i in 0..n {
            let a = tau * i as Real / n as Real;
            for j in 0..m {
                let b = tau * j as Real / m as Real;
                let r = big + small * b.cos();
                v.push(Vector::new(r * a.cos(), small * b.sin(), r * a.sin()));
            }
        }
        let id = |i: usize, j: usize| ((i % n) * m + j % m) as u32;
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..m {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                t.extend([[a, d, b], [b, d, c]]);
            }
        }
        Surface::new(v, t).expect("a torus is a closed surface")
    }

    /// The smallest and the largest dihedral angle of the mesh's tetrahedra, in degrees.
    pub fn dihedral_range(mesh: &Mesh) -> (Real, Real) {
        let x = mesh.nodes();
        let (mut lo, mut hi): (Real, Real) = (180.0, 0.0);
        for c in mesh.cell_indices().chunks_exact(4) {
            let p = [0, 1, 2, 3].map(|k| x[c[k] as usize]);
            for (i, j, k, l) in [
                (0, 1, 2, 3),
                (0, 2, 1, 3),
                (0, 3, 1, 2),
                (1, 2, 0, 3),
                (1, 3, 0, 2),
                (2, 3, 0, 1),
            ] {
                // The angle between the half-planes through edge ij that hold k and l.
                let e = p[j] - p[i];
                let (n1, n2) = (e.cross(p[k] - p[i]), e.cross(p[l] - p[i]));
                let angle = (n1.dot(n2) / (n1.length() * n2.length()))
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees();
                lo = lo.min(angle);
                hi = hi.max(angle);
            }
        }
        (lo, hi)
    }
}
