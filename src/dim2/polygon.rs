//! Triangle meshes of 2D polygons: [`Mesh::polygon`] and [`Mesh::polygon_with_holes`].
//!
//! The polygon (an outer ring and optional holes, each ring in either orientation) is
//! checked first — at least three vertices per ring, finite, no repeated consecutive vertex,
//! no edge crossing or touching another, holes inside the outer ring and not inside each
//! other — then triangulated by [spade](https://docs.rs/spade)'s constrained Delaunay
//! triangulation with every ring edge a constraint, and refined (Ruppert / Chew, spade's
//! `refine`) until no triangle is larger than `max_area` and no angle smaller than 20°.
//! Refinement may split a ring edge by inserting points on it, but never moves the boundary:
//! the mesh covers exactly the polygon.

use spade::handles::{FixedFaceHandle, InnerTag};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::math::{Real, Vector};
use super::{BuildError, CellKind, Mesh};

/// Why a polygon could not be triangulated. Rings are numbered 0 (the outer ring), then 1,
/// 2, ... for the holes in the order given; vertices and edges from 0 within their ring
/// (edge `k` runs from vertex `k` to vertex `k + 1`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PolygonError {
    /// A ring has fewer than three vertices.
    #[error("ring {ring} has {count} vertices; a polygon ring needs at least 3")]
    TooFewVertices {
        /// The ring.
        ring: usize,
        /// Its vertex count.
        count: usize,
    },
    /// A vertex is NaN or infinite.
    #[error("ring {ring}, vertex {vertex} is not finite: {point:?}")]
    NonFinite {
        /// The ring.
        ring: usize,
        /// The vertex.
        vertex: usize,
        /// Its coordinates.
        point: [Real; 2],
    },
    /// Two consecutive vertices coincide (a zero-length edge).
    #[error("ring {ring}: vertices {vertex} and the next one coincide (zero-length edge)")]
    RepeatedVertex {
        /// The ring.
        ring: usize,
        /// The first of the two vertices.
        vertex: usize,
    },
    /// A ring encloses no area (all its vertices on a line).
    #[error("ring {ring} has zero area")]
    ZeroArea {
        /// The ring.
        ring: usize,
    },
    /// Two edges cross, touch or overlap (a ring folding back on itself included).
    #[error("the polygon intersects itself: ring {ring_a} edge {edge_a} meets ring {ring_b} edge {edge_b}")]
    SelfIntersecting {
        /// The ring of the first edge.
        ring_a: usize,
        /// The first edge.
        edge_a: usize,
        /// The ring of the second edge.
        ring_b: usize,
        /// The second edge.
        edge_b: usize,
    },
    /// A hole is outside the outer ring.
    #[error("hole (ring {ring}) is not inside the outer ring")]
    HoleOutside {
        /// The hole's ring.
        ring: usize,
    },
    /// A hole lies inside another hole.
    #[error("hole (ring {ring}) lies inside hole (ring {outer})")]
    NestedHole {
        /// The inner hole's ring.
        ring: usize,
        /// The ring around it.
        outer: usize,
    },
    /// `max_area` is not positive and finite.
    #[error("max_area must be positive and finite, got {value}")]
    InvalidMaxArea {
        /// The value given.
        value: Real,
    },
    /// Refinement would need more vertices than allowed.
    #[error("refining to max_area {max_area} needs more than {limit} vertices; raise max_area")]
    TooFine {
        /// The value given.
        max_area: Real,
        /// The vertex budget.
        limit: usize,
    },
    /// spade refused an input point (e.g. coordinates too large for exact predicates).
    #[error("triangulation failed: {0}")]
    Triangulation(String),
    /// The triangulation does not make a valid mesh.
    #[error(transparent)]
    Mesh(#[from] BuildError),
}

/// Largest number of vertices the refinement may create.
const MAX_VERTICES: usize = 1 << 24;

impl Mesh {
    /// A triangle mesh of the simple polygon `outer` (in either orientation), refined until
    /// no triangle is larger than `max_area`. See [`Mesh::polygon_with_holes`].
    ///
    /// ```
    /// use sinew::dim2::Mesh;
    /// use sinew::dim2::math::Vector;
    ///
    /// let l_shape = [
    ///     Vector::new(0.0, 0.0), Vector::new(2.0, 0.0), Vector::new(2.0, 1.0),
    ///     Vector::new(1.0, 1.0), Vector::new(1.0, 2.0), Vector::new(0.0, 2.0),
    /// ];
    /// let mesh = Mesh::polygon(&l_shape, 0.05).unwrap();
    /// assert!((mesh.total_volume() - 3.0).abs() < 1e-4);
    /// ```
    pub fn polygon(outer: &[Vector], max_area: Real) -> Result<Mesh, PolygonError> {
        Mesh::polygon_with_holes(outer, &[], max_area)
    }

    /// A triangle mesh of the polygon with outer ring `outer` and the given holes (each ring
    /// in either orientation), refined until no triangle is larger than `max_area` and no
    /// angle is smaller than 20° (except at sharper corners of the input). Every ring edge
    /// is kept as a boundary of the mesh (possibly split into shorter edges).
    ///
    /// Errors: [`PolygonError`] for fewer than three vertices in a ring, a non-finite vertex,
    /// a zero-length edge, a ring without area, edges that cross or touch, a hole outside
    /// the outer ring or inside another hole, a bad `max_area`.
    pub fn polygon_with_holes(
        outer: &[Vector],
        holes: &[Vec<Vector>],
        max_area: Real,
    ) -> Result<Mesh, PolygonError> {
        if !(max_area.is_finite() && max_area > 0.0) {
            return Err(PolygonError::InvalidMaxArea { value: max_area });
        }
        let rings: Vec<Vec<[f64; 2]>> = std::iter::once(outer)
            .chain(holes.iter().map(Vec::as_slice))
            .map(|r| r.iter().map(|p| [p.x as f64, p.y as f64]).collect())
            .collect();
        validate(&rings)?;

        let area =
            ring_area(&rings[0]).abs() - rings[1..].iter().map(|r| ring_area(r).abs()).sum::<f64>();
        let input: usize = rings.iter().map(Vec::len).sum();
        let estimate = (4.0 * area / max_area as f64).ceil();
        if estimate.is_nan() || estimate >= MAX_VERTICES as f64 {
            return Err(PolygonError::TooFine {
                max_area,
                limit: MAX_VERTICES,
            });
        }
        let limit = (estimate as usize)
            .max(10 * input)
            .saturating_add(64)
            .min(MAX_VERTICES);

        let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
        for ring in &rings {
            let mut handles = Vec::with_capacity(ring.len());
            for p in ring {
                let h = cdt
                    .insert(Point2::new(p[0], p[1]))
                    .map_err(|e| PolygonError::Triangulation(e.to_string()))?;
                handles.push(h);
            }
            for k in 0..handles.len() {
                cdt.add_constraint(handles[k], handles[(k + 1) % handles.len()]);
            }
        }
        let result = cdt.refine(
            RefinementParameters::new()
                .exclude_outer_faces(true)
                .with_max_allowed_area(max_area as f64)
                .with_angle_limit(AngleLimit::from_deg(20.0))
                .with_max_additional_vertices(limit),
        );
        if !result.refinement_complete {
            return Err(PolygonError::TooFine { max_area, limit });
        }
        let excluded: std::collections::HashSet<FixedFaceHandle<InnerTag>> =
            result.excluded_faces.into_iter().collect();

        let mut index = vec![u32::MAX; cdt.num_vertices()];
        let mut nodes = Vec::new();
        let mut cells = Vec::new();
        for face in cdt.inner_faces() {
            if excluded.contains(&face.fix()) {
                continue;
            }
            for v in face.vertices() {
                let slot = &mut index[v.fix().index()];
                if *slot == u32::MAX {
                    *slot = nodes.len() as u32;
                    let p = v.position();
                    nodes.push(Vector::new(p.x as Real, p.y as Real));
                }
                cells.push(*slot);
            }
        }
        Ok(Mesh::new(nodes, cells, CellKind::Simplex)?)
    }
}

/// Twice the signed area (positive counter-clockwise).
fn ring_area(r: &[[f64; 2]]) -> f64 {
    let n = r.len();
    (0..n)
        .map(|k| {
            let (a, b) = (r[k], r[(k + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        * 0.5
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether `p`, known to be on the line through `a b`, lies within the segment's box.
fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether the closed segments `a b` and `c d` share a point.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    (o1 == 0.0 && on_segment(a, b, c))
        || (o2 == 0.0 && on_segment(a, b, d))
        || (o3 == 0.0 && on_segment(c, d, a))
        || (o4 == 0.0 && on_segment(c, d, b))
}

/// Even-odd point-in-ring test (for a point not on the ring).
fn inside(r: &[[f64; 2]], p: [f64; 2]) -> bool {
    let n = r.len();
    let mut odd = false;
    for k in 0..n {
        let (a, b) = (r[k], r[(k + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

fn validate(rings: &[Vec<[f64; 2]>]) -> Result<(), PolygonError> {
    for (ring, r) in rings.iter().enumerate() {
        if r.len() < 3 {
            return Err(PolygonError::TooFewVertices {
                ring,
                count: r.len(),
            });
        }
        for (vertex, p) in r.iter().enumerate() {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(PolygonError::NonFinite {
                    ring,
                    vertex,
                    point: [p[0] as Real, p[1] as Real],
                });
            }
        }
        for k in 0..r.len() {
            if r[k] == r[(k + 1) % r.len()] {
                return Err(PolygonError::RepeatedVertex { ring, vertex: k });
            }
        }
        if ring_area(r) == 0.0 {
            return Err(PolygonError::ZeroArea { ring });
        }
    }
    // Every pair of edges: adjacent edges of a ring may share only their common vertex.
    let edges: Vec<(usize, usize, [f64; 2], [f64; 2])> = rings
        .iter()
        .enumerate()
        .flat_map(|(ring, r)| (0..r.len()).map(move |k| (ring, k, r[k], r[(k + 1) % r.len()])))
        .collect();
    for (i, &(ra, ea, a, b)) in edges.iter().enumerate() {
        for &(rb, eb, c, d) in &edges[i + 1..] {
            let n = rings[ra].len();
            let adjacent = ra == rb && (eb == (ea + 1) % n || ea == (eb + 1) % n);
            let meet = if adjacent {
                // Edges p–s and s–q share s; they meet elsewhere only if the ring folds
                // back along itself (q and p on the same side of s).
                let (p, s, q) = if eb == (ea + 1) % n {
                    (a, b, d)
                } else {
                    (b, a, c)
                };
                orient(p, s, q) == 0.0
                    && (q[0] - s[0]) * (p[0] - s[0]) + (q[1] - s[1]) * (p[1] - s[1]) > 0.0
            } else {
                segments_meet(a, b, c, d)
            };
            if meet {
                return Err(PolygonError::SelfIntersecting {
                    ring_a: ra,
                    edge_a: ea,
                    ring_b: rb,
                    edge_b: eb,
                });
            }
        }
    }
    for ring in 1..rings.len() {
        let p = rings[ring][0];
        if !inside(&rings[0], p) {
            return Err(PolygonError::HoleOutside { ring });
        }
        for (outer, r) in rings.iter().enumerate().skip(1) {
            if outer != ring && inside(r, p) {
                return Err(PolygonError::NestedHole { ring, outer });
            }
        }
    }
    Ok(())
}
