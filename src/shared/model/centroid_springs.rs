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
//! `k_c = s E (V_cell/n) / L0²` with the same `s`, `c_c = 2 ζ √(k_c m_cell/n)`.

use super::super::material::Resolved;
use super::super::math::{Real, Vector};
use super::super::mesh::Mesh;
use super::springs::{Law, Springs, MATERIAL_SCALE};
use super::Accumulator;

/// Largest cell arity (hexahedron).
const MAX_ARITY: usize = 8;

/// Edge springs plus centroid springs.
#[derive(Clone, Debug)]
pub(crate) struct CentroidSprings {
    edges: Springs,
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

    pub fn accumulate(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        self.edges.accumulate(x, v, acc);
        let n = self.arity;
        let inv_n = 1.0 / n as Real;
        for (cell, ids) in self.cells.chunks_exact(n).enumerate() {
            let mut xc = Vector::ZERO;
            let mut vc = Vector::ZERO;
            for &i in ids {
                xc += x[i as usize];
                vc += v[i as usize];
            }
            xc *= inv_n;
            vc *= inv_n;
            let mut reaction = Vector::ZERO;
            let mut k_sum = 0.0;
            let mut c_sum = 0.0;
            let mut own = [Vector::ZERO; MAX_ARITY];
            for (a, &i) in ids.iter().enumerate() {
                let s = cell * n + a;
                let f = centroid_force(
                    x[i as usize],
                    xc,
                    v[i as usize],
                    vc,
                    self.rest[s],
                    self.k[s],
                    self.c[s],
                );
                own[a] = f;
                reaction += f;
                k_sum += self.k[s];
                c_sum += self.c[s];
                // Row bound of the rank-one term with weights (1 − 1/n at i, −1/n elsewhere).
                let w = 2.0 * (1.0 - inv_n);
                acc.stiffness[i as usize] += self.k[s] * w;
                acc.damping[i as usize] += self.c[s] * w;
            }
            for (a, &i) in ids.iter().enumerate() {
                acc.force[i as usize] += own[a] - reaction * inv_n;
                acc.stiffness[i as usize] += k_sum * 2.0 * inv_n;
                acc.damping[i as usize] += c_sum * 2.0 * inv_n;
            }
        }
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
