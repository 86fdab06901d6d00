//! Plastic flow of simplex cells ([`Plasticity`]): each cell keeps its own rest shape, which
//! flows toward the cell's shape when the cell is strained past yield.
//!
//! After every step, for each cell: its elastic deformation `F = D_s D_m⁻¹` (edge vectors of
//! its shape now, `D_s`, against those of its rest shape, `D_m`), the principal stretches `λ_k`
//! and directions `v_k` of `F` (`FᵀF = V diag(λ²) Vᵀ`, in the rest frame), and the log strains
//! `e_k = ln λ_k`. Past yield (`|e_k| > yield`, or only in tension or only in compression) the
//! excess `e_k ∓ yield` flows by the share `1 − e^(−rate·dt)` (all of it when the rate is
//! infinite): the rest shape is stretched along `v_k` by `e^(δ_k)`,
//! `D_m ← V diag(e^δ) Vᵀ D_m`, which leaves the elastic strain at yield and the rotation
//! untouched. The flow stops at `max_strain`: the rest shape's stretches against the built one
//! (the polar factor of `D_m D_m,built⁻¹`) are clamped to `e^(±max)`, so a rest shape is never
//! flat and, a product of positive stretches, never inverted.
//!
//! Each model then derives its rest data from the cells' rest shapes
//! ([`ElementLaw::set_rest`](super::ElementLaw::set_rest)): shape matching its rest offsets,
//! edge repulsion its rest heights and its edges' rest lengths (the mean over the cells that
//! share an edge), the springs models the same rest lengths (centroid springs also their
//! vertices' rest distances to the centroid), the volumetric term its rest volumes. The energy
//! the flow releases (the elastic energy at the same positions, before less after) is the
//! step's plastic dissipation (`DeformableReport::plastic_dissipation`).

use super::super::material::{FlowIn, Plasticity};
use super::super::math::{self, Matrix, Real, Vector, DIM, SIMPLEX_ARITY};

/// The rest shapes of a body's simplex cells under plastic flow.
#[derive(Clone, Debug)]
pub(crate) struct Plastic {
    pub params: Plasticity,
    /// The cells' vertex indices, by slot.
    cells: Vec<u32>,
    /// Each cell's rest vertices as built, by slot (`cell · n + a`).
    built: Vec<Vector>,
    /// Each cell's rest vertices now, by slot.
    rest: Vec<Vector>,
    /// The rest vertices the last flow replaced: each changed cell and its vertices before.
    replaced: Vec<(u32, [Vector; SIMPLEX_ARITY])>,
}

/// A strain change below this is no flow (it would only round the rest data).
const NO_FLOW: Real = 1e-6;

impl Plastic {
    /// The cells `cells` (vertex indices, by slot) at rest at `nodes`, none flowed yet.
    pub fn new(params: Plasticity, cells: &[u32], nodes: &[Vector]) -> Self {
        let built: Vec<Vector> = cells.iter().map(|&i| nodes[i as usize]).collect();
        Plastic {
            params,
            cells: cells.to_vec(),
            rest: built.clone(),
            replaced: Vec::new(),
            built,
        }
    }

    /// The cells' vertex indices, by slot.
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// Each cell's rest vertices now, by slot.
    pub fn rest(&self) -> &[Vector] {
        &self.rest
    }

    /// Sets the cells' rest vertices (a snapshot's); `Err(expected length)` if the length is
    /// wrong or a rest shape is not one the flow can reach (not finite, flat or inverted, or
    /// stretched past `max_strain` against its built shape).
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn set_rest(&mut self, rest: &[Vector]) -> Result<(), usize> {
        let reachable = rest.len() == self.rest.len()
            && rest
                .chunks_exact(SIMPLEX_ARITY)
                .zip(self.built.chunks_exact(SIMPLEX_ARITY))
                .all(|(r, b)| {
                    let plastic = edges(r) * edges(b).inverse();
                    plastic.is_finite()
                        && plastic.determinant() > 0.0
                        && principal_strains(plastic).abs().max_element()
                            <= self.params.max_strain + 1e-3
                });
        if !reachable {
            return Err(self.rest.len());
        }
        self.rest.copy_from_slice(rest);
        Ok(())
    }

    /// Undoes the last flow: its cells get their rest vertices back.
    pub fn undo(&mut self) {
        for (cell, before) in self.replaced.drain(..) {
            let first = cell as usize * SIMPLEX_ARITY;
            self.rest[first..first + SIMPLEX_ARITY].copy_from_slice(&before);
        }
    }

    /// The cells whose rest shape is not the built one, in order.
    #[cfg_attr(not(feature = "serde"), allow(dead_code))]
    pub fn flowed(&self) -> Vec<u32> {
        let bits = |p: &Vector| p.to_array().map(Real::to_bits);
        (0..self.rest.len() / SIMPLEX_ARITY)
            .filter(|&c| {
                let slots = c * SIMPLEX_ARITY..(c + 1) * SIMPLEX_ARITY;
                self.rest[slots.clone()]
                    .iter()
                    .zip(&self.built[slots])
                    .any(|(a, b)| bits(a) != bits(b))
            })
            .map(|c| c as u32)
            .collect()
    }

    /// Each cell's plastic strain: the largest magnitude of the principal log strains of its
    /// rest shape against its built shape.
    pub fn strains(&self) -> Vec<Real> {
        (0..self.rest.len() / SIMPLEX_ARITY)
            .map(|c| {
                let slots = c * SIMPLEX_ARITY..(c + 1) * SIMPLEX_ARITY;
                let plastic =
                    edges(&self.rest[slots.clone()]) * edges(&self.built[slots]).inverse();
                let strains = principal_strains(plastic);
                (0..DIM).map(|k| strains[k].abs()).fold(0.0, Real::max)
            })
            .collect()
    }

    /// Flows the cells at `x` over a step of `dt`: the cells whose rest shape changed, in
    /// order.
    pub fn flow(&mut self, x: &[Vector], dt: Real) -> Vec<u32> {
        let p = self.params;
        let share = if p.flow_rate.is_infinite() {
            1.0
        } else {
            1.0 - (-p.flow_rate * dt).exp()
        };
        let mut changed = Vec::new();
        self.replaced.clear();
        if share.is_nan() || share <= 0.0 {
            return changed;
        }
        for (cell, ids) in self.cells.chunks_exact(SIMPLEX_ARITY).enumerate() {
            let slots = cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY;
            let now: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|a| x[ids[a] as usize]);
            let rest = &self.rest[slots.clone()];
            let dm = edges(rest);
            let f = edges(&now) * dm.inverse();
            if !f.is_finite() || f.determinant() <= 0.0 {
                // A flat or inverted cell has no principal strains to flow by.
                continue;
            }
            let (squares, directions) = symmetric_eigen(f.transpose() * f);
            let mut flowed = false;
            let delta = Vector::from_array(std::array::from_fn(|k| {
                let e = 0.5 * squares[k].max(Real::MIN_POSITIVE).ln();
                let y = p.yield_strain;
                let excess = match p.flow {
                    FlowIn::Both => e - e.clamp(-y, y),
                    FlowIn::Tension => (e - y).max(0.0),
                    FlowIn::Compression => (e + y).min(0.0),
                };
                flowed |= (share * excess).abs() > NO_FLOW;
                share * excess
            }));
            if !flowed {
                continue;
            }
            let stretch = directions * Matrix::from_diagonal(delta.exp()) * directions.transpose();
            let dm = limited(
                stretch * dm,
                edges(&self.built[slots.clone()]),
                p.max_strain,
            );
            let Some(dm) = dm else { continue };
            let before: [Vector; SIMPLEX_ARITY] =
                std::array::from_fn(|a| self.rest[slots.start + a]);
            self.replaced.push((cell as u32, before));
            let origin = self.rest[slots.start];
            for b in 0..DIM {
                self.rest[slots.start + 1 + b] = origin + dm.col(b);
            }
            changed.push(cell as u32);
        }
        changed
    }
}

/// The eigenvalues of the symmetric `a` and its eigenvectors (the columns, orthonormal), by
/// cyclic Jacobi rotations: exact for repeated eigenvalues and a diagonal `a`, where a
/// closed form divides by an off-diagonal entry.
fn symmetric_eigen(mut a: Matrix) -> (Vector, Matrix) {
    let mut v = Matrix::IDENTITY;
    let scale = (0..DIM).map(|k| a.col(k)[k].abs()).fold(0.0, Real::max);
    for _ in 0..12 {
        let mut off: Real = 0.0;
        for p in 0..DIM {
            for q in p + 1..DIM {
                off = off.max(a.col(q)[p].abs());
            }
        }
        if off <= 1e-7 * scale || off == 0.0 {
            break;
        }
        for p in 0..DIM {
            for q in p + 1..DIM {
                let apq = a.col(q)[p];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a.col(q)[q] - a.col(p)[p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                let mut j = Matrix::IDENTITY;
                j.col_mut(p)[p] = c;
                j.col_mut(q)[q] = c;
                j.col_mut(q)[p] = s;
                j.col_mut(p)[q] = -s;
                a = j.transpose() * a * j;
                v *= j;
            }
        }
    }
    (Vector::from_array(std::array::from_fn(|k| a.col(k)[k])), v)
}

/// The log strains `½ ln λ²` of the principal stretches whose squares are `squares`.
fn log_strains(squares: Vector) -> Vector {
    Vector::from_array(std::array::from_fn(|k| {
        0.5 * squares[k].max(Real::MIN_POSITIVE).ln()
    }))
}

/// The principal log strains of the deformation `f`.
fn principal_strains(f: Matrix) -> Vector {
    log_strains(symmetric_eigen(f.transpose() * f).0)
}

/// The edge vectors `p_{b+1} − p_0` of a simplex, as columns.
fn edges(p: &[Vector]) -> Matrix {
    let mut m = Matrix::ZERO;
    for b in 0..DIM {
        m += math::outer(p[b + 1] - p[0], Vector::AXES[b]);
    }
    m
}

/// The rest edges `dm`, their stretch against the built edges `built` clamped to `e^(±max)`
/// along each principal direction; `None` if not finite.
fn limited(dm: Matrix, built: Matrix, max: Real) -> Option<Matrix> {
    let plastic = dm * built.inverse();
    let (squares, directions) = symmetric_eigen(plastic.transpose() * plastic);
    let strains = log_strains(squares);
    let clamped = strains.clamp(Vector::splat(-max), Vector::splat(max));
    let out = if clamped == strains {
        dm
    } else {
        // plastic = R U; keep R, clamp U's stretches.
        let u = directions * Matrix::from_diagonal(strains.exp()) * directions.transpose();
        let u_clamped = directions * Matrix::from_diagonal(clamped.exp()) * directions.transpose();
        plastic * u.inverse() * u_clamped * built
    };
    out.is_finite().then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn simplex() -> (Vec<u32>, Vec<Vector>) {
        let mut nodes = vec![Vector::ZERO];
        for b in 0..DIM {
            nodes.push(Vector::AXES[b] * 0.1);
        }
        ((0..SIMPLEX_ARITY as u32).collect(), nodes)
    }

    fn params(flow: FlowIn, rate: Real) -> Plasticity {
        Plasticity {
            yield_strain: 0.05,
            flow_rate: rate,
            max_strain: 0.5,
            flow,
        }
    }

    /// The cell's stretch along the first axis against its built rest length.
    fn rest_strain(plastic: &Plastic) -> Real {
        let r = plastic.rest();
        ((r[1] - r[0]).length() / 0.1).ln()
    }

    #[test]
    fn a_cell_stretched_past_yield_keeps_the_strain_beyond_it() {
        let (cells, nodes) = simplex();
        for (flow, stretch, kept) in [
            (FlowIn::Both, 0.2, 0.15),
            (FlowIn::Both, -0.2, -0.15),
            (FlowIn::Tension, 0.2, 0.15),
            (FlowIn::Tension, -0.2, 0.0),
            (FlowIn::Compression, 0.2, 0.0),
            (FlowIn::Compression, -0.2, -0.15),
            (FlowIn::Both, 0.03, 0.0),
            // Clamped at the largest plastic strain.
            (FlowIn::Both, 0.9, 0.5),
        ] {
            let mut plastic = Plastic::new(params(flow, Real::INFINITY), &cells, &nodes);
            let x: Vec<Vector> = nodes
                .iter()
                .map(|p| {
                    let mut q = *p;
                    q[0] *= Real::exp(stretch);
                    q
                })
                .collect();
            let changed = plastic.flow(&x, 0.01);
            assert_eq!(changed.is_empty(), kept == 0.0, "{flow:?} {stretch}");
            let got = rest_strain(&plastic);
            assert!(
                (got - kept).abs() < 1e-4,
                "{flow:?} {stretch}: kept {got}, not {kept}"
            );
            // Across the stretch the rest shape is untouched.
            let r = plastic.rest();
            assert!(((r[2] - r[0]).length() - 0.1).abs() < 1e-6);
        }
    }

    #[test]
    fn a_slow_flow_creeps_toward_yield_and_a_turn_flows_nothing() {
        let (cells, nodes) = simplex();
        let mut plastic = Plastic::new(params(FlowIn::Both, 10.0), &cells, &nodes);
        // Stretched 0.2 along the first axis and turned a quarter about the last.
        let x: Vec<Vector> = nodes
            .iter()
            .map(|p| {
                let mut q = *p * 0.0;
                q[1] = p[0] * Real::exp(0.2);
                q[0] = -p[1];
                if DIM == 3 {
                    q[DIM - 1] = p[DIM - 1];
                }
                q
            })
            .collect();
        plastic.flow(&x, 0.01);
        // A tenth of a second at 10/s flows 1 − e^(−0.1) of the excess 0.15.
        let first = rest_strain(&plastic);
        let expected = 0.15 * (1.0 - Real::exp(-0.1));
        assert!(
            (first - expected).abs() < 1e-4,
            "{first} against {expected}"
        );
        for _ in 0..2000 {
            plastic.flow(&x, 0.01);
        }
        assert!((rest_strain(&plastic) - 0.15).abs() < 1e-4);
        // A rigid turn of the flowed shape strains nothing: no flow.
        let before = plastic.rest().to_vec();
        let turned: Vec<Vector> = x.iter().map(|p| -*p).collect();
        let mut twice = plastic.clone();
        if DIM == 2 {
            assert!(twice.flow(&turned, 0.01).is_empty());
            assert_eq!(twice.rest(), &before[..]);
        }
    }
}
