//! Backward Euler by Vertex Block Descent (Chen, Liu, Yang, Yuksel, SIGGRAPH 2024; issue 15).
//!
//! One step of length `h` minimises the incremental potential
//! `G(x) = ½/h² ‖x − y‖²_M + E(x) + D(x)` over the free nodes' positions, `y = x₀ + h v₀ + h² g`
//! the inertial prediction, `E` the model's elastic energy, `D` the springs' dashpots taken
//! implicitly (`c/(2h) ((Δx_i − Δx_j)·n)²`, `Δx = x − x₀`). Held nodes (bound to a bone, or
//! stopped by a contact) end where they are held. Vertex Block Descent
//! sweeps the nodes in order (Gauss–Seidel), each a `DIM × DIM` Newton step on `G` with the
//! others fixed: `Δ = H_i⁻¹ f_i`, `f_i = −∂G/∂x_i`, `H_i = m_i/h² I + Σ` the positive
//! semi-definite blocks of [`super::hessian`] of the terms at `i`. A fixed number of sweeps is
//! the cost knob.
//!
//! Edge repulsion keeps its promise under the large step with a backtracking line search: a
//! node's step is halved until every repulsion of its cells keeps the vertex above a tenth of
//! its rest height on the rest side (ten halvings, then the node stays), and the iteration
//! starts from `y` only if no cell is inverted there, else from `x₀`. Springs, nonlinear
//! springs and edge repulsion have this step; the others (centroid springs, shape matching)
//! take the explicit one.

use super::super::math::{self, Matrix, Real, Vector, FACET_ARITY, SIMPLEX_ARITY};
use super::edge_repulsion::{repulsion, EdgeRepulsion, OPPOSITE};
use super::hessian;
use super::springs::{Law, Springs};
use super::{Elements, ModelState};

/// Smallest height a line-searched step may leave a vertex at, over its rest height.
pub const MIN_STEP_HEIGHT: Real = 0.1;

/// Which terms touch each node (compressed rows): springs, and (cell, local vertex) slots.
#[derive(Clone, Debug, Default)]
pub(crate) struct Incidence {
    spring_start: Vec<u32>,
    springs: Vec<u32>,
    cell_start: Vec<u32>,
    cells: Vec<(u32, u8)>,
}

impl Incidence {
    fn build(nodes: usize, springs: Option<&Springs>, cells: Option<&[u32]>) -> Self {
        let mut out = Incidence::default();
        let mut by_node: Vec<Vec<u32>> = vec![Vec::new(); nodes];
        if let Some(s) = springs {
            for (k, [i, j]) in s.pairs.iter().enumerate() {
                by_node[*i as usize].push(k as u32);
                by_node[*j as usize].push(k as u32);
            }
        }
        out.spring_start.push(0);
        for list in &by_node {
            out.springs.extend_from_slice(list);
            out.spring_start.push(out.springs.len() as u32);
        }
        let mut by_node: Vec<Vec<(u32, u8)>> = vec![Vec::new(); nodes];
        if let Some(c) = cells {
            for (cell, ids) in c.chunks_exact(SIMPLEX_ARITY).enumerate() {
                for (a, &i) in ids.iter().enumerate() {
                    by_node[i as usize].push((cell as u32, a as u8));
                }
            }
        }
        out.cell_start.push(0);
        for list in &by_node {
            out.cells.extend_from_slice(list);
            out.cell_start.push(out.cells.len() as u32);
        }
        out
    }

    fn springs_of(&self, i: usize) -> &[u32] {
        &self.springs[self.spring_start[i] as usize..self.spring_start[i + 1] as usize]
    }

    fn cells_of(&self, i: usize) -> &[(u32, u8)] {
        &self.cells[self.cell_start[i] as usize..self.cell_start[i + 1] as usize]
    }
}

/// The inputs of one implicit step.
pub(crate) struct StepInput<'a> {
    /// Positions and velocities at the start of the step.
    pub x0: &'a [Vector],
    pub v0: &'a [Vector],
    pub masses: &'a [Real],
    /// Where a held node ends the step (a bound node on its bone, a node a contact stopped),
    /// `None` for a free one.
    pub held: &'a [Option<Vector>],
    /// Where the sweeps start (the inertial prediction when `None`).
    pub start: Option<&'a [Vector]>,
    pub gravity: Vector,
    pub h: Real,
    pub iterations: usize,
}

impl ModelState {
    /// Whether this model has an implicit step.
    pub fn has_implicit(&self) -> bool {
        matches!(
            self.elements,
            Elements::Springs(_) | Elements::NonlinearSprings(_) | Elements::EdgeRepulsion(_)
        )
    }

    /// One backward-Euler step (see the module docs): the end positions into `x`. Does
    /// nothing (and returns `false`) for a model without one.
    pub fn implicit_step(&self, input: &StepInput<'_>, x: &mut Vec<Vector>) -> bool {
        let (springs, er) = match &self.elements {
            Elements::Springs(s) | Elements::NonlinearSprings(s) => (s, None),
            Elements::EdgeRepulsion(e) => (&e.edges, Some(e)),
            _ => return false,
        };
        let n = input.x0.len();
        let incidence = self
            .incidence
            .get_or_init(|| Incidence::build(n, Some(springs), er.map(|e| e.cells.as_slice())));
        let StepInput {
            x0, v0, masses, h, ..
        } = *input;
        let y: Vec<Vector> = (0..n)
            .map(|i| input.held[i].unwrap_or(x0[i] + v0[i] * h + input.gravity * (h * h)))
            .collect();
        x.clear();
        match input.start {
            Some(start) => x.extend((0..n).map(|i| input.held[i].unwrap_or(start[i]))),
            None => x.extend_from_slice(&y),
        }
        if let Some(er) = er {
            if !all_upright(er, x) {
                for i in 0..n {
                    if input.held[i].is_none() {
                        x[i] = x0[i];
                    }
                }
            }
        }
        let vertex = Vertex {
            springs,
            er,
            incidence,
            x0,
            h,
        };
        for _ in 0..input.iterations {
            for i in 0..n {
                if input.held[i].is_some() {
                    continue;
                }
                let inertia = masses[i] / (h * h);
                let (f, block) = vertex.newton(i, x, inertia, y[i]);
                let Some(inverse) = invert(block) else {
                    continue;
                };
                let step = inverse * f;
                x[i] = vertex.line_search(i, x, step);
            }
        }
        true
    }
}

/// A node's Newton step on the incremental potential.
struct Vertex<'a> {
    springs: &'a Springs,
    er: Option<&'a EdgeRepulsion>,
    incidence: &'a Incidence,
    x0: &'a [Vector],
    h: Real,
}

impl Vertex<'_> {
    /// `f_i = −∂G/∂x_i` and the block `H_i` at `x`.
    fn newton(&self, i: usize, x: &[Vector], inertia: Real, y: Vector) -> (Vector, Matrix) {
        let mut f = (y - x[i]) * inertia;
        let mut block = Matrix::IDENTITY * inertia;
        let s = self.springs;
        for &k in self.incidence.springs_of(i) {
            let k = k as usize;
            let [a, b] = s.pairs[k];
            let j = if a as usize == i { b } else { a } as usize;
            let d = x[i] - x[j];
            let l = d.length();
            if l <= Real::MIN_POSITIVE {
                continue;
            }
            let normal = d / l;
            let (du, ddu) = match s.law {
                Law::Linear => hessian::linear_spring(l, s.rest[k], s.k[k]),
                Law::Nonlinear => hessian::nonlinear_spring(l, s.rest[k], s.k[k]),
            };
            f -= normal * du;
            block += hessian::radial_block(d, du, ddu);
            // The dashpot, implicit: c/h along the spring, on the step's relative motion.
            let c = s.c[k] / self.h;
            let moved = (x[i] - self.x0[i]) - (x[j] - self.x0[j]);
            f -= normal * (c * normal.dot(moved));
            block += math::outer(normal, normal) * c;
        }
        if let Some(er) = self.er {
            for &(cell, a) in self.incidence.cells_of(i) {
                let (cell, a) = (cell as usize, a as usize);
                let ids = &er.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
                for (b, facet_ids) in OPPOSITE.iter().enumerate() {
                    let slot = cell * SIMPLEX_ARITY + b;
                    let facet: [Vector; FACET_ARITY] =
                        std::array::from_fn(|m| x[ids[facet_ids[m]] as usize]);
                    let r = repulsion(
                        x[ids[b] as usize],
                        &facet,
                        er.side[slot],
                        er.h0[slot],
                        er.k[slot],
                    );
                    let blocks = hessian::repulsion_blocks(&r);
                    if b == a {
                        f += r.force;
                        block += blocks[0];
                    } else if let Some(m) = facet_ids.iter().position(|&l| l == a) {
                        f -= r.force * r.weights[m];
                        block += blocks[m + 1];
                    }
                }
            }
        }
        (f, block)
    }

    /// `x_i + α step` with the largest `α ∈ {1, ½, ¼, …}` (ten halvings) that keeps every
    /// repulsion of the node's cells above [`MIN_STEP_HEIGHT`] of its rest height; the node
    /// stays if none does.
    fn line_search(&self, i: usize, x: &mut [Vector], step: Vector) -> Vector {
        let start = x[i];
        let Some(er) = self.er else {
            return start + step;
        };
        let mut alpha = 1.0;
        for _ in 0..=10 {
            x[i] = start + step * alpha;
            let ok = self
                .incidence
                .cells_of(i)
                .iter()
                .all(|&(cell, _)| cell_upright(er, cell as usize, x));
            if ok {
                let end = x[i];
                x[i] = start;
                return end;
            }
            alpha *= 0.5;
        }
        x[i] = start;
        start
    }
}

/// Whether every repulsion of `cell` keeps its vertex above [`MIN_STEP_HEIGHT`] of its rest
/// height, on the rest side.
fn cell_upright(er: &EdgeRepulsion, cell: usize, x: &[Vector]) -> bool {
    let ids = &er.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
    OPPOSITE.iter().enumerate().all(|(b, facet_ids)| {
        let slot = cell * SIMPLEX_ARITY + b;
        let facet: [Vector; FACET_ARITY] = std::array::from_fn(|m| x[ids[facet_ids[m]] as usize]);
        let normal = math::facet_normal(&facet);
        let len = normal.length();
        len > Real::MIN_POSITIVE
            && (normal * (er.side[slot] / len)).dot(x[ids[b] as usize] - facet[0])
                > MIN_STEP_HEIGHT * er.h0[slot]
    })
}

fn all_upright(er: &EdgeRepulsion, x: &[Vector]) -> bool {
    (0..er.cells.len() / SIMPLEX_ARITY).all(|c| cell_upright(er, c, x))
}

/// The inverse of a block, if it is well conditioned enough to have one.
fn invert(m: Matrix) -> Option<Matrix> {
    let det = m.determinant();
    (det.is_finite() && det.abs() > Real::MIN_POSITIVE).then(|| m.inverse())
}
