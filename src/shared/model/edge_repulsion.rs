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
//! Two details make it work under explicit integration (`docs/ARCHITECTURE.md` §4.3):
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
//! repulsion `k_r = s E (V_cell/n) / h0²`, with [`MATERIAL_SCALE`]` = 47/33 ≈ 1.42` in 3D,
//! `5/6` in 2D. Only the edges are damped. Derivation as in [`super::springs`]: at rest the
//! barrier is `2 k_r` stiff along the facet normal `n` and a small strain changes `h` by
//! `h0 (n·εn)`, so each barrier stores `s E (V_cell/n) (n·εn)²` — a spring of twice its volume
//! share. With the edges, the mirrored Kuhn lattice's Young's modulus along an axis is
//! `33/47 · s E` in 3D (ν = 7/47 ≈ 0.15) and `6/5 · s E` in 2D (ν = 1/5); `s` makes it `E`.
//! The `cantilever` scene's beam sags within 2 % of Euler–Bernoulli at res 9 with it.
//! (Earlier `s = 1`, from a prototype's compression test: 1.42× too soft in 3D, 1.2× too stiff
//! in 2D.)

use super::super::material::Resolved;
use super::super::math::{self, Real, Vector, FACET_ARITY, SIMPLEX_ARITY};
use super::super::mesh::Mesh;
use super::lanes::{self, each, Lane, LaneVector, LANES};
use super::nonlinear_springs::{SERIES, SERIES_REACH};
use super::springs::{Law, Springs};
use super::volume::Volume;
use super::{Accumulator, NodeBounds};

/// Calibration constant `s` of the ER material mapping: 47/33 in 3D, 5/6 in 2D (see the
/// module's docs).
pub const MATERIAL_SCALE: Real = if super::super::math::DIM == 3 {
    47.0 / 33.0
} else {
    5.0 / 6.0
};

/// Fraction of the remaining height a vertex may cover in one substep.
pub const CROSSING_FRACTION: Real = 0.1;

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

/// Each vertex's side of its opposite facet (`±1`, the sign that makes the facet normal point
/// to it) and its height above the facet, in the simplex `p`.
fn heights(p: &[Vector; SIMPLEX_ARITY]) -> [(Real, Real); SIMPLEX_ARITY] {
    std::array::from_fn(|a| {
        let f = OPPOSITE[a];
        let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| p[f[m]]);
        let normal = math::facet_normal(&facet);
        let c = p[a];
        let side = if normal.dot(c - facet[0]) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        (side, (normal.dot(c - facet[0]) / normal.length()).abs())
    })
}

/// ER elements on simplex cells.
#[derive(Clone, Debug)]
pub(crate) struct EdgeRepulsion {
    pub edges: Springs,
    pub(super) cells: Vec<u32>,
    /// Per cell: the sign of its rest `D` ([`math::simplex_gradients`]).
    pub(super) sign: Vec<Real>,
    /// Per cell vertex: rest height, side sign, repulsion stiffness.
    pub(super) h0: Vec<Real>,
    pub(super) side: Vec<Real>,
    pub(super) k: Vec<Real>,
    /// For the next evaluation only: the crossing times at or above a cap need not be exact,
    /// and a bound on the nodes' speeds relative to each other ([`relative_speed`]).
    pub(super) crossing: Option<(Real, Real)>,
}

/// Local indices of the facet opposite each vertex, in increasing order.
const fn opposite(a: usize) -> [usize; FACET_ARITY] {
    let mut f = [0; FACET_ARITY];
    let mut n = 0;
    let mut b = 0;
    while b < SIMPLEX_ARITY {
        if b != a {
            f[n] = b;
            n += 1;
        }
        b += 1;
    }
    f
}

/// [`opposite`] for every vertex.
pub(super) const OPPOSITE: [[usize; FACET_ARITY]; SIMPLEX_ARITY] = {
    let mut t = [[0; FACET_ARITY]; SIMPLEX_ARITY];
    let mut a = 0;
    while a < SIMPLEX_ARITY {
        t[a] = opposite(a);
        a += 1;
    }
    t
};

impl EdgeRepulsion {
    pub fn build(mesh: &Mesh, masses: &[Real], params: &Resolved) -> Self {
        let edges = Springs::build(mesh, masses, params, MATERIAL_SCALE, Law::Linear);
        let nodes = mesh.nodes();
        let mut out = EdgeRepulsion {
            edges,
            cells: mesh.cell_indices().to_vec(),
            sign: Vec::new(),
            h0: Vec::new(),
            side: Vec::new(),
            k: Vec::new(),
            crossing: None,
        };
        for (cell, ids) in mesh.cells().enumerate() {
            let rest: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| nodes[ids[a] as usize]);
            out.sign.push(math::simplex_gradients(&rest).0.signum());
            let v = mesh.rest_volumes()[cell];
            let share = v / SIMPLEX_ARITY as Real;
            for (side, h0) in heights(&rest) {
                let material_k = MATERIAL_SCALE * params.material.young_modulus * share / (h0 * h0);
                let (k, _) = params.k_c(material_k, params.material.density * share);
                out.h0.push(h0);
                out.side.push(side);
                out.k.push(k);
            }
        }
        out
    }

    /// The edges' constant bounds (the repulsions' stiffness changes with the heights and only
    /// the edges are damped).
    pub fn constant_bounds(&self, bounds: &mut NodeBounds) {
        self.edges.constant_bounds(bounds);
    }

    /// Adds forces and the repulsions' stiffness bounds, with those of the volumetric term
    /// `volume` on the same cells (one pass over the cells); returns the largest substep the
    /// crossing limiter allows.
    pub fn accumulate(
        &self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        volume: Option<&Volume>,
    ) -> Real {
        self.edges.accumulate(x, v, acc);
        let n = x.len();
        let (v, force, stiffness) = (&v[..n], &mut acc.force[..n], &mut acc.stiffness[..n]);
        self.each_cell(0..self.sign.len(), (x, v, volume), |_, ids, f, k_row| {
            for a in 0..SIMPLEX_ARITY {
                let i = ids[a] as usize;
                force[i] += f[a];
                stiffness[i] += k_row[a];
            }
        })
    }

    /// Adds the repulsions (and volumetric terms) of cells `ids` into `force` and `stiffness`,
    /// which hold nodes `first..first + force.len()` (every node of the cells), as
    /// [`EdgeRepulsion::accumulate`] adds them; returns the cells' crossing limiter.
    #[cfg(feature = "parallel")]
    pub(crate) fn add_cells(
        &self,
        ids: std::ops::Range<usize>,
        first: usize,
        (x, v, volume): (&[Vector], &[Vector], Option<&Volume>),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) -> Real {
        if first == 0 && force.len() == x.len() {
            // All of the nodes (one thread): indexed as the serial loop indexes them.
            let n = x.len();
            let (v, force, stiffness) = (&v[..n], &mut force[..n], &mut stiffness[..n]);
            return self.each_cell(ids, (x, v, volume), |_, ids, f, k_row| {
                for a in 0..SIMPLEX_ARITY {
                    let i = ids[a] as usize;
                    force[i] += f[a];
                    stiffness[i] += k_row[a];
                }
            });
        }
        let (v, stiffness) = (&v[..x.len()], &mut stiffness[..force.len()]);
        self.each_cell(ids, (x, v, volume), |_, ids, f, k_row| {
            for a in 0..SIMPLEX_ARITY {
                let i = ids[a] as usize - first;
                force[i] += f[a];
                stiffness[i] += k_row[a];
            }
        })
    }

    /// Writes each cell's repulsion force and stiffness bound on each of its vertices into
    /// `force` and `stiffness` (one entry per slot), on rayon's threads; returns the crossing
    /// limiter.
    #[cfg(feature = "parallel")]
    pub fn evaluate_cells(
        &self,
        x: &[Vector],
        v: &[Vector],
        force: &mut [Vector],
        stiffness: &mut [Real],
        volume: Option<&Volume>,
    ) -> Real {
        use super::parallel::CELLS_PER_TASK as CHUNK;
        use rayon::prelude::*;
        let v = &v[..x.len()];
        let (force, _) = force.as_chunks_mut::<SIMPLEX_ARITY>();
        let (stiffness, _) = stiffness.as_chunks_mut::<SIMPLEX_ARITY>();
        force
            .par_chunks_mut(CHUNK)
            .zip(stiffness.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(t, (force, stiffness))| {
                let cells = t * CHUNK..t * CHUNK + force.len();
                self.each_cell(cells, (x, v, volume), |c, _, f, k_row| {
                    force[c - t * CHUNK] = *f;
                    stiffness[c - t * CHUNK] = *k_row;
                })
            })
            .reduce(|| Real::INFINITY, Real::min)
    }

    /// Calls `out(cell, its vertices, the force on each, its stiffness row)` for each cell of
    /// `cells` in order (the repulsions and the `volume` term at `x`, `v`), evaluated
    /// [`LANES`] at a time; returns the cells' crossing limiter.
    #[inline(always)]
    fn each_cell(
        &self,
        cells: std::ops::Range<usize>,
        (x, v, volume): (&[Vector], &[Vector], Option<&Volume>),
        mut out: impl FnMut(
            usize,
            &[u32; SIMPLEX_ARITY],
            &[Vector; SIMPLEX_ARITY],
            &[Real; SIMPLEX_ARITY],
        ),
    ) -> Real {
        let (ids, _) = self.cells.as_chunks::<SIMPLEX_ARITY>();
        let mut limit = Real::INFINITY;
        let crossing = self.crossing;
        for first in cells.clone().step_by(LANES) {
            // The last batch repeats its last cell in the lanes past the end.
            let batch: [usize; LANES] = each(|l| (first + l).min(cells.end - 1));
            let (f, rows, batch_limit) = cell_terms(self, batch, (x, v), volume, crossing);
            for l in 0..LANES.min(cells.end - first) {
                out(first + l, &ids[first + l], &f[l], &rows[l]);
            }
            limit = limit.min(batch_limit);
        }
        limit
    }

    /// The repulsions' elastic energy in cells `cells`, [`LANES`] cells at a time.
    pub fn cell_energy(&self, x: &[Vector], cells: std::ops::Range<usize>) -> Real {
        let (ids, _) = self.cells.as_chunks::<SIMPLEX_ARITY>();
        let (h0, _) = self.h0.as_chunks::<SIMPLEX_ARITY>();
        let (k, _) = self.k.as_chunks::<SIMPLEX_ARITY>();
        let lane_index = Lane::new(each(|l| l as Real));
        let tiny = Lane::splat(Real::MIN_POSITIVE);
        let mut e = Lane::ZERO;
        for first in cells.clone().step_by(LANES) {
            // The last batch repeats its last cell in the lanes past the end, and counts it
            // once.
            let batch: [usize; LANES] = each(|l| (first + l).min(cells.end - 1));
            let counted = lane_index.simd_lt(Lane::splat((cells.end - first) as Real));
            let xs: [LaneVector; SIMPLEX_ARITY] =
                each(|a| LaneVector::gather(|l| x[ids[batch[l]][a] as usize]));
            let sign = Lane::new(each(|l| self.sign[batch[l]]));
            // The heights as the forces measure them (`cell_terms`).
            let (_, g) = lanes::simplex_gradients(&xs);
            for a in 0..SIMPLEX_ARITY {
                let h0 = Lane::new(each(|l| h0[batch[l]][a]));
                let k = Lane::new(each(|l| k[batch[l]][a]));
                let g2 = g[a].length_squared();
                let live = g2.simd_gt(tiny) & counted;
                let len = live.select(g2, Lane::ONE).sqrt();
                let h = g[a].dot(xs[a] - xs[OPPOSITE[a][0]]) * sign / len;
                let hc = h.fast_max(Lane::splat(MIN_HEIGHT_RATIO) * h0);
                e += live.select(k * h0 * h0 * stored((hc - h0) / h0), Lane::ZERO);
            }
        }
        e.reduce_add()
    }
}

/// [`stored`](super::nonlinear_springs::stored) in lanes: the energy of a repulsion over `k h0²` at the
/// relative height `1 + t` (the law is the nonlinear spring's, on the height).
#[inline(always)]
fn stored(t: Lane) -> Lane {
    let series = SERIES
        .iter()
        .rev()
        .fold(Lane::ZERO, |s, c| Lane::splat(*c) + t * s);
    let near = t * t * (Lane::ONE + t * series);
    let far = t.abs().simd_ge(Lane::splat(SERIES_REACH));
    if far.any() {
        let u = Lane::ONE + t;
        far.select(Lane::splat(0.5) * (u * u - Lane::ONE) - u.ln(), near)
    } else {
        near
    }
}

/// The crossing limiter of [`LANES`] cells `cells` (vertices `ids`, velocities `v`): for each
/// repulsion closing on its facet, `CROSSING_FRACTION` of the time its vertex takes to reach
/// the facet at the rate it closes (the foot moving with the facet's vertices, weights `w`).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn crossing_times(
    ids: &[[u32; SIMPLEX_ARITY]],
    cells: [usize; LANES],
    v: &[Vector],
    (heights, normals, weights, lives): (
        &[Lane; SIMPLEX_ARITY],
        &[LaneVector; SIMPLEX_ARITY],
        &[[Lane; FACET_ARITY]; SIMPLEX_ARITY],
        &[Lane; SIMPLEX_ARITY],
    ),
) -> Lane {
    let vs: [LaneVector; SIMPLEX_ARITY] =
        each(|a| LaneVector::gather(|l| v[ids[cells[l]][a] as usize]));
    let mut limit = Lane::splat(Real::INFINITY);
    for a in 0..SIMPLEX_ARITY {
        let f = OPPOSITE[a];
        let mut foot_velocity = LaneVector::ZERO;
        for m in 0..FACET_ARITY {
            foot_velocity += vs[f[m]] * weights[a][m];
        }
        let h = heights[a];
        let rate = normals[a].dot(vs[a] - foot_velocity);
        let closing = h.simd_gt(Lane::ZERO) & rate.simd_lt(Lane::ZERO) & lives[a];
        let time = Lane::splat(CROSSING_FRACTION) * h / -rate;
        limit = closing
            .select(time, Lane::splat(Real::INFINITY))
            .fast_min(limit);
    }
    limit
}

/// A bound on how fast any node of a body moving at `v` closes on any point that moves
/// with a weighted mean of other nodes whose weights sum to one, over that mean's weight
/// sum: the largest speed relative to the mean velocity, with margins for rounding.
pub(super) fn relative_speed(v: &[Vector]) -> Real {
    if v.is_empty() {
        return 0.0;
    }
    let mean = v.iter().fold(Vector::ZERO, |s, u| s + *u) / v.len() as Real;
    // The longest deviation by its square (a square root keeps the order), over fixed chunks
    // (on rayon's threads for a large body): a maximum is exact in any order.
    let part = |r: std::ops::Range<usize>| {
        v[r].iter()
            .map(|u| (*u - mean).length_squared())
            .fold(0.0, Real::max)
    };
    let most = super::super::threads::chunked_fold(v.len(), part, Real::max)
        .unwrap_or(0.0)
        .sqrt();
    most * 1.01 + mean.length() * 1e-4
}

/// The repulsions of [`LANES`] cells `cells` of `er` and their `volume` terms, summed per
/// vertex: each cell's force on each vertex and its Gershgorin stiffness row, and the crossing
/// limiter of the cells (infinite when no vertex approaches its facet).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn cell_terms(
    er: &EdgeRepulsion,
    cells: [usize; LANES],
    (x, v): (&[Vector], &[Vector]),
    volume: Option<&Volume>,
    crossing: Option<(Real, Real)>,
) -> (
    [[Vector; SIMPLEX_ARITY]; LANES],
    [[Real; SIMPLEX_ARITY]; LANES],
    Real,
) {
    let (ids, _) = er.cells.as_chunks::<SIMPLEX_ARITY>();
    let (rest_heights, _) = er.h0.as_chunks::<SIMPLEX_ARITY>();
    let (stiffnesses, _) = er.k.as_chunks::<SIMPLEX_ARITY>();
    let xs: [LaneVector; SIMPLEX_ARITY] =
        each(|a| LaneVector::gather(|l| x[ids[cells[l]][a] as usize]));
    let per_vertex = |t: &[[Real; SIMPLEX_ARITY]], a: usize| Lane::new(each(|l| t[cells[l]][a]));
    let sign = Lane::new(each(|l| er.sign[cells[l]]));
    // One evaluation of the cells' volume gradients serves every repulsion and the volumetric
    // term: `g_a` is normal to the facet opposite `a`, `n = sign · g_a / |g_a|` points to `a`'s
    // rest side, and the foot's weight at facet vertex `b` is `−g_a·g_b / |g_a|²`. The height
    // is measured along `n` from a facet vertex: `sign · D / |g_a|` is the same height, but
    // `D`, one product for the whole cell, rounds worse where the strain is small (a 2D bar
    // ringing at 0.3 % strain came out 11 % low).
    let (d, g) = lanes::simplex_gradients(&xs);
    let mut force = [LaneVector::ZERO; SIMPLEX_ARITY];
    let mut stiffness = [Lane::ZERO; SIMPLEX_ARITY];
    let mut length = [Lane::ZERO; SIMPLEX_ARITY];
    // What the crossing limiter reads of each repulsion.
    let mut heights = [Lane::ZERO; SIMPLEX_ARITY];
    let mut normals = [LaneVector::ZERO; SIMPLEX_ARITY];
    let mut weights = [[Lane::ZERO; FACET_ARITY]; SIMPLEX_ARITY];
    let mut lives = [Lane::ZERO; SIMPLEX_ARITY];
    let mut far = Lane::splat(1.0).simd_eq(Lane::ONE);
    let (one, tiny) = (Lane::ONE, Lane::splat(Real::MIN_POSITIVE));
    for a in 0..SIMPLEX_ARITY {
        let f = OPPOSITE[a];
        let (h0, k) = (per_vertex(rest_heights, a), per_vertex(stiffnesses, a));
        let g2 = g[a].length_squared();
        // A facet collapsed to a point or a line has no direction this substep: no push, the
        // foot's weights even, the stiffness at rest.
        let live = g2.simd_gt(tiny);
        let g2 = live.select(g2, one);
        length[a] = g2.sqrt();
        // Division for division as [`repulsion`] and [`magnitude`] write the law, so that both
        // round alike (a fold in self contact is chaotic enough to tell reciprocals apart).
        let normal = g[a] * (sign / length[a]);
        let h = live.select(normal.dot(xs[a] - xs[f[0]]), Lane::ZERO);
        let hc = h.fast_max(Lane::splat(MIN_HEIGHT_RATIO) * h0);
        let k_eff = live.select(k * (one + h0 * h0 / (hc * hc)), k + k);
        let push = live.select(k * (h0 * h0 / hc - h), Lane::ZERO);
        let push = normal.or_zero(live) * push;
        let even = Lane::splat(1.0 / FACET_ARITY as Real);
        let w: [Lane; FACET_ARITY] = each(|m| live.select(-g[a].dot(g[f[m]]) / g2, even));
        force[a] += push;
        let mut wsum = one;
        for m in 0..FACET_ARITY {
            force[f[m]] += -(push * w[m]);
            wsum += w[m].abs();
        }
        // Gershgorin rows of the rank-one term k_eff a aᵀ, a = (1, −w).
        stiffness[a] += k_eff * wsum;
        for m in 0..FACET_ARITY {
            stiffness[f[m]] += k_eff * w[m].abs() * wsum;
        }
        (heights[a], normals[a], weights[a], lives[a]) = (h, normal, w, live);
        // The vertex closes on its foot at most `wsum` times the speed bound: then its
        // crossing time is at least `CROSSING_FRACTION h / (wsum · speed)`.
        if let Some((cap, speed)) = crossing {
            let reach = Lane::splat(CROSSING_FRACTION) * h;
            let slow = reach.simd_ge(Lane::splat(cap) * (wsum * Lane::splat(speed)));
            far &= slow | !(h.simd_gt(Lane::ZERO) & live);
        } else {
            far = Lane::ZERO;
        }
    }
    let limit = if far.all() {
        Lane::splat(Real::INFINITY)
    } else {
        crossing_times(ids, cells, v, (&heights, &normals, &weights, &lives))
    };
    if let Some(volume) = volume {
        let (f, k) = volume.cell_lanes(cells, d, &g, &length);
        for a in 0..SIMPLEX_ARITY {
            force[a] += f[a];
            stiffness[a] += k[a];
        }
    }
    let force: [[Vector; LANES]; SIMPLEX_ARITY] = each(|a| force[a].lanes());
    let stiffness: [[Real; LANES]; SIMPLEX_ARITY] = each(|a| stiffness[a].to_array());
    let limit = limit.to_array().into_iter().fold(Real::INFINITY, Real::min);
    (
        each(|l| each(|a| force[a][l])),
        each(|l| each(|a| stiffness[a][l])),
        limit,
    )
}

impl super::ElementLaw for EdgeRepulsion {
    fn boxed_clone(&self) -> Box<dyn super::ElementLaw> {
        Box::new(self.clone())
    }

    fn accumulate(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        volume: Option<&Volume>,
    ) -> Real {
        EdgeRepulsion::accumulate(self, x, v, acc, volume)
    }

    /// The volumetric term shares the repulsions' pass over the cells (their volume
    /// gradients).
    fn sums_volume(&self) -> bool {
        true
    }

    fn flows(&self) -> bool {
        true
    }

    /// A flowed cell's rest heights from its rest vertices, and its edges' rest lengths as the
    /// springs derive them ([`Springs::flow_rest_lengths`]).
    fn set_rest(&mut self, _: &[u32], rest: &[Vector], changed: &[u32]) {
        for &cell in changed {
            let cell = cell as usize;
            let p: [Vector; SIMPLEX_ARITY] =
                std::array::from_fn(|a| rest[cell * SIMPLEX_ARITY + a]);
            for (a, (_, h0)) in heights(&p).into_iter().enumerate() {
                self.h0[cell * SIMPLEX_ARITY + a] = h0;
            }
        }
        self.edges.flow_rest_lengths(&self.cells, rest, changed);
    }

    fn energy(&self, x: &[Vector]) -> Real {
        use super::super::threads::chunked_sum;
        chunked_sum(self.edges.pairs.len(), |r| self.edges.energy_of(x, r))
            + chunked_sum(self.h0.len() / SIMPLEX_ARITY, |r| self.cell_energy(x, r))
    }

    fn constant_bounds(&self, bounds: &mut NodeBounds) {
        EdgeRepulsion::constant_bounds(self, bounds);
    }

    fn implicit_terms(&self) -> Option<super::ImplicitTerms<'_>> {
        Some(super::ImplicitTerms {
            springs: Some(&self.edges),
            repulsion: Some(self),
            shape: None,
        })
    }

    #[cfg(any(test, feature = "parallel"))]
    fn edge_repulsion(&self) -> Option<&EdgeRepulsion> {
        Some(self)
    }

    fn edge_repulsion_mut(&mut self) -> Option<&mut EdgeRepulsion> {
        Some(self)
    }

    #[cfg(feature = "parallel")]
    fn edge_springs(&self) -> Option<&Springs> {
        Some(&self.edges)
    }

    #[cfg(feature = "parallel")]
    fn cost_per_cell(&self) -> usize {
        20
    }

    #[cfg(feature = "parallel")]
    fn varying(&self) -> super::Varying {
        super::Varying::Cells
    }

    #[cfg(feature = "parallel")]
    fn evaluate(
        &mut self,
        (x, v): (&[Vector], &[Vector]),
        spring_force: &mut [Vector],
        slot_force: &mut [Vector],
        stiffness: &mut [Real],
        volume: Option<&Volume>,
    ) -> Real {
        self.edges.evaluate(x, v, spring_force, &mut []);
        self.evaluate_cells(x, v, slot_force, stiffness, volume)
    }
}

#[cfg(test)]
mod tests {
    use super::super::Accumulator;
    use super::*;

    #[test]
    fn the_repulsions_energy_is_the_potential_of_their_forces() {
        // A squashed, sheared lattice: moving one node changes the repulsions' energy by the
        // work of their force on it.
        let half = Vector::splat(0.05);
        let body = super::super::fixtures::er_lattice(half, [3; math::DIM]);
        let er = super::super::fixtures::er_of(&body);
        let x = super::super::squashed(&body.state.positions, 0.7, 0.4);
        let n = x.len();
        let cells = 0..er.sign.len();
        let mut acc = Accumulator::new(n);
        er.accumulate(&x, &vec![Vector::ZERO; n], &mut acc, None);
        let mut edges = Accumulator::new(n);
        er.edges.accumulate(&x, &vec![Vector::ZERO; n], &mut edges);
        let eps = 1e-2 * half.x;
        let scale = (0..n)
            .map(|i| (acc.force[i] - edges.force[i]).length())
            .fold(0.0, Real::max);
        for i in [0, n / 2, n - 1] {
            for d in 0..math::DIM {
                let (mut plus, mut minus) = (x.clone(), x.clone());
                plus[i][d] += eps;
                minus[i][d] -= eps;
                let work = (er.cell_energy(&minus, cells.clone())
                    - er.cell_energy(&plus, cells.clone()))
                    / (2.0 * eps);
                let force = acc.force[i][d] - edges.force[i][d];
                assert!(
                    (work - force).abs() < 2e-2 * scale,
                    "node {i} axis {d}: {work} against {force}"
                );
            }
        }
        // Near rest, where the law's two terms cancel, the energy is the barrier's `k (δh)²`.
        let y = super::super::squashed(&body.state.positions, 1.0 - 1e-4, 0.0);
        let mut exact = 0.0;
        for (cell, ids) in er.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            for a in 0..SIMPLEX_ARITY {
                let s = cell * SIMPLEX_ARITY + a;
                let facet: [Vector; FACET_ARITY] =
                    std::array::from_fn(|m| y[ids[OPPOSITE[a][m]] as usize]);
                let r = repulsion(y[ids[a] as usize], &facet, er.side[s], er.h0[s], er.k[s]);
                let t = (r.height / er.h0[s]) as f64 - 1.0;
                exact += er.k[s] as f64 * (er.h0[s] as f64).powi(2) * (t + 0.5 * t * t - t.ln_1p());
            }
        }
        let e = er.cell_energy(&y, cells.clone()) as f64;
        assert!((e / exact - 1.0).abs() < 1e-2, "{e} against {exact}");
        assert!(er.cell_energy(&x, cells.clone()) > 0.0);
        assert!(er.cell_energy(&body.state.positions, cells).abs() < 1e-9);
    }

    #[test]
    fn the_cell_pass_gives_each_repulsion_its_force_and_bound() {
        // A lattice squashed to 60 % of its height and sheared, moving: the pass over the
        // cells (from the cells' volume gradients) must give every node the forces, stiffness
        // rows and crossing limiter of the repulsions evaluated one by one.
        let mut half = Vector::splat(0.05);
        half[0] = 0.5;
        let mut res = [3; math::DIM];
        res[0] = 21;
        let body = super::super::fixtures::er_lattice(half, res);
        let er = super::super::fixtures::er_of(&body);
        let x = super::super::squashed(&body.state.positions, 0.6, 3.0);
        let v: Vec<Vector> = x.iter().map(|p| -*p * 2.0).collect();
        let n = x.len();
        let mut acc = Accumulator::new(n);
        let volume = body
            .state
            .elements
            .volume
            .as_ref()
            .expect("ν 0.3 takes a volumetric term");
        let limit = er.accumulate(&x, &v, &mut acc, Some(volume));
        let mut force = vec![Vector::ZERO; n];
        let mut stiffness = vec![0.0; n];
        let mut expected_limit = Real::INFINITY;
        for (cell, ids) in er.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            for a in 0..SIMPLEX_ARITY {
                let s = cell * SIMPLEX_ARITY + a;
                let f = OPPOSITE[a];
                let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| x[ids[f[m]] as usize]);
                let c = ids[a] as usize;
                let r = repulsion(x[c], &facet, er.side[s], er.h0[s], er.k[s]);
                let wsum = 1.0 + r.weights.iter().map(|w| w.abs()).sum::<Real>();
                force[c] += r.force;
                stiffness[c] += r.stiffness * wsum;
                let mut foot = Vector::ZERO;
                for m in 0..FACET_ARITY {
                    let j = ids[f[m]] as usize;
                    force[j] -= r.force * r.weights[m];
                    stiffness[j] += r.stiffness * r.weights[m].abs() * wsum;
                    foot += v[j] * r.weights[m];
                }
                let rate = r.normal.dot(v[c] - foot);
                if r.height > 0.0 && rate < 0.0 {
                    expected_limit = expected_limit.min(CROSSING_FRACTION * r.height / -rate);
                }
            }
        }
        // Less the edges' and the volumetric term's, only the repulsions are left in `acc`.
        let mut edges = Accumulator::new(n);
        er.edges.accumulate(&x, &v, &mut edges);
        volume.accumulate(&x, &mut edges);
        let scale = force.iter().map(|f| f.length()).fold(1e-3, Real::max);
        let k_scale = stiffness.iter().copied().fold(1e-3, Real::max);
        for i in 0..n {
            let got = acc.force[i] - edges.force[i];
            assert!(
                (got - force[i]).length() < 1e-4 * scale,
                "node {i}: {got} {}",
                force[i]
            );
            let got = acc.stiffness[i] - edges.stiffness[i];
            assert!(
                (got - stiffness[i]).abs() < 1e-4 * k_scale,
                "node {i}: {got} {}",
                stiffness[i]
            );
        }
        assert!(
            (limit / expected_limit - 1.0).abs() < 1e-4,
            "{limit} {expected_limit}"
        );
        assert!(expected_limit.is_finite(), "the cells close");
    }

    #[test]
    fn a_capped_pass_is_exact_below_its_cap_and_the_same_otherwise() {
        // The squashed, sheared, moving lattice of the test above: under any cap, the forces
        // and stiffness rows keep their bits, and the limiter is exact where it is below the
        // cap, at or above the cap otherwise; a small cap leaves the closing cells out.
        let mut half = Vector::splat(0.05);
        half[0] = 0.5;
        let mut res = [3; math::DIM];
        res[0] = 21;
        let body = super::super::fixtures::er_lattice(half, res);
        let mut er = super::super::fixtures::er_of(&body).clone();
        let volume = body.state.elements.volume.as_ref();
        let x = super::super::squashed(&body.state.positions, 0.6, 3.0);
        let v: Vec<Vector> = x.iter().map(|p| -*p * 2.0).collect();
        let bits = |acc: &Accumulator| -> Vec<u32> {
            let forces = acc.force.iter().flat_map(|f| f.to_array());
            forces
                .chain(acc.stiffness.iter().copied())
                .map(Real::to_bits)
                .collect()
        };
        let mut exact = Accumulator::new(x.len());
        let limit = er.accumulate(&x, &v, &mut exact, volume);
        assert!(limit.is_finite() && limit > 0.0, "the cells close: {limit}");
        let speed = relative_speed(&v);
        for cap in [limit * 1e-3, limit * 0.5, limit, limit * 2.0, limit * 1e3] {
            let mut capped = Accumulator::new(x.len());
            er.crossing = Some((cap, speed));
            let got = er.accumulate(&x, &v, &mut capped, volume);
            er.crossing = None;
            assert_eq!(bits(&capped), bits(&exact), "cap {cap}");
            if limit < cap {
                assert_eq!(got.to_bits(), limit.to_bits(), "cap {cap}");
            } else {
                assert!(got >= cap, "cap {cap}: {got}");
            }
        }
        let mut small = Accumulator::new(x.len());
        er.crossing = Some((limit * 1e-3, speed));
        assert_eq!(er.accumulate(&x, &v, &mut small, volume), Real::INFINITY);
    }
}
