//! The 2D crate: triangles and quads beside `rapier2d`.

pub use rapier2d as rapier;

/// 2D math: rapier's glam types plus the per-dimension geometry that the shared code needs
/// (simplex area, edge normals, the exact rotation fit).
pub mod math {
    pub use rapier2d::math::{Matrix, Pose, Real, Rotation, Vector, DIM};

    /// An angular quantity (torque, angular velocity, angular momentum): a scalar in 2D.
    pub type AngVector = Real;

    /// A linear map of angular quantities (an inverse inertia): a scalar in 2D.
    pub type AngMatrix = Real;

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

    /// The component of angular quantity `w` about in-plane axis `n`: none, every 2D turn is
    /// about the normal of the plane.
    pub fn twist_about(_w: AngVector, _n: Vector) -> Real {
        0.0
    }

    /// The unit vector along the line across unit `normal`, and zero (the line has one).
    pub fn tangents(normal: Vector) -> [Vector; 2] {
        [normal.perp(), Vector::ZERO]
    }

    /// Magnitude of an angular quantity.
    #[inline]
    pub fn ang_norm(w: AngVector) -> Real {
        w.abs()
    }

    /// Zero angular quantity.
    pub const ANG_ZERO: AngVector = 0.0;

    /// Degrees of freedom of a rigid body's velocity: 2 linear, 1 angular.
    pub const TWIST_DIM: usize = 3;

    /// A rigid velocity as one array: linear components, then angular.
    #[inline]
    pub fn twist_to_array(v: Vector, w: AngVector) -> [Real; TWIST_DIM] {
        [v.x, v.y, w]
    }

    /// The rigid velocity of [`twist_to_array`]'s array.
    #[inline]
    pub fn twist_from_array(a: &[Real; TWIST_DIM]) -> (Vector, AngVector) {
        (Vector::new(a[0], a[1]), a[2])
    }

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

    /// `DIM_FACTORIAL ×` the signed area of the triangle `p`, `D = det(p1 − p0, p2 − p0)`, and
    /// its gradient with respect to each vertex (`g_a` is the opposite edge turned a quarter,
    /// its length long, pointing to `a`'s side when `D > 0`; they sum to zero).
    #[inline]
    pub fn simplex_gradients(p: &[Vector; SIMPLEX_ARITY]) -> (Real, [Vector; SIMPLEX_ARITY]) {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (g1, g2) = (-e2.perp(), e1.perp());
        (e1.dot(g1), [-(g1 + g2), g1, g2])
    }

    /// A surface facet as a parry shape (a segment).
    pub type FacetShape = rapier2d::parry::shape::Segment;

    /// The facet through `p` as a parry shape.
    #[inline]
    pub fn facet_shape(p: &[Vector]) -> FacetShape {
        rapier2d::parry::shape::Segment::new(p[0], p[1])
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

    /// The sum of the two singular values of `a`, `√(|a|²_F + 2|det a|)`: how fast the
    /// rotation of `a`'s polar decomposition can turn as `a` changes (`|δθ| ≤ |δa| / (σ₁ + σ₂)`).
    pub fn least_singular_pair_sum(a: Matrix) -> Real {
        let frob = a.x_axis.length_squared() + a.y_axis.length_squared();
        (frob + 2.0 * a.determinant().abs()).sqrt()
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

    /// The polar moment of inertia `Σ m |r|²` of masses `m` at offsets `r`.
    fn polar_inertia(r: &[Vector], m: &[Real]) -> Real {
        r.iter()
            .zip(m)
            .map(|(ri, mi)| mi * ri.length_squared())
            .sum()
    }

    /// The inverse inertia `1 / Σ m |r|²` of masses `m` at offsets `r` (from their centre of
    /// mass); zero when they all sit at the centre.
    pub fn inverse_inertia(r: &[Vector], m: &[Real]) -> AngMatrix {
        let i = polar_inertia(r, m);
        if i <= Real::MIN_POSITIVE {
            0.0
        } else {
            1.0 / i
        }
    }

    /// The angular velocity `ω` that gives masses `m` at offsets `r` (from their centre of
    /// mass) the angular momentum `l`: `ω = l / Σ m |r|²`.
    pub fn angular_velocity_for(r: &[Vector], m: &[Real], l: AngVector) -> AngVector {
        let i = polar_inertia(r, m);
        if i <= Real::MIN_POSITIVE {
            0.0
        } else {
            l / i
        }
    }

    /// The rigid turn of masses `m` at offsets `r` (from their centre of mass) with angular
    /// momentum `l`: its angular velocity ([`angular_velocity_for`]) and its angular
    /// acceleration with no torque, zero in 2D, where every turn is about a principal axis.
    pub fn torque_free_turn(r: &[Vector], m: &[Real], l: AngVector) -> (AngVector, AngVector) {
        (angular_velocity_for(r, m, l), 0.0)
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

    /// An angular quantity from its first components out of three (all three in 3D, the
    /// first — about the plane's normal — in 2D).
    #[inline]
    pub fn ang_from_components(c: [Real; 3]) -> AngVector {
        c[0]
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

    /// A convex polygon's edge lines: outward unit normal `n` and offset `d`, the inside being
    /// `n·x ≤ d` for every edge.
    pub fn convex_planes(shape: &dyn rapier2d::geometry::Shape) -> Option<Vec<(Vector, Real)>> {
        let poly = shape.as_convex_polygon()?;
        Some(
            poly.points()
                .iter()
                .zip(poly.normals())
                .map(|(p, n)| (*n, n.dot(*p)))
                .collect(),
        )
    }

    /// A rotation angle in the x-y plane, as an angular quantity.
    #[inline]
    pub fn planar_angle(theta: Real) -> AngVector {
        theta
    }
}

/// Rerun primitives for 2D (used by the shared recorder): a 2D view, with rapier's y up.
#[cfg(feature = "rerun")]
pub(crate) mod render {
    use super::math::{Pose, Vector};
    use rapier2d::geometry::Shape;
    use rerun::external::re_sdk_types::blueprint::archetypes::VisualBounds2D;
    use rerun::external::re_sdk_types::datatypes::{Range1D, Range2D};
    use rerun::{
        Boxes2D, Color, Ellipses2D, LineStrips2D, Points2D, Quaternion, RecordingStream,
        RecordingStreamResult, Transform3D,
    };

    /// The world view's space origin in the blueprint (above `world`, whose transform mirrors y).
    pub const VIEW_ORIGIN: &str = "/";

    /// The world view's class in the blueprint.
    pub const VIEW_CLASS: &str = "2D";

    /// Rerun's 2D views draw y downwards (image convention); rapier's y is up. Positions are
    /// logged as they are and `world` gets a transform that mirrors y, so a view rooted above
    /// it (sinew's layout roots it at `/`) draws y up.
    pub fn view_coordinates(rec: &RecordingStream) -> RecordingStreamResult<()> {
        rec.log_static("world", &Transform3D::from_scale([1.0, -1.0, 1.0]))
    }

    fn p(v: Vector) -> [f32; 2] {
        v.to_array()
    }

    /// Frames the 2D view at `view` (a blueprint path) on the box `lo`–`hi` (in `world`'s
    /// coordinates, y up), with a margin of a quarter of its size.
    pub fn frame_view(
        rec: &RecordingStream,
        view: &str,
        lo: Vector,
        hi: Vector,
        _track: Option<&str>,
    ) -> RecordingStreamResult<()> {
        let margin = 0.25 * (hi - lo).max(Vector::splat(0.1));
        let (lo, hi) = ((lo - margin).as_dvec2(), (hi + margin).as_dvec2());
        let bounds = Range2D {
            x_range: Range1D([lo.x, hi.x]),
            // The view sees `world` mirrored in y.
            y_range: Range1D([-hi.y, -lo.y]),
        };
        rec.log(
            format!("{view}/VisualBounds2D"),
            &VisualBounds2D::new(bounds),
        )
    }

    /// What a 3D eye follows; 2D views are framed by their bounds, so nothing.
    pub fn focus(
        _rec: &RecordingStream,
        _path: &str,
        _vertices: &[Vector],
    ) -> RecordingStreamResult<()> {
        Ok(())
    }

    /// The surface's wireframe: a 2D surface is already drawn as lines, so nothing.
    pub fn wireframe(
        _rec: &RecordingStream,
        _path: &str,
        _vertices: &[Vector],
        _strips: &[Vec<u32>],
        _color: Color,
    ) -> RecordingStreamResult<()> {
        Ok(())
    }

    /// The surface topology is carried by the strips themselves in 2D.
    pub fn surface_topology(
        _rec: &RecordingStream,
        _path: &str,
        _facets: &[[u32; 2]],
        _changes: bool,
    ) -> RecordingStreamResult<()> {
        Ok(())
    }

    /// A render polyline's topology: nothing to log ahead in 2D (each frame sends its strips).
    pub fn render_mesh_topology(
        _rec: &RecordingStream,
        _path: &str,
        _facets: &[[u32; 2]],
    ) -> RecordingStreamResult<()> {
        Ok(())
    }

    /// A render polyline at one frame: one two-point strip per segment, grey.
    pub fn render_mesh(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
        _normals: &[Vector],
        facets: &[[u32; 2]],
    ) -> RecordingStreamResult<()> {
        rec.log(
            path,
            &rerun::LineStrips2D::new(
                facets
                    .iter()
                    .map(|f| [p(vertices[f[0] as usize]), p(vertices[f[1] as usize])]),
            )
            .with_colors([Color::from_rgb(190, 190, 200)]),
        )
    }

    /// The surface of one frame: one two-point strip per boundary segment, coloured by the mean
    /// of its two vertices' colours.
    pub fn surface(
        rec: &RecordingStream,
        path: &str,
        vertices: &[Vector],
        facets: &[[u32; 2]],
        colors: &[Color],
    ) -> RecordingStreamResult<()> {
        let strips = facets
            .iter()
            .map(|f| [p(vertices[f[0] as usize]), p(vertices[f[1] as usize])]);
        let strip_colors = facets.iter().map(|f| {
            let (a, b) = (
                colors[f[0] as usize].to_array(),
                colors[f[1] as usize].to_array(),
            );
            Color::from_unmultiplied_rgba(
                ((a[0] as u16 + b[0] as u16) / 2) as u8,
                ((a[1] as u16 + b[1] as u16) / 2) as u8,
                ((a[2] as u16 + b[2] as u16) / 2) as u8,
                255,
            )
        });
        rec.log(
            path,
            &LineStrips2D::new(strips)
                .with_colors(strip_colors)
                .with_radii([rerun::Radius::new_ui_points(2.5)]),
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
            &Points2D::new(at.iter().map(|v| p(*v)))
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
            &LineStrips2D::new(segments.iter().map(|s| [p(s[0]), p(s[1])]))
                .with_colors([color])
                .with_radii([radius]),
        )
    }

    /// A rigid pose as a transform (rotation about the view's normal).
    pub fn pose(rec: &RecordingStream, path: &str, pose: &Pose) -> RecordingStreamResult<()> {
        let half = 0.5 * pose.rotation.angle();
        let t = pose.translation;
        rec.log(
            path,
            &Transform3D::from_translation_rotation(
                [t.x, t.y, 0.0],
                Quaternion::from_xyzw([0.0, 0.0, half.sin(), half.cos()]),
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
                &Boxes2D::from_half_sizes([p(c.half_extents)]).with_colors([color]),
            )?;
        } else if let Some(b) = shape.as_ball() {
            rec.log_static(
                path,
                &Ellipses2D::from_half_sizes([[b.radius, b.radius]]).with_colors([color]),
            )?;
        } else if let Some(c) = shape.as_capsule() {
            // Outline: two sides and two half circles.
            let (a, b, r) = (c.segment.a, c.segment.b, c.radius);
            let axis = (b - a).normalize_or(Vector::X);
            let side = axis.perp() * r;
            let mut outline = vec![p(a + side), p(b + side)];
            let base = side.to_angle();
            for k in 1..16 {
                let t = base - std::f32::consts::PI * k as f32 / 16.0;
                outline.push(p(b + Vector::from_angle(t) * r));
            }
            outline.push(p(b - side));
            outline.push(p(a - side));
            for k in 1..16 {
                let t = base + std::f32::consts::PI - std::f32::consts::PI * k as f32 / 16.0;
                outline.push(p(a + Vector::from_angle(t) * r));
            }
            outline.push(p(a + side));
            rec.log_static(path, &LineStrips2D::new([outline]).with_colors([color]))?;
        } else if let Some(poly) = shape.as_convex_polygon() {
            let mut loop_points: Vec<[f32; 2]> = poly.points().iter().map(|v| p(*v)).collect();
            if let Some(first) = loop_points.first().copied() {
                loop_points.push(first);
            }
            rec.log_static(path, &LineStrips2D::new([loop_points]).with_colors([color]))?;
        } else if let Some(line) = shape.as_polyline() {
            let v = line.vertices();
            let strips = line
                .indices()
                .iter()
                .map(|s| [p(v[s[0] as usize]), p(v[s[1] as usize])]);
            rec.log_static(path, &LineStrips2D::new(strips).with_colors([color]))?;
        } else if let Some(compound) = shape.as_compound() {
            let mut all = true;
            for (k, (local, sub)) in compound.shapes().iter().enumerate() {
                let sub_path = format!("{path}/{k}");
                let half = 0.5 * local.rotation.angle();
                let t = local.translation;
                rec.log_static(
                    sub_path.as_str(),
                    &Transform3D::from_translation_rotation(
                        [t.x, t.y, 0.0],
                        Quaternion::from_xyzw([0.0, 0.0, half.sin(), half.cos()]),
                    ),
                )?;
                all &= self::shape(rec, &sub_path, sub.as_ref(), color)?;
            }
            return Ok(all);
        } else {
            return Ok(false);
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
            &rerun::Arrows2D::from_vectors(vectors.iter().map(|v| p(*v)))
                .with_origins(origins.iter().map(|v| p(*v)))
                .with_colors([color]),
        )
    }
}

pub mod polygon;
#[path = "shared/mod.rs"]
mod shared;
pub use polygon::PolygonError;
pub use shared::*;
