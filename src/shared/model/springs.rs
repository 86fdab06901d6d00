//! Damped springs on every vertex pair of every cell (Cooper & Maddock 1999, eq. 1 and 3).
//!
//! For a spring between nodes `i` and `j` with rest length `L0`, current length
//! `L = |x_i − x_j|` and unit direction `n = (x_i − x_j)/L`, the force on `i` is
//!
//! ```text
//! f_i = [ k (L0 − L) − c (v_i − v_j)·n ] n,      f_j = −f_i          (eq. 1)
//! ```
//!
//! Summed over the three edges of a triangle this is the "standard element" of eq. 3. Edges of
//! triangles and tetrahedra are all their vertex pairs; for quads and hexahedra the face and
//! body diagonals are springs too (a box of edge springs alone has no shear stiffness).
//!
//! Material mapping: a spring standing for volume `V_s` (each cell gives `V_cell / pairs` to
//! each of its vertex pairs) gets `k = s · E · V_s / L0²` with `s =` [`MATERIAL_SCALE`]
//! (`31/7 ≈ 4.43` in 3D, `5/2` in 2D), and `c = 2 ζ √(k μ)` with `μ` the reduced mass of the
//! two nodes. Derivation (Cauchy–Born): under a uniform small strain `ε` a spring of direction
//! `n` stores `½ s E V_s (n·εn)²`, so a lattice's stiffness tensor is `s E ⟨n⊗n⊗n⊗n⟩`, the
//! average over its springs weighted by `V_s`. For the mirrored Kuhn lattice of
//! `Mesh::cuboid` its Young's modulus along a lattice axis (uniaxial stress, free sides) is
//! `7/31 · s E` in 3D (Poisson's ratio 5/31 ≈ 0.16) and `2/5 · s E` in 2D (ν = 1/5); `s` makes
//! it `E`. The `cantilever` scene checks it: a clamped beam's sag is within 3 % of
//! Euler–Bernoulli at res 9 in both dimensions. (Earlier `s = 5.8`, from a compression test of
//! a prototype's lattice, made this lattice 1.31× too stiff in 3D and 2.32× in 2D.) The [`NonlinearSprings`] model shares this
//! file's loop with the law of [`super::nonlinear_springs`].
//!
//! [`NonlinearSprings`]: super::ElementModel::NonlinearSprings

use std::ops::Range;

use super::super::material::Resolved;
use super::super::math::{Real, Vector, SIMPLEX_ARITY};
use super::super::mesh::Mesh;
use super::super::threads;
use super::lanes::{each, Lane, LaneVector, LANES};
use super::{reduced_mass, Accumulator, NodeBounds};

/// Calibration constant `s` of the material mapping `k = s E V_s / L0²`: 31/7 in 3D, 5/2 in
/// 2D (see the module's docs).
pub const MATERIAL_SCALE: Real = if super::super::math::DIM == 3 {
    31.0 / 7.0
} else {
    2.5
};

/// The force on node `i` of a damped linear spring (eq. 1), and the stiffness it presents
/// along its axis (`k`). Zero when the two nodes coincide (no direction).
#[inline]
pub fn linear_force(
    xi: Vector,
    xj: Vector,
    vi: Vector,
    vj: Vector,
    rest_length: Real,
    k: Real,
    c: Real,
) -> Vector {
    let d = xi - xj;
    let l = d.length();
    if l <= Real::MIN_POSITIVE {
        return Vector::ZERO;
    }
    let n = d / l;
    n * (k * (rest_length - l) - c * (vi - vj).dot(n))
}

/// Which spring law a [`Springs`] set uses.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Law {
    Linear,
    Nonlinear,
}

/// A set of springs: flat arrays, one entry per spring.
#[derive(Clone, Debug)]
pub(crate) struct Springs {
    pub pairs: Vec<[u32; 2]>,
    pub rest: Vec<Real>,
    pub k: Vec<Real>,
    pub c: Vec<Real>,
    pub law: Law,
}

impl Springs {
    /// After plastic flow (`plastic.rs`): each spring on an edge of a cell in `changed` takes
    /// as its rest length the mean of that edge's length over the rest shapes `rest` (by slot;
    /// `cells` their node indices) of the cells that share it, which differ once they flow;
    /// the other springs keep theirs. Stiffness and damping stay as built.
    pub fn flow_rest_lengths(&mut self, cells: &[u32], rest: &[Vector], changed: &[u32]) {
        let pairs = &self.pairs;
        let (ids, _) = cells.as_chunks::<SIMPLEX_ARITY>();
        // Each pair of a cell's vertices: its local indices and its spring.
        let springs = |cell: usize| {
            let ids = ids[cell];
            (0..SIMPLEX_ARITY).flat_map(move |a| {
                (a + 1..SIMPLEX_ARITY).filter_map(move |b| {
                    let pair = [ids[a].min(ids[b]), ids[a].max(ids[b])];
                    pairs.binary_search(&pair).ok().map(|e| (a, b, e))
                })
            })
        };
        let mut touched = vec![false; pairs.len()];
        for &cell in changed {
            for (_, _, e) in springs(cell as usize) {
                touched[e] = true;
            }
        }
        let mut length = vec![0.0; pairs.len()];
        let mut count = vec![0u32; pairs.len()];
        for cell in 0..ids.len() {
            for (a, b, e) in springs(cell) {
                if touched[e] {
                    let at = |v: usize| rest[cell * SIMPLEX_ARITY + v];
                    length[e] += at(a).distance(at(b));
                    count[e] += 1;
                }
            }
        }
        for (e, rest) in self.rest.iter_mut().enumerate() {
            if touched[e] && count[e] > 0 {
                *rest = length[e] / count[e] as Real;
            }
        }
    }

    pub fn build(mesh: &Mesh, masses: &[Real], params: &Resolved, scale: Real, law: Law) -> Self {
        let pairs = mesh.vertex_pairs();
        let nodes = mesh.nodes();
        let mut out = Springs {
            pairs: Vec::with_capacity(pairs.len()),
            rest: Vec::with_capacity(pairs.len()),
            k: Vec::with_capacity(pairs.len()),
            c: Vec::with_capacity(pairs.len()),
            law,
        };
        for ([i, j], share) in pairs {
            let l0 = nodes[i as usize].distance(nodes[j as usize]);
            let material_k = scale * params.material.young_modulus * share / (l0 * l0);
            let (k, c) = params.k_c(
                material_k,
                reduced_mass(masses[i as usize], masses[j as usize]),
            );
            out.pairs.push([i, j]);
            out.rest.push(l0);
            out.k.push(k);
            out.c.push(c);
        }
        out
    }

    /// Adds the bounds that do not change with the state: each spring is a rank-one term with
    /// weights `(1, −1)`, so it adds `2c` to both nodes' damping rows and, for the linear law,
    /// `2k` to their stiffness rows.
    pub fn constant_bounds(&self, bounds: &mut NodeBounds) {
        for s in 0..self.pairs.len() {
            let [i, j] = self.pairs[s];
            let (i, j) = (i as usize, j as usize);
            if self.law == Law::Linear {
                bounds.stiffness[i] += 2.0 * self.k[s];
                bounds.stiffness[j] += 2.0 * self.k[s];
            }
            bounds.damping[i] += 2.0 * self.c[s];
            bounds.damping[j] += 2.0 * self.c[s];
        }
    }

    /// Adds the spring forces (and, for the nonlinear law, the stiffness that changes with the
    /// length) into `acc`. The constant bounds are added by [`Springs::constant_bounds`].
    pub fn accumulate(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        let all = 0..self.pairs.len();
        match self.law {
            Law::Linear => self.accumulate_law::<false, false>(all, x, v, acc),
            Law::Nonlinear => self.accumulate_law::<true, false>(all, x, v, acc),
        };
    }

    /// [`Springs::accumulate`] (the same bits) and the springs' elastic energy, that of
    /// [`ElementLaw::energy`](super::ElementLaw::energy) (the same bits: summed chunk by chunk
    /// as [`threads::chunked_sum`] sums it), in one pass.
    pub fn accumulate_measured(&self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        threads::chunks(self.pairs.len())
            .map(|springs| match self.law {
                Law::Linear => self.accumulate_law::<false, true>(springs, x, v, acc),
                Law::Nonlinear => self.accumulate_law::<true, true>(springs, x, v, acc),
            })
            .sum()
    }

    /// Adds the forces of `springs` (and, for the nonlinear law, their stiffness rows) into
    /// `acc`; with `MEASURE`, returns their energy as [`Springs::energy_of`] gives it (else 0).
    fn accumulate_law<const NONLINEAR: bool, const MEASURE: bool>(
        &self,
        springs: Range<usize>,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
    ) -> Real {
        // Equal lengths let one bounds check per index cover every array.
        let n = x.len();
        let (v, force, stiffness) = (&v[..n], &mut acc.force[..n], &mut acc.stiffness[..n]);
        if !NONLINEAR {
            return self.accumulate_linear::<MEASURE>(springs, x, v, force);
        }
        let mut e = 0.0;
        let first = springs.start;
        for (s, (((&[i, j], &l0), &k), &c)) in self.terms(first).take(springs.len()).enumerate() {
            let (f, k_row) = term::<NONLINEAR>([i, j], l0, k, c, x, v);
            let (i, j) = (i as usize, j as usize);
            force[i] += f;
            force[j] -= f;
            if NONLINEAR {
                stiffness[i] += k_row;
                stiffness[j] += k_row;
            }
            if MEASURE {
                e += self.energy_at(first + s, x[i].distance(x[j]));
            }
        }
        e
    }

    /// The linear law's forces of `springs`, added spring by spring as [`linear_force`] gives
    /// them (the same bits), evaluated [`LANES`] springs at a time; with `MEASURE`, their
    /// energy as [`Springs::energy_of`] gives it (else 0).
    fn accumulate_linear<const MEASURE: bool>(
        &self,
        springs: Range<usize>,
        x: &[Vector],
        v: &[Vector],
        force: &mut [Vector],
    ) -> Real {
        let mut e = 0.0;
        for first in springs.clone().step_by(LANES) {
            // The last batch repeats its last spring in the lanes past the end.
            let s: [usize; LANES] = each(|l| (first + l).min(springs.end - 1));
            let ends =
                |e: usize, p: &[Vector]| LaneVector::gather(|l| p[self.pairs[s[l]][e] as usize]);
            let d = ends(0, x) - ends(1, x);
            let l = d.length_squared().sqrt();
            let dead = l.simd_le(Lane::splat(Real::MIN_POSITIVE));
            let n = d / l;
            let rest = Lane::new(each(|i| self.rest[s[i]]));
            let k = Lane::new(each(|i| self.k[s[i]]));
            let c = Lane::new(each(|i| self.c[s[i]]));
            let along = (ends(0, v) - ends(1, v)).dot(n);
            let f = (n * (k * (rest - l) - c * along)).or_zero(!dead).lanes();
            for (lane, f) in f.iter().enumerate().take(springs.end - first) {
                let [i, j] = self.pairs[first + lane];
                let (i, j) = (i as usize, j as usize);
                force[i] += *f;
                force[j] -= *f;
                if MEASURE {
                    e += self.energy_at(first + lane, x[i].distance(x[j]));
                }
            }
        }
        e
    }

    /// Adds the forces of springs `ids` (and, for the nonlinear law, their stiffness rows) into
    /// `force` and `stiffness`, which hold nodes `first..first + force.len()` (every node of
    /// the springs), as [`Springs::accumulate`] adds them.
    #[cfg(feature = "parallel")]
    pub(crate) fn add_some(
        &self,
        ids: std::ops::Range<usize>,
        first: usize,
        state: (&[Vector], &[Vector]),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) {
        match self.law {
            Law::Linear => self.add_some_law::<false>(ids, first, state, force, stiffness),
            Law::Nonlinear => self.add_some_law::<true>(ids, first, state, force, stiffness),
        }
    }

    #[cfg(feature = "parallel")]
    fn add_some_law<const NONLINEAR: bool>(
        &self,
        ids: std::ops::Range<usize>,
        first: usize,
        (x, v): (&[Vector], &[Vector]),
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) {
        let count = ids.len();
        let v = &v[..x.len()];
        let stiffness = &mut stiffness[..force.len()];
        for (((&pair, &l0), &k), &c) in self.terms(ids.start).take(count) {
            let (f, k_row) = term::<NONLINEAR>(pair, l0, k, c, x, v);
            let (i, j) = (pair[0] as usize - first, pair[1] as usize - first);
            force[i] += f;
            force[j] -= f;
            if NONLINEAR {
                stiffness[i] += k_row;
                stiffness[j] += k_row;
            }
        }
    }

    /// Writes each spring's force on its first node (the second takes `−f`) into `force` and,
    /// for the nonlinear law, its row bound on both into `stiffness` (ignored for the linear
    /// law), on rayon's threads.
    #[cfg(feature = "parallel")]
    pub fn evaluate(
        &self,
        x: &[Vector],
        v: &[Vector],
        force: &mut [Vector],
        stiffness: &mut [[Real; 2]],
    ) {
        use super::parallel::TERMS_PER_TASK as CHUNK;
        use rayon::prelude::*;
        let v = &v[..x.len()];
        match self.law {
            Law::Linear => force
                .par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(t, force)| {
                    for (f, (((&pair, &l0), &k), &c)) in force.iter_mut().zip(self.terms(t * CHUNK))
                    {
                        (*f, _) = term::<false>(pair, l0, k, c, x, v);
                    }
                }),
            Law::Nonlinear => force
                .par_chunks_mut(CHUNK)
                .zip(stiffness.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(|(t, (force, stiffness))| {
                    let out = force.iter_mut().zip(stiffness);
                    for ((f, k_row), (((&pair, &l0), &k), &c)) in out.zip(self.terms(t * CHUNK)) {
                        let ki;
                        (*f, ki) = term::<true>(pair, l0, k, c, x, v);
                        *k_row = [ki, ki];
                    }
                }),
        }
    }

    /// The springs from `first` on: node pair, rest length, stiffness, damping.
    #[allow(clippy::type_complexity)]
    fn terms(&self, first: usize) -> impl Iterator<Item = (((&[u32; 2], &Real), &Real), &Real)> {
        let pairs = &self.pairs[first..];
        pairs
            .iter()
            .zip(&self.rest[first..])
            .zip(&self.k[first..])
            .zip(&self.c[first..])
    }

    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        self.energy_of(x, 0..self.pairs.len())
    }

    /// The elastic energy of springs `springs`.
    pub fn energy_of(&self, x: &[Vector], springs: Range<usize>) -> Real {
        let mut e = 0.0;
        for s in springs {
            let [i, j] = self.pairs[s];
            e += self.energy_at(s, x[i as usize].distance(x[j as usize]));
        }
        e
    }

    /// The energy of spring `s` at length `l`.
    #[inline(always)]
    fn energy_at(&self, s: usize, l: Real) -> Real {
        match self.law {
            Law::Linear => 0.5 * self.k[s] * (l - self.rest[s]).powi(2),
            Law::Nonlinear => super::nonlinear_springs::energy(l, self.rest[s], self.k[s]),
        }
    }
}

/// One spring: the force on its first node and, for the nonlinear law, the row bound `2 k_eff`
/// of its current axial stiffness (the linear law's bound is constant).
#[inline(always)]
fn term<const NONLINEAR: bool>(
    [i, j]: [u32; 2],
    l0: Real,
    k: Real,
    c: Real,
    x: &[Vector],
    v: &[Vector],
) -> (Vector, Real) {
    let (i, j) = (i as usize, j as usize);
    if NONLINEAR {
        let (f, k_eff) = super::nonlinear_springs::force(x[i], x[j], v[i], v[j], l0, k, c);
        (f, 2.0 * k_eff)
    } else {
        (linear_force(x[i], x[j], v[i], v[j], l0, k, c), 0.0)
    }
}

impl super::ElementLaw for Springs {
    fn boxed_clone(&self) -> Box<dyn super::ElementLaw> {
        Box::new(self.clone())
    }

    fn flows(&self) -> bool {
        true
    }

    fn set_rest(&mut self, cells: &[u32], rest: &[Vector], changed: &[u32]) {
        self.flow_rest_lengths(cells, rest, changed);
    }

    fn accumulate(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        _: Option<&super::volume::Volume>,
    ) -> Real {
        Springs::accumulate(self, x, v, acc);
        Real::INFINITY
    }

    fn energy(&self, x: &[Vector]) -> Real {
        threads::chunked_sum(self.pairs.len(), |r| self.energy_of(x, r))
    }

    fn measures_in_pass(&self) -> bool {
        true
    }

    fn accumulate_measured(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) -> Real {
        Springs::accumulate_measured(self, x, v, acc)
    }

    fn constant_bounds(&self, bounds: &mut NodeBounds) {
        Springs::constant_bounds(self, bounds);
    }

    fn implicit_terms(&self) -> Option<super::ImplicitTerms<'_>> {
        Some(super::ImplicitTerms {
            springs: Some(self),
            ..Default::default()
        })
    }

    #[cfg(feature = "parallel")]
    fn edge_springs(&self) -> Option<&Springs> {
        Some(self)
    }

    #[cfg(feature = "parallel")]
    fn cost_per_cell(&self) -> usize {
        0
    }

    #[cfg(feature = "parallel")]
    fn cell_slots(&self) -> bool {
        false
    }

    #[cfg(feature = "parallel")]
    fn varying(&self) -> super::Varying {
        match self.law {
            Law::Linear => super::Varying::Nothing,
            Law::Nonlinear => super::Varying::Springs,
        }
    }

    #[cfg(feature = "parallel")]
    fn evaluate(
        &mut self,
        (x, v): (&[Vector], &[Vector]),
        spring_force: &mut [Vector],
        _: &mut [Vector],
        stiffness: &mut [Real],
        _: Option<&super::volume::Volume>,
    ) -> Real {
        Springs::evaluate(self, x, v, spring_force, stiffness.as_chunks_mut::<2>().0);
        Real::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::body::DeformableBuilder;
    use super::super::super::material::Material;
    use super::super::super::math::{Vector, DIM};
    use super::super::super::mesh::CellKind;
    use super::super::{squashed, ElementModel};
    use super::*;

    #[test]
    fn a_force_pass_that_measures_gives_the_bits_of_the_forces_energy_and_ratios_apart() {
        // Enough cells and springs for several chunks of the energy's sums.
        let res = if DIM == 3 { 9 } else { 25 };
        for model in [ElementModel::Springs, ElementModel::NonlinearSprings] {
            // With the volumetric term (ν = 0.3) and without (the lattice's own ratio).
            let lattice = super::super::lattice_poisson(model, CellKind::Simplex).unwrap();
            for nu in [0.3, lattice] {
                let body = DeformableBuilder::cuboid(Vector::splat(0.5), [res; DIM])
                    .model(model)
                    .material(Material {
                        poisson_ratio: nu,
                        ..Material::default()
                    })
                    .build()
                    .unwrap();
                let mut state = body.state.elements.clone();
                assert!(state.measures_in_pass());
                assert_eq!(state.volume.is_some(), nu != lattice, "{model:?}");
                let x = squashed(&body.state.positions, 0.7, 0.2);
                let v: Vec<Vector> = x.iter().map(|p| *p * (0.5 * p[0])).collect();
                let n = x.len();
                let (mut apart, mut fused) = (Accumulator::new(n), Accumulator::new(n));
                let limit = state.accumulate_capped(&x, &v, &mut apart, Real::INFINITY);
                let measured = state.accumulate_measured(&x, &v, &mut fused);
                assert_eq!(measured, Some(state.elastic_energy_and_ratios(&x)));
                assert!(measured.unwrap().0 > 0.0);
                assert_eq!(limit, Real::INFINITY);
                let bits = |a: &Accumulator| {
                    let f = a.force.iter().flat_map(|f| f.to_array()).map(Real::to_bits);
                    let k = a.stiffness.iter().chain(&a.damping).map(|k| k.to_bits());
                    f.chain(k).collect::<Vec<_>>()
                };
                assert_eq!(bits(&fused), bits(&apart), "{model:?}, ν {nu}");
            }
        }
        for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
            let body = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
                .model(model)
                .build()
                .unwrap();
            assert!(!body.state.elements.measures_in_pass(), "{model:?}");
        }
    }

    #[test]
    fn the_linear_springs_in_lanes_add_the_bits_of_one_by_one() {
        // A squashed, sheared, moving lattice with two nodes made to coincide (a spring of
        // zero length, which pushes nothing): every node's force, bit for bit.
        let mut half = Vector::splat(0.05);
        half[0] = 0.3;
        let mut res = [3; DIM];
        res[0] = 9;
        let body = super::super::fixtures::er_lattice(half, res);
        let springs = &super::super::fixtures::er_of(&body).edges;
        let mut x = super::super::squashed(&body.state.positions, 0.7, 2.0);
        let [a, b] = springs.pairs[5];
        x[b as usize] = x[a as usize];
        let v: Vec<Vector> = x.iter().map(|p| *p * -3.0 + Vector::splat(0.1)).collect();
        let mut acc = Accumulator::new(x.len());
        springs.accumulate(&x, &v, &mut acc);
        let mut expected = vec![Vector::ZERO; x.len()];
        for (k, &[i, j]) in springs.pairs.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let f = linear_force(
                x[i],
                x[j],
                v[i],
                v[j],
                springs.rest[k],
                springs.k[k],
                springs.c[k],
            );
            expected[i] += f;
            expected[j] -= f;
        }
        assert!(expected.iter().any(|f| f.length() > 0.0));
        for (i, (got, want)) in acc.force.iter().zip(&expected).enumerate() {
            assert_eq!(
                got.to_array().map(Real::to_bits),
                want.to_array().map(Real::to_bits),
                "node {i}"
            );
        }
    }
}
