//! The edge-repulsion (ER) element (Cooper & Maddock 1999, §4.3 eq. 5; face repulsion in 3D,
//! §6).
//!
//! A simplex cell carries damped linear springs on its edges ([`super::springs`], eq. 1) and,
//! for each vertex `C`, a repulsion from the line (2D) / plane (3D) of the opposite facet. With
//! `E` the foot of `C` on that line/plane, `h = |EC|` its distance and `h0` the rest distance,
//! eq. 5 adds to the edge springs' force on `C`
//!
//! ```text
//! F_C = k_r (h0²/h − h) n,        n = EC / |EC|  (the facet normal on C's side)      (eq. 5)
//! ```
//!
//! the nonlinear law of eq. 4 applied to the height: zero at rest, `→ +∞` as `C` approaches the
//! facet, so the cell cannot collapse or flip. The reaction `−F_C` acts at `E` and is shared by
//! the facet's vertices with the barycentric weights of `E`; since `F_C ∥ EC` the pair has no
//! moment, so linear and angular momentum are conserved.
//!
//! Two details make it work under explicit integration (`DESIGN.md` §4):
//! * the barrier's stiffness `k_r (1 + h0²/h²)` enters each node's stability bound, so the
//!   substep shrinks as a cell compresses;
//! * a *crossing limiter*: a substep may not let a vertex cover more than
//!   [`CROSSING_FRACTION`] of its remaining height `h / |dh/dt|`, because the mirrored state
//!   (vertex through its facet) is also an equilibrium of eq. 5 and a cell that jumps there stays
//!   inverted.
//!
//! The law is evaluated at `max(h, 10⁻⁶ h0)` so that an already inverted cell (reached only
//! through a crossing forced from outside, e.g. by a bone) is pushed back with a large but
//! finite force.
//!
//! Material mapping: edges `k = s E V_s / L0²` with `V_s` as in [`super::springs`]; each
//! repulsion `k_r = s E (V_cell/n) / h0²`, with [`MATERIAL_SCALE`]` = 1` (the barrier adds
//! `2 k_r` of stiffness at rest, so ER needs a smaller constant than springs). Only the edges
//! are damped.

use super::super::material::Resolved;
use super::super::math::{self, Real, Vector, FACET_ARITY, SIMPLEX_ARITY};
use super::super::mesh::Mesh;
use super::springs::{Law, Springs};
use super::Accumulator;

/// Calibration constant `s` of the ER material mapping.
pub const MATERIAL_SCALE: Real = 1.0;

/// Fraction of the remaining height a vertex may cover in one substep.
pub const CROSSING_FRACTION: Real = 0.5;

/// Smallest height (relative to `h0`) at which the law is evaluated.
pub const MIN_HEIGHT_RATIO: Real = 1e-6;

/// The magnitude of the repulsion, `k (h0²/h − h)` (eq. 4 applied to the height).
#[inline]
pub fn magnitude(h: Real, h0: Real, k: Real) -> Real {
    let hc = h.max(MIN_HEIGHT_RATIO * h0);
    k * (h0 * h0 / hc - h)
}

/// One evaluated repulsion term.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Repulsion {
    /// Force on the vertex `C`.
    pub force: Vector,
    /// Unit facet normal on `C`'s rest side.
    pub normal: Vector,
    /// Barycentric weights of the foot `E`: the reaction on facet vertex `j` is
    /// `−weights[j] · force`.
    pub weights: [Real; FACET_ARITY],
    /// Signed height of `C` above the facet (negative once through it).
    pub height: Real,
    /// Current stiffness `k (1 + h0²/h²)`.
    pub stiffness: Real,
}

/// One repulsion term: vertex `c` against the facet `facet` (its vertices in the order used at
/// rest), `side` being `+1` or `−1` so that `side · facet_normal` points to `c` at rest.
#[inline]
pub fn repulsion(c: Vector, facet: &[Vector], side: Real, h0: Real, k: Real) -> Repulsion {
    let normal = math::facet_normal(facet);
    let len = normal.length();
    if len <= Real::MIN_POSITIVE {
        // The facet itself collapsed to a point/line: no defined direction this substep.
        return Repulsion {
            force: Vector::ZERO,
            normal: Vector::ZERO,
            weights: [1.0 / FACET_ARITY as Real; FACET_ARITY],
            height: 0.0,
            stiffness: 2.0 * k,
        };
    }
    let n = normal * (side / len);
    let h = n.dot(c - facet[0]);
    let hc = h.max(MIN_HEIGHT_RATIO * h0);
    Repulsion {
        force: n * magnitude(h, h0, k),
        normal: n,
        weights: math::facet_barycentric(facet, c),
        height: h,
        stiffness: k * (1.0 + h0 * h0 / (hc * hc)),
    }
}

/// ER elements on simplex cells.
#[derive(Clone, Debug)]
pub(crate) struct EdgeRepulsion {
    edges: Springs,
    cells: Vec<u32>,
    /// Per cell vertex: rest height, side sign, repulsion stiffness.
    h0: Vec<Real>,
    side: Vec<Real>,
    k: Vec<Real>,
}

/// Local indices of the facet opposite each vertex, in increasing order.
fn opposite(a: usize) -> [usize; FACET_ARITY] {
    let mut f = [0; FACET_ARITY];
    let mut n = 0;
    for b in 0..SIMPLEX_ARITY {
        if b != a {
            f[n] = b;
            n += 1;
        }
    }
    f
}

impl EdgeRepulsion {
    pub fn build(mesh: &Mesh, masses: &[Real], params: &Resolved) -> Self {
        let edges = Springs::build(mesh, masses, params, MATERIAL_SCALE, Law::Linear);
        let nodes = mesh.nodes();
        let mut out = EdgeRepulsion {
            edges,
            cells: mesh.cell_indices().to_vec(),
            h0: Vec::new(),
            side: Vec::new(),
            k: Vec::new(),
        };
        for (cell, ids) in mesh.cells().enumerate() {
            let v = mesh.rest_volumes()[cell];
            let share = v / SIMPLEX_ARITY as Real;
            for a in 0..SIMPLEX_ARITY {
                let f = opposite(a);
                let facet: [Vector; FACET_ARITY] =
                    std::array::from_fn(|m| nodes[ids[f[m]] as usize]);
                let normal = math::facet_normal(&facet);
                let c = nodes[ids[a] as usize];
                let side = if normal.dot(c - facet[0]) >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
                let h0 = (normal.dot(c - facet[0]) / normal.length()).abs();
                let material_k = MATERIAL_SCALE * params.material.young_modulus * share / (h0 * h0);
                let (k, _) = params.k_c(material_k, params.material.density * share);
                out.h0.push(h0);
                out.side.push(side);
                out.k.push(k);
            }
        }
        out
    }

    /// Adds forces; returns the largest substep the crossing limiter allows.
    pub fn accumulate(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        self.edges.accumulate(x, v, acc);
        let mut limit = Real::INFINITY;
        for (cell, ids) in self.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            for a in 0..SIMPLEX_ARITY {
                let s = cell * SIMPLEX_ARITY + a;
                let f = opposite(a);
                let fid: [u32; FACET_ARITY] = std::array::from_fn(|m| ids[f[m]]);
                let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| x[fid[m] as usize]);
                let c = ids[a] as usize;
                let r = repulsion(x[c], &facet, self.side[s], self.h0[s], self.k[s]);
                let (force, w, h, k_eff) = (r.force, r.weights, r.height, r.stiffness);
                acc.force[c] += force;
                let mut foot_velocity = Vector::ZERO;
                let mut wsum = 1.0;
                for m in 0..FACET_ARITY {
                    acc.force[fid[m] as usize] -= force * w[m];
                    foot_velocity += v[fid[m] as usize] * w[m];
                    wsum += w[m].abs();
                }
                // Gershgorin rows of the rank-one term k_eff a aᵀ, a = (1, −w).
                acc.stiffness[c] += k_eff * wsum;
                for m in 0..FACET_ARITY {
                    acc.stiffness[fid[m] as usize] += k_eff * w[m].abs() * wsum;
                }
                // Crossing limiter.
                if h > 0.0 {
                    let rate = r.normal.dot(v[c] - foot_velocity);
                    if rate < 0.0 {
                        limit = limit.min(CROSSING_FRACTION * h / -rate);
                    }
                }
            }
        }
        limit
    }

    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        let mut e = self.edges.elastic_energy(x);
        for (cell, ids) in self.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            for a in 0..SIMPLEX_ARITY {
                let s = cell * SIMPLEX_ARITY + a;
                let f = opposite(a);
                let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| x[ids[f[m]] as usize]);
                let normal = math::facet_normal(&facet);
                let len = normal.length();
                if len <= Real::MIN_POSITIVE {
                    continue;
                }
                let h = (normal * (self.side[s] / len)).dot(x[ids[a] as usize] - facet[0]);
                let h0 = self.h0[s];
                let hc = h.max(MIN_HEIGHT_RATIO * h0);
                e += self.k[s] * (0.5 * (hc * hc - h0 * h0) - h0 * h0 * (hc / h0).ln());
            }
        }
        e
    }
}
