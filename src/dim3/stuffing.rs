//! Conforming tetrahedra from a shape by isosurface stuffing (Labelle and Shewchuk,
//! "Isosurface Stuffing: Fast Tetrahedral Meshes with Good Dihedral Angles", SIGGRAPH 2007):
//! [`Mesh::stuffed`].
//!
//! 1. **Lattice.** A body-centred cubic lattice over the shape's bounding box, one cell wider
//!    on every side: the corners of cubes of side `h` (black vertices) and their centres
//!    (red). Long edges (length `h`) join neighbouring vertices of one colour along an axis,
//!    short edges (`√3/2 h`) a centre to its cube's corners. Each long black edge and the four
//!    cubes around it give four BCC tetrahedra (the edge and a long red edge between two of
//!    those cubes' centres): all congruent, dihedral angles 60° and 90°.
//! 2. **Signs.** Each lattice vertex is inside (−) or outside (+) the shape (parry's point
//!    query). An edge whose ends differ has a **cut point** where it crosses the surface
//!    (parry's ray cast from the inside end).
//! 3. **Warping.** A cut point closer to an end of its edge than `α` of the edge's length
//!    (α_long = 0.24999 on long edges, α_short = 0.40173 on short ones, the paper's "safe"
//!    values) violates that end; a violated vertex, in vertex order, moves onto the nearest
//!    cut point still violating it and is then on the surface (0); the cut points of the
//!    edges it ends are dropped.
//! 4. **Stencils.** Each BCC tetrahedron becomes what lies inside: nothing if no vertex is
//!    inside (a tetrahedron with all four on the surface too), itself if none is outside,
//!    else the tetrahedra of the paper's stencil for its signs. Where the surface cuts a
//!    lattice triangle into a quadrilateral whose black edge is whole, the diagonal is the
//!    paper's parity rule, which depends on the face alone (so both tetrahedra that share
//!    it agree) and gives the stencil of best quality. With these α the dihedral angles lie
//!    between 9.06° and 160.5° (the paper's computer-assisted bound); every boundary vertex
//!    is on the surface (a cut point or a warped vertex).
//!
//! The surface is sampled at the cell size: a crease sharper than the cells is rounded over
//! about one cell, and a wall thinner than a cell may come out with holes or not at all
//! (stuff it with a finer cell).

use std::collections::HashMap;

use rapier3d::parry::query::Ray;
use rapier3d::parry::shape::Shape;

use super::math::{simplex_volume, Real, Vector};
use super::shared::mesh::voxel::{boxes_over, check_cell_size, oriented};
use super::{BuildError, CellKind, Mesh};

/// Violation thresholds on long and short edges: the paper's "safe" values (no BCC
/// tetrahedron inverted by warping), for dihedral angles between 9.06° and 160.5°.
const ALPHA_LONG: Real = 0.24999;
const ALPHA_SHORT: Real = 0.40173;

/// The BCC lattice over the shape: `n` cubes along each axis from `origin`. A vertex is named
/// by its doubled coordinates (`2 i` along an axis for a black vertex, `2 i + 1` for a red one:
/// all even or all odd).
struct Lattice {
    origin: Vector,
    h: Real,
    n: [i64; 3],
}

impl Lattice {
    fn black_count(&self) -> usize {
        ((self.n[0] + 1) * (self.n[1] + 1) * (self.n[2] + 1)) as usize
    }

    fn vertex_count(&self) -> usize {
        self.black_count() + (self.n[0] * self.n[1] * self.n[2]) as usize
    }

    /// The vertex at doubled coordinates `d`, if it is in the lattice.
    fn id(&self, d: [i64; 3]) -> Option<usize> {
        let red = d[0] & 1;
        if (d[1] & 1) != red || (d[2] & 1) != red {
            return None;
        }
        let c = d.map(|x| (x - red) / 2);
        let m = self.n.map(|x| x + 1 - red);
        if (0..3).any(|a| c[a] < 0 || c[a] >= m[a]) {
            return None;
        }
        let flat = (c[0] + m[0] * (c[1] + m[1] * c[2])) as usize;
        Some(if red == 1 {
            self.black_count() + flat
        } else {
            flat
        })
    }

    /// The doubled coordinates of vertex `id`.
    fn coords(&self, id: usize) -> [i64; 3] {
        let (red, flat) = match id.checked_sub(self.black_count()) {
            Some(flat) => (1, flat as i64),
            None => (0, id as i64),
        };
        let m = self.n.map(|x| x + 1 - red);
        let c = [flat % m[0], (flat / m[0]) % m[1], flat / (m[0] * m[1])];
        c.map(|x| 2 * x + red)
    }

    fn position(&self, d: [i64; 3]) -> Vector {
        self.origin + Vector::new(d[0] as Real, d[1] as Real, d[2] as Real) * (0.5 * self.h)
    }

    /// Every BCC tetrahedron: per black edge along each axis, the four pairs of neighbouring
    /// centres of the cubes around it.
    fn tetrahedra(&self) -> Vec<[usize; 4]> {
        let mut out = Vec::with_capacity(6 * self.black_count() * 4);
        let rings = [(1, 1), (1, -1), (-1, -1), (-1, 1)];
        for id in 0..self.black_count() {
            let b = self.coords(id);
            for a in 0..3 {
                let (u, w) = ((a + 1) % 3, (a + 2) % 3);
                let mut end = b;
                end[a] += 2;
                let Some(far) = self.id(end) else { continue };
                for k in 0..4 {
                    let centre = |(su, sw): (i64, i64)| {
                        let mut c = b;
                        c[a] += 1;
                        c[u] += su;
                        c[w] += sw;
                        self.id(c)
                    };
                    if let (Some(r1), Some(r2)) = (centre(rings[k]), centre(rings[(k + 1) % 4])) {
                        out.push([id, far, r1, r2]);
                    }
                }
            }
        }
        out
    }
}

/// Whether the edge between lattice vertices `a` and `b` is long (same colour).
fn long(lattice: &Lattice, a: usize, b: usize) -> bool {
    (a < lattice.black_count()) == (b < lattice.black_count())
}

/// A lattice vertex's sign after warping.
#[derive(Copy, Clone, PartialEq, Eq, Debug)]
enum Sign {
    Inside,
    On,
    Outside,
}

/// The stuffing under way: lattice vertices (positions, signs) and cut points by edge.
struct Stuffing<'a> {
    shape: &'a dyn Shape,
    lattice: Lattice,
    positions: Vec<Vector>,
    signs: Vec<Sign>,
    /// Cut points by edge (lower vertex id first): the point, and whether it was dropped by
    /// warping an end of its edge.
    cuts: HashMap<(usize, usize), (Vector, bool)>,
}

impl<'a> Stuffing<'a> {
    fn new(shape: &'a dyn Shape, lattice: Lattice) -> Self {
        let positions: Vec<Vector> = (0..lattice.vertex_count())
            .map(|id| lattice.position(lattice.coords(id)))
            .collect();
        let signs = positions
            .iter()
            .map(|p| {
                if shape.contains_local_point(*p) {
                    Sign::Inside
                } else {
                    Sign::Outside
                }
            })
            .collect();
        Stuffing {
            shape,
            lattice,
            positions,
            signs,
            cuts: HashMap::new(),
        }
    }

    /// The point where the edge from inside vertex `a` to outside vertex `b` leaves the shape:
    /// parry's ray cast from `a`, or, where it finds no boundary (a triangle mesh's ray cast
    /// can slip between triangles), bisection of the edge by inside tests.
    fn cut_point(&self, a: usize, b: usize) -> Vector {
        let (pa, pb) = (self.positions[a], self.positions[b]);
        let ray = Ray::new(pa, pb - pa);
        if let Some(t) = self.shape.cast_local_ray(&ray, 1.0, false) {
            return pa + (pb - pa) * t.clamp(0.0, 1.0);
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if self.shape.contains_local_point(pa + (pb - pa) * mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        pa + (pb - pa) * (0.5 * (lo + hi))
    }

    /// The cut points of every edge of `tets` whose ends are on either side.
    fn find_cuts(&mut self, tets: &[[usize; 4]]) {
        for t in tets {
            for (i, j) in EDGES {
                let (a, b) = (t[i].min(t[j]), t[i].max(t[j]));
                if self.signs[a] == self.signs[b] || self.cuts.contains_key(&(a, b)) {
                    continue;
                }
                let c = if self.signs[a] == Sign::Inside {
                    self.cut_point(a, b)
                } else {
                    self.cut_point(b, a)
                };
                self.cuts.insert((a, b), (c, false));
            }
        }
    }

    /// The violation threshold of the edge between `a` and `b`, as a distance from an end.
    fn reach(&self, (a, b): (usize, usize)) -> Real {
        let alpha = if long(&self.lattice, a, b) {
            ALPHA_LONG
        } else {
            ALPHA_SHORT
        };
        alpha * self.positions[a].distance(self.positions[b])
    }

    /// Moves every violated vertex, in vertex order, onto the nearest cut point violating it
    /// (one not yet dropped), and drops the cut points of its edges.
    fn warp(&mut self) {
        // Per vertex, the cut points of its edges: (distance to it, edge).
        let mut near: Vec<Vec<(Real, (usize, usize))>> = vec![Vec::new(); self.positions.len()];
        for (&(a, b), &(c, _)) in &self.cuts {
            for v in [a, b] {
                near[v].push((self.positions[v].distance(c), (a, b)));
            }
        }
        for (v, list) in near.iter_mut().enumerate() {
            list.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            let violating = list
                .iter()
                .find(|(d, e)| !self.cuts[e].1 && *d < self.reach(*e));
            let Some(&(_, edge)) = violating else {
                continue;
            };
            self.positions[v] = self.cuts[&edge].0;
            self.signs[v] = Sign::On;
            for (_, e) in list.iter() {
                if let Some(cut) = self.cuts.get_mut(e) {
                    cut.1 = true;
                }
            }
        }
    }
}

/// A node of the stuffed mesh: a lattice vertex (warped or not) or a cut point.
#[derive(Copy, Clone, PartialEq, Eq, Hash, Debug)]
enum Node {
    Lattice(usize),
    Cut(usize, usize),
}

impl Stuffing<'_> {
    fn cut(&self, a: usize, b: usize) -> Node {
        Node::Cut(a.min(b), a.max(b))
    }

    fn black(&self, v: usize) -> bool {
        v < self.lattice.black_count()
    }

    /// Whether `a` and `b` are joined by a black (long) edge.
    fn black_edge(&self, a: usize, b: usize) -> bool {
        long(&self.lattice, a, b)
    }

    /// The parity rule on the lattice triangle of black edge `a`–`b` and apex `u`, both red
    /// edges cut: the endpoint `x` of the diagonal `x`–`c(y, u)` (`y` the other endpoint).
    /// On a black edge of cube corners it is the endpoint with an odd number of coordinates
    /// above the apex's; on one of cube centres, the endpoint with an even number.
    fn parity(&self, a: usize, b: usize, u: usize) -> (usize, usize) {
        let above = |v: usize| {
            let (cv, cu) = (self.lattice.coords(v), self.lattice.coords(u));
            (0..3).filter(|&k| cv[k] > cu[k]).count()
        };
        let odd = above(a) % 2 == 1;
        if odd == self.black(a) {
            (a, b)
        } else {
            (b, a)
        }
    }

    /// The stencil's tetrahedra for BCC tetrahedron `t`.
    fn stencil(&self, t: [usize; 4], out: &mut Vec<[Node; 4]>) {
        let of = |s: Sign| t.iter().copied().filter(move |&v| self.signs[v] == s);
        let inside: Vec<usize> = of(Sign::Inside).collect();
        let on: Vec<usize> = of(Sign::On).collect();
        let outside: Vec<usize> = of(Sign::Outside).collect();
        let l = Node::Lattice;
        let c = |a: usize, b: usize| self.cut(a, b);
        match (inside.len(), on.len(), outside.len()) {
            (0, _, _) => {}
            (_, _, 0) => out.push(t.map(l)),
            (1, 2, 1) => {
                let (p, m) = (inside[0], outside[0]);
                out.push([l(p), l(on[0]), l(on[1]), c(p, m)]);
            }
            (1, 1, 2) => {
                let p = inside[0];
                out.push([l(p), l(on[0]), c(p, outside[0]), c(p, outside[1])]);
            }
            (1, 0, 3) => {
                let p = inside[0];
                let [m1, m2, m3] = [outside[0], outside[1], outside[2]];
                out.push([l(p), c(p, m1), c(p, m2), c(p, m3)]);
            }
            (2, 1, 1) => {
                let (z, m) = (on[0], outside[0]);
                if self.black_edge(z, m) {
                    // G1: the parity rule on face (a, b, m).
                    let (x, y) = self.parity(inside[0], inside[1], m);
                    let (a, b) = (inside[0], inside[1]);
                    out.push([l(a), l(b), l(z), c(y, m)]);
                    out.push([l(x), l(z), c(y, m), c(x, m)]);
                } else {
                    // E: p black-joined to m, q to z.
                    let (p, q) = if self.black_edge(inside[0], m) {
                        (inside[0], inside[1])
                    } else {
                        (inside[1], inside[0])
                    };
                    out.push([l(z), l(q), l(p), c(p, m)]);
                    out.push([l(z), l(q), c(p, m), c(q, m)]);
                }
            }
            (3, 0, 1) => {
                // G2: u outside, v its black partner; a, b the other black edge.
                let u = outside[0];
                let v = *inside.iter().find(|&&v| self.black_edge(u, v)).unwrap();
                let ab: Vec<usize> = inside.iter().copied().filter(|&w| w != v).collect();
                let (a, b) = (ab[0], ab[1]);
                let (x, y) = self.parity(a, b, u);
                out.push([l(x), c(y, u), c(x, u), c(v, u)]);
                out.push([l(a), l(b), l(v), c(v, u)]);
                out.push([l(a), l(b), c(y, u), c(v, u)]);
            }
            (2, 0, 2) => {
                let (a, b) = (inside[0], inside[1]);
                if self.black_edge(a, b) {
                    // G3: the front face (a, b, u) by the parity rule, the back (a, b, v) the
                    // other diagonal.
                    let (u, v) = (outside[0], outside[1]);
                    let (x, y) = self.parity(a, b, u);
                    debug_assert_eq!(self.parity(a, b, v), (y, x));
                    out.push([l(x), c(y, u), c(x, u), c(x, v)]);
                    out.push([l(a), l(b), c(y, u), c(x, v)]);
                    out.push([l(y), c(y, u), c(y, v), c(x, v)]);
                } else {
                    // F: p, q inside with black partners r, s outside.
                    let (p, q) = (a, b);
                    let (r, s) = if self.black_edge(p, outside[0]) {
                        (outside[0], outside[1])
                    } else {
                        (outside[1], outside[0])
                    };
                    out.push([l(p), l(q), c(p, r), c(q, s)]);
                    out.push([l(q), c(p, r), c(q, s), c(q, r)]);
                    out.push([l(p), c(p, r), c(q, s), c(p, s)]);
                }
            }
            _ => unreachable!("four vertices, at least one inside and one outside"),
        }
    }

    /// The mesh of every BCC tetrahedron's stencil, nodes numbered as first used.
    fn fill(&self, tets: &[[usize; 4]]) -> Result<Mesh, BuildError> {
        let mut stencils = Vec::new();
        for t in tets {
            self.stencil(*t, &mut stencils);
        }
        if stencils.is_empty() {
            return Err(BuildError::InvalidParameter {
                name: "cell_size",
                value: self.lattice.h,
                expected: "a cell size small enough that some lattice vertex is inside the shape",
            });
        }
        let mut index: HashMap<Node, u32> = HashMap::new();
        let mut nodes = Vec::new();
        let mut cells = Vec::with_capacity(4 * stencils.len());
        for s in &stencils {
            let mut ids = s.map(|node| {
                *index.entry(node).or_insert_with(|| {
                    nodes.push(match node {
                        Node::Lattice(v) => self.positions[v],
                        Node::Cut(a, b) => self.cuts[&(a, b)].0,
                    });
                    nodes.len() as u32 - 1
                })
            });
            let p = ids.map(|i| nodes[i as usize]);
            if simplex_volume(&p) < 0.0 {
                ids.swap(0, 1);
            }
            cells.extend_from_slice(&ids);
        }
        Mesh::new(nodes, cells, CellKind::Simplex)
    }
}

/// A tetrahedron's six edges, as pairs of its vertex slots.
const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

impl Mesh {
    /// Conforming tetrahedra filling `shape` (in its local frame) by isosurface stuffing
    /// (see [the module](self)): cells about `cell_size` across inside, the boundary vertices
    /// on the shape's surface, dihedral angles between 10.7° and 164.8°.
    ///
    /// Any bounded shape that answers point queries and ray casts works: balls, capsules,
    /// convex polyhedra, compounds, and closed triangle meshes (a
    /// [`Surface`](super::Surface)'s [`to_trimesh`](super::Surface::to_trimesh)), which get
    /// `TriMeshFlags::ORIENTED` if they lack it.
    ///
    /// Errors: [`BuildError::InvalidParameter`] for a cell size that is not positive and
    /// finite, an unbounded shape, a lattice of more than 2^27 cubes, or a shape that no
    /// lattice vertex falls into.
    ///
    /// ```
    /// use sinew::dim3::rapier::parry::shape::Ball;
    /// use sinew::dim3::Mesh;
    ///
    /// let mesh = Mesh::stuffed(&Ball::new(0.5), 0.1).unwrap();
    /// let exact = 4.0 / 3.0 * std::f32::consts::PI * 0.125;
    /// assert!((mesh.total_volume() - exact).abs() < 0.02 * exact);
    /// ```
    pub fn stuffed(shape: &dyn Shape, cell_size: Real) -> Result<Mesh, BuildError> {
        check_cell_size(cell_size)?;
        let owned = oriented(shape)?;
        let shape: &dyn Shape = owned.as_ref().map_or(shape, |t| t as &dyn Shape);
        let (centre, counts) = boxes_over(shape, cell_size, 1)?;
        let n = counts.map(|c| c as i64);
        let half = Vector::new(n[0] as Real, n[1] as Real, n[2] as Real) * (0.5 * cell_size);
        let lattice = Lattice {
            origin: centre - half,
            h: cell_size,
            n,
        };
        let tets = lattice.tetrahedra();
        let mut stuffing = Stuffing::new(shape, lattice);
        stuffing.find_cuts(&tets);
        stuffing.warp();
        stuffing.fill(&tets)
    }
}
