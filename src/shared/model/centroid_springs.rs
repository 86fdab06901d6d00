//! Springs along the edges plus springs from each vertex to its cell's centroid (Cooper &
//! Maddock 1999, §4.1, after Miyazaki et al.).
//!
//! The edge springs are those of [`super::springs`]. For vertex `i` of a cell with `n`
//! vertices and centroid `x_c = Σ x_j / n`, with `d = x_i − x_c`, `L = |d|`, `u = d/L` and
//! rest distance `L0`, the centroid spring pulls
//!
//! ```text
//! F = k_c (L0 − L) − c_c (v_i − v_c)·u,     f_i += F u,     f_j −= F u / n  for every vertex j
//! ```
//!
//! The reaction acts on the centroid, i.e. on every vertex with weight `1/n`; since it is
//! parallel to `x_i − x_c`, its moment about the centroid vanishes, so momentum and angular
//! momentum are conserved. The paper found these extra springs change little: linear springs
//! still compress fully.
//!
//! Material mapping: edges as [`super::springs`]; each centroid spring stands for `V_cell / n`,
//! `k_c = s E (V_cell/n) / L0²`, `c_c = 2 ζ √(k_c m_cell/n)`, with one `s` =
//! [`MATERIAL_SCALE`] for both kinds (`29/10` in 3D, `109/68 ≈ 1.60` in 2D). Derivation as in
//! [`super::springs`]: under a uniform strain `ε` a centroid spring of direction `u` stores
//! `½ s E (V_cell/n) (u·εu)²`, a second set of springs whose weights also sum to the volume, so
//! the lattice is stiffer than the edges alone: along an axis of `Mesh::cuboid`'s mirrored Kuhn
//! lattice its Young's modulus is `10/29 · s E` in 3D and `68/109 · s E` in 2D
//! (`docs/cauchy-born.py` computes both). With the springs' constant (31/7, 5/2) the
//! `cantilever` beam sagged only 0.66 (3D) and 0.63 (2D) of Euler–Bernoulli at res 9.

use super::super::material::Resolved;
use super::super::math::SIMPLEX_ARITY;
use super::super::math::{Real, Vector};
use super::super::mesh::{CellKind, Mesh};
use super::springs::{Law, Springs};
use super::{Accumulator, NodeBounds};

/// Calibration constant `s` of the mapping, for the edges and the centroid springs alike:
/// 29/10 in 3D, 109/68 in 2D (see the module's docs).
pub const MATERIAL_SCALE: Real = if super::super::math::DIM == 3 {
    29.0 / 10.0
} else {
    109.0 / 68.0
};

/// Vertices of a cube cell.
const CUBE_ARITY: usize = CellKind::Cube.arity();

/// Edge springs plus centroid springs.
#[derive(Clone, Debug)]
pub(crate) struct CentroidSprings {
    pub edges: Springs,
    kind: CellKind,
    arity: usize,
    cells: Vec<u32>,
    /// Per cell vertex: rest distance to the centroid, stiffness, damping.
    rest: Vec<Real>,
    k: Vec<Real>,
    c: Vec<Real>,
}

/// The force on vertex `i` (at `xi`, velocity `vi`) of a damped spring to the point `xc`
/// moving with `vc`; the reaction `−f` acts on that point.
#[inline]
pub fn centroid_force(
    xi: Vector,
    xc: Vector,
    vi: Vector,
    vc: Vector,
    rest: Real,
    k: Real,
    c: Real,
) -> Vector {
    super::springs::linear_force(xi, xc, vi, vc, rest, k, c)
}

impl CentroidSprings {
    pub fn build(mesh: &Mesh, masses: &[Real], params: &Resolved) -> Self {
        let edges = Springs::build(mesh, masses, params, MATERIAL_SCALE, Law::Linear);
        let arity = mesh.kind().arity();
        let nodes = mesh.nodes();
        let mut out = CentroidSprings {
            edges,
            kind: mesh.kind(),
            arity,
            cells: mesh.cell_indices().to_vec(),
            rest: Vec::new(),
            k: Vec::new(),
            c: Vec::new(),
        };
        for (cell, ids) in mesh.cells().enumerate() {
            let v = mesh.rest_volumes()[cell];
            let centroid = ids.iter().map(|&i| nodes[i as usize]).sum::<Vector>() / arity as Real;
            let mass = params.material.density * v / arity as Real;
            for &i in ids {
                let l0 = nodes[i as usize].distance(centroid);
                let material_k =
                    MATERIAL_SCALE * params.material.young_modulus * (v / arity as Real)
                        / (l0 * l0);
                let (k, c) = params.k_c(material_k, mass);
                out.rest.push(l0);
                out.k.push(k);
                out.c.push(c);
            }
        }
        out
    }

    /// Adds the state-independent bounds of edges and centroid springs. A centroid spring is
    /// a rank-one term with weights `1 − 1/n` at its vertex and `−1/n` at the others: its rows
    /// sum to `2k(1 − 1/n)` at the vertex and `2k/n` elsewhere.
    pub fn constant_bounds(&self, bounds: &mut NodeBounds) {
        self.edges.constant_bounds(bounds);
        let n = self.arity;
        let inv_n = 1.0 / n as Real;
        let w = 2.0 * (1.0 - inv_n);
        for (cell, ids) in self.cells.chunks_exact(n).enumerate() {
            let mut k_sum = 0.0;
            let mut c_sum = 0.0;
            for (a, &i) in ids.iter().enumerate() {
                let s = cell * n + a;
                k_sum += self.k[s];
                c_sum += self.c[s];
                bounds.stiffness[i as usize] += self.k[s] * w;
                bounds.damping[i as usize] += self.c[s] * w;
            }
            for &i in ids {
                bounds.stiffness[i as usize] += k_sum * 2.0 * inv_n;
                bounds.damping[i as usize] += c_sum * 2.0 * inv_n;
            }
        }
    }

    /// Adds the forces of edges and centroid springs into `acc`.
    pub fn accumulate(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        self.edges.accumulate(x, v, acc);
        match self.kind {
            CellKind::Simplex => self.accumulate_cells::<SIMPLEX_ARITY>(x, v, acc),
            CellKind::Cube => self.accumulate_cells::<CUBE_ARITY>(x, v, acc),
        }
    }

    fn accumulate_cells<const N: usize>(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        let n = x.len();
        let (v, force) = (&v[..n], &mut acc.force[..n]);
        for (((ids, rest), k), c) in self.cell_data::<N>(0) {
            let f = cell_forces(ids, rest, k, c, x, v);
            for a in 0..N {
                force[ids[a] as usize] += f[a];
            }
        }
    }

    /// Writes each cell's force on each of its vertices into `force` (one entry per slot), on
    /// rayon's threads.
    #[cfg(feature = "parallel")]
    pub fn evaluate_cells(&self, x: &[Vector], v: &[Vector], force: &mut [Vector]) {
        match self.kind {
            CellKind::Simplex => self.evaluate_cells_n::<SIMPLEX_ARITY>(x, v, force),
            CellKind::Cube => self.evaluate_cells_n::<CUBE_ARITY>(x, v, force),
        }
    }

    #[cfg(feature = "parallel")]
    fn evaluate_cells_n<const N: usize>(&self, x: &[Vector], v: &[Vector], force: &mut [Vector]) {
        use super::parallel::CELLS_PER_TASK as CHUNK;
        use rayon::prelude::*;
        let v = &v[..x.len()];
        let (out, _) = force.as_chunks_mut::<N>();
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(t, out)| {
            for (f, (((ids, rest), k), c)) in out.iter_mut().zip(self.cell_data::<N>(t * CHUNK)) {
                *f = cell_forces(ids, rest, k, c, x, v);
            }
        });
    }

    /// From cell `first` on, per cell: its vertex indices and its per-vertex rest distance,
    /// stiffness and damping.
    #[allow(clippy::type_complexity)]
    fn cell_data<const N: usize>(
        &self,
        first: usize,
    ) -> impl Iterator<Item = (((&[u32; N], &[Real; N]), &[Real; N]), &[Real; N])> {
        let (cells, _) = self.cells.as_chunks::<N>();
        let (rest, _) = self.rest.as_chunks::<N>();
        let (k, _) = self.k.as_chunks::<N>();
        let (c, _) = self.c.as_chunks::<N>();
        cells[first..]
            .iter()
            .zip(&rest[first..])
            .zip(&k[first..])
            .zip(&c[first..])
    }

    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        let n = self.arity;
        let mut e = self.edges.elastic_energy(x);
        for (cell, ids) in self.cells.chunks_exact(n).enumerate() {
            let xc = ids.iter().map(|&i| x[i as usize]).sum::<Vector>() / n as Real;
            for (a, &i) in ids.iter().enumerate() {
                let s = cell * n + a;
                e += 0.5 * self.k[s] * (x[i as usize].distance(xc) - self.rest[s]).powi(2);
            }
        }
        e
    }
}

/// The centroid springs of one cell: the force on each vertex, its own spring's pull plus its
/// `1/n` share of every spring's reaction on the centroid.
#[inline(always)]
fn cell_forces<const N: usize>(
    ids: &[u32; N],
    rest: &[Real; N],
    k: &[Real; N],
    c: &[Real; N],
    x: &[Vector],
    v: &[Vector],
) -> [Vector; N] {
    let inv_n = 1.0 / N as Real;
    let xs = ids.map(|i| x[i as usize]);
    let vs = ids.map(|i| v[i as usize]);
    let mut xc = Vector::ZERO;
    let mut vc = Vector::ZERO;
    for a in 0..N {
        xc += xs[a];
        vc += vs[a];
    }
    xc *= inv_n;
    vc *= inv_n;
    let mut reaction = Vector::ZERO;
    let mut own = [Vector::ZERO; N];
    for a in 0..N {
        own[a] = centroid_force(xs[a], xc, vs[a], vc, rest[a], k[a], c[a]);
        reaction += own[a];
    }
    own.map(|f| f - reaction * inv_n)
}

/// Centroid springs have no implicit step: their terms couple a vertex to its cell's centroid,
/// which the implicit step's term families do not cover.
impl super::ElementLaw for CentroidSprings {
    fn boxed_clone(&self) -> Box<dyn super::ElementLaw> {
        Box::new(self.clone())
    }

    /// Plastic flow reaches simplex cells (the only ones that flow): their edges' rest lengths
    /// as the springs derive them, and each vertex's rest distance to its cell's centroid
    /// from the cell's rest shape.
    fn flows(&self) -> bool {
        self.kind == CellKind::Simplex
    }

    fn set_rest(&mut self, cells: &[u32], rest: &[Vector], changed: &[u32]) {
        for &cell in changed {
            let cell = cell as usize;
            let p = &rest[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
            let centroid = p.iter().sum::<Vector>() / SIMPLEX_ARITY as Real;
            for (a, pa) in p.iter().enumerate() {
                self.rest[cell * SIMPLEX_ARITY + a] = pa.distance(centroid);
            }
        }
        self.edges.flow_rest_lengths(cells, rest, changed);
    }

    fn accumulate(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        _: Option<&super::volume::Volume>,
    ) -> Real {
        CentroidSprings::accumulate(self, x, v, acc);
        Real::INFINITY
    }

    fn energy(&self, x: &[Vector]) -> Real {
        self.elastic_energy(x)
    }

    fn constant_bounds(&self, bounds: &mut NodeBounds) {
        CentroidSprings::constant_bounds(self, bounds);
    }

    #[cfg(feature = "parallel")]
    fn edge_springs(&self) -> Option<&Springs> {
        Some(&self.edges)
    }

    #[cfg(feature = "parallel")]
    fn cost_per_cell(&self) -> usize {
        5
    }

    #[cfg(feature = "parallel")]
    fn varying(&self) -> super::Varying {
        super::Varying::Nothing
    }

    #[cfg(feature = "parallel")]
    fn evaluate(
        &mut self,
        (x, v): (&[Vector], &[Vector]),
        spring_force: &mut [Vector],
        slot_force: &mut [Vector],
        _: &mut [Real],
        _: Option<&super::volume::Volume>,
    ) -> Real {
        self.edges.evaluate(x, v, spring_force, &mut []);
        self.evaluate_cells(x, v, slot_force);
        Real::INFINITY
    }
}
