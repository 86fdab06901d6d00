//! The shape-based element: each cell pulled towards its rest shape rotated about its
//! centroid (the shape-based elasticity paper, §3–4; its equations were lost in extraction
//! and are restated here and in `docs/ARCHITECTURE.md` §3).
//!
//! With `r_i = x_i − x_c` the current offsets from the cell centroid (equal weights) and `R0_i`
//! the rest offsets, the equilibrium shape is `R_i = M R0_i` for the rotation `M` that makes
//! the internal moment vanish, `Σ r_i × M R0_i = 0` (paper eq. 5–6). The force (eq. 4) is
//!
//! ```text
//! f_i = −k (r_i − R_i) − c v_i,e
//! ```
//!
//! Σ f_i = 0 because both offset sets sum to zero, and Σ r_i × f_i = k Σ r_i × R_i = 0 exactly
//! when `M` solves eq. 6 — i.e. for [`RotationFit::Polar`], and up to the iteration's residual
//! for [`RotationFit::Iterative`].
//!
//! Finding `M`:
//! * 2D (eq. 9): `θ = atan2(Σ R0_i × r_i, Σ R0_i · r_i)`, exact.
//! * 3D (eq. 10–16): from last substep's rotation `q`, with `R_i = q R0_i` and `M ≈ 𝟙 + [w]×`,
//!   solve `(Σ (r_i·R_i) 𝟙 − Σ R_i r_iᵀ) w = Σ R_i × r_i` and rotate by `|w|` about `w/|w|`;
//!   repeat `n` times (§4.2: two is enough in practice). Its fixed point is the rotation of the
//!   polar decomposition of `Σ r_i R0_iᵀ`, offered as [`RotationFit::Polar`].
//!
//! Damping: the paper damps `v_i,e = v_i − v_c` (velocity relative to the centroid), which
//! also damps rigid spin ([`ShapeDamping::Centroid`]); the default subtracts the cell's
//! least-squares rigid motion `v_c + ω × r_i` instead ([`ShapeDamping::RigidMotion`]), which
//! conserves angular momentum.
//!
//! Material mapping: per vertex `k = s E V_cell / Σ|R0_i|²` with `s =` [`MATERIAL_SCALE`]
//! (`747/187 ≈ 3.99` in 3D, `7/3` in 2D), `c = 2 ζ √(k m_cell/n)`. Derivation (Cauchy–Born):
//! under a small uniform strain `ε` a cell stores `½ k min_w Σ |(ε − [w]×) R0_i|²` — the fit
//! removes the rotation, and on a cell whose `Σ R0_i R0_iᵀ` is not isotropic also the skew
//! part a normal strain couples into. For a regular cell that is `½ (s E/DIM) ε:ε`, so
//! `s = DIM`; averaged over the mirrored Kuhn cells of `Mesh::cuboid` the Young's modulus
//! along a lattice axis is `187/747 · s E` in 3D (ν ≈ 0.12) and `3/7 · s E` in 2D (ν = 1/7),
//! and `s` makes it `E`. The `cantilever` scene measures it against beam theory. (Earlier
//! `s = 4.7`, from a prototype's compression test: this lattice 1.18× too stiff in 3D and 2×
//! in 2D.)

use super::super::material::Resolved;
use super::super::math::{self, Real, Rotation, Vector, SIMPLEX_ARITY};
use super::super::mesh::{CellKind, Mesh};
use super::super::threads;
use super::{Accumulator, NodeBounds, RotationFit, ShapeDamping};

/// Calibration constant `s` of the shape-based material mapping: 747/187 in 3D, 7/3 in 2D
/// (see the module's docs).
pub const MATERIAL_SCALE: Real = if super::super::math::DIM == 3 {
    747.0 / 187.0
} else {
    7.0 / 3.0
};

/// Vertices of a cube cell.
const CUBE_ARITY: usize = CellKind::Cube.arity();

/// The rotation the element fits for current offsets `current` (from the centroid) and rest
/// offsets `rest`, starting from `warm` (last substep's rotation).
pub fn fit_rotation(
    rest: &[Vector],
    current: &[Vector],
    fit: RotationFit,
    warm: Rotation,
) -> Rotation {
    match fit {
        RotationFit::Polar => {
            let mut a = math::outer(Vector::ZERO, Vector::ZERO);
            for (r0, r) in rest.iter().zip(current) {
                a += math::outer(*r, *r0);
            }
            math::polar_rotation(a)
        }
        RotationFit::Iterative(n) => math::iterate_rotation(rest, current, warm, n),
    }
}

/// The residual internal moment `|Σ r_i × k (R_i − r_i)|` left by a rotation `q`: zero for the
/// exact fit.
pub fn residual_torque(rest: &[Vector], current: &[Vector], q: Rotation, k: Real) -> Real {
    let mut t = math::ANG_ZERO;
    for (r0, r) in rest.iter().zip(current) {
        t += math::cross(*r, (q * *r0 - *r) * k);
    }
    math::ang_norm(t)
}

/// The law of one shape-based cell: stiffness `k` and damping `c` per vertex, how its rotation
/// is fitted and which velocity is damped.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CellLaw {
    /// Stiffness per vertex, N/m.
    pub k: Real,
    /// Damping per vertex, N·s/m.
    pub c: Real,
    /// How the rotation is found.
    pub fit: RotationFit,
    /// Which velocity is damped.
    pub damping: ShapeDamping,
}

/// Forces of one shape-based element with `N` vertices at `x` moving with `v`, rest offsets
/// `rest` (from the rest centroid), under `law`, its rotation warm-started from `warm`. Returns the force
/// on each vertex, the fitted rotation, and the smallest sum of two singular values of
/// `A = Σ r_i R0_iᵀ` (see `ShapeMatching::turning_stiffness`).
///
/// Offsets are taken from the first vertex before the centroid is subtracted: in `f32` the
/// centroid of coordinates far from the origin, `Σx · (1/n)`, is off by an ulp of `x`, and that
/// error times `k` was a net force on the cell that grew with Young's modulus (a stiff 2D
/// beam stretched 1.3 mm with gravity off).
#[inline]
pub fn element_forces<const N: usize>(
    rest: &[Vector; N],
    x: &[Vector; N],
    v: &[Vector; N],
    law: CellLaw,
    warm: Rotation,
) -> ([Vector; N], Rotation, Real) {
    let CellLaw { k, c, fit, damping } = law;
    let inv_n = 1.0 / N as Real;
    let x0 = x[0];
    let xc = x.iter().map(|xa| *xa - x0).sum::<Vector>() * inv_n;
    let vc = v.iter().copied().sum::<Vector>() * inv_n;
    let r = x.map(|xa| (xa - x0) - xc);
    let dv = v.map(|va| va - vc);
    let q = fit_rotation(rest, &r, fit, warm);
    let mut a = math::outer(Vector::ZERO, Vector::ZERO);
    for (r, r0) in r.iter().zip(rest) {
        a += math::outer(*r, *r0);
    }
    let pair = math::least_singular_pair_sum(a);
    let w = match damping {
        ShapeDamping::RigidMotion if c > 0.0 => math::rigid_angular_velocity(&r, &dv),
        _ => math::ANG_ZERO,
    };
    let mut out = [Vector::ZERO; N];
    for a in 0..N {
        let goal = q * rest[a];
        let ve = dv[a] - math::ang_cross(w, r[a]);
        out[a] = (goal - r[a]) * k - ve * c;
    }
    (out, q, pair)
}

/// Shape-based elements on any cells.
#[derive(Clone, Debug)]
pub(crate) struct ShapeMatching {
    kind: CellKind,
    arity: usize,
    cells: Vec<u32>,
    rest: Vec<Vector>,
    k: Vec<Real>,
    c: Vec<Real>,
    /// Per cell: `Σ_b |R0_b|`, and the smallest singular pair sum of `Σ R0 R0ᵀ` at rest.
    rest_sum: Vec<Real>,
    rest_pair: Vec<Real>,
    /// Per simplex cell, its signed rest volume (empty for cubes).
    rest_volume: Vec<Real>,
    rotations: Vec<Rotation>,
    fit: RotationFit,
    damping: ShapeDamping,
}

impl ShapeMatching {
    pub fn build(
        mesh: &Mesh,
        params: &Resolved,
        fit: RotationFit,
        damping: ShapeDamping,
        initial: Rotation,
    ) -> Self {
        let arity = mesh.kind().arity();
        let nodes = mesh.nodes();
        let cells = mesh.num_cells();
        let simplex = arity == SIMPLEX_ARITY;
        let mut out = ShapeMatching {
            kind: mesh.kind(),
            arity,
            cells: mesh.cell_indices().to_vec(),
            rest: vec![Vector::ZERO; mesh.cell_indices().len()],
            k: Vec::new(),
            c: Vec::new(),
            rest_sum: vec![0.0; cells],
            rest_pair: vec![0.0; cells],
            rest_volume: vec![0.0; if simplex { cells } else { 0 }],
            rotations: vec![initial; cells],
            fit,
            damping,
        };
        for (cell, ids) in mesh.cells().enumerate() {
            let spread = out.set_cell_rest(cell, |a| nodes[ids[a] as usize]);
            let v = mesh.rest_volumes()[cell];
            let material_k = MATERIAL_SCALE * params.material.young_modulus * v / spread;
            let (k, c) = params.k_c(material_k, params.material.density * v / arity as Real);
            out.k.push(k);
            out.c.push(c);
        }
        out
    }

    /// Sets cell `cell`'s rest offsets (from its centroid) and what is derived from them, its
    /// vertices at rest at `p(a)`; returns `Σ |R0_a|²`.
    fn set_cell_rest(&mut self, cell: usize, p: impl Fn(usize) -> Vector) -> Real {
        let n = self.arity;
        let o = p(0);
        let centroid = (0..n).map(|a| p(a) - o).sum::<Vector>() / n as Real;
        let mut spread = 0.0;
        let mut sum = 0.0;
        let mut pairs = math::outer(Vector::ZERO, Vector::ZERO);
        for a in 0..n {
            let r0 = (p(a) - o) - centroid;
            spread += r0.length_squared();
            sum += r0.length();
            pairs += math::outer(r0, r0);
            self.rest[cell * n + a] = r0;
        }
        self.rest_sum[cell] = sum;
        self.rest_pair[cell] = math::least_singular_pair_sum(pairs);
        if n == SIMPLEX_ARITY {
            let rest: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| self.rest[cell * n + a]);
            self.rest_volume[cell] = math::simplex_volume(&rest);
        }
        spread
    }

    /// Each cell's warm-start rotation (the last fitted one).
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn rotations(&self) -> &[Rotation] {
        &self.rotations
    }

    /// Restores the warm-start rotations. `Err(expected length)` if the length is wrong.
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn set_rotations(&mut self, rotations: &[Rotation]) -> Result<(), usize> {
        if rotations.len() != self.rotations.len() {
            return Err(self.rotations.len());
        }
        self.rotations.copy_from_slice(rotations);
        Ok(())
    }

    /// Adds the cells' bounds that do not change with the state: the row bound of
    /// `k (𝟙 − 𝟏𝟏ᵀ/n)`, `2k(1 − 1/n) ≤ 2k`. The fitted rotation's dependence on the nodes adds
    /// a part that does change ([`ShapeMatching::turning_stiffness`]).
    pub fn constant_bounds(&self, bounds: &mut NodeBounds) {
        for (cell, ids) in self.cells.chunks_exact(self.arity).enumerate() {
            for &i in ids {
                bounds.stiffness[i as usize] += 2.0 * self.k[cell];
                bounds.damping[i as usize] += 2.0 * self.c[cell];
            }
        }
    }

    /// The stiffness row bound that the fitted rotation adds to vertex `a` of `cell`, given the
    /// smallest singular pair sum `pair` of the cell's `A = Σ r_b R0_bᵀ` now.
    ///
    /// The goal `R R0_a` turns with `R`, and `|δR| ≤ |δA| / pair ≤ Σ_b |δx_b| |R0_b| / pair`
    /// (the polar decomposition's rotation turns at `1/(σᵢ + σⱼ)`), so the row of vertex `a`
    /// gains `k |R0_a| Σ_b |R0_b| / pair`: about `k` for a cell at rest, growing as a cell is
    /// flattened (without it the substep came from `2k` alone and the manipulator's strikes
    /// blew shape matching up, in 2D and 3D). `pair` is taken no smaller than a twentieth of its
    /// rest value: a cell crushed flat would otherwise stop the body's clock.
    #[inline]
    fn turning_stiffness(&self, cell: usize, pair: Real) -> Real {
        turning(
            self.k[cell],
            self.rest_sum[cell],
            self.rest_pair[cell],
            pair,
        )
    }

    /// Adds the cells' forces into `acc` and advances each cell's warm-start rotation.
    pub fn accumulate(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        match self.kind {
            CellKind::Simplex => self.accumulate_n::<SIMPLEX_ARITY>(x, v, acc),
            CellKind::Cube => self.accumulate_n::<CUBE_ARITY>(x, v, acc),
        }
    }

    fn accumulate_n<const N: usize>(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        let n = x.len();
        let (v, force, stiffness) = (&v[..n], &mut acc.force[..n], &mut acc.stiffness[..n]);
        let (fit, damping) = (self.fit, self.damping);
        let (cells, _) = self.cells.as_chunks::<N>();
        let (rest, _) = self.rest.as_chunks::<N>();
        for (cell, (ids, rest)) in cells.iter().zip(rest).enumerate() {
            let (k, c, q) = (self.k[cell], self.c[cell], self.rotations[cell]);
            let law = CellLaw { k, c, fit, damping };
            let (f, q, pair) = cell_forces(ids, rest, law, q, x, v);
            self.rotations[cell] = q;
            let turning = self.turning_stiffness(cell, pair);
            for a in 0..N {
                let i = ids[a] as usize;
                force[i] += f[a];
                stiffness[i] += turning * rest[a].length();
            }
        }
    }

    /// Writes each cell's force on each of its vertices into `force` and its turning
    /// stiffness into `stiffness` (one entry per slot) and advances the cells' rotations, on
    /// rayon's threads.
    #[cfg(feature = "parallel")]
    pub fn evaluate_cells(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) {
        match self.kind {
            CellKind::Simplex => self.evaluate_cells_n::<SIMPLEX_ARITY>(x, v, force, stiffness),
            CellKind::Cube => self.evaluate_cells_n::<CUBE_ARITY>(x, v, force, stiffness),
        }
    }

    #[cfg(feature = "parallel")]
    fn evaluate_cells_n<const N: usize>(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        force: &mut [Vector],
        stiffness: &mut [Real],
    ) {
        use super::parallel::CELLS_PER_TASK as CHUNK;
        use rayon::prelude::*;
        let v = &v[..x.len()];
        let (fit, damping) = (self.fit, self.damping);
        let (cells, _) = self.cells.as_chunks::<N>();
        let (rest, _) = self.rest.as_chunks::<N>();
        let (k, c) = (&self.k, &self.c);
        let (rest_sum, rest_pair) = (&self.rest_sum, &self.rest_pair);
        let (out, _) = force.as_chunks_mut::<N>();
        let (out_k, _) = stiffness.as_chunks_mut::<N>();
        out.par_chunks_mut(CHUNK)
            .zip(out_k.par_chunks_mut(CHUNK))
            .zip(self.rotations.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(t, ((out, out_k), rotations))| {
                let first = t * CHUNK;
                let slots = out.iter_mut().zip(out_k).zip(rotations);
                for (j, ((f, fk), q)) in slots.enumerate() {
                    let cell = first + j;
                    let (ids, rest) = (&cells[cell], &rest[cell]);
                    let pair;
                    let law = CellLaw {
                        k: k[cell],
                        c: c[cell],
                        fit,
                        damping,
                    };
                    (*f, *q, pair) = cell_forces(ids, rest, law, *q, x, v);
                    let turning = turning(k[cell], rest_sum[cell], rest_pair[cell], pair);
                    for a in 0..N {
                        fk[a] = turning * rest[a].length();
                    }
                }
            });
    }

    /// The elastic energy of cells `cells`.
    pub fn energy_of(&self, x: &[Vector], cells: std::ops::Range<usize>) -> Real {
        let n = self.arity;
        let mut e = 0.0;
        for cell in cells {
            let ids = &self.cells[cell * n..(cell + 1) * n];
            let o = x[ids[0] as usize];
            let xc = ids.iter().map(|&i| x[i as usize] - o).sum::<Vector>() / n as Real;
            let q = self.rotations[cell];
            for (a, &i) in ids.iter().enumerate() {
                let goal = q * self.rest[cell * n + a];
                e += 0.5 * self.k[cell] * ((x[i as usize] - o) - xc - goal).length_squared();
            }
        }
        e
    }
}

/// Smallest singular pair sum a cell's turning stiffness is computed with, as a fraction of
/// its rest value (see [`ShapeMatching::turning_stiffness`]).
const TURNING_FLOOR: Real = 0.05;

/// `k Σ_b |R0_b| / max(pair, TURNING_FLOOR · rest_pair)`: the turning stiffness per unit of
/// `|R0_a|`.
#[inline]
fn turning(k: Real, rest_sum: Real, rest_pair: Real, pair: Real) -> Real {
    k * rest_sum / pair.max(TURNING_FLOOR * rest_pair)
}

/// [`element_forces`] of the cell with vertices `ids`.
#[inline(always)]
fn cell_forces<const N: usize>(
    ids: &[u32; N],
    rest: &[Vector; N],
    law: CellLaw,
    warm: Rotation,
    x: &[Vector],
    v: &[Vector],
) -> ([Vector; N], Rotation, Real) {
    let xs = ids.map(|i| x[i as usize]);
    let vs = ids.map(|i| v[i as usize]);
    element_forces(rest, &xs, &vs, law, warm)
}

/// The implicit step's view of the cells (`implicit.rs`): the rotation of each cell is held
/// while the nodes sweep, and refitted between sweeps.
impl ShapeMatching {
    /// Vertices per cell.
    pub(super) fn arity(&self) -> usize {
        self.arity
    }

    /// The cells' vertex indices, `arity` per cell.
    pub(super) fn cell_indices(&self) -> &[u32] {
        &self.cells
    }

    /// The cells' warm-start rotations, for the implicit step to advance.
    pub(super) fn rotations_mut(&mut self) -> &mut [Rotation] {
        &mut self.rotations
    }

    /// Vertex `a`'s residual `r_a − q R0_a` in `cell` at `x`, offsets from the centroid.
    #[inline]
    pub(super) fn residual(&self, cell: usize, a: usize, x: &[Vector], q: Rotation) -> Vector {
        self.residual_with(cell, a, |i| x[i], q)
    }

    /// [`ShapeMatching::residual`] with node `i` at `x(i)`.
    #[inline(always)]
    pub(super) fn residual_with(
        &self,
        cell: usize,
        a: usize,
        x: impl Fn(usize) -> Vector,
        q: Rotation,
    ) -> Vector {
        let n = self.arity;
        let ids = &self.cells[cell * n..(cell + 1) * n];
        let o = x(ids[0] as usize);
        let xc = ids.iter().map(|&i| x(i as usize) - o).sum::<Vector>() / n as Real;
        (x(ids[a] as usize) - o) - xc - q * self.rest[cell * n + a]
    }

    /// Refits every cell's rotation at `x`, each from its value in `rotations`.
    pub(super) fn refit(&self, x: &[Vector], rotations: &mut [Rotation]) {
        let n = self.arity;
        threads::for_each_mut(rotations, |cell, q| {
            let mut r = [Vector::ZERO; CUBE_ARITY];
            let ids = &self.cells[cell * n..(cell + 1) * n];
            let o = x[ids[0] as usize];
            let xc = ids.iter().map(|&i| x[i as usize] - o).sum::<Vector>() / n as Real;
            for (r, &i) in r.iter_mut().zip(ids) {
                *r = (x[i as usize] - o) - xc;
            }
            let rest = &self.rest[cell * n..(cell + 1) * n];
            *q = fit_rotation(rest, &r[..n], self.fit, *q);
        });
    }

    /// A simplex cell's signed volume at `x` over its rest volume.
    pub(super) fn volume_ratio(&self, cell: usize, x: &[Vector]) -> Real {
        let n = self.arity;
        let ids = &self.cells[cell * n..(cell + 1) * n];
        self.volume_ratio_of(cell, &std::array::from_fn(|a| x[ids[a] as usize]))
    }

    /// [`ShapeMatching::volume_ratio`] with the cell's vertices at `now`.
    pub(super) fn volume_ratio_of(&self, cell: usize, now: &[Vector; SIMPLEX_ARITY]) -> Real {
        math::simplex_volume(now) / self.rest_volume[cell]
    }

    /// Stiffness and damping per vertex of `cell`.
    pub(super) fn law(&self, cell: usize) -> (Real, Real) {
        (self.k[cell], self.c[cell])
    }
}

impl super::ElementLaw for ShapeMatching {
    fn boxed_clone(&self) -> Box<dyn super::ElementLaw> {
        Box::new(self.clone())
    }

    fn accumulate(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        acc: &mut Accumulator,
        _: Option<&super::volume::Volume>,
    ) -> Real {
        ShapeMatching::accumulate(self, x, v, acc);
        Real::INFINITY
    }

    fn energy(&self, x: &[Vector]) -> Real {
        threads::chunked_sum(self.rotations.len(), |r| self.energy_of(x, r))
    }

    fn constant_bounds(&self, bounds: &mut NodeBounds) {
        ShapeMatching::constant_bounds(self, bounds);
    }

    fn rotations(&self) -> &[Rotation] {
        ShapeMatching::rotations(self)
    }

    fn set_rotations(&mut self, rotations: &[Rotation]) -> Result<(), usize> {
        ShapeMatching::set_rotations(self, rotations)
    }

    fn flows(&self) -> bool {
        true
    }

    fn set_rest(&mut self, _: &[u32], rest: &[Vector], changed: &[u32]) {
        let n = self.arity;
        for &cell in changed {
            let cell = cell as usize;
            self.set_cell_rest(cell, |a| rest[cell * n + a]);
        }
    }

    fn implicit_terms(&self) -> Option<super::ImplicitTerms<'_>> {
        Some(super::ImplicitTerms {
            shape: Some(self),
            ..Default::default()
        })
    }

    /// Its rotations held, each cell's energy is quadratic in its vertices.
    fn convex_implicit(&self) -> bool {
        true
    }

    fn shape_mut(&mut self) -> Option<&mut ShapeMatching> {
        Some(self)
    }

    #[cfg(feature = "parallel")]
    fn edge_springs(&self) -> Option<&super::springs::Springs> {
        None
    }

    #[cfg(feature = "parallel")]
    fn cost_per_cell(&self) -> usize {
        30
    }

    #[cfg(feature = "parallel")]
    fn varying(&self) -> super::Varying {
        super::Varying::Cells
    }

    #[cfg(feature = "parallel")]
    fn evaluate(
        &mut self,
        (x, v): (&[Vector], &[Vector]),
        _: &mut [Vector],
        slot_force: &mut [Vector],
        stiffness: &mut [Real],
        _: Option<&super::volume::Volume>,
    ) -> Real {
        self.evaluate_cells(x, v, slot_force, stiffness);
        Real::INFINITY
    }
}
