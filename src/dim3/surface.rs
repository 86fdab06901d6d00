//! Closed triangle surfaces: what a user's asset (an STL, OBJ or glTF file, a parry
//! `TriMesh`) is before it becomes a volume [`Mesh`].
//!
//! [`Surface::new`] checks what a volume mesher needs of a surface, and names the element at
//! fault when it is not so:
//! * every coordinate finite, every index in range, no triangle with a repeated vertex or no
//!   area;
//! * **closed and manifold**: every edge shared by exactly two triangles (one is an open
//!   edge, three or more a non-manifold edge), and the triangles around every vertex one fan
//!   (two cones touching at their tips share a vertex but not a fan);
//! * **consistently oriented**: the two triangles at an edge run along it in opposite
//!   directions (a triangle with flipped winding runs along its neighbours' edges in theirs).
//!
//! A surface whose triangles all turn inwards (a negative enclosed volume) is turned outwards
//! whole, as the volume readers reorder inverted cells: exporters disagree on the winding
//! convention and users cannot choose it. Vertices that no triangle uses are dropped and the
//! others renumbered in order. Not checked: that the surface does not cut through itself, and
//! the orientation of one closed shell against another (a hollow body's inner shell must face
//! inwards, which a flipped separate shell also does).
//!
//! Files store each triangle's corners separately (STL) or repeat a vertex across seams
//! (normals, texture coordinates): [`Surface::welded`] first merges vertices closer than a
//! tolerance. The readers ([`stl`], [`obj`], [`gltf`], behind the features of the same names;
//! `stl` and `obj` on by default) weld at 10⁻⁶ of the surface's bounding-box diagonal.

#[cfg(any(feature = "stl", feature = "obj", feature = "gltf"))]
mod files;
#[cfg(feature = "gltf")]
pub use files::gltf;
#[cfg(feature = "obj")]
pub use files::obj;
#[cfg(feature = "stl")]
pub use files::stl;
#[cfg(any(feature = "stl", feature = "obj", feature = "gltf"))]
pub use files::SurfaceReadError;

use std::collections::HashMap;

use rapier3d::parry::shape::{TriMesh, TriMeshFlags};

use super::math::{Real, Vector};

/// Why a triangle surface is not a closed, manifold, consistently oriented one. Triangles and
/// vertices are numbered from 0 in the order given (before welding drops or merges any: the
/// index of a welded vertex is its first occurrence).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// Fewer triangles than a closed surface needs (a tetrahedron's four).
    #[error("{count} triangles; a closed surface needs at least 4")]
    TooFewTriangles {
        /// The triangle count.
        count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} is not finite: {point:?}")]
    NonFinite {
        /// The vertex.
        vertex: usize,
        /// Its coordinates.
        point: [Real; 3],
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} names vertex {index}, but there are {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The index it gives.
        index: u32,
        /// How many vertices there are.
        vertices: usize,
    },
    /// A triangle repeats a vertex or has no area.
    #[error("triangle {triangle} ({vertices:?}) is degenerate: repeated vertex or no area")]
    DegenerateTriangle {
        /// The triangle.
        triangle: usize,
        /// Its vertices.
        vertices: [u32; 3],
    },
    /// An edge belongs to one triangle only: the surface has a hole there.
    #[error("edge {a}–{b} of triangle {triangle} is open: no other triangle shares it")]
    OpenEdge {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
        /// The triangle that has it.
        triangle: usize,
    },
    /// An edge is shared by more than two triangles.
    #[error("edge {a}–{b} is shared by {count} triangles (first {triangle}); a manifold has 2")]
    NonManifoldEdge {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
        /// The first triangle that has it.
        triangle: usize,
        /// How many triangles share it.
        count: usize,
    },
    /// Two triangles run along their shared edge in the same direction: one of them has its
    /// winding flipped.
    #[error(
        "triangle {triangle} runs along edge {a}→{b} in the same direction as triangle \
         {neighbour}: one of them is wound the other way"
    )]
    InconsistentWinding {
        /// The later of the two triangles.
        triangle: usize,
        /// The earlier one.
        neighbour: usize,
        /// The edge's first vertex, in both triangles' order.
        a: u32,
        /// Its second vertex.
        b: u32,
    },
    /// The triangles around a vertex form more than one fan (surfaces touching at a point).
    #[error("vertex {vertex} joins {fans} separate fans of triangles; a manifold has one")]
    NonManifoldVertex {
        /// The vertex.
        vertex: u32,
        /// How many fans meet there.
        fans: usize,
    },
    /// The surface encloses no volume (it is flat, or its shells cancel).
    #[error("the surface encloses no volume")]
    NoVolume,
    /// The weld tolerance is negative or not finite.
    #[error("weld tolerance must be non-negative and finite, got {value}")]
    InvalidTolerance {
        /// The tolerance given.
        value: Real,
    },
}

impl SurfaceError {
    /// The error with its triangle numbers mapped through `kept` (the given triangle each
    /// checked one came from).
    fn renumbered(self, kept: &[usize]) -> SurfaceError {
        let back = |t: usize| kept.get(t).copied().unwrap_or(t);
        match self {
            SurfaceError::DegenerateTriangle { triangle, vertices } => {
                SurfaceError::DegenerateTriangle {
                    triangle: back(triangle),
                    vertices,
                }
            }
            SurfaceError::OpenEdge { a, b, triangle } => SurfaceError::OpenEdge {
                a,
                b,
                triangle: back(triangle),
            },
            SurfaceError::NonManifoldEdge {
                a,
                b,
                triangle,
                count,
            } => SurfaceError::NonManifoldEdge {
                a,
                b,
                triangle: back(triangle),
                count,
            },
            SurfaceError::InconsistentWinding {
                triangle,
                neighbour,
                a,
                b,
            } => SurfaceError::InconsistentWinding {
                triangle: back(triangle),
                neighbour: back(neighbour),
                a,
                b,
            },
            other => other,
        }
    }
}

/// A closed, manifold, consistently and outwards oriented triangle surface (see the module
/// documentation for what is checked).
///
/// ```
/// use sinew::dim3::math::Vector;
/// use sinew::dim3::surface::{Surface, SurfaceError};
///
/// let v = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z];
/// let tetrahedron = Surface::new(v.clone(), vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
///     .unwrap();
/// assert!((tetrahedron.volume() - 1.0 / 6.0).abs() < 1e-6);
/// // One face wound the other way:
/// let flipped = Surface::new(v, vec![[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 3, 2]]);
/// assert!(matches!(flipped, Err(SurfaceError::InconsistentWinding { .. })));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    vertices: Vec<Vector>,
    triangles: Vec<[u32; 3]>,
}

impl Surface {
    /// The surface of these triangles over these vertices, checked (see the module
    /// documentation); vertices are taken as they are, not welded.
    pub fn new(vertices: Vec<Vector>, triangles: Vec<[u32; 3]>) -> Result<Surface, SurfaceError> {
        check_input(&vertices, &triangles)?;
        check_edges(&triangles)?;
        check_fans(&triangles)?;
        let (vertices, mut triangles) = drop_unused(vertices, triangles);
        let volume = signed_volume(&vertices, &triangles);
        if volume.is_nan() || volume == 0.0 {
            return Err(SurfaceError::NoVolume);
        }
        if volume < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        Ok(Surface {
            vertices,
            triangles,
        })
    }

    /// [`Surface::new`] after merging the vertices closer than `tolerance` to an earlier one
    /// (0: only identical ones) into it. A triangle two of whose corners merge is dropped
    /// (a sliver thinner than the tolerance, or a zero-area triangle with a repeated corner,
    /// which CAD exports contain). Errors number triangles and vertices as given.
    pub fn welded(
        vertices: Vec<Vector>,
        triangles: Vec<[u32; 3]>,
        tolerance: Real,
    ) -> Result<Surface, SurfaceError> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(SurfaceError::InvalidTolerance { value: tolerance });
        }
        // Numbers and indices first (the weld reads them); a degenerate triangle may be a
        // sliver that the weld collapses and drops, so [`Surface::new`] judges it after.
        check_numbers(&vertices, &triangles)?;
        let map = weld_map(&vertices, tolerance);
        let (kept, welded): (Vec<usize>, Vec<[u32; 3]>) = triangles
            .iter()
            .map(|t| t.map(|i| map[i as usize]))
            .enumerate()
            .filter(|(_, t)| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
            .unzip();
        Surface::new(vertices, welded).map_err(|e| e.renumbered(&kept))
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Vector] {
        &self.vertices
    }

    /// The triangles, counter-clockwise seen from outside.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The enclosed volume (positive).
    pub fn volume(&self) -> Real {
        signed_volume(&self.vertices, &self.triangles)
    }

    /// The total area of the triangles.
    pub fn area(&self) -> Real {
        self.triangles
            .iter()
            .map(|t| 0.5 * corners(&self.vertices, t).cross_len())
            .sum()
    }

    /// The smallest box holding every vertex: `(min, max)`.
    pub fn bounds(&self) -> (Vector, Vector) {
        bounds(&self.vertices)
    }

    /// The surface scaled by `scale` about the origin, then moved by `offset` (a negative
    /// scale turns it inside out, which [`Surface::new`] turns back).
    pub fn scaled(&self, scale: Real, offset: Vector) -> Result<Surface, SurfaceError> {
        let vertices = self.vertices.iter().map(|p| *p * scale + offset).collect();
        Surface::new(vertices, self.triangles.clone())
    }

    /// The surface as a parry triangle mesh with pseudo-normals (`TriMeshFlags::ORIENTED`),
    /// so that point queries tell inside from outside: the shape to give
    /// [`Mesh::from_shape`](super::Mesh::from_shape) or a rapier collider.
    pub fn to_trimesh(&self) -> TriMesh {
        TriMesh::with_flags(
            self.vertices.clone(),
            self.triangles.clone(),
            TriMeshFlags::ORIENTED,
        )
        .expect("a checked closed surface is a valid parry triangle mesh")
    }
}

/// A triangle's three corners.
struct Corners(Vector, Vector, Vector);

impl Corners {
    /// Twice the triangle's area.
    fn cross_len(&self) -> Real {
        (self.1 - self.0).cross(self.2 - self.0).length()
    }

    /// Its longest edge, squared.
    fn longest_squared(&self) -> Real {
        let (a, b, c) = (self.0, self.1, self.2);
        (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared())
    }
}

fn corners(vertices: &[Vector], t: &[u32; 3]) -> Corners {
    Corners(
        vertices[t[0] as usize],
        vertices[t[1] as usize],
        vertices[t[2] as usize],
    )
}

fn bounds(vertices: &[Vector]) -> (Vector, Vector) {
    vertices.iter().fold(
        (
            Vector::splat(Real::INFINITY),
            Vector::splat(-Real::INFINITY),
        ),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Finite vertices, indices in range.
fn check_numbers(vertices: &[Vector], triangles: &[[u32; 3]]) -> Result<(), SurfaceError> {
    for (vertex, p) in vertices.iter().enumerate() {
        if !p.is_finite() {
            return Err(SurfaceError::NonFinite {
                vertex,
                point: p.to_array(),
            });
        }
    }
    for (triangle, t) in triangles.iter().enumerate() {
        for &index in t {
            if index as usize >= vertices.len() {
                return Err(SurfaceError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: vertices.len(),
                });
            }
        }
    }
    Ok(())
}

/// [`check_numbers`], no degenerate triangle, enough triangles.
fn check_input(vertices: &[Vector], triangles: &[[u32; 3]]) -> Result<(), SurfaceError> {
    check_numbers(vertices, triangles)?;
    for (triangle, t) in triangles.iter().enumerate() {
        let c = corners(vertices, t);
        let repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
        // No area, to the precision of the coordinates.
        if repeated || c.cross_len() <= Real::EPSILON * c.longest_squared() {
            return Err(SurfaceError::DegenerateTriangle {
                triangle,
                vertices: *t,
            });
        }
    }
    if triangles.len() < 4 {
        return Err(SurfaceError::TooFewTriangles {
            count: triangles.len(),
        });
    }
    Ok(())
}

/// Every edge in exactly two triangles, running along it in opposite directions.
fn check_edges(triangles: &[[u32; 3]]) -> Result<(), SurfaceError> {
    // (low end, high end, triangle, whether the triangle runs low → high)
    let mut edges: Vec<(u32, u32, usize, bool)> = Vec::with_capacity(3 * triangles.len());
    for (k, t) in triangles.iter().enumerate() {
        for j in 0..3 {
            let (a, b) = (t[j], t[(j + 1) % 3]);
            edges.push((a.min(b), a.max(b), k, a < b));
        }
    }
    edges.sort_unstable();
    for group in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let (lo, hi, first, forward) = group[0];
        match group.len() {
            1 => {
                return Err(SurfaceError::OpenEdge {
                    a: lo,
                    b: hi,
                    triangle: first,
                })
            }
            2 if group[1].3 == forward => {
                let (a, b) = if forward { (lo, hi) } else { (hi, lo) };
                return Err(SurfaceError::InconsistentWinding {
                    triangle: group[1].2,
                    neighbour: first,
                    a,
                    b,
                });
            }
            2 => {}
            count => {
                return Err(SurfaceError::NonManifoldEdge {
                    a: lo,
                    b: hi,
                    triangle: first,
                    count,
                })
            }
        }
    }
    Ok(())
}

/// The triangles around each vertex form one fan. With every edge shared by two consistently
/// wound triangles, the far edges of a vertex's triangles link up into closed loops, one per
/// fan: a vertex is manifold when its first loop takes in all its triangles.
fn check_fans(triangles: &[[u32; 3]]) -> Result<(), SurfaceError> {
    // (vertex, far edge's first end, its second end): the far edge as the triangle runs it.
    let mut links: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        for j in 0..3 {
            links.push((t[j], t[(j + 1) % 3], t[(j + 2) % 3]));
        }
    }
    links.sort_unstable();
    for fan in links.chunk_by(|x, y| x.0 == y.0) {
        let next = |from: u32| {
            fan.binary_search_by(|l| l.1.cmp(&from))
                .map(|k| fan[k].2)
                .ok()
        };
        let (start, mut at, mut steps) = (fan[0].1, fan[0].2, 1);
        while at != start && steps <= fan.len() {
            match next(at) {
                Some(to) => at = to,
                None => break,
            }
            steps += 1;
        }
        if steps < fan.len() {
            return Err(SurfaceError::NonManifoldVertex {
                vertex: fan[0].0,
                fans: count_loops(fan),
            });
        }
    }
    Ok(())
}

/// How many closed loops the far edges of one vertex (its `fan` of links, sorted) make.
fn count_loops(fan: &[(u32, u32, u32)]) -> usize {
    let mut seen = vec![false; fan.len()];
    let mut loops = 0;
    for k in 0..fan.len() {
        if seen[k] {
            continue;
        }
        loops += 1;
        let mut at = k;
        while !seen[at] {
            seen[at] = true;
            match fan.binary_search_by(|l| l.1.cmp(&fan[at].2)) {
                Ok(next) => at = next,
                Err(_) => break,
            }
        }
    }
    loops
}

/// The vertices that some triangle uses, renumbered in order, and the triangles over them.
fn drop_unused(vertices: Vec<Vector>, triangles: Vec<[u32; 3]>) -> (Vec<Vector>, Vec<[u32; 3]>) {
    let mut remap = vec![u32::MAX; vertices.len()];
    for t in &triangles {
        for &i in t {
            remap[i as usize] = 0;
        }
    }
    let mut kept = Vec::with_capacity(vertices.len());
    for (i, p) in vertices.into_iter().enumerate() {
        if remap[i] == 0 {
            remap[i] = kept.len() as u32;
            kept.push(p);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .collect();
    (kept, triangles)
}

/// The signed volume the triangles enclose (positive when they face outwards).
fn signed_volume(vertices: &[Vector], triangles: &[[u32; 3]]) -> Real {
    // About the bounding box's centre, which keeps the sum's rounding small far from the origin.
    let (lo, hi) = bounds(vertices);
    let o = 0.5 * (lo + hi);
    triangles
        .iter()
        .map(|t| {
            let c = corners(vertices, t);
            (c.0 - o).dot((c.1 - o).cross(c.2 - o))
        })
        .sum::<Real>()
        / 6.0
}

/// For each vertex, the first vertex at most `tolerance` from it (itself if none): a grid of
/// cells of the tolerance's size, each vertex compared with those in its and the neighbouring
/// cells.
fn weld_map(vertices: &[Vector], tolerance: Real) -> Vec<u32> {
    let key = |p: Vector| -> [i64; 3] {
        if tolerance > 0.0 {
            (p / tolerance).floor().to_array().map(|c| c as i64)
        } else {
            p.to_array().map(|c| c.to_bits() as i64)
        }
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut map = Vec::with_capacity(vertices.len());
    for (i, p) in vertices.iter().enumerate() {
        let k = key(*p);
        let mut found = None;
        let reach = if tolerance > 0.0 { 1 } else { 0 };
        'search: for dx in -reach..=reach {
            for dy in -reach..=reach {
                for dz in -reach..=reach {
                    let cell = [k[0] + dx, k[1] + dy, k[2] + dz];
                    for &j in grid.get(&cell).into_iter().flatten() {
                        if vertices[j as usize].distance(*p) <= tolerance {
                            found = Some(j);
                            break 'search;
                        }
                    }
                }
            }
        }
        match found {
            Some(j) => map.push(j),
            None => {
                grid.entry(k).or_default().push(i as u32);
                map.push(i as u32);
            }
        }
    }
    map
}

/// The readers' weld tolerance for these vertices: 10⁻⁶ of their bounding-box diagonal.
#[cfg(any(feature = "stl", feature = "obj", feature = "gltf"))]
fn file_tolerance(vertices: &[Vector]) -> Real {
    let (lo, hi) = bounds(vertices);
    let diagonal = (hi - lo).length();
    if diagonal.is_finite() {
        1e-6 * diagonal
    } else {
        0.0
    }
}
