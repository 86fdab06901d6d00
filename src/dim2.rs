//! The 2D crate: triangles and quads beside `rapier2d`.

pub use rapier2d as rapier;

/// 2D math: rapier's glam types plus the per-dimension geometry that the shared code needs
/// (simplex area, edge normals, the exact rotation fit).
pub mod math {
    pub use rapier2d::math::{Matrix, Pose, Real, Rotation, Vector, DIM};

    /// An angular quantity (torque, angular velocity, angular momentum): a scalar in 2D.
    pub type AngVector = Real;

    /// Number of vertices of a simplex cell (triangle).
    pub const SIMPLEX_ARITY: usize = 3;
    /// Number of vertices of a facet of a simplex (an edge).
    pub const FACET_ARITY: usize = 2;
    /// `DIM!`: the area of a triangle is `det(edges) / DIM_FACTORIAL`.
    pub const DIM_FACTORIAL: Real = 2.0;
    /// The dimension's name, for messages.
    pub const DIM_NAME: &str = "2D";

    /// The 2D cross product `a × b = a.x b.y − a.y b.x`.
    #[inline]
    pub fn cross(a: Vector, b: Vector) -> AngVector {
        a.perp_dot(b)
    }

    /// `w × r` for a scalar angular velocity `w`.
    #[inline]
    pub fn ang_cross(w: AngVector, r: Vector) -> Vector {
        r.perp() * w
    }

    /// Magnitude of an angular quantity.
    #[inline]
    pub fn ang_norm(w: AngVector) -> Real {
        w.abs()
    }

    /// Zero angular quantity.
    pub const ANG_ZERO: AngVector = 0.0;

    /// Determinant of the `DIM` edge vectors `e`.
    #[inline]
    pub fn det(e: &[Vector]) -> Real {
        e[0].perp_dot(e[1])
    }

    /// Signed area of a triangle (positive when counter-clockwise).
    #[inline]
    pub fn simplex_volume(p: &[Vector]) -> Real {
        det(&[p[1] - p[0], p[2] - p[0]]) / DIM_FACTORIAL
    }

    /// Unnormalised normal of a facet (an edge `p0 → p1`): the edge turned a quarter to
    /// the left.
    #[inline]
    pub fn facet_normal(p: &[Vector]) -> Vector {
        (p[1] - p[0]).perp()
    }

    /// Barycentric weights of the orthogonal projection of `x` onto the line through the
    /// edge `p` (weights sum to one; negative outside the segment).
    pub fn facet_barycentric(p: &[Vector], x: Vector) -> [Real; FACET_ARITY] {
        let e = p[1] - p[0];
        let l2 = e.length_squared();
        if l2 <= Real::MIN_POSITIVE {
            return [0.5, 0.5];
        }
        let t = (x - p[0]).dot(e) / l2;
        [1.0 - t, t]
    }

    /// Outer product `a bᵀ`.
    #[inline]
    pub fn outer(a: Vector, b: Vector) -> Matrix {
        Matrix::from_cols(a * b.x, a * b.y)
    }

    /// Rotation from an angle in radians.
    #[inline]
    pub fn rotation_from_angle(w: AngVector) -> Rotation {
        Rotation::new(w)
    }

    /// The angle of the relative rotation between `a` and `b`.
    #[inline]
    pub fn rotation_angle_between(a: Rotation, b: Rotation) -> Real {
        a.angle_between(&b).abs()
    }

    /// Least-squares rigid angular velocity of points at offsets `r` (from their centroid)
    /// moving with relative velocities `v`: `ω = Σ r × v / Σ |r|²`.
    pub fn rigid_angular_velocity(r: &[Vector], v: &[Vector]) -> AngVector {
        let mut i = 0.0;
        let mut l = 0.0;
        for (ri, vi) in r.iter().zip(v) {
            i += ri.length_squared();
            l += ri.perp_dot(*vi);
        }
        if i <= Real::MIN_POSITIVE {
            0.0
        } else {
            l / i
        }
    }

    /// The rotation of the polar decomposition of `a = Σ r_i R0_iᵀ`: in 2D the angle
    /// `atan2(a₂₁ − a₁₂, a₁₁ + a₂₂)`, which is the shape-based paper's eq. 9.
    pub fn polar_rotation(a: Matrix) -> Rotation {
        let s = a.x_axis.y - a.y_axis.x;
        let c = a.x_axis.x + a.y_axis.y;
        if s == 0.0 && c == 0.0 {
            return Rotation::identity();
        }
        Rotation::new(s.atan2(c))
    }

    /// In 2D the shape-based rotation needs no iteration: every iteration count gives the
    /// exact angle of eq. 9.
    pub fn iterate_rotation(
        rest: &[Vector],
        current: &[Vector],
        _q: Rotation,
        _iterations: usize,
    ) -> Rotation {
        exact_rotation(rest, current).unwrap_or_else(Rotation::identity)
    }

    /// The exact rotation of the shape-based element (eq. 9):
    /// `θ = atan2(Σ R0_i × r_i, Σ R0_i · r_i)`.
    pub fn exact_rotation(rest: &[Vector], current: &[Vector]) -> Option<Rotation> {
        let mut s = 0.0;
        let mut c = 0.0;
        for (r0, r) in rest.iter().zip(current) {
            s += r0.perp_dot(*r);
            c += r0.dot(*r);
        }
        if s == 0.0 && c == 0.0 {
            return Some(Rotation::identity());
        }
        Some(Rotation::new(s.atan2(c)))
    }

    /// A vector from its `DIM` components.
    #[inline]
    pub fn vector_from_slice(c: &[Real]) -> Vector {
        Vector::new(c[0], c[1])
    }

    /// The "up" axis used for heights in reports and examples.
    pub const UP: Vector = Vector::Y;

    /// Product of two angular quantities (scalars in 2D).
    #[inline]
    pub fn ang_dot(a: AngVector, b: AngVector) -> Real {
        a * b
    }

    /// The vertices and edges of a convex polygon shape, in its local frame.
    pub fn convex_outline(
        shape: &dyn rapier2d::geometry::Shape,
    ) -> Option<(Vec<Vector>, Vec<[usize; 2]>)> {
        let poly = shape.as_convex_polygon()?;
        let n = poly.points().len();
        let edges = (0..n).map(|i| [i, (i + 1) % n]).collect();
        Some((poly.points().to_vec(), edges))
    }

    /// A rotation angle in the x-y plane, as an angular quantity.
    #[inline]
    pub fn planar_angle(theta: Real) -> AngVector {
        theta
    }
}

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;
