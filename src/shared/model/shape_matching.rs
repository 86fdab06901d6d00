//! The shape-based element: each cell pulled towards its rest shape rotated about its
//! centroid (the shape-based elasticity paper, §3–4; its equations were lost in extraction
//! and are restated here and in `DESIGN.md` §3).
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
//! Material mapping: per vertex `k = s E V_cell / Σ|R0_i|²` with [`MATERIAL_SCALE`]` = 4.7`
//! (`DESIGN.md` §4, lesson 9), `c = 2 ζ √(k m_cell/n)`.

use super::super::material::Resolved;
use super::super::math::{self, Real, Rotation, Vector};
use super::super::mesh::Mesh;
use super::{Accumulator, RotationFit, ShapeDamping};

/// Calibration constant `s` of the shape-based material mapping.
pub const MATERIAL_SCALE: Real = 4.7;

/// Largest cell arity (hexahedron).
const MAX_ARITY: usize = 8;

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

/// Forces of one shape-based element with vertices at `x` moving with `v`, rest offsets
/// `rest` (from the rest centroid), stiffness `k` and damping `c` per vertex. Writes the force
/// on each vertex into `out` and returns the fitted rotation.
#[allow(clippy::too_many_arguments)]
pub fn element_forces(
    rest: &[Vector],
    x: &[Vector],
    v: &[Vector],
    k: Real,
    c: Real,
    fit: RotationFit,
    damping: ShapeDamping,
    warm: Rotation,
    out: &mut [Vector],
) -> Rotation {
    let n = rest.len();
    let inv_n = 1.0 / n as Real;
    let xc = x.iter().copied().sum::<Vector>() * inv_n;
    let vc = v.iter().copied().sum::<Vector>() * inv_n;
    let mut r = [Vector::ZERO; MAX_ARITY];
    let mut dv = [Vector::ZERO; MAX_ARITY];
    for a in 0..n {
        r[a] = x[a] - xc;
        dv[a] = v[a] - vc;
    }
    let q = fit_rotation(rest, &r[..n], fit, warm);
    let w = match damping {
        ShapeDamping::RigidMotion if c > 0.0 => math::rigid_angular_velocity(&r[..n], &dv[..n]),
        _ => math::ANG_ZERO,
    };
    for a in 0..n {
        let goal = q * rest[a];
        let ve = dv[a] - math::ang_cross(w, r[a]);
        out[a] = (goal - r[a]) * k - ve * c;
    }
    q
}

/// Shape-based elements on any cells.
#[derive(Clone, Debug)]
pub(crate) struct ShapeMatching {
    arity: usize,
    cells: Vec<u32>,
    rest: Vec<Vector>,
    k: Vec<Real>,
    c: Vec<Real>,
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
        let mut out = ShapeMatching {
            arity,
            cells: mesh.cell_indices().to_vec(),
            rest: Vec::with_capacity(mesh.cell_indices().len()),
            k: Vec::new(),
            c: Vec::new(),
            rotations: vec![initial; mesh.num_cells()],
            fit,
            damping,
        };
        for (cell, ids) in mesh.cells().enumerate() {
            let centroid = ids.iter().map(|&i| nodes[i as usize]).sum::<Vector>() / arity as Real;
            let mut spread = 0.0;
            for &i in ids {
                let r0 = nodes[i as usize] - centroid;
                spread += r0.length_squared();
                out.rest.push(r0);
            }
            let v = mesh.rest_volumes()[cell];
            let material_k = MATERIAL_SCALE * params.material.young_modulus * v / spread;
            let (k, c) = params.k_c(material_k, params.material.density * v / arity as Real);
            out.k.push(k);
            out.c.push(c);
        }
        out
    }

    pub fn accumulate(&mut self, x: &[Vector], v: &[Vector], acc: &mut Accumulator) {
        let n = self.arity;
        let mut xs = [Vector::ZERO; MAX_ARITY];
        let mut vs = [Vector::ZERO; MAX_ARITY];
        let mut fs = [Vector::ZERO; MAX_ARITY];
        for (cell, ids) in self.cells.chunks_exact(n).enumerate() {
            for (a, &i) in ids.iter().enumerate() {
                xs[a] = x[i as usize];
                vs[a] = v[i as usize];
            }
            let (k, c) = (self.k[cell], self.c[cell]);
            self.rotations[cell] = element_forces(
                &self.rest[cell * n..(cell + 1) * n],
                &xs[..n],
                &vs[..n],
                k,
                c,
                self.fit,
                self.damping,
                self.rotations[cell],
                &mut fs[..n],
            );
            for (a, &i) in ids.iter().enumerate() {
                acc.force[i as usize] += fs[a];
                // Row bound of k (𝟙 − 𝟏𝟏ᵀ/n): 2k(1 − 1/n) ≤ 2k, plus the rotation's variation.
                acc.stiffness[i as usize] += 2.0 * k;
                acc.damping[i as usize] += 2.0 * c;
            }
        }
    }

    pub fn elastic_energy(&self, x: &[Vector]) -> Real {
        let n = self.arity;
        let mut e = 0.0;
        for (cell, ids) in self.cells.chunks_exact(n).enumerate() {
            let xc = ids.iter().map(|&i| x[i as usize]).sum::<Vector>() / n as Real;
            let q = self.rotations[cell];
            for (a, &i) in ids.iter().enumerate() {
                let goal = q * self.rest[cell * n + a];
                e += 0.5 * self.k[cell] * (x[i as usize] - xc - goal).length_squared();
            }
        }
        e
    }
}
