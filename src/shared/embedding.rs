//! Render meshes that follow a body: [`Embedding`].
//!
//! A render mesh (any triangle mesh in 3D, any polyline in 2D, typically finer and smoother
//! than the simulation surface) is bound once to the body's rest cells: each vertex to the
//! cell that contains it, by barycentric weights, or, for a vertex outside every cell (a
//! smooth surface bulges past its stuffed or voxelised cells), to the cell it is least outside
//! of (the largest smallest weight), whose weights then extrapolate. After each step a vertex
//! is that weighted sum of its cell's current nodes, so the render mesh moves, stretches and
//! turns with the cells around it; its normals are the area-weighted facet normals.

use std::collections::HashMap;

use super::error::BuildError;
use super::math::{facet_normal, simplex_gradients, Real, Vector, DIM, FACET_ARITY, SIMPLEX_ARITY};
use super::mesh::{CellKind, Mesh};

/// A render mesh bound to a body's simplex cells (see the module documentation). Built by
/// [`Deformable::set_render_mesh`](super::Deformable::set_render_mesh) (the pipeline updates
/// it after every step) or by [`Embedding::bind`] for a mesh of one's own, updated by
/// [`Embedding::update`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, PartialEq)]
pub struct Embedding {
    /// Per vertex, its cell.
    cells: Vec<u32>,
    /// Per vertex, its cell's nodes.
    nodes: Vec<[u32; SIMPLEX_ARITY]>,
    /// Per vertex, the weights of its cell's nodes.
    weights: Vec<[Real; SIMPLEX_ARITY]>,
    facets: Vec<[u32; FACET_ARITY]>,
    vertices: Vec<Vector>,
    normals: Vec<Vector>,
}

impl Embedding {
    /// Binds `vertices` (with `facets` over them: triangles in 3D, segments in 2D) to the
    /// cells of `mesh` at its rest nodes, and places them there.
    ///
    /// Errors ([`BuildError::InvalidParameter`]): a mesh of cube cells, a vertex that is not
    /// finite, a facet index out of range.
    pub fn bind(
        mesh: &Mesh,
        vertices: &[Vector],
        facets: Vec<[u32; FACET_ARITY]>,
    ) -> Result<Embedding, BuildError> {
        if mesh.kind() != CellKind::Simplex {
            return Err(BuildError::InvalidParameter {
                name: "mesh",
                value: 0.0,
                expected: "simplex cells (a render mesh binds to simplices)",
            });
        }
        if let Some(p) = vertices.iter().find(|p| !p.is_finite()) {
            return Err(BuildError::InvalidParameter {
                name: "render vertex",
                value: p
                    .to_array()
                    .into_iter()
                    .find(|c| !c.is_finite())
                    .unwrap_or(0.0),
                expected: "finite coordinates",
            });
        }
        if let Some(&i) = facets
            .iter()
            .flatten()
            .find(|&&i| i as usize >= vertices.len())
        {
            return Err(BuildError::InvalidParameter {
                name: "render facet index",
                value: i as Real,
                expected: "an index below the render vertex count",
            });
        }
        let grid = CellGrid::new(mesh);
        let (cells, weights): (Vec<u32>, _) =
            vertices.iter().map(|p| grid.locate(mesh, *p)).unzip();
        let ids = mesh.cell_indices();
        let nodes = cells
            .iter()
            .map(|&c| std::array::from_fn(|k| ids[c as usize * SIMPLEX_ARITY + k]))
            .collect();
        let mut embedding = Embedding {
            cells,
            nodes,
            weights,
            facets,
            vertices: vertices.to_vec(),
            normals: vec![Vector::ZERO; vertices.len()],
        };
        embedding.update(mesh.nodes());
        Ok(embedding)
    }

    /// Moves the vertices with the body's nodes at `positions` (its [`positions`]
    /// (super::Deformable::positions)) and recomputes the normals.
    ///
    /// Panics if `positions` is not one per node of the mesh it was bound to.
    pub fn update(&mut self, positions: &[Vector]) {
        for ((v, ids), w) in self.vertices.iter_mut().zip(&self.nodes).zip(&self.weights) {
            *v = ids
                .iter()
                .zip(w)
                .map(|(&i, &w)| positions[i as usize] * w)
                .sum();
        }
        self.normals.fill(Vector::ZERO);
        for f in &self.facets {
            let p: [Vector; FACET_ARITY] = f.map(|i| self.vertices[i as usize]);
            let n = facet_normal(&p);
            for &i in f {
                self.normals[i as usize] += n;
            }
        }
        for n in &mut self.normals {
            *n = n.normalize_or_zero();
        }
    }

    /// Takes each vertex's cell's nodes from `mesh` again, after a tear gave some cells
    /// copies of their nodes (cells keep their indices).
    pub(crate) fn rebind(&mut self, mesh: &Mesh) {
        let ids = mesh.cell_indices();
        for (nodes, &c) in self.nodes.iter_mut().zip(&self.cells) {
            *nodes = std::array::from_fn(|k| ids[c as usize * SIMPLEX_ARITY + k]);
        }
    }

    /// Whether the embedding is whole and binds to nodes below `nodes` (a snapshot's check).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, nodes: usize) -> Result<(), String> {
        let n = self.vertices.len();
        let counts = [
            self.cells.len(),
            self.nodes.len(),
            self.weights.len(),
            self.normals.len(),
        ];
        if counts.iter().any(|&c| c != n) {
            return Err("render mesh arrays are not one entry per vertex".into());
        }
        if self.nodes.iter().flatten().any(|&i| i as usize >= nodes) {
            return Err(format!(
                "a render vertex binds to a node past the {nodes} nodes"
            ));
        }
        if self.facets.iter().flatten().any(|&i| i as usize >= n) {
            return Err("a render facet names a vertex past the render vertices".into());
        }
        if !self.weights.iter().flatten().all(|w| w.is_finite()) {
            return Err("a render vertex has a weight that is not finite".into());
        }
        Ok(())
    }

    /// The vertices where the body's cells carry them.
    pub fn vertices(&self) -> &[Vector] {
        &self.vertices
    }

    /// Unit vertex normals (area-weighted facet normals; zero where no facet has area).
    pub fn normals(&self) -> &[Vector] {
        &self.normals
    }

    /// The facets, as given.
    pub fn facets(&self) -> &[[u32; FACET_ARITY]] {
        &self.facets
    }

    /// Per vertex, the cell it is bound to and its weights on that cell's nodes.
    pub fn binding(&self) -> impl Iterator<Item = (u32, [Real; SIMPLEX_ARITY])> + '_ {
        self.cells.iter().copied().zip(self.weights.iter().copied())
    }
}

/// The barycentric weights of `x` in the simplex `p` (they sum to one; negative outside).
fn barycentric(p: &[Vector; SIMPLEX_ARITY], x: Vector) -> [Real; SIMPLEX_ARITY] {
    let (d, g) = simplex_gradients(p);
    let mut w = [0.0; SIMPLEX_ARITY];
    for a in 0..SIMPLEX_ARITY {
        // The weight of node a is 1 at it, 0 on the opposite facet, linear in between.
        w[a] = 1.0 + g[a].dot(x - p[a]) / d;
    }
    w
}

/// A uniform grid of the mesh's cells by their bounding boxes.
struct CellGrid {
    origin: Vector,
    size: Real,
    bins: HashMap<[i64; DIM], Vec<u32>>,
    /// The largest key along each axis (the smallest is 0).
    top: [i64; DIM],
}

impl CellGrid {
    fn new(mesh: &Mesh) -> Self {
        let x = mesh.nodes();
        let mut origin = Vector::splat(Real::INFINITY);
        let mut total = 0.0;
        let mut boxes = Vec::new();
        for c in mesh.cells() {
            let (mut lo, mut hi) = (x[c[0] as usize], x[c[0] as usize]);
            for &i in c {
                lo = lo.min(x[i as usize]);
                hi = hi.max(x[i as usize]);
            }
            total += (hi - lo).max_element();
            origin = origin.min(lo);
            boxes.push((lo, hi));
        }
        let size = (total / boxes.len().max(1) as Real).max(Real::MIN_POSITIVE);
        let mut grid = CellGrid {
            origin,
            size,
            bins: HashMap::new(),
            top: [0; DIM],
        };
        for (k, (lo, hi)) in boxes.into_iter().enumerate() {
            let (a, b) = (grid.key(lo), grid.key(hi));
            for (t, b) in grid.top.iter_mut().zip(b) {
                *t = (*t).max(b);
            }
            for_each_key(a, b, |key| grid.bins.entry(key).or_default().push(k as u32));
        }
        grid
    }

    fn key(&self, p: Vector) -> [i64; DIM] {
        let mut k = [0i64; DIM];
        for (d, kd) in k.iter_mut().enumerate() {
            *kd = ((p[d] - self.origin[d]) / self.size).floor() as i64;
        }
        k
    }

    /// The cell that holds `p` (or that `p` is least outside of) and its weights there: the
    /// cells of `p`'s bin, then of ever wider rings of bins until some are found and one
    /// more ring has been searched.
    fn locate(&self, mesh: &Mesh, p: Vector) -> (u32, [Real; SIMPLEX_ARITY]) {
        let x = mesh.nodes();
        let cells = mesh.cell_indices();
        let centre = self.key(p);
        // Past this ring every bin has been searched.
        let last = (0..DIM)
            .map(|d| centre[d].abs().max((self.top[d] - centre[d]).abs()))
            .max()
            .unwrap_or(0);
        let mut best: Option<(Real, u32, [Real; SIMPLEX_ARITY])> = None;
        let mut found_at = None;
        for ring in 0..=last {
            if found_at.is_some_and(|at| ring > at + 1) {
                break;
            }
            let a = centre.map(|c| (c - ring).max(0));
            let mut b = centre.map(|c| c + ring);
            for (b, t) in b.iter_mut().zip(self.top) {
                *b = (*b).min(t);
            }
            if (0..DIM).any(|d| a[d] > b[d]) {
                continue;
            }
            for_each_key(a, b, |key| {
                let distance = (0..DIM).map(|d| (key[d] - centre[d]).abs()).max();
                if distance != Some(ring) {
                    return;
                }
                for &c in self.bins.get(&key).into_iter().flatten() {
                    let ids = &cells[c as usize * SIMPLEX_ARITY..][..SIMPLEX_ARITY];
                    let q: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|k| x[ids[k] as usize]);
                    let w = barycentric(&q, p);
                    let worst = w.iter().copied().fold(Real::INFINITY, Real::min);
                    if best.is_none_or(|b| worst > b.0 || (worst == b.0 && c < b.1)) {
                        best = Some((worst, c, w));
                    }
                }
            });
            if best.is_some_and(|b| b.0 >= 0.0) {
                break;
            }
            if best.is_some() && found_at.is_none() {
                found_at = Some(ring);
            }
        }
        let (_, c, w) = best.expect("a mesh has at least one cell");
        (c, w)
    }
}

/// Calls `f` for every key of the box from key `a` to key `b`.
fn for_each_key(a: [i64; DIM], b: [i64; DIM], mut f: impl FnMut([i64; DIM])) {
    let mut key = a;
    loop {
        f(key);
        let mut d = 0;
        while d < DIM {
            key[d] += 1;
            if key[d] <= b[d] {
                break;
            }
            key[d] = a[d];
            d += 1;
        }
        if d == DIM {
            return;
        }
    }
}
