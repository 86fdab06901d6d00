//! The volumetric term that gives a model the Poisson's ratio asked for (issue 15).
//!
//! Each simplex cell stores `κ V0/2 (J − 1)²`, `J = D/D0` its volume over its rest volume
//! (`D` as in [`math::simplex_gradients`]): force `−κ V0 (J − 1) g_a / D0` on vertex `a`.
//! Under a small uniform strain it adds `κ` to `C11` and `C12` of the lattice and nothing to its
//! shear, so together with a scale `σ` of the model's own terms it sets both Young's modulus and
//! Poisson's ratio along a lattice axis ([`mapping`]). `κ` is negative when the ratio asked is
//! below the lattice's own; the sum stays positive definite for any `ν > −1` (the bulk modulus
//! is that of the material asked), but the term alone is not, so the implicit step leaves its
//! block out then (its gradient is exact either way).

use std::ops::Range;

use super::super::math::{self, Matrix, Real, Vector, DIM, DIM_FACTORIAL, SIMPLEX_ARITY};
use super::super::threads;
use super::lanes::{self, each, Lane, LaneVector, LANES};
use super::Accumulator;

/// The scale `σ` of a model's own terms and the volumetric modulus `κ` (over `E`) that give a
/// lattice of Poisson's ratio `lattice` (and Young's modulus `E` along its axes) the ratio
/// `nu`, keeping `E`.
///
/// Along an axis of a cubic lattice, `E = (C11 − C12)(C11 + (DIM−1) C12)/(C11 + (DIM−2) C12)`
/// and `ν = C12/(C11 + (DIM−2) C12)`; `C11 − C12 = E/(1 + ν)` in both dimensions, so
/// `σ = (1 + ν_lattice)/(1 + ν)` keeps the shear and `κ = C12(ν) − σ C12(ν_lattice)`, with
/// `C12 = E ν/((1 + ν)(1 − 2ν))` in 3D and `E ν/(1 − ν²)` in 2D.
pub fn mapping(lattice: Real, nu: Real) -> (Real, Real) {
    let sigma = (1.0 + lattice) / (1.0 + nu);
    let c12 = |n: Real| {
        if DIM == 3 {
            n / ((1.0 + n) * (1.0 - 2.0 * n))
        } else {
            n / (1.0 - n * n)
        }
    };
    (sigma, c12(nu) - sigma * c12(lattice))
}

/// Volumetric terms on simplex cells.
#[derive(Clone, Debug)]
pub(crate) struct Volume {
    cells: Vec<u32>,
    /// Per cell: rest `D`, and `κ V0`.
    d0: Vec<Real>,
    k: Vec<Real>,
}

impl Volume {
    /// Terms of modulus `kappa` (Pa) on the simplex cells `cells` at rest positions `nodes`.
    pub fn build(cells: &[u32], nodes: &[Vector], kappa: Real) -> Self {
        let mut out = Volume {
            cells: cells.to_vec(),
            d0: Vec::new(),
            k: Vec::new(),
        };
        for ids in cells.chunks_exact(SIMPLEX_ARITY) {
            let p: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| nodes[ids[a] as usize]);
            let (d0, _) = math::simplex_gradients(&p);
            out.d0.push(d0);
            out.k.push(kappa * d0.abs() / DIM_FACTORIAL);
        }
        out
    }

    /// Sets the rest `D` of the cells `changed` from their rest vertices `rest` (by slot), after
    /// plastic flow; `κ V0` stays the built cell's.
    pub fn set_rest(&mut self, rest: &[Vector], changed: &[u32]) {
        for &cell in changed {
            let cell = cell as usize;
            let p: [Vector; SIMPLEX_ARITY] =
                std::array::from_fn(|a| rest[cell * SIMPLEX_ARITY + a]);
            self.d0[cell] = math::simplex_gradients(&p).0;
        }
    }

    /// The scale of cell `cell`'s Gauss–Newton Hessian `κ V0/D0² ∇D ∇Dᵀ` (zero for a
    /// negative `κ`, as in [`Volume::vertex_terms_at`]).
    pub fn hessian_scale(&self, cell: usize) -> Real {
        let d0 = self.d0[cell];
        let k = self.k[cell] / (d0 * d0);
        if k > 0.0 && k.is_finite() {
            k
        } else {
            0.0
        }
    }

    /// The cells' vertex indices.
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// Adds the forces and their stiffness bounds (`|κ| V0 |g_a| Σ_b |g_b| / D0²`, the
    /// Gershgorin row of `κ V0 ∇J ∇Jᵀ`), [`LANES`] cells at a time.
    pub fn accumulate(&self, x: &[Vector], acc: &mut Accumulator) {
        self.accumulate_cells::<false>(0..self.d0.len(), x, acc);
    }

    /// [`Volume::accumulate`] (the same bits) and the cells' energy and volume ratios, those
    /// of [`Volume::energy_and_ratios`] over the chunks of [`threads::chunked_fold`] combined
    /// by [`both`] (the same bits), in one pass.
    pub fn accumulate_measured(&self, x: &[Vector], acc: &mut Accumulator) -> (Real, Ratios) {
        threads::chunks(self.d0.len())
            .map(|cells| self.accumulate_cells::<true>(cells, x, acc))
            .reduce(both)
            .unwrap_or((0.0, Ratios::NONE))
    }

    /// Adds the forces and stiffness bounds of `cells`; with `MEASURE`, returns their energy
    /// and volume ratios as [`Volume::energy_and_ratios`] gives them (else nothing measured).
    fn accumulate_cells<const MEASURE: bool>(
        &self,
        cells: Range<usize>,
        x: &[Vector],
        acc: &mut Accumulator,
    ) -> (Real, Ratios) {
        let (ids, _) = self.cells.as_chunks::<SIMPLEX_ARITY>();
        let n = x.len();
        let (force, stiffness) = (&mut acc.force[..n], &mut acc.stiffness[..n]);
        let mut measure = LaneMeasure::new();
        for first in cells.clone().step_by(LANES) {
            // The last batch repeats its last cell in the lanes past the end.
            let batch: [usize; LANES] = each(|l| (first + l).min(cells.end - 1));
            let p: [LaneVector; SIMPLEX_ARITY] =
                each(|a| LaneVector::gather(|l| x[ids[batch[l]][a] as usize]));
            let (d, g) = lanes::simplex_gradients(&p);
            let length: [Lane; SIMPLEX_ARITY] = each(|a| g[a].length_squared().sqrt());
            let (f, row) = self.cell_lanes(batch, d, &g, &length);
            let f: [[Vector; LANES]; SIMPLEX_ARITY] = each(|a| f[a].lanes());
            let row: [[Real; LANES]; SIMPLEX_ARITY] = each(|a| row[a].to_array());
            for l in 0..LANES.min(cells.end - first) {
                for a in 0..SIMPLEX_ARITY {
                    let i = ids[first + l][a] as usize;
                    force[i] += f[a][l];
                    stiffness[i] += row[a][l];
                }
            }
            if MEASURE {
                measure.add(self, batch, cells.end - first, d);
            }
        }
        measure.finish()
    }

    /// [`LANES`] cells `cells`, from their `D`, its gradients and their lengths: the force on
    /// each vertex and its stiffness bound.
    #[inline(always)]
    pub fn cell_lanes(
        &self,
        cells: [usize; LANES],
        d: Lane,
        g: &[LaneVector; SIMPLEX_ARITY],
        length: &[Lane; SIMPLEX_ARITY],
    ) -> ([LaneVector; SIMPLEX_ARITY], [Lane; SIMPLEX_ARITY]) {
        let d0 = Lane::new(each(|l| self.d0[cells[l]]));
        let (strain, k) = (
            d / d0 - Lane::ONE,
            Lane::new(each(|l| self.k[cells[l]])) / d0,
        );
        let mut sum = length[0];
        for l in &length[1..] {
            sum += *l;
        }
        let row = (k / d0).abs() * sum;
        (each(|a| -(g[a] * (k * strain))), each(|a| row * length[a]))
    }

    /// Vertex `a` of `cell`: `−∂E/∂x_a` and its Gauss–Newton block `κ V0 ∇_a J ∇_a Jᵀ` (left
    /// out for a negative `κ`).
    #[cfg(test)]
    pub fn vertex_terms(&self, cell: usize, a: usize, x: &[Vector]) -> (Vector, Matrix) {
        let ids = &self.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
        let p: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| x[ids[a] as usize]);
        let (d, g) = math::simplex_gradients(&p);
        self.vertex_terms_at(cell, a, d, &g)
    }

    /// [`Volume::vertex_terms`] from the cell's `D` and its gradients, already evaluated.
    #[inline]
    pub fn vertex_terms_at(
        &self,
        cell: usize,
        a: usize,
        d: Real,
        g: &[Vector; SIMPLEX_ARITY],
    ) -> (Vector, Matrix) {
        let d0 = self.d0[cell];
        let (strain, k) = (d / d0 - 1.0, self.k[cell] / d0);
        let block = if k * self.d0[cell] > 0.0 {
            math::outer(g[a], g[a]) * (k / self.d0[cell])
        } else {
            Matrix::ZERO
        };
        (-g[a] * (k * strain), block)
    }

    /// [`Volume::vertex_terms_at`] of [`LANES`] cells `cells` at one vertex each, from their
    /// `D` and the gradient `ga` at that vertex: the force, and the scale `s` of the block
    /// `s ga gaᵀ`.
    #[inline(always)]
    pub fn vertex_lanes(
        &self,
        cells: [usize; LANES],
        d: Lane,
        ga: LaneVector,
    ) -> (LaneVector, Lane) {
        let d0 = Lane::new(each(|l| self.d0[cells[l]]));
        let (strain, k) = (
            d / d0 - Lane::ONE,
            Lane::new(each(|l| self.k[cells[l]])) / d0,
        );
        let scale = (k * d0).simd_gt(Lane::ZERO).select(k / d0, Lane::ZERO);
        (-(ga * (k * strain)), scale)
    }

    #[cfg(test)]
    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        self.energy_of(x, 0..self.d0.len())
    }

    /// The elastic energy of cells `cells`.
    pub fn energy_of(&self, x: &[Vector], cells: Range<usize>) -> Real {
        self.energy_and_ratios(x, cells).0
    }

    /// The elastic energy of cells `cells` and their volume ratios, one pass [`LANES`] cells
    /// at a time. A ratio is `(D/DIM!) / (D0/DIM!)`, which rounds as [`Mesh::cell_quality`]
    /// (whose rest volume is `D0/DIM!`).
    ///
    /// [`Mesh::cell_quality`]: super::super::mesh::Mesh::cell_quality
    #[inline]
    pub fn energy_and_ratios(&self, x: &[Vector], cells: Range<usize>) -> (Real, Ratios) {
        let (ids, _) = self.cells.as_chunks::<SIMPLEX_ARITY>();
        let mut measure = LaneMeasure::new();
        for first in cells.clone().step_by(LANES) {
            // The last batch repeats its last cell in the lanes past the end, and counts it
            // once.
            let batch: [usize; LANES] = each(|l| (first + l).min(cells.end - 1));
            let p: [LaneVector; SIMPLEX_ARITY] =
                each(|a| LaneVector::gather(|l| x[ids[batch[l]][a] as usize]));
            // `D` alone: the optimiser drops the gradients.
            let (d, _) = lanes::simplex_gradients(&p);
            measure.add(self, batch, cells.end - first, d);
        }
        measure.finish()
    }
}

/// The energy and volume ratios of cells measured [`LANES`] at a time, lane by lane.
struct LaneMeasure {
    energy: Lane,
    inverted: usize,
    least: Lane,
    most: Lane,
}

impl LaneMeasure {
    fn new() -> Self {
        LaneMeasure {
            energy: Lane::ZERO,
            inverted: 0,
            least: Lane::splat(Real::INFINITY),
            most: Lane::splat(-Real::INFINITY),
        }
    }

    /// Adds the cells `batch` of `volume`, of determinants `d`, of which the first `counted`
    /// lanes count (the others repeat the last cell).
    #[inline(always)]
    fn add(&mut self, volume: &Volume, batch: [usize; LANES], counted: usize, d: Lane) {
        let lane_index = Lane::new(each(|l| l as Real));
        let counted = lane_index.simd_lt(Lane::splat(counted as Real));
        let d0 = Lane::new(each(|l| volume.d0[batch[l]]));
        let k = Lane::new(each(|l| volume.k[batch[l]]));
        let strain = d / d0 - Lane::ONE;
        self.energy += counted.select(Lane::splat(0.5) * k * strain * strain, Lane::ZERO);
        let factorial = Lane::splat(DIM_FACTORIAL);
        let ratio = (d / factorial) / (d0 / factorial);
        self.inverted += (ratio.simd_le(Lane::ZERO) & counted)
            .to_bitmask()
            .count_ones() as usize;
        self.least = counted
            .select(ratio, Lane::splat(Real::INFINITY))
            .fast_min(self.least);
        self.most = counted
            .select(ratio, Lane::splat(-Real::INFINITY))
            .fast_max(self.most);
    }

    fn finish(self) -> (Real, Ratios) {
        let ratios = Ratios {
            inverted: self.inverted,
            least: self
                .least
                .to_array()
                .into_iter()
                .fold(Real::INFINITY, Real::min),
            most: self
                .most
                .to_array()
                .into_iter()
                .fold(-Real::INFINITY, Real::max),
        };
        (self.energy.reduce_add(), ratios)
    }
}

/// The energy and volume ratios of two sets of cells, as [`Volume::energy_and_ratios`]
/// gives them, taken together (`a`'s first).
pub(crate) fn both((e1, r1): (Real, Ratios), (e2, r2): (Real, Ratios)) -> (Real, Ratios) {
    (e1 + e2, r1.and(r2))
}

/// The volume ratios `V/V0` of some cells.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Ratios {
    /// Cells collapsed or inverted (ratio ≤ 0).
    pub inverted: usize,
    /// The smallest ratio (infinite for no cell).
    pub least: Real,
    /// The largest ratio (minus infinity for no cell).
    pub most: Real,
}

impl Ratios {
    /// Those of no cell.
    pub const NONE: Ratios = Ratios {
        inverted: 0,
        least: Real::INFINITY,
        most: -Real::INFINITY,
    };

    /// Those of the cells of both.
    pub fn and(self, o: Ratios) -> Ratios {
        Ratios {
            inverted: self.inverted + o.inverted,
            least: self.least.min(o.least),
            most: self.most.max(o.most),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mapping_keeps_the_lattice_as_it_is_and_gives_any_ratio_its_moduli() {
        let (s, k) = mapping(0.2, 0.2);
        assert!((s - 1.0).abs() < 1e-6 && k.abs() < 1e-6);
        // C11 and C12 of the scaled lattice plus κ are the isotropic material's.
        let c = |n: Real| {
            let c12 = if DIM == 3 {
                n / ((1.0 + n) * (1.0 - 2.0 * n))
            } else {
                n / (1.0 - n * n)
            };
            (c12 + 1.0 / (1.0 + n), c12)
        };
        for (lattice, nu) in [(0.15, 0.0), (0.15, 0.3), (0.2, 0.45), (1.0 / 7.0, 0.49)] {
            let (s, k) = mapping(lattice, nu);
            let ((a11, a12), (b11, b12)) = (c(lattice), c(nu));
            assert!((s * a11 + k - b11).abs() < 1e-4 * b11, "{lattice} {nu}");
            assert!((s * a12 + k - b12).abs() < 1e-4 * b11, "{lattice} {nu}");
        }
    }

    #[test]
    fn the_energy_pass_measures_each_cells_ratio_as_the_mesh_does() {
        use super::super::super::mesh::{CellKind, Mesh};
        let mesh = Mesh::cuboid(Vector::splat(0.5), [5; DIM], CellKind::Simplex).unwrap();
        let v = Volume::build(mesh.cell_indices(), mesh.nodes(), 2.0);
        // One half squashed, the other folded through itself (inverted cells), sheared.
        let x: Vec<Vector> = mesh
            .nodes()
            .iter()
            .map(|p| {
                let mut q = *p;
                q[1] *= if p[0] > 0.1 { -0.3 } else { 0.7 };
                q[0] += 0.2 * p[1];
                q
            })
            .collect();
        let cells = mesh.num_cells();
        // Whole, and cut where a batch of lanes is part full at both ends.
        for range in [0..cells, 3..cells - 2, 5..6] {
            let (energy, ratios) = v.energy_and_ratios(&x, range.clone());
            let quality: Vec<Real> = range.clone().map(|c| mesh.cell_quality(c, &x)).collect();
            let inverted = quality.iter().filter(|q| **q <= 0.0).count();
            let least = quality.iter().copied().fold(Real::INFINITY, Real::min);
            let most = quality.iter().copied().fold(-Real::INFINITY, Real::max);
            assert_eq!(
                (ratios.inverted, ratios.least, ratios.most),
                (inverted, least, most)
            );
            let expected: Real = range
                .zip(&quality)
                .map(|(c, q)| 0.5 * v.k[c] * (q - 1.0).powi(2))
                .sum();
            assert!(
                (energy - expected).abs() <= 1e-4 * expected,
                "{energy} {expected}"
            );
        }
        assert!(v.energy_and_ratios(&x, 0..cells).1.inverted > 0);
    }

    #[test]
    fn forces_are_the_energys_gradient_and_the_block_its_hessian_at_rest() {
        let mut nodes: Vec<Vector> = (0..SIMPLEX_ARITY)
            .map(|a| {
                let mut p = Vector::ZERO;
                if a > 0 {
                    p[a - 1] = 1.0;
                }
                p
            })
            .collect();
        let cells: Vec<u32> = (0..SIMPLEX_ARITY as u32).collect();
        let v = Volume::build(&cells, &nodes, 3.0);
        nodes[1] += Vector::splat(0.1);
        let eps = 1e-2;
        for a in 0..SIMPLEX_ARITY {
            let (f, _) = v.vertex_terms(0, a, &nodes);
            for d in 0..DIM {
                let mut plus = nodes.clone();
                let mut minus = nodes.clone();
                plus[a][d] += eps;
                minus[a][d] -= eps;
                let fd = (v.elastic_energy(&plus) - v.elastic_energy(&minus)) / (2.0 * eps);
                assert!((fd + f[d]).abs() < 1e-2 * f.length().max(1e-2), "{a} {d}");
            }
        }
        // At rest the Gauss–Newton block is the exact Hessian.
        let rest = Volume::build(&cells, &nodes, 3.0);
        let (_, block) = rest.vertex_terms(0, 2, &nodes);
        for d in 0..DIM {
            let mut plus = nodes.clone();
            let mut minus = nodes.clone();
            plus[2][d] += eps;
            minus[2][d] -= eps;
            let col = (rest.vertex_terms(0, 2, &minus).0 - rest.vertex_terms(0, 2, &plus).0)
                / (2.0 * eps);
            assert!((col - block.col(d)).length() < 1e-2 * block.col(d).length().max(1e-3));
        }
    }
}
