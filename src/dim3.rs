//! The 3D crate: tetrahedra and hexahedra beside `rapier3d`.

pub use rapier3d as rapier;

/// 3D math: rapier's glam types plus the per-dimension geometry that the shared code needs
/// (simplex volume, facet normals, rotation fits).
pub mod math {
    use rapier3d::glamx::{DMat3, DVec3, Svd3};
    pub use rapier3d::math::{Matrix, Pose, Real, Rotation, Vector, DIM};

    /// An angular quantity (torque, angular velocity, angular momentum): a vector in 3D.
    pub type AngVector = Vector;

    /// A linear map of angular quantities (an inverse inertia): a 3 × 3 matrix in 3D.
    pub type AngMatrix = Matrix;

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

    /// The component of angular vector `w` about unit axis `n` (its twist about it).
    pub fn twist_about(w: AngVector, n: Vector) -> Real {
        w.dot(n)
    }

    /// Two unit vectors spanning the plane across unit `normal`.
    pub fn tangents(normal: Vector) -> [Vector; 2] {
        let (a, b) = normal.any_orthonormal_pair();
        [a, b]
    }

    /// Magnitude of an angular vector.
    #[inline]
    pub fn ang_norm(w: AngVector) -> Real {
        w.length()
    }

    /// Zero angular vector.
    pub const ANG_ZERO: AngVector = Vector::ZERO;

    /// Degrees of freedom of a rigid body's velocity: 3 linear, 3 angular.
    pub const TWIST_DIM: usize = 6;

    /// A rigid velocity as one array: linear components, then angular.
    #[inline]
    pub fn twist_to_array(v: Vector, w: AngVector) -> [Real; TWIST_DIM] {
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// The rigid velocity of [`twist_to_array`]'s array.
    #[inline]
    pub fn twist_from_array(a: &[Real; TWIST_DIM]) -> (Vector, AngVector) {
        (Vector::new(a[0], a[1], a[2]), Vector::new(a[3], a[4], a[5]))
    }

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

    /// `DIM_FACTORIAL ×` the signed volume of the simplex `p`, `D = det(p1 − p0, p2 − p0, p3 − p0)`,
    /// and its gradient with respect to each vertex (`g_a` is the area vector of the facet
    /// opposite `a`, twice its area long, pointing to `a`'s side when `D > 0`; they sum to zero).
    #[inline]
    pub fn simplex_gradients(p: &[Vector; SIMPLEX_ARITY]) -> (Real, [Vector; SIMPLEX_ARITY]) {
        let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
        let (g1, g2, g3) = (e2.cross(e3), e3.cross(e1), e1.cross(e2));
        (e1.dot(g1), [-(g1 + g2 + g3), g1, g2, g3])
    }

    /// A surface facet as a parry shape (a triangle).
    pub type FacetShape = rapier3d::parry::shape::Triangle;

    /// The facet through `p` as a parry shape.
    #[inline]
    pub fn facet_shape(p: &[Vector]) -> FacetShape {
        rapier3d::parry::shape::Triangle::new(p[0], p[1], p[2])
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

    /// The angular velocity `ω` that gives masses `m` at offsets `r` (from their centre of
    /// mass) the angular momentum `l`: `I ω = l`, `I = Σ m (|r|² 𝟙 − r rᵀ)`. Zero when the
    /// masses are (nearly) collinear.
    pub fn angular_velocity_for(r: &[Vector], m: &[Real], l: AngVector) -> AngVector {
        inertia_of(r, m).map_or(Vector::ZERO, |inertia| inertia.inverse() * l)
    }

    /// The inverse of the inertia tensor of masses `m` at offsets `r` (from their centre of
    /// mass); zero when they are (nearly) collinear.
    pub fn inverse_inertia(r: &[Vector], m: &[Real]) -> AngMatrix {
        inertia_of(r, m).map_or(Matrix::ZERO, |inertia| inertia.inverse())
    }

    /// The inertia tensor `Σ m (|r|² 𝟙 − r rᵀ)` of masses `m` at offsets `r`; `None` when they
    /// are (nearly) collinear (it is singular).
    fn inertia_of(r: &[Vector], m: &[Real]) -> Option<Matrix> {
        let mut inertia = Matrix::ZERO;
        for (ri, mi) in r.iter().zip(m) {
            inertia +=
                (Matrix::from_diagonal(Vector::splat(ri.length_squared())) - outer(*ri, *ri)) * *mi;
        }
        let d = inertia.determinant();
        let scale = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
        (d.abs() > 1e-9 * scale * scale * scale).then_some(inertia)
    }

    /// The rigid turn of masses `m` at offsets `r` (from their centre of mass) with angular
    /// momentum `l`: its angular velocity `ω = I⁻¹ l` ([`angular_velocity_for`]) and its
    /// angular acceleration with no torque, `α = −I⁻¹ (ω × I ω)` (Euler's equations; zero
    /// about a principal axis). Both zero when the masses are (nearly) collinear.
    pub fn torque_free_turn(r: &[Vector], m: &[Real], l: AngVector) -> (AngVector, AngVector) {
        inertia_of(r, m).map_or((Vector::ZERO, Vector::ZERO), |inertia| {
            let inverse = inertia.inverse();
            let w = inverse * l;
            (w, -(inverse * w.cross(inertia * w)))
        })
    }

    /// The smallest sum of two singular values of `a` (`σ₂ + σ₃`): how fast the rotation of
    /// `a`'s polar decomposition can turn as `a` changes (`|δR| ≤ |δa| / (σ₂ + σ₃)`).
    pub fn least_singular_pair_sum(a: Matrix) -> Real {
        let ev = rapier3d::glamx::SymmetricEigen3::eigenvalues(a.transpose() * a);
        let s = ev.max(Vector::ZERO).map(Real::sqrt);
        let sum = s.x + s.y + s.z;
        if sum.is_finite() {
            sum - s.max_element()
        } else {
            0.0
        }
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
            // Relative to the cell's size: an absolute threshold stalls the fit at the warm
            // start for cells smaller than a few centimetres (det ∝ size⁶).
            let det = a.determinant();
            let trace = a.x_axis.x + a.y_axis.y + a.z_axis.z;
            if !det.is_finite() || det.abs() <= Real::EPSILON * (trace * trace * trace).abs() {
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

    /// An angular quantity from its first components out of three (all three in 3D, the
    /// first — about the plane's normal — in 2D).
    #[inline]
    pub fn ang_from_components(c: [Real; 3]) -> AngVector {
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

    /// A convex polyhedron's face planes: outward unit normal `n` and offset `d`, the inside
    /// being `n·x ≤ d` for every face.
    pub fn convex_planes(shape: &dyn rapier3d::geometry::Shape) -> Option<Vec<(Vector, Real)>> {
        let poly = shape.as_convex_polyhedron()?;
        let (points, adj) = (poly.points(), poly.vertices_adj_to_face());
        Some(
            poly.faces()
                .iter()
                .map(|f| {
                    let p = points[adj[f.first_vertex_or_edge as usize] as usize];
                    (f.normal, f.normal.dot(p))
                })
                .collect(),
        )
    }

    /// A rotation angle about the axis normal to the x-y plane, as an angular quantity.
    #[inline]
    pub fn planar_angle(theta: Real) -> AngVector {
        Vector::new(0.0, 0.0, theta)
    }
}

/// Rerun primitives for 3D (used by the shared recorder).
#[cfg(feature = "rerun")]
pub(crate) mod render {
    use super::math::{Pose, Real, Vector};
    use rapier3d::geometry::Shape;
    use rerun::external::re_sdk_types::blueprint::archetypes::EyeControls3D;
    use rerun::external::re_sdk_types::blueprint::components::Eye3DKind;
    use rerun::{
        Boxes3D, Capsules3D, Color, Ellipsoids3D, LineStrips3D, Mesh3D, Points3D, Quaternion,
        Radius, RecordingStream, RecordingStreamResult, Transform3D, ViewCoordinates,
    };

    /// The world view's space origin in the blueprint (the view coordinates are logged there).
    pub const VIEW_ORIGIN: &str = "/world";

    /// The world view's class in the blueprint.
    pub const VIEW_CLASS: &str = "3D";

    /// Frames the 3D view at `view` (a blueprint path) on the box `lo`–`hi`: an orbit eye in
    /// front, to the right and above its centre, far enough to see the whole box, y up;
    /// following `track` if given.
    pub fn frame_view(
        rec: &RecordingStream,
        view: &str,
        lo: Vector,
        hi: Vector,
        track: Option<&str>,
    ) -> RecordingStreamResult<()> {
        let centre = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(0.05);
        let eye = centre + Vector::new(0.6, 0.5, 1.0).normalize() * (2.8 * radius);
        let mut controls = EyeControls3D::new()
            .with_kind(Eye3DKind::Orbital)
            .with_position(p(eye))
            .with_look_target(p(centre))
            .with_eye_up([0.0, 1.0, 0.0]);
        if let Some(entity) = track {
            controls = controls.with_tracking_entity(entity);
        }
        rec.log(format!("{view}/EyeControls3D"), &controls)
    }

    /// What the eye follows: two invisible points (radius 0) at the corners of the box of
    /// `vertices` grown 1.2 times about its centre. The viewer keeps a followed entity at 1.5
    /// times its bounding radius; following the surface itself puts its bottom out of view.
    pub fn focus(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
    ) -> RecordingStreamResult<()> {
        let (lo, hi) = vertices.iter().fold(
            (
                Vector::splat(Real::INFINITY),
                Vector::splat(Real::NEG_INFINITY),
            ),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        let (centre, half) = (0.5 * (lo + hi), 0.6 * (hi - lo));
        rec.log(
            path,
            &Points3D::new([p(centre - half), p(centre + half)])
                .with_radii([0.0])
                .with_colors([Color::from_unmultiplied_rgba(0, 0, 0, 0)]),
        )
    }

    /// Thin lines of a fixed on-screen width (the surface's wireframe).
    pub fn wireframe(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
        strips: &[Vec<u32>],
        color: Color,
    ) -> RecordingStreamResult<()> {
        let strips = strips.iter().map(|s| {
            s.iter()
                .map(|&i| p(vertices[i as usize]))
                .collect::<Vec<_>>()
        });
        rec.log(
            path,
            &LineStrips3D::new(strips)
                .with_colors([color])
                .with_radii([Radius::new_ui_points(0.6)]),
        )
    }

    /// The world's axes: y up, right-handed (as rapier).
    pub fn view_coordinates(rec: &RecordingStream) -> RecordingStreamResult<()> {
        rec.log_static("world", &ViewCoordinates::RIGHT_HAND_Y_UP())
    }

    fn p(v: Vector) -> [f32; 3] {
        v.to_array()
    }

    /// The surface topology: triangles over the surface vertices, static, or on the timeline
    /// if it `changes` (a body that tears logs it again after each tear).
    pub fn surface_topology(
        rec: &RecordingStream,
        path: &str,
        facets: &[[u32; 3]],
        changes: bool,
    ) -> RecordingStreamResult<()> {
        let topology = Mesh3D::update_fields().with_triangle_indices(facets.iter().copied());
        if changes {
            rec.log(path, &topology)
        } else {
            rec.log_static(path, &topology)
        }
    }

    /// The surface of one frame: vertex positions and colours.
    pub fn surface(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
        _facets: &[[u32; 3]],
        colors: &[Color],
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &Mesh3D::update_fields()
                .with_vertex_positions(vertices.iter().map(|v| p(*v)))
                .with_vertex_colors(colors.iter().copied()),
        )
    }

    /// A render mesh's triangles, logged once (and again when they change).
    pub fn render_mesh_topology(
        rec: &RecordingStream,
        path: &str,
        facets: &[[u32; 3]],
    ) -> RecordingStreamResult<()> {
        rec.log_static(
            path,
            &Mesh3D::update_fields()
                .with_triangle_indices(facets.iter().copied())
                .with_albedo_factor(Color::from_rgb(190, 190, 200).0),
        )
    }

    /// A render mesh at one frame: its vertices and normals.
    pub fn render_mesh(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
        normals: &[Vector],
        _facets: &[[u32; 3]],
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &Mesh3D::update_fields()
                .with_vertex_positions(vertices.iter().map(|v| p(*v)))
                .with_vertex_normals(normals.iter().map(|v| p(*v))),
        )
    }

    /// Points.
    pub fn points(
        rec: &RecordingStream,
        path: &str,
        at: &[Vector],
        colors: &[Color],
        radius: f32,
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &Points3D::new(at.iter().map(|v| p(*v)))
                .with_colors(colors.iter().copied())
                .with_radii([radius]),
        )
    }

    /// Line segments.
    pub fn segments(
        rec: &RecordingStream,
        path: &str,
        segments: &[[Vector; 2]],
        color: Color,
        radius: f32,
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &LineStrips3D::new(segments.iter().map(|s| [p(s[0]), p(s[1])]))
                .with_colors([color])
                .with_radii([radius]),
        )
    }

    /// A rigid pose as a transform.
    pub fn pose(rec: &RecordingStream, path: &str, pose: &Pose) -> RecordingStreamResult<()> {
        let q = pose.rotation;
        rec.log(
            path,
            &Transform3D::from_translation_rotation(
                p(pose.translation),
                Quaternion::from_xyzw([q.x, q.y, q.z, q.w]),
            ),
        )
    }

    /// A collider shape in its own frame, once. Returns false for a shape it cannot draw.
    pub fn shape(
        rec: &RecordingStream,
        path: &str,
        shape: &dyn Shape,
        color: Color,
    ) -> RecordingStreamResult<bool> {
        if let Some(c) = shape.as_cuboid() {
            rec.log_static(
                path,
                &Boxes3D::from_half_sizes([p(c.half_extents)]).with_colors([color]),
            )?;
        } else if let Some(b) = shape.as_ball() {
            rec.log_static(
                path,
                &Ellipsoids3D::from_radii([b.radius]).with_colors([color]),
            )?;
        } else if let Some(c) = shape.as_capsule() {
            rec.log_static(
                path,
                &Capsules3D::from_endpoints_and_radii(
                    [p(c.segment.a)],
                    [p(c.segment.b)],
                    [c.radius],
                )
                .with_colors([color]),
            )?;
        } else if let Some(compound) = shape.as_compound() {
            let mut all = true;
            for (k, (local, sub)) in compound.shapes().iter().enumerate() {
                let sub_path = format!("{path}/{k}");
                let q = local.rotation;
                rec.log_static(
                    sub_path.as_str(),
                    &Transform3D::from_translation_rotation(
                        p(local.translation),
                        Quaternion::from_xyzw([q.x, q.y, q.z, q.w]),
                    ),
                )?;
                all &= self::shape(rec, &sub_path, sub.as_ref(), color)?;
            }
            return Ok(all);
        } else {
            let mesh = if let Some(c) = shape.as_convex_polyhedron() {
                Some(c.to_trimesh())
            } else if let Some(t) = shape.as_trimesh() {
                Some((t.vertices().to_vec(), t.indices().to_vec()))
            } else {
                shape.as_heightfield().map(|h| h.to_trimesh())
            };
            let Some((vertices, indices)) = mesh else {
                return Ok(false);
            };
            rec.log_static(
                path,
                &Mesh3D::new(vertices.iter().map(|v| p(*v)))
                    .with_triangle_indices(indices)
                    .with_albedo_factor(color.0),
            )?;
        }
        Ok(true)
    }

    /// Arrows (contact normals).
    pub fn arrows(
        rec: &RecordingStream,
        path: &str,
        origins: &[Vector],
        vectors: &[Vector],
        color: Color,
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &rerun::Arrows3D::from_vectors(vectors.iter().map(|v| p(*v)))
                .with_origins(origins.iter().map(|v| p(*v)))
                .with_colors([color]),
        )
    }
}

#[path = "shared/mod.rs"]
mod shared;
pub use shared::*;
mod stuffing;
pub mod surface;
pub use surface::{Surface, SurfaceError};
