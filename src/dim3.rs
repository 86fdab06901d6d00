//! The 3D crate: tetrahedra and hexahedra beside `rapier3d`.

pub use rapier3d as rapier;

/// 3D math: rapier's glam types plus the per-dimension geometry that the shared code needs
/// (simplex volume, facet normals, rotation fits).
pub mod math {
    use rapier3d::glamx::{DMat3, DVec3, Svd3};
    pub use rapier3d::math::{Matrix, Pose, Real, Rotation, Vector, DIM};

    /// An angular quantity (torque, angular velocity, angular momentum): a vector in 3D.
    pub type AngVector = Vector;

    /// Number of vertices of a simplex cell (tetrahedron).
    pub const SIMPLEX_ARITY: usize = 4;
    /// Number of vertices of a facet of a simplex (triangle).
    pub const FACET_ARITY: usize = 3;
    /// `DIM!`: the volume of a simplex is `det(edges) / DIM_FACTORIAL`.
    pub const DIM_FACTORIAL: Real = 6.0;
    /// The dimension's name, for messages.
    pub const DIM_NAME: &str = "3D";

    /// Cross product `a × b`.
    #[inline]
    pub fn cross(a: Vector, b: Vector) -> AngVector {
        a.cross(b)
    }

    /// `w × r` for an angular vector `w`.
    #[inline]
    pub fn ang_cross(w: AngVector, r: Vector) -> Vector {
        w.cross(r)
    }

    /// Magnitude of an angular vector.
    #[inline]
    pub fn ang_norm(w: AngVector) -> Real {
        w.length()
    }

    /// Zero angular vector.
    pub const ANG_ZERO: AngVector = Vector::ZERO;

    /// Determinant of the `DIM` edge vectors `e` (triple product).
    #[inline]
    pub fn det(e: &[Vector]) -> Real {
        e[0].dot(e[1].cross(e[2]))
    }

    /// Signed volume of a tetrahedron (positive when `p1 - p0, p2 - p0, p3 - p0` is
    /// right-handed).
    #[inline]
    pub fn simplex_volume(p: &[Vector]) -> Real {
        det(&[p[1] - p[0], p[2] - p[0], p[3] - p[0]]) / DIM_FACTORIAL
    }

    /// Unnormalised normal of a facet (a triangle): `(p1 - p0) × (p2 - p0)`.
    #[inline]
    pub fn facet_normal(p: &[Vector]) -> Vector {
        (p[1] - p[0]).cross(p[2] - p[0])
    }

    /// Barycentric weights of the orthogonal projection of `x` onto the plane of the
    /// triangle `p` (weights sum to one; they may be negative outside the triangle).
    pub fn facet_barycentric(p: &[Vector], x: Vector) -> [Real; FACET_ARITY] {
        let e1 = p[1] - p[0];
        let e2 = p[2] - p[0];
        let d = x - p[0];
        let d11 = e1.dot(e1);
        let d12 = e1.dot(e2);
        let d22 = e2.dot(e2);
        let d1 = d.dot(e1);
        let d2 = d.dot(e2);
        let den = d11 * d22 - d12 * d12;
        if den.abs() <= Real::EPSILON * d11 * d22 {
            return [1.0 / 3.0; 3];
        }
        let b = (d22 * d1 - d12 * d2) / den;
        let c = (d11 * d2 - d12 * d1) / den;
        [1.0 - b - c, b, c]
    }

    /// Outer product `a bᵀ`.
    #[inline]
    pub fn outer(a: Vector, b: Vector) -> Matrix {
        Matrix::from_cols(a * b.x, a * b.y, a * b.z)
    }

    /// Rotation from an angular vector (scaled axis).
    #[inline]
    pub fn rotation_from_angle(w: AngVector) -> Rotation {
        Rotation::from_scaled_axis(w)
    }

    /// The angle of the relative rotation between `a` and `b`.
    #[inline]
    pub fn rotation_angle_between(a: Rotation, b: Rotation) -> Real {
        a.angle_between(b)
    }

    /// Least-squares rigid angular velocity of points at offsets `r` (from their centroid)
    /// moving with relative velocities `v`: solves `I ω = Σ r × v` with
    /// `I = Σ (|r|² 𝟙 − r rᵀ)`. Zero when the points are (nearly) collinear.
    pub fn rigid_angular_velocity(r: &[Vector], v: &[Vector]) -> AngVector {
        let mut inertia = Matrix::ZERO;
        let mut momentum = Vector::ZERO;
        for (ri, vi) in r.iter().zip(v) {
            inertia += Matrix::from_diagonal(Vector::splat(ri.length_squared())) - outer(*ri, *ri);
            momentum += ri.cross(*vi);
        }
        let d = inertia.determinant();
        let scale = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
        if d.abs() <= 1e-9 * scale * scale * scale {
            return Vector::ZERO;
        }
        inertia.inverse() * momentum
    }

    /// The rotation of the polar decomposition of `a = Σ r_i R0_iᵀ` (the rotation that best
    /// maps the rest offsets onto the current ones, Müller et al. 2005). Computed in `f64` by
    /// the scaled Newton iteration `X ← ½(γX + X⁻ᵀ/γ)`, which converges quadratically for
    /// `det a > 0`; for an inverted or flat `a` the closest proper rotation comes from the SVD
    /// with the smallest singular direction flipped.
    pub fn polar_rotation(a: Matrix) -> Rotation {
        let mut x = DMat3::from_cols(
            a.x_axis.as_dvec3(),
            a.y_axis.as_dvec3(),
            a.z_axis.as_dvec3(),
        );
        let scale = x.x_axis.length() + x.y_axis.length() + x.z_axis.length();
        if !scale.is_finite() || scale == 0.0 {
            return Rotation::IDENTITY;
        }
        if x.determinant() > 1e-9 * scale * scale * scale {
            for _ in 0..30 {
                let inv_t = x.inverse().transpose();
                // Frobenius-norm scaling speeds up the first iterations.
                let gamma = (frob(inv_t) / frob(x)).sqrt();
                let next = (x * gamma + inv_t * (1.0 / gamma)) * 0.5;
                let delta = frob(next - x);
                x = next;
                if delta <= 1e-13 {
                    break;
                }
            }
            let m = Matrix::from_cols(x.x_axis.as_vec3(), x.y_axis.as_vec3(), x.z_axis.as_vec3());
            return Rotation::from_mat3(&m).normalize();
        }
        let svd = Svd3::from_matrix(a);
        let mut u = svd.u;
        if (u * svd.vt).determinant() < 0.0 {
            u.z_axis = -u.z_axis;
        }
        Rotation::from_mat3(&(u * svd.vt)).normalize()
    }

    fn frob(m: DMat3) -> f64 {
        let c = [m.x_axis, m.y_axis, m.z_axis];
        c.iter()
            .map(|v: &DVec3| v.length_squared())
            .sum::<f64>()
            .sqrt()
    }

    /// One to `iterations` steps of the shape-based paper's rotation update (its eq. 11–16):
    /// from the current estimate `q` (last step's rotation), with `R_i = q R0_i`, solve the
    /// small-rotation system `(Σ (r_i·R_i) 𝟙 − Σ R_i r_iᵀ) w = Σ R_i × r_i` and rotate by the
    /// axis `w/|w|` and angle `|w|`. Converges to [`polar_rotation`].
    pub fn iterate_rotation(
        rest: &[Vector],
        current: &[Vector],
        mut q: Rotation,
        iterations: usize,
    ) -> Rotation {
        for _ in 0..iterations {
            let mut a = Matrix::ZERO;
            let mut rhs = Vector::ZERO;
            for (r0, r) in rest.iter().zip(current) {
                let big_r = q * *r0;
                a += Matrix::from_diagonal(Vector::splat(r.dot(big_r))) - outer(big_r, *r);
                rhs += big_r.cross(*r);
            }
            let det = a.determinant();
            if !det.is_finite() || det.abs() < Real::EPSILON {
                break;
            }
            let w = a.inverse() * rhs;
            if !w.is_finite() {
                break;
            }
            q = (Rotation::from_scaled_axis(w) * q).normalize();
        }
        q
    }

    /// The exact rotation of the shape-based element in 2D; unused in 3D.
    pub fn exact_rotation(_rest: &[Vector], _current: &[Vector]) -> Option<Rotation> {
        None
    }

    /// A vector from its `DIM` components.
    #[inline]
    pub fn vector_from_slice(c: &[Real]) -> Vector {
        Vector::new(c[0], c[1], c[2])
    }

    /// The "up" axis used for heights in reports and examples.
    pub const UP: Vector = Vector::Y;

    /// Dot product of two angular quantities.
    #[inline]
    pub fn ang_dot(a: AngVector, b: AngVector) -> Real {
        a.dot(b)
    }

    /// The vertices and edges of a convex polyhedron shape, in its local frame.
    pub fn convex_outline(
        shape: &dyn rapier3d::geometry::Shape,
    ) -> Option<(Vec<Vector>, Vec<[usize; 2]>)> {
        let poly = shape.as_convex_polyhedron()?;
        let edges = poly
            .edges()
            .iter()
            .map(|e| [e.vertices[0] as usize, e.vertices[1] as usize])
            .collect();
        Some((poly.points().to_vec(), edges))
    }

    /// A rotation angle about the axis normal to the x-y plane, as an angular quantity.
    #[inline]
    pub fn planar_angle(theta: Real) -> AngVector {
        Vector::new(0.0, 0.0, theta)
    }
}

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;
