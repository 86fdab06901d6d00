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
//! The sweeps start from `x₀ + h v₀`, inertia without gravity: a resting body starts where it
//! rests, the minimiser. (Starting from `y`, the few sweeps could not lift the body back up by
//! `h² g` each step, and it rested 3 % low at 3 sweeps.) Held nodes or a body that rings may
//! start elsewhere ([`start_scaled`], [`start_rigid`]). A body with no held node then moves
//! as a whole by the best translation, which is exact because the energy does not change under
//! one: `Σ m (y − x) / Σ m`. Gauss–Seidel hardly moves a body much stiffer than `m/h²` as a
//! whole; with this its free flight is ballistic whatever the sweeps.
//!
//! The prediction carries a body's rigid turn on ([`carried_ahead`]): a backward-Euler step's
//! velocities are chords, and `x₀ + h v₀` takes every node of a spinning body straight out
//! along its chord; the step pulls it back in and takes the spin with it. `y` adds the turn's
//! centripetal and Euler parts for the turn per step the chords fit, so a rigid spin is the
//! step's minimiser and carries on (the midpoint step, whose velocities are not chords, keeps
//! its turn by its own rule). Edge-repulsion terms are
//! evaluated once per cell and vertex from the cell's volume gradients
//! ([`math::simplex_gradients`]). A large body sweeps by slabs of consecutive nodes, on rayon's
//! threads with feature `parallel` ([`Solve::sweep_alone`]).
//!
//! Edge repulsion keeps its promise under the large step with a backtracking line search: a
//! node's step is halved until every repulsion of its cells keeps the vertex above a tenth of
//! its rest height on the rest side (ten halvings, then the node stays), and the iteration
//! starts from `x₀ + h v₀` only if no cell is too flat there (held nodes, e.g. ones a contact
//! threw back, can move through a cell), else from `x₀`.
//!
//! Shape-based cells (`k/2 Σ |r_a − q R0_a|²`) fit their rotation `q` once, at the start of
//! the sweeps, and hold it: then vertex `a`'s force is `−k e_a`, `e_a = r_a − q R0_a`, and its
//! block `k (1 − 1/n) 𝟙`. Their dashpot damps the change of `e_a` over the step, so a rigid
//! turn is not damped. Simplex cells get the same line search on their volume (a tenth of the
//! rest volume, or no flatter than the start if a held node left them flatter). Without it a
//! 60 Hz fall inverted 164 cells at the impact: the contact threw the bottom nodes back up
//! through the layer above, still falling.
//!
//! Held nodes ([`Hold`]): a bound node ends where its bone takes it. A node a collider stopped
//! (or threw back, with restitution) ends where the contact set it, unless that leaves one of
//! its cells too flat to start from: then it starts where it started the step and may end
//! anywhere on the free side of the collider's plane, its inertia drawing it to where the
//! contact set it, its cells' barriers pushing it off (`Hold::Above`; the lift-off's Newton
//! step is the quadratic model's minimiser on that side). A 60 Hz silicone ball needed both: its
//! bottom nodes, thrown back by the contact, passed through the 2 cm layer above them, and a
//! cell of four surface nodes pressed flat onto the floor could not be pushed off it (a Newton
//! step on a barrier at `h ≈ 0` barely moves). Letting every contact node lift off always made
//! a resting cube climb at two or three sweeps (0.50 → 0.55 m in 3 s): the unconverged sweeps
//! ratchet it up. The sweeps alternate their order (forward, backward).
//!
//! Springs, nonlinear springs, edge repulsion and shape matching have this step; centroid
//! springs take the explicit one.

mod global;

use std::ops::Range;

use super::super::math::{self, Matrix, Real, Rotation, Vector, DIM, SIMPLEX_ARITY};
use super::super::threads;
use super::edge_repulsion::EdgeRepulsion;
use super::gas::Chambers;
use super::hessian;
use super::lanes::{self, each, Lane, LaneVector, LANES};
use super::shape_matching::ShapeMatching;
use super::springs::{Law, Springs};
use super::volume::Volume;
use super::{ElementLaw, ModelState, Motion};

/// Smallest height a line-searched step may leave a vertex at, over its rest height.
pub const MIN_STEP_HEIGHT: Real = 0.1;

/// Smallest volume a line-searched step may leave a shape-based simplex cell at, over its rest
/// volume.
pub const MIN_STEP_VOLUME: Real = 0.1;

/// Which terms touch each node (compressed rows): springs, and (cell, local vertex) slots.
#[derive(Clone, Debug, Default)]
pub(crate) struct Incidence {
    spring_start: Vec<u32>,
    springs: Vec<u32>,
    cell_start: Vec<u32>,
    cells: Vec<(u32, u8)>,
    /// Nodes per slab of the sweeps ([`Solve::sweep_alone`]): wider than any term's span of
    /// node indices, so a term touches at most two consecutive slabs; the node count when the
    /// body is too small or its numbering too wide for [`MIN_SLABS`] slabs.
    slab: usize,
}

impl Incidence {
    /// The incidence of `elements` over `nodes` nodes (`None` for a model without an implicit
    /// step).
    fn of(elements: &dyn ElementLaw, volume: Option<&Volume>, nodes: usize) -> Option<Self> {
        let terms = elements.implicit_terms()?;
        let cells = match (terms.repulsion, terms.shape) {
            (Some(e), _) => Some((&e.cells[..], SIMPLEX_ARITY)),
            (None, Some(s)) => Some((s.cell_indices(), s.arity())),
            (None, None) => volume.map(|v| (v.cells(), SIMPLEX_ARITY)),
        };
        Some(Self::build(nodes, terms.springs, cells))
    }

    fn build(nodes: usize, springs: Option<&Springs>, cells: Option<(&[u32], usize)>) -> Self {
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
        if let Some((c, arity)) = cells {
            for (cell, ids) in c.chunks_exact(arity).enumerate() {
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
        out.slab = slab_size(nodes, springs, cells);
        out
    }

    /// The slabs' node ranges, in order.
    fn slabs(&self, nodes: usize) -> impl DoubleEndedIterator<Item = Range<usize>> + Clone {
        let slab = self.slab.max(1);
        (0..nodes.div_ceil(slab)).map(move |k| k * slab..((k + 1) * slab).min(nodes))
    }

    fn springs_of(&self, i: usize) -> &[u32] {
        &self.springs[self.spring_start[i] as usize..self.spring_start[i + 1] as usize]
    }

    fn cells_of(&self, i: usize) -> &[(u32, u8)] {
        &self.cells[self.cell_start[i] as usize..self.cell_start[i + 1] as usize]
    }
}

/// Sweeps over fewer slabs than this go in node order, in one slab.
const MIN_SLABS: usize = 4;

/// The most slabs a sweep is cut into (a fixed count, so the slabs and the result do not depend
/// on the threads).
const MAX_SLABS: usize = 16;

/// The fewest nodes of a slab.
const MIN_SLAB_NODES: usize = 256;

/// [`Incidence::slab`] for `nodes` nodes with these terms.
fn slab_size(nodes: usize, springs: Option<&Springs>, cells: Option<(&[u32], usize)>) -> usize {
    let mut span = 0;
    if let Some(s) = springs {
        for [i, j] in &s.pairs {
            span = span.max(i.abs_diff(*j) as usize);
        }
    }
    if let Some((ids, arity)) = cells {
        for cell in ids.chunks_exact(arity) {
            let (low, high) = cell
                .iter()
                .fold((u32::MAX, 0), |(l, h), &i| (l.min(i), h.max(i)));
            span = span.max((high - low) as usize);
        }
    }
    // A multiple of four: each kind has an even count of slabs, which two threads share
    // evenly.
    let slabs = (nodes / (span + 1).max(MIN_SLAB_NODES)).min(MAX_SLABS) / 4 * 4;
    if slabs < MIN_SLABS {
        nodes
    } else {
        nodes.div_ceil(slabs)
    }
}

/// The unit vector along axis `d`.
fn unit(d: usize) -> Vector {
    let mut e = Vector::ZERO;
    e[d] = 1.0;
    e
}

/// The nodes' positions as a sweep reads them.
trait Positions: Sync {
    fn at(&self, j: usize) -> Vector;
}

impl Positions for [Vector] {
    #[inline(always)]
    fn at(&self, j: usize) -> Vector {
        self[j]
    }
}

#[cfg(feature = "parallel")]
thread_local! {
    /// A thread's copy of the nodes a parallel sweep's slab reads ([`Solve::sweep_window`]).
    static WINDOW: std::cell::Cell<Vec<Vector>> = const { std::cell::Cell::new(Vec::new()) };
}

/// How a node is held over an implicit step.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum Hold {
    /// Free.
    Free,
    /// Ends the step here (bound to a bone; what [`Hold::Pressed`] and [`Hold::Contact`]
    /// become).
    At(Vector),
    /// A node of a facet a rigid feature pressed, set to end the step here: held there
    /// ([`Hold::At`]) or, if that leaves one of its cells too flat to start from, short of it
    /// on the way from where it started the step, so that the feature meets the cell's
    /// barrier over the next steps instead of carrying the node through the cell.
    Pressed(Vector),
    /// Ends the step at `at` or further along `normal`, its inertia drawing it to `target` (a
    /// node a collider stopped, or threw back to `target`: it may lift off further, so a cell of
    /// nodes all pressed onto a floor is not flattened with them, and its cells may hold it
    /// back from the bounce).
    Above {
        at: Vector,
        normal: Vector,
        target: Vector,
    },
    /// A node a dynamic body lighter than the deformable stopped: free, but carrying `mass`,
    /// its share of the body's effective mass, drawn to `target`, where the body's surface
    /// would go unstopped. Held there, as for a body that does not yield, the node's cells
    /// pushed the body as if it could hold them (a 0.08 kg box landing on a slab of 1 kg nodes
    /// was launched at 28 m/s). What the carried mass exerts on the node is its reaction,
    /// passed on to the body. A heavier body holds its nodes ([`Hold::Contact`]): a 1000 kg
    /// box carried by a 1 kg cube's nodes turned its cells inside out.
    Carries { target: Vector, mass: Real },
    /// A node a collider stopped (or threw back) to `target`: held there
    /// ([`Hold::At`]) unless that leaves one of its cells too flat to start from, then lifted
    /// off the collider's plane through `low` along `normal` ([`Hold::Above`]).
    Contact {
        target: Vector,
        normal: Vector,
        low: Vector,
    },
}

impl Hold {
    /// Where a held node's inertia draws it (and, without a lift-off, where it ends).
    fn at(self) -> Option<Vector> {
        match self {
            Hold::Free => None,
            Hold::At(at)
            | Hold::Pressed(at)
            | Hold::Above { target: at, .. }
            | Hold::Contact { target: at, .. } => Some(at),
            // Its own inertia draws it where it would go, the body's to `target`.
            Hold::Carries { .. } => None,
        }
    }

    /// The mass a node carries beside its own ([`Hold::Carries`]).
    fn carried(self) -> Real {
        match self {
            Hold::Carries { mass, .. } => mass,
            _ => 0.0,
        }
    }

    /// A contact held where it was set.
    fn held(self) -> Self {
        match self {
            Hold::Contact { target, .. } | Hold::Pressed(target) => Hold::At(target),
            other => other,
        }
    }

    /// A contact lifted off.
    fn lifted(self) -> Self {
        match self {
            Hold::Contact {
                target,
                normal,
                low,
            } => Hold::Above {
                at: low,
                normal,
                target,
            },
            other => other,
        }
    }

    /// Where the sweeps start node with this hold: `free` if free, a lift-off node where it
    /// started the step (`x0`, kept above the plane), so the sweeps bring it down onto the
    /// collider with its cells' barriers in play. (Started on the plane, a cell of four
    /// surface nodes was flat, and a Newton step on a barrier at `h ≈ 0` barely moves it.)
    fn start(self, free: Vector, x0: Vector) -> Vector {
        match self {
            Hold::Free => free,
            Hold::At(at)
            | Hold::Pressed(at)
            | Hold::Carries { target: at, .. }
            | Hold::Contact { target: at, .. } => at,
            Hold::Above { .. } => self.project(x0),
        }
    }

    /// The Newton step `H⁻¹ f` from `x`, for a lift-off node the minimiser of the quadratic
    /// model on the free side of its plane: `H⁻¹ (f + λ n)`, `λ ≥ 0` the least that keeps it
    /// there (projecting `H⁻¹ f` instead can raise the energy where `H` is not isotropic).
    fn constrained_step(self, x: Vector, inverse: Matrix, f: Vector) -> Vector {
        let step = inverse * f;
        let Hold::Above { at, normal, .. } = self else {
            return step;
        };
        let short = normal.dot(at - x - step);
        let along = normal.dot(inverse * normal);
        if short <= 0.0 || along <= Real::MIN_POSITIVE {
            return step;
        }
        step + inverse * normal * (short / along)
    }

    /// `x` kept on the free side of a lift-off's plane.
    fn project(self, x: Vector) -> Vector {
        match self {
            Hold::Above { at, normal, .. } => at + normal * normal.dot(x - at).max(0.0),
            _ => x,
        }
    }
}

/// The inputs of one implicit step.
pub(crate) struct StepInput<'a> {
    /// Positions and velocities at the start of the step.
    pub x0: &'a [Vector],
    pub v0: &'a [Vector],
    pub masses: &'a [Real],
    /// How each node is held (a bound node on its bone, a node a contact stopped).
    pub held: &'a [Hold],
    /// Where the sweeps start ([`StepInput::guess`] when `None`).
    pub start: Option<&'a [Vector]>,
    pub gravity: Vector,
    pub h: Real,
    pub iterations: usize,
    /// Conjugate-gradient iterations of a Newton step over the whole body before the sweeps
    /// ([`global`]; 0: none).
    pub global: usize,
    /// Whether `v0` are a backward-Euler step's chord velocities, whose rigid turn the step
    /// carries on ([`carried_ahead`]); not in the midpoint step, which keeps the turn itself.
    pub chords: bool,
}

impl ModelState {
    /// Whether this model has an implicit step.
    pub fn has_implicit(&self) -> bool {
        self.elements.implicit_terms().is_some()
    }

    /// Whether the step's energy is convex (shape matching's, its rotations held): only then
    /// does the step take contacts between bodies as terms of it. With springs, nonlinear
    /// springs and edge repulsion, whose energies are not, a pile of fifty cubes in a bowl
    /// exploded (`scenes pile --bodies 50 --integrator implicit`).
    pub fn has_convex_implicit(&self) -> bool {
        self.elements.convex_implicit()
    }

    /// One backward-Euler step (see the module docs): the end positions into `x`. Does
    /// nothing (and returns `false`) for a model without one.
    ///
    /// `reactions` gets, per node, the force its hold exerted on it over the step (zero for a
    /// free node): `m (x − y)/h² − f_el`, what balances inertia and the elastic force, with `y`
    /// the node's own inertial prediction. A contact's impulse on a rigid body is its opposite
    /// times `h`: a node held by a collider passes on the body's elastic force, which its
    /// velocity change alone (a fraction `m/(k h²)` of it) would not.
    pub fn implicit_step(
        &mut self,
        input: &StepInput<'_>,
        x: &mut Vec<Vector>,
        reactions: &mut Vec<Vector>,
    ) -> bool {
        let Some(mut solve) = self.begin_implicit(input, x) else {
            return false;
        };
        if input.global > 0 {
            solve.global_step(x, input.global);
            // The step turned shape-based cells: the sweeps' held rotations follow.
            solve.refit_rotations(x);
        }
        for sweep in 0..input.iterations {
            solve.sweep_alone(x, sweep % 2 == 1);
        }
        let rotations = solve.finish(x, reactions, true);
        self.keep_rotations(rotations);
        true
    }

    /// Sets up one backward-Euler step (see the module docs), the sweeps' start into `x`;
    /// `None` for a model without one. [`Solve::sweep`] then sweeps it as often as wanted and
    /// [`Solve::finish`] ends it.
    pub(crate) fn begin_implicit<'a>(
        &'a self,
        input: &StepInput<'a>,
        x: &mut Vec<Vector>,
    ) -> Option<Solve<'a>> {
        let n = input.x0.len();
        let ModelState {
            elements,
            incidence,
            volume,
            gas,
            ..
        } = self;
        let gas = gas.as_ref();
        let elements = &**elements;
        let terms = elements.implicit_terms()?;
        let volume = volume.as_ref();
        let incidence = incidence
            .get_or_init(|| Incidence::of(elements, volume, n))
            .as_ref()?;
        let (x0, v0, h) = (input.x0, input.v0, input.h);
        let ahead = if input.chords {
            carried_ahead(x0, v0, input.masses, h)
        } else {
            x0.iter().zip(v0).map(|(x, v)| *x + *v * h).collect()
        };
        let y: Vec<Vector> = (0..n)
            .map(|i| {
                let own = ahead[i] + input.gravity * (h * h);
                match input.held[i] {
                    // The node and the mass it carries, each drawn to its own prediction.
                    Hold::Carries { target, mass } => {
                        let m = input.masses[i];
                        (own * m + target * mass) / (m + mass)
                    }
                    hold => hold.at().unwrap_or(own),
                }
            })
            .collect();
        let mut held: Vec<Hold> = input.held.iter().map(|h| h.held()).collect();
        x.clear();
        match input.start {
            Some(start) => x.extend((0..n).map(|i| held[i].start(start[i], x0[i]))),
            None => {
                x.extend((0..n).map(|i| held[i].start(ahead[i], x0[i])));
                if held.iter().any(|h| *h != Hold::Free) {
                    start_scaled((elements, volume, gas), input, (&held, &y), x);
                } else {
                    start_rigid((elements, volume, gas), input, &y, x);
                }
            }
        }
        let mut vertex = Vertex {
            springs: None,
            er: None,
            shape: None,
            volume,
            gas,
            incidence,
            x0,
            h,
        };
        vertex.springs = terms.springs;
        if let Some(e) = terms.repulsion {
            vertex.er = Some(e);
            let upright = |c: usize, x: &[Vector]| cell_upright(e, c, &cell_positions(e, c, x));
            let start = Start {
                x0,
                given: input.held,
            };
            let all_upright = threads::chunked_fold(
                e.cells.len() / SIMPLEX_ARITY,
                |cells| cells_upright(e, x, cells),
                |a, b| a && b,
            );
            if all_upright != Some(true) {
                start.fix(&e.cells, SIMPLEX_ARITY, upright, x, &mut held);
            }
        }
        if let Some(sm) = terms.shape {
            if sm.arity() == SIMPLEX_ARITY {
                let upright = |c: usize, x: &[Vector]| sm.volume_ratio(c, x) > MIN_STEP_VOLUME;
                let start = Start {
                    x0,
                    given: input.held,
                };
                start.fix(sm.cell_indices(), SIMPLEX_ARITY, upright, x, &mut held);
            }
            // The rotations are fitted once, where the sweeps start (inertia carries a
            // turning cell's fit on), and held: refitting before every sweep cost 1.8× as
            // much for the same fall.
            let mut rotations = sm.rotations().to_vec();
            let start = shape_residuals(sm, x0, &rotations);
            sm.refit(x, &mut rotations);
            vertex.shape = Some(Shape {
                cells: sm,
                rotations,
                start,
            });
        }
        Some(Solve {
            vertex,
            held,
            y,
            ahead,
            masses: input.masses,
            gravity: input.gravity,
            h,
        })
    }

    /// Refits shape matching's rotations at `x` (a step that moved the nodes past where its
    /// sweeps fitted them; the elastic energy and the next fit read them).
    pub(crate) fn refit_rotations(&mut self, x: &[Vector]) {
        if let Some(sm) = self.elements.shape_mut() {
            let mut rotations = sm.rotations().to_vec();
            sm.refit(x, &mut rotations);
            sm.rotations_mut().copy_from_slice(&rotations);
        }
    }

    /// Keeps the rotations a finished step fitted (shape matching's warm start).
    pub(crate) fn keep_rotations(&mut self, rotations: Option<Vec<Rotation>>) {
        if let (Some(rotations), Some(sm)) = (rotations, self.elements.shape_mut()) {
            sm.rotations_mut().copy_from_slice(&rotations);
        }
    }
}

/// An implicit step under way ([`ModelState::begin_implicit`]).
pub(crate) struct Solve<'a> {
    vertex: Vertex<'a>,
    held: Vec<Hold>,
    /// Each node's inertial prediction (a held node's hold).
    y: Vec<Vector>,
    /// Where each node's motion carries it ([`carried_ahead`]).
    ahead: Vec<Vector>,
    masses: &'a [Real],
    gravity: Vector,
    h: Real,
}

impl Solve<'_> {
    /// One Gauss–Seidel sweep over the nodes in node order (`backward`: last first; the
    /// sweeps alternate, as one order only leans the body: a cube on a floor tipped towards
    /// its first nodes): each free node's Newton step in turn, `extra(i, x, f, block)` adding
    /// terms other than the body's own (contacts with other bodies) to its force and block.
    /// (Node order passes a contact's push through a lattice in one sweep:
    /// `docs/ARCHITECTURE.md` §4.2.)
    pub fn sweep(
        &self,
        x: &mut [Vector],
        backward: bool,
        mut extra: impl FnMut(usize, &[Vector], &mut Vector, &mut Matrix),
    ) {
        let mut volumes = self.gas_volumes(x);
        in_order(0..x.len(), backward, |i| {
            let x_now: &[Vector] = x;
            let extra = |f: &mut Vector, block: &mut Matrix| extra(i, x_now, f, block);
            if let Some(p) = self.node_step(i, x_now, &mut volumes, extra) {
                x[i] = p;
            }
        });
    }

    /// The gas chambers' volumes at `x` (empty without gas).
    fn gas_volumes(&self, x: &[Vector]) -> Vec<Real> {
        self.vertex.gas.map_or(Vec::new(), |g| g.volumes(x))
    }

    /// [`Solve::sweep`] without other terms, by slabs of consecutive nodes
    /// ([`Incidence::slab`]): the even slabs, then the odd ones (`backward`: the odd ones
    /// first, each slab last node first), each slab in node order. No term joins two slabs of
    /// one kind, so the slabs of a kind may go at once on rayon's threads (feature `parallel`):
    /// each reads only its own nodes and its neighbours', which none of the others writes, and
    /// the sweep ends where the serial one does, bit for bit, whatever the thread count. Within
    /// a slab the order is the node order, which on a lattice passes a push from one side of
    /// the body to the other in one sweep (`docs/ARCHITECTURE.md` §4.2). A gas joins every
    /// node of a chamber: each slab starts from the chambers' volumes where its kind started
    /// and follows its own nodes' moves.
    pub fn sweep_alone(&self, x: &mut [Vector], backward: bool) {
        let n = x.len();
        let slabs = self.vertex.incidence.slabs(n);
        let kinds = if backward { [1, 0] } else { [0, 1] };
        #[cfg(feature = "parallel")]
        if rayon::current_num_threads() > 1
            && self.vertex.incidence.slab < n
            && self.vertex.gas.is_none()
        {
            self.sweep_flowing(x, kinds);
            return;
        }
        for kind in kinds {
            let volumes = self.gas_volumes(x);
            #[cfg(feature = "parallel")]
            if rayon::current_num_threads() > 1 && self.vertex.incidence.slab < n {
                self.sweep_kind_parallel(x, kind, backward, &volumes);
                continue;
            }
            for slab in slabs.clone().skip(kind).step_by(2) {
                self.sweep_slab(slab, backward, x, &mut volumes.clone());
            }
        }
    }

    /// [`Solve::sweep_alone`] on rayon's threads without a gas, `kinds` the slabs' kinds in
    /// sweep order: each slab of the second kind starts as soon as its neighbours of the first
    /// are swept (they are all it reads that the first kind writes), not when all of them are,
    /// so a thread that ends its share of the first kind early goes on to the second.
    #[cfg(feature = "parallel")]
    fn sweep_flowing(&self, x: &mut [Vector], kinds: [usize; 2]) {
        use std::sync::atomic::{AtomicU8, Ordering};
        use std::sync::Mutex;
        let (slab, backward, n) = (self.vertex.incidence.slab, kinds[0] == 1, x.len());
        let slabs: Vec<Mutex<&mut [Vector]>> = x.chunks_mut(slab).map(Mutex::new).collect();
        let count = slabs.len();
        // Per slab of the second kind, its neighbours of the first still to sweep.
        let waiting: Vec<AtomicU8> = (0..count)
            .map(|k| AtomicU8::new(u8::from(k > 0) + u8::from(k + 1 < count)))
            .collect();
        let sweep = |k: usize| self.sweep_window(&slabs, n, k, backward, &mut []);
        rayon::scope(|s| {
            for k in (0..count).filter(|k| k % 2 == kinds[0]) {
                let (sweep, waiting) = (&sweep, &waiting);
                s.spawn(move |s| {
                    sweep(k);
                    for j in [k.wrapping_sub(1), k + 1] {
                        if j < count && waiting[j].fetch_sub(1, Ordering::AcqRel) == 1 {
                            s.spawn(move |_| sweep(j));
                        }
                    }
                });
            }
        });
    }

    /// Sweeps slab `k` of `slabs` (of `n` nodes in all; the gas chambers at `volumes`) in a
    /// copy of itself and its neighbours, which no slab of its kind writes, then writes it
    /// back. The copy sits at the nodes' own indices in a buffer of the thread's, so the sweep
    /// takes the serial sweep's code (read at an offset, it cost 12 % more).
    #[cfg(feature = "parallel")]
    fn sweep_window(
        &self,
        slabs: &[std::sync::Mutex<&mut [Vector]>],
        n: usize,
        k: usize,
        backward: bool,
        volumes: &mut [Real],
    ) {
        let slab = self.vertex.incidence.slab;
        let lock = |j: usize| slabs[j].lock().expect("a slab's lock");
        let end = ((k + 2) * slab).min(n);
        let mut window = WINDOW.take();
        if window.len() < end {
            window.resize(end, Vector::ZERO);
        }
        for j in k.saturating_sub(1)..(k + 2).min(slabs.len()) {
            let nodes = lock(j);
            window[j * slab..j * slab + nodes.len()].copy_from_slice(&nodes);
        }
        let nodes = k * slab..((k + 1) * slab).min(n);
        in_order(nodes.clone(), backward, |i| {
            if let Some(p) = self.node_step(i, &window[..end], volumes, |_, _| {}) {
                window[i] = p;
            }
        });
        lock(k).copy_from_slice(&window[nodes]);
        WINDOW.set(window);
    }

    /// The slabs of one kind (`kind`: 0 even, 1 odd) at once on rayon's threads, each from
    /// the gas chambers' `volumes` where the kind started.
    #[cfg(feature = "parallel")]
    fn sweep_kind_parallel(&self, x: &mut [Vector], kind: usize, backward: bool, volumes: &[Real]) {
        use rayon::prelude::*;
        let (slab, n) = (self.vertex.incidence.slab, x.len());
        let slabs: Vec<std::sync::Mutex<&mut [Vector]>> =
            x.chunks_mut(slab).map(std::sync::Mutex::new).collect();
        (0..slabs.len())
            .into_par_iter()
            .filter(|k| k % 2 == kind)
            .for_each(|k| self.sweep_window(&slabs, n, k, backward, &mut volumes.to_vec()));
    }

    /// Steps the nodes of `slab` in node order (`backward`: last first).
    fn sweep_slab(
        &self,
        slab: Range<usize>,
        backward: bool,
        x: &mut [Vector],
        volumes: &mut [Real],
    ) {
        in_order(slab, backward, |i| {
            if let Some(p) = self.node_step(i, &*x, volumes, |_, _| {}) {
                x[i] = p;
            }
        });
    }

    /// Where node `i`'s Newton step takes it from `x` (line-searched; `None`: it stays), the
    /// gas chambers at `volumes`, which follow the node's move.
    #[inline]
    fn node_step<P: Positions + ?Sized>(
        &self,
        i: usize,
        x: &P,
        volumes: &mut [Real],
        extra: impl FnOnce(&mut Vector, &mut Matrix),
    ) -> Option<Vector> {
        let hold = self.held[i];
        if matches!(hold, Hold::At(_)) {
            return None;
        }
        let inertia = (self.masses[i] + hold.carried()) / (self.h * self.h);
        let (mut f, mut block, reach) = self.vertex.newton(i, x, inertia, self.y[i], volumes);
        extra(&mut f, &mut block);
        let inverse = invert(block)?;
        let step = hold.constrained_step(x.at(i), inverse, f);
        let to = self.vertex.line_search(i, x, step, hold, reach);
        if let Some(gas) = self.vertex.gas {
            // Exact: a chamber's volume is affine in each node.
            let moved = to - x.at(i);
            gas.gradients_at(i, |j| x.at(j), |c, g| volumes[c] += g.dot(moved));
        }
        Some(to)
    }

    /// Refits the held rotations of shape-based cells at `x`.
    pub fn refit_rotations(&mut self, x: &[Vector]) {
        if let Some(shape) = &mut self.vertex.shape {
            shape.cells.refit(x, &mut shape.rotations);
        }
    }

    /// Whether no node is held (the body may move as a whole).
    pub fn all_free(&self) -> bool {
        self.held.iter().all(|h| *h == Hold::Free)
    }

    /// The body's inertial force at `x` for a translation of it as a whole, and its stiffness:
    /// `Σ m_i/h² (y_i − x_i)` and `Σ m_i/h²` (its elastic energy does not change under one).
    pub fn inertia_as_a_whole(&self, x: &[Vector]) -> (Vector, Real) {
        let h2 = self.h * self.h;
        let force = (0..x.len())
            .map(|i| (self.y[i] - x[i]) * self.masses[i])
            .sum::<Vector>()
            / h2;
        (force, self.masses.iter().sum::<Real>() / h2)
    }

    /// Ends the step at `x`: `reactions` gets, per node, the force its hold exerted on it
    /// ([`ModelState::implicit_step`]); with `translate` and no node held, the body moves by
    /// the best translation (see the module docs). Returns shape matching's rotations, for
    /// [`ModelState::keep_rotations`].
    pub fn finish(
        self,
        x: &mut [Vector],
        reactions: &mut Vec<Vector>,
        translate: bool,
    ) -> Option<Vec<Rotation>> {
        let n = x.len();
        let (h, held, vertex) = (self.h, &self.held, &self.vertex);
        let at: &[Vector] = x;
        let volumes = self.gas_volumes(at);
        *reactions = threads::collect(n, |i| {
            if held[i] == Hold::Free {
                return Vector::ZERO;
            }
            let inertia = self.masses[i] / (h * h);
            let inertial = self.ahead[i] + self.gravity * (h * h);
            -vertex.newton(i, at, inertia, inertial, &volumes).0
        });
        if translate && held.iter().all(|h| *h == Hold::Free) {
            // The energy does not change under a translation, so the best one is exact: the
            // centre of mass where inertia and gravity take it. A few sweeps cannot move a
            // body much stiffer than `m/h²` as a whole; this makes its free flight ballistic.
            let masses = self.masses;
            let mass: Real = masses.iter().sum();
            let shift = (0..n)
                .map(|i| (self.y[i] - x[i]) * masses[i])
                .sum::<Vector>()
                / mass;
            if mass > 0.0 && shift.is_finite() {
                x.iter_mut().for_each(|p| *p += shift);
            }
        }
        self.vertex.shape.map(|s| s.rotations)
    }
}

/// Where each node's motion carries it over a step of length `h` without forces: `x₀ + h v₀`
/// plus the part of the body's rigid turn that a straight line misses, its centripetal and
/// Euler accelerations `ω × (ω × r) + α × r` (`r` the node's offset from the centre of mass,
/// `α = −I⁻¹ (ω × I ω)`, which cancels the centripetal part's torque), times
/// `2 (1 − cos θ)/|ω|²` for the turn per step `θ` whose chord velocities (a backward-Euler
/// step's) the body's rigid angular velocity `ω` fits: `sin θ = h |ω|` (at most 30° a step).
/// Straight ahead, every node of a spinning body ends farther out, the step pulls it back in
/// and the body spins slower: a box spun at 3 rad/s kept 54 % of its angular momentum over 5 s
/// at 60 Hz with two sweeps. With it a rigid turn carries on.
fn carried_ahead(x0: &[Vector], v0: &[Vector], masses: &[Real], h: Real) -> Vec<Vector> {
    let mut ahead: Vec<Vector> = x0.iter().zip(v0).map(|(x, v)| *x + *v * h).collect();
    let Some(Motion { r, momentum, .. }) = Motion::of(x0, v0, masses) else {
        return ahead;
    };
    let (omega, alpha) = math::torque_free_turn(&r, masses, momentum);
    let spin = math::ang_dot(omega, omega);
    let sine = (spin.sqrt() * h).min(0.5);
    if sine.is_nan() || sine <= 1e-6 {
        return ahead;
    }
    let scale = 2.0 * (1.0 - sine.asin().cos()) / spin;
    for (a, r) in ahead.iter_mut().zip(&r) {
        let turning =
            math::ang_cross(omega, math::ang_cross(omega, *r)) + math::ang_cross(alpha, *r);
        *a += turning * scale;
    }
    ahead
}

/// `f(i)` for each node of `nodes`, in order (`backward`: last first).
#[inline(always)]
fn in_order(nodes: Range<usize>, backward: bool, f: impl FnMut(usize)) {
    if backward {
        nodes.rev().for_each(f);
    } else {
        nodes.for_each(f);
    }
}

/// The terms of a body's elastic energy: its model's, the volumetric term's, the gas's.
type Energy<'a> = (&'a dyn ElementLaw, Option<&'a Volume>, Option<&'a Chambers>);

/// The fractions of each free node's inertial motion `h v₀` a step with held nodes may start
/// from.
const START_FRACTIONS: [Real; 3] = [1.0, 0.5, 0.0];

/// Moves the free nodes' start `x` (at `x₀ + h v₀`) to whichever of [`START_FRACTIONS`] of
/// their inertial motion has the least incremental potential (inertia and elastic energy, the
/// sweeps' own objective): a few sweeps cannot undo a start that pressed the free nodes into
/// the held ones (`docs/ARCHITECTURE.md` §4.2).
fn start_scaled(
    energy: Energy<'_>,
    input: &StepInput<'_>,
    (held, y): (&[Hold], &[Vector]),
    x: &mut [Vector],
) {
    let (x0, h, masses) = (input.x0, input.h, input.masses);
    let free: Vec<usize> = (0..x.len()).filter(|&i| held[i] == Hold::Free).collect();
    let objective = |x: &[Vector]| -> Real {
        let inertia: Real = free
            .iter()
            .map(|&i| masses[i] * (x[i] - y[i]).length_squared())
            .sum();
        inertia * (0.5 / (h * h)) + super::elastic_energy(energy.0, energy.1, energy.2, x)
    };
    let motion: Vec<Vector> = free.iter().map(|&i| x[i] - x0[i]).collect();
    let (mut best, mut least) = (1.0, objective(x));
    for &fraction in &START_FRACTIONS[1..] {
        for (&i, m) in free.iter().zip(&motion) {
            x[i] = x0[i] + *m * fraction;
        }
        let g = objective(x);
        if g < least {
            (best, least) = (fraction, g);
        }
    }
    for (&i, m) in free.iter().zip(&motion) {
        x[i] = x0[i] + *m * best;
    }
}

/// Share of a free body's kinetic energy about its centre of mass in motion relative to its
/// rigid motion above which [`start_rigid`] weighs the rigid start.
const RINGING: Real = 0.01;

/// Moves a free body's start `x` (at its motion carried ahead) to its rigid motion carried
/// ahead instead, if the body rings (more than [`RINGING`] of its kinetic energy about its
/// centre relative to its rigid motion) and that start has the lesser incremental potential:
/// the stiff modes a step cannot resolve carried `h v₀` ahead flatten cells (a silicone
/// ball's first implicit step after an impact's explicit substeps started 2 cm cells a
/// centimetre out of shape), and a few sweeps leave most of that stored.
fn start_rigid(energy: Energy<'_>, input: &StepInput<'_>, y: &[Vector], x: &mut [Vector]) {
    let (x0, v0, h, masses) = (input.x0, input.v0, input.h, input.masses);
    let Some(Motion {
        velocity,
        r,
        momentum,
    }) = Motion::of(x0, v0, masses)
    else {
        return;
    };
    let omega = math::angular_velocity_for(&r, masses, momentum);
    let rigid: Vec<Vector> = r
        .iter()
        .map(|r| velocity + math::ang_cross(omega, *r))
        .collect();
    let (mut about, mut relative) = (0.0, 0.0);
    for ((v, w), m) in v0.iter().zip(&rigid).zip(masses) {
        about += m * (*v - velocity).length_squared();
        relative += m * (*v - *w).length_squared();
    }
    if relative.partial_cmp(&(RINGING * about)) != Some(std::cmp::Ordering::Greater) {
        return;
    }
    let ahead = if input.chords {
        carried_ahead(x0, &rigid, masses, h)
    } else {
        x0.iter().zip(&rigid).map(|(x, v)| *x + *v * h).collect()
    };
    let objective = |x: &[Vector]| -> Real {
        let inertia: Real = x
            .iter()
            .zip(y)
            .zip(masses)
            .map(|((x, y), m)| m * (*x - *y).length_squared())
            .sum();
        inertia * (0.5 / (h * h)) + super::elastic_energy(energy.0, energy.1, energy.2, x)
    };
    if objective(&ahead) < objective(x) {
        x.copy_from_slice(&ahead);
    }
}

/// Where the sweeps may start.
struct Start<'a> {
    x0: &'a [Vector],
    /// The holds the step was given.
    given: &'a [Hold],
}

impl Start<'_> {
    /// Makes the start `x` one the line search can go on from, if a cell is too flat there
    /// (the held nodes moved through it): the contact nodes of such cells lift off (from where
    /// they started the step), and of the cells that leaves flat in turn; the pressed nodes of
    /// those still flat are held short of their targets ([`Hold::Pressed`]); then, if a cell
    /// still is, the free nodes go back to where they started the step. (A 60 Hz ball bounced
    /// its bottom nodes up through the 2 cm layer above, still falling, and every move of its
    /// nodes was then refused.)
    fn fix(
        &self,
        cells: &[u32],
        arity: usize,
        upright: impl Fn(usize, &[Vector]) -> bool + Sync,
        x: &mut [Vector],
        held: &mut [Hold],
    ) {
        let count = cells.len() / arity;
        if threads::all(count, |c| upright(c, x)) {
            return;
        }
        // Lifting a node off moves it back up, which can flatten a cell of its that was not:
        // lift until no cell is flat or every contact node of the flat ones is lifted.
        let lift = |x: &mut [Vector], held: &mut [Hold]| {
            let mut any = false;
            loop {
                let mut lifted = false;
                for c in 0..count {
                    if upright(c, x) {
                        continue;
                    }
                    any = true;
                    for &i in &cells[c * arity..(c + 1) * arity] {
                        let i = i as usize;
                        // A node that carries a body's share starts where it started the step.
                        if matches!(self.given[i], Hold::Carries { .. }) && x[i] != self.x0[i] {
                            x[i] = self.x0[i];
                            lifted = true;
                            continue;
                        }
                        if matches!(self.given[i], Hold::Contact { .. })
                            && !matches!(held[i], Hold::Above { .. })
                        {
                            held[i] = self.given[i].lifted();
                            x[i] = held[i].start(x[i], self.x0[i]);
                            lifted = true;
                        }
                    }
                }
                if !lifted {
                    return any;
                }
            }
        };
        let any_flat = lift(x, held);
        // The pressed nodes of each cell still flat go back together toward where they
        // started the step, halving (a node's share of its target only ever shrinks), until
        // no flat cell has one left to move.
        let mut fraction: Vec<Real> = vec![1.0; x.len()];
        loop {
            let mut moved = false;
            for c in 0..count {
                if upright(c, x) {
                    continue;
                }
                for &i in &cells[c * arity..(c + 1) * arity] {
                    let i = i as usize;
                    let Hold::Pressed(target) = self.given[i] else {
                        continue;
                    };
                    if fraction[i] == 0.0 {
                        continue;
                    }
                    fraction[i] *= 0.5;
                    if fraction[i] < 1.0 / 1024.0 {
                        fraction[i] = 0.0;
                    }
                    x[i] = self.x0[i] + (target - self.x0[i]) * fraction[i];
                    held[i] = Hold::At(x[i]);
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        if any_flat && (0..count).any(|c| !upright(c, x)) {
            for ((x, x0), held) in x.iter_mut().zip(self.x0).zip(held.iter()) {
                if *held == Hold::Free {
                    *x = *x0;
                }
            }
            lift(x, held);
        }
    }
}

/// Each shape-based cell vertex's residual `r − q R0` at `x` (one per slot).
fn shape_residuals(sm: &ShapeMatching, x: &[Vector], rotations: &[Rotation]) -> Vec<Vector> {
    let n = sm.arity();
    threads::collect(sm.cell_indices().len(), |slot| {
        sm.residual(slot / n, slot % n, x, rotations[slot / n])
    })
}

/// The shape-based cells under the implicit step: their rotations as last refitted, and each
/// slot's residual at the start of the step (its dashpot damps the residual's change, so a
/// rigid turn is not damped).
struct Shape<'a> {
    cells: &'a ShapeMatching,
    rotations: Vec<Rotation>,
    start: Vec<Vector>,
}

/// A node's Newton step on the incremental potential.
struct Vertex<'a> {
    springs: Option<&'a Springs>,
    er: Option<&'a EdgeRepulsion>,
    shape: Option<Shape<'a>>,
    /// The volumetric term (on the same cells as the incidence's).
    volume: Option<&'a Volume>,
    /// The gas, its pressures at the chamber volumes each Newton step is given.
    gas: Option<&'a Chambers>,
    incidence: &'a Incidence,
    x0: &'a [Vector],
    h: Real,
}

impl Vertex<'_> {
    /// `f_i = −∂G/∂x_i` and the block `H_i` at `x`, and how far node `i` may move from `x`,
    /// at least, keeping every cell of its upright ([`cell_upright`]; zero, unknown, without
    /// edge repulsion).
    fn newton<P: Positions + ?Sized>(
        &self,
        i: usize,
        x: &P,
        inertia: Real,
        y: Vector,
        volumes: &[Real],
    ) -> (Vector, Matrix, Real) {
        let mut f = (y - x.at(i)) * inertia;
        let mut block = Matrix::IDENTITY * inertia;
        if let Some(gas) = self.gas {
            if gas.touches(i) {
                let (df, db) = gas.node_terms(i, |j| x.at(j), volumes);
                f += df;
                block += db;
            }
        }
        if let Some(s) = self.springs {
            self.add_springs(s, i, x, &mut f, &mut block);
        }
        let mut reach = 0.0;
        if let Some(er) = self.er {
            let df;
            let db;
            (df, db, reach) = cell_lanes_at(er, self.volume, self.incidence.cells_of(i), x);
            f += df;
            block += db;
        } else if let Some(volume) = self.volume {
            for &(cell, a) in self.incidence.cells_of(i) {
                let cell = cell as usize;
                let ids = &volume.cells()[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
                let p: [Vector; SIMPLEX_ARITY] = std::array::from_fn(|b| x.at(ids[b] as usize));
                let (d, g) = math::simplex_gradients(&p);
                let (df, db) = volume.vertex_terms_at(cell, a as usize, d, &g);
                f += df;
                block += db;
            }
        }
        if let Some(shape) = &self.shape {
            // `k/2 |r_a − q R0_a|²` with `q` held: force `−k e_a` (the other vertices' residuals
            // sum to `−e_a`), block `k (1 − 1/n)`; the dashpot `c/(2h) |e_a − e_a⁰|²` likewise.
            let n = shape.cells.arity();
            for &(cell, a) in self.incidence.cells_of(i) {
                let (cell, a) = (cell as usize, a as usize);
                let (k, c) = shape.cells.law(cell);
                let e = shape
                    .cells
                    .residual_with(cell, a, |j| x.at(j), shape.rotations[cell]);
                let c = c / self.h;
                f -= e * k + (e - shape.start[cell * n + a]) * c;
                block += hessian::shape_block(n, k + c);
            }
        }
        (f, block, reach)
    }

    /// The springs at node `i` (with their dashpots, implicit).
    fn add_springs<P: Positions + ?Sized>(
        &self,
        s: &Springs,
        i: usize,
        x: &P,
        f: &mut Vector,
        block: &mut Matrix,
    ) {
        if s.law == Law::Linear {
            let (df, db) =
                linear_spring_lanes_at(s, i, self.incidence.springs_of(i), x, self.x0, self.h);
            *f += df;
            *block += db;
            return;
        }
        for &k in self.incidence.springs_of(i) {
            let k = k as usize;
            let [a, b] = s.pairs[k];
            let j = if a as usize == i { b } else { a } as usize;
            let (xi, xj) = (x.at(i), x.at(j));
            let d = xi - xj;
            let l = d.length();
            if l <= Real::MIN_POSITIVE {
                continue;
            }
            let normal = d / l;
            let (du, ddu) = match s.law {
                Law::Linear => hessian::linear_spring(l, s.rest[k], s.k[k]),
                Law::Nonlinear => hessian::nonlinear_spring(l, s.rest[k], s.k[k]),
            };
            *f -= normal * du;
            *block += hessian::radial_block(d, du, ddu);
            // The dashpot, implicit: c/h along the spring, on the step's relative motion.
            let c = s.c[k] / self.h;
            let moved = (xi - self.x0[i]) - (xj - self.x0[j]);
            *f -= normal * (c * normal.dot(moved));
            *block += math::outer(normal, normal) * c;
        }
    }

    /// `x_i + α step` with the largest `α ∈ {1, ½, ¼, …}` (ten halvings) that keeps every
    /// repulsion of the node's cells above [`MIN_STEP_HEIGHT`] of its rest height; the node
    /// stays if none does.
    fn line_search<P: Positions + ?Sized>(
        &self,
        i: usize,
        x: &P,
        step: Vector,
        hold: Hold,
        reach: Real,
    ) -> Vector {
        let start = x.at(i);
        let whole = hold.project(start + step);
        if (whole - start).length() < reach {
            return whole;
        }
        let simplex_shapes = self
            .shape
            .as_ref()
            .filter(|s| s.cells.arity() == SIMPLEX_ARITY);
        if self.er.is_none() && simplex_shapes.is_none() {
            return hold.project(start + step);
        }
        // The vertices of a cell, node `i` at `p`.
        let at = |ids: &[u32], p: Vector| -> [Vector; SIMPLEX_ARITY] {
            std::array::from_fn(|a| {
                let j = ids[a] as usize;
                if j == i {
                    p
                } else {
                    x.at(j)
                }
            })
        };
        // A cell that the held nodes left flatter than the bound may not get flatter (else
        // it could never come back: every move of its free vertices would be refused).
        let upright = |cell: usize, p: Vector| match (self.er, simplex_shapes) {
            (Some(er), _) => {
                let ids = &er.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
                let (now, then) = (at(ids, p), at(ids, start));
                cell_upright(er, cell, &now)
                    || height_ratio(er, cell, &now) >= height_ratio(er, cell, &then)
            }
            (None, Some(shape)) => {
                let n = SIMPLEX_ARITY;
                let ids = &shape.cells.cell_indices()[cell * n..(cell + 1) * n];
                let now = shape.cells.volume_ratio_of(cell, &at(ids, p));
                now > MIN_STEP_VOLUME || now >= shape.cells.volume_ratio_of(cell, &at(ids, start))
            }
            (None, None) => true,
        };
        let cells = self.incidence.cells_of(i);
        let mut alpha = 1.0;
        for _ in 0..=10 {
            let p = hold.project(start + step * alpha);
            let kept = match self.er {
                // Most cells pass the cheaper test, several at a time.
                Some(er) => cells.chunks(LANES).all(|batch| {
                    let passed = uprights(er, batch, i, p, x);
                    batch
                        .iter()
                        .enumerate()
                        .all(|(l, &(cell, _))| passed & (1 << l) != 0 || upright(cell as usize, p))
                }),
                None => cells.iter().all(|&(cell, _)| upright(cell as usize, p)),
            };
            if kept {
                return p;
            }
            alpha *= 0.5;
        }
        start
    }
}

/// The linear springs `springs` of node `i` at `i`, with their implicit dashpots: `−∂G/∂x_i`
/// and the block, as [`Vertex::add_springs`] sums them one by one ([`hessian::radial_block`]
/// plus the dashpot's `c/h n nᵀ`), [`LANES`] springs at a time.
#[inline(always)]
fn linear_spring_lanes_at<P: Positions + ?Sized>(
    s: &Springs,
    i: usize,
    springs: &[u32],
    x: &P,
    x0: &[Vector],
    h: Real,
) -> (Vector, Matrix) {
    let (one, zero, tiny) = (Lane::ONE, Lane::ZERO, Lane::splat(Real::MIN_POSITIVE));
    let lane_index = Lane::new(each(|l| l as Real));
    let (xi, x0i) = (x.at(i), x0[i]);
    let splat = |v: Vector| LaneVector(each(|d| Lane::splat(v[d])));
    let (xi_lanes, moved_i) = (splat(xi), splat(xi - x0i));
    let mut f = LaneVector::ZERO;
    let mut outer = [[zero; DIM]; DIM];
    let mut diagonal = zero;
    for batch in springs.chunks(LANES) {
        // Lanes past the end repeat the last spring and count for nothing.
        let counted = lane_index.simd_lt(Lane::splat(batch.len() as Real));
        let k: [usize; LANES] = each(|l| batch[l.min(batch.len() - 1)] as usize);
        let other: [usize; LANES] = each(|l| {
            let [a, b] = s.pairs[k[l]];
            (if a as usize == i { b } else { a }) as usize
        });
        let xj = LaneVector::gather(|l| x.at(other[l]));
        let moved_j = LaneVector::gather(|l| x.at(other[l]) - x0[other[l]]);
        let rest = Lane::new(each(|l| s.rest[k[l]]));
        let stiffness = Lane::new(each(|l| s.k[k[l]]));
        let c = Lane::new(each(|l| s.c[k[l]])) / Lane::splat(h);
        let d = xi_lanes - xj;
        let l2 = d.length_squared();
        let live = l2.simd_gt(tiny) & counted;
        let l = live.select(l2, one).sqrt();
        let n = d * (one / l);
        let du = stiffness * (l - rest);
        let transverse = (du / l).fast_max(zero);
        let along = n.dot(moved_i - moved_j);
        f += n.or_zero(live) * -(du + c * along);
        // `n nᵀ (k − transverse + c) + transverse I`.
        let w = live.select(stiffness - transverse + c, zero);
        for (col, column) in outer.iter_mut().enumerate() {
            for (row, entry) in column.iter_mut().enumerate().take(col + 1) {
                *entry += n.0[row] * n.0[col] * w;
            }
        }
        diagonal += live.select(transverse, zero);
    }
    let diagonal = diagonal.reduce_add();
    let mut out = Matrix::ZERO;
    for (col, column) in outer.iter().enumerate() {
        for (row, entry) in column.iter().enumerate().take(col + 1) {
            let sum = entry.reduce_add();
            out.col_mut(col)[row] = sum;
            out.col_mut(row)[col] = sum;
        }
        out.col_mut(col)[col] += diagonal;
    }
    (Vector::from_array(each(|d| f.0[d].reduce_add())), out)
}

/// The positions of `cell`'s vertices.
#[inline(always)]
fn cell_positions<P: Positions + ?Sized>(
    er: &EdgeRepulsion,
    cell: usize,
    x: &P,
) -> [Vector; SIMPLEX_ARITY] {
    let ids = &er.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
    std::array::from_fn(|a| x.at(ids[a] as usize))
}

/// `D` of a cell at vertex positions `p` and its gradients ([`math::simplex_gradients`]), `D`
/// signed so that it is positive on the rest side.
#[inline(always)]
fn cell_geometry(
    er: &EdgeRepulsion,
    cell: usize,
    p: &[Vector; SIMPLEX_ARITY],
) -> (Real, [Vector; SIMPLEX_ARITY]) {
    let (d, g) = math::simplex_gradients(p);
    (d * er.sign[cell], g)
}

/// The repulsions of `cell` at its vertex `a`: `−∂E/∂x_a` and the Gauss–Newton block, the
/// same terms as [`super::edge_repulsion::repulsion`] and [`hessian::repulsion_blocks`] from
/// one evaluation of the cell. Each height is `h_b = D / |g_b|` along `n_b = ± g_b / |g_b|`,
/// and the foot of vertex `b` has weight `−g_a·g_b / |g_b|²` at a facet vertex `a`. (The
/// step sums these for many cells at once: [`cell_lanes_at`].)
#[cfg(test)]
fn repulsion_terms(
    er: &EdgeRepulsion,
    cell: usize,
    a: usize,
    (d, g): (Real, &[Vector; SIMPLEX_ARITY]),
) -> (Vector, Matrix) {
    let sign = er.sign[cell];
    let mut f = Vector::ZERO;
    let mut block = Matrix::ZERO;
    for (b, gb) in g.iter().enumerate() {
        let g2 = gb.length_squared();
        if g2 <= Real::MIN_POSITIVE {
            continue;
        }
        let slot = cell * SIMPLEX_ARITY + b;
        let (h0, k) = (er.h0[slot], er.k[slot]);
        // Written with one root and two divisions: `n = ± g_b / |g_b|`, `h = D / |g_b|`, the
        // term's force `k (h0²/h − h) n` and stiffness `k (1 + h0²/h²)` (the law clamped as in
        // [`magnitude`]).
        let inv_g2 = 1.0 / g2;
        let len = g2.sqrt();
        let h = d * len * inv_g2;
        let (push, stiffness) = barrier(h, h0, k);
        // The share of the term at `a`: 1 at the vertex, minus its foot weight on the facet.
        let share = if b == a { 1.0 } else { g[a].dot(*gb) * inv_g2 };
        f += *gb * (sign * len * inv_g2 * push * share);
        block += math::outer(*gb, *gb) * (inv_g2 * stiffness * share * share);
    }
    (f, block)
}

/// The repulsions and volumetric terms of the cells `cells` (each with the local index of
/// the vertex asked) at that vertex: [`repulsion_terms`] plus [`Volume::vertex_terms_at`]
/// summed, [`LANES`] cells at a time, and how far the vertex may move, at least, keeping every
/// cell upright ([`cell_upright`]). One evaluation of each cell's volume gradients serves its
/// repulsions, its volumetric term and that reach.
///
/// The reach: moving vertex `a` by `δ` changes `D` by `g_a·δ` and, for `b ≠ a`, `g_b` by
/// `δ × e` (3D; `e` an edge of the facet opposite `a`) or by `δ` turned (2D), so `D ≥ d − |g_a|
/// |δ|` and `|g_b| ≤ |g_b| + L |δ|` (`L` the facet's longest edge, 1 in 2D). The cell stays
/// upright (`D > h_min,b |g_b|` for every `b`) while `|δ|` is below each
/// `(D − h_min,b |g_b|) / (|g_a| + h_min,b L)` (`L` left out for `b = a`, whose `g_a` does not
/// change); half the smallest is returned, so rounding cannot matter.
#[inline(always)]
fn cell_lanes_at<P: Positions + ?Sized>(
    er: &EdgeRepulsion,
    volume: Option<&Volume>,
    cells: &[(u32, u8)],
    x: &P,
) -> (Vector, Matrix, Real) {
    let (ids, _) = er.cells.as_chunks::<SIMPLEX_ARITY>();
    let (rest_heights, _) = er.h0.as_chunks::<SIMPLEX_ARITY>();
    let (stiffnesses, _) = er.k.as_chunks::<SIMPLEX_ARITY>();
    let (one, zero, tiny) = (Lane::ONE, Lane::ZERO, Lane::splat(Real::MIN_POSITIVE));
    let lane_index = Lane::new(each(|l| l as Real));
    let mut f = LaneVector::ZERO;
    let mut block = [[zero; DIM]; DIM];
    let mut reach = Real::INFINITY;
    for batch in cells.chunks(LANES) {
        // Lanes past the end repeat the last cell and count for nothing.
        let counted = lane_index.simd_lt(Lane::splat(batch.len() as Real));
        let lane: [(usize, usize); LANES] = each(|l| {
            let (cell, a) = batch[l.min(batch.len() - 1)];
            (cell as usize, a as usize)
        });
        let xs: [LaneVector; SIMPLEX_ARITY] =
            each(|b| LaneVector::gather(|l| x.at(ids[lane[l].0][b] as usize)));
        let sign = Lane::new(each(|l| er.sign[lane[l].0]));
        let (raw, g) = lanes::simplex_gradients(&xs);
        let d = raw * sign;
        let vertex = Lane::new(each(|l| lane[l].1 as Real));
        let is: [Lane; SIMPLEX_ARITY] = each(|b| vertex.simd_eq(Lane::splat(b as Real)));
        // `g_a`, the gradient at each lane's own vertex.
        let mut ga = LaneVector::ZERO;
        for b in 0..SIMPLEX_ARITY {
            ga += g[b].or_zero(is[b]);
        }
        let ga_length = ga.length_squared().sqrt();
        // The longest edge of the facet opposite each lane's vertex (its square).
        let mut longest = zero;
        if DIM == 3 {
            for u in 0..SIMPLEX_ARITY {
                for w in u + 1..SIMPLEX_ARITY {
                    let off = !(is[u] | is[w]);
                    longest = off
                        .select((xs[u] - xs[w]).length_squared(), zero)
                        .fast_max(longest);
                }
            }
        } else {
            longest = one;
        }
        let longest = longest.sqrt();
        let mut lane_reach = d.simd_gt(zero).select(Lane::splat(Real::INFINITY), zero);
        // The block is symmetric: its upper triangle is summed, mirrored at the end.
        let mut add_block = |v: LaneVector, s: Lane| {
            for (c, column) in block.iter_mut().enumerate() {
                for (r, entry) in column.iter_mut().enumerate().take(c + 1) {
                    *entry += v.0[r] * v.0[c] * s;
                }
            }
        };
        for b in 0..SIMPLEX_ARITY {
            let h0 = Lane::new(each(|l| rest_heights[lane[l].0][b]));
            let k = Lane::new(each(|l| stiffnesses[lane[l].0][b]));
            let g2 = g[b].length_squared();
            let live = g2.simd_gt(tiny) & counted;
            let g2 = live.select(g2, one);
            let inv_g2 = one / g2;
            let len = g2.sqrt();
            let (push, stiffness) = barrier_lanes(d * len * inv_g2, h0, k);
            let h_min = Lane::splat(MIN_STEP_HEIGHT) * h0;
            let room = d - h_min * len;
            let rate = ga_length + is[b].select(zero, h_min * longest);
            let allowed = room.simd_gt(zero).select(room / rate, zero);
            lane_reach = live.select(allowed, zero).fast_min(lane_reach);
            // The share of the term at the vertex: 1 at it, minus its foot weight on the facet.
            let share = is[b].select(one, ga.dot(g[b]) * inv_g2);
            f += g[b].or_zero(live) * (sign * len * inv_g2 * push * share);
            add_block(g[b], live.select(inv_g2 * stiffness * share * share, zero));
        }
        if let Some(volume) = volume {
            let (force, scale) = volume.vertex_lanes(each(|l| lane[l].0), raw, ga);
            f += force.or_zero(counted);
            add_block(ga, counted.select(scale, zero));
        }
        let lane_reach = counted.select(lane_reach, Lane::splat(Real::INFINITY));
        reach = lane_reach.to_array().into_iter().fold(reach, Real::min);
    }
    let mut out = Matrix::ZERO;
    for (c, column) in block.iter().enumerate() {
        for (r, entry) in column.iter().enumerate().take(c + 1) {
            let sum = entry.reduce_add();
            out.col_mut(c)[r] = sum;
            out.col_mut(r)[c] = sum;
        }
    }
    (
        Vector::from_array(each(|d| f.0[d].reduce_add())),
        out,
        0.5 * reach,
    )
}

/// [`barrier`] in lanes.
#[inline(always)]
fn barrier_lanes(h: Lane, h0: Lane, k: Lane) -> (Lane, Lane) {
    let at = h.fast_max(Lane::splat(MIN_STEP_HEIGHT) * h0);
    let q = h0 / at;
    let stiffness = k * (Lane::ONE + q * q);
    (k * (h0 * q - at) + stiffness * (at - h), stiffness)
}

/// A repulsion's push `k (h0²/h − h)` and stiffness `k (1 + h0²/h²)` at height `h`, continued
/// below [`MIN_STEP_HEIGHT`] of the rest height by the law's tangent there (a quadratic energy):
/// a cell held that flat or turned inside out gets a Newton step that brings it back up to
/// that height, where the law's own stiffness (~10¹² k, clamped only near zero) gives it none.
#[inline(always)]
fn barrier(h: Real, h0: Real, k: Real) -> (Real, Real) {
    let low = MIN_STEP_HEIGHT * h0;
    let at = h.max(low);
    let q = h0 / at;
    let stiffness = k * (1.0 + q * q);
    (k * (h0 * q - at) + stiffness * (at - h), stiffness)
}

/// Whether every repulsion of `cell` (its vertices at `p`) keeps its vertex above
/// [`MIN_STEP_HEIGHT`] of its rest height, on the rest side.
fn cell_upright(er: &EdgeRepulsion, cell: usize, p: &[Vector; SIMPLEX_ARITY]) -> bool {
    let (d, g) = cell_geometry(er, cell, p);
    d > 0.0
        && g.iter().enumerate().all(|(b, gb)| {
            let h_min = MIN_STEP_HEIGHT * er.h0[cell * SIMPLEX_ARITY + b];
            d * d > h_min * h_min * gb.length_squared()
        })
}

/// Whether every cell of `cells` is upright at `x` ([`cell_upright`], the same arithmetic),
/// [`LANES`] cells at a time.
fn cells_upright(er: &EdgeRepulsion, x: &[Vector], cells: Range<usize>) -> bool {
    let (ids, _) = er.cells.as_chunks::<SIMPLEX_ARITY>();
    let (rest_heights, _) = er.h0.as_chunks::<SIMPLEX_ARITY>();
    let h_min = Lane::splat(MIN_STEP_HEIGHT);
    cells.clone().step_by(LANES).all(|first| {
        // The last batch repeats its last cell in the lanes past the end.
        let cell: [usize; LANES] = each(|l| (first + l).min(cells.end - 1));
        let xs: [LaneVector; SIMPLEX_ARITY] =
            each(|b| LaneVector::gather(|l| x[ids[cell[l]][b] as usize]));
        let (d, g) = lanes::simplex_gradients(&xs);
        let d = d * Lane::new(each(|l| er.sign[cell[l]]));
        let mut ok = d.simd_gt(Lane::ZERO);
        for (b, gb) in g.iter().enumerate() {
            let low = h_min * Lane::new(each(|l| rest_heights[cell[l]][b]));
            ok &= (d * d).simd_gt(low * low * gb.length_squared());
        }
        ok.all()
    })
}

/// [`cell_upright`] of the cells `batch` (at most [`LANES`]), node `i` at `p` and the others
/// at `x`: bit `l` set where cell `l` is.
#[inline(always)]
fn uprights<P: Positions + ?Sized>(
    er: &EdgeRepulsion,
    batch: &[(u32, u8)],
    i: usize,
    p: Vector,
    x: &P,
) -> u32 {
    let (ids, _) = er.cells.as_chunks::<SIMPLEX_ARITY>();
    let (rest_heights, _) = er.h0.as_chunks::<SIMPLEX_ARITY>();
    let cell: [usize; LANES] = each(|l| batch[l.min(batch.len() - 1)].0 as usize);
    let xs: [LaneVector; SIMPLEX_ARITY] = each(|b| {
        LaneVector::gather(|l| {
            let j = ids[cell[l]][b] as usize;
            if j == i {
                p
            } else {
                x.at(j)
            }
        })
    });
    let (d, g) = lanes::simplex_gradients(&xs);
    let d = d * Lane::new(each(|l| er.sign[cell[l]]));
    let mut ok = d.simd_gt(Lane::ZERO);
    for (b, gb) in g.iter().enumerate() {
        let h_min = Lane::splat(MIN_STEP_HEIGHT) * Lane::new(each(|l| rest_heights[cell[l]][b]));
        ok &= (d * d).simd_gt(h_min * h_min * gb.length_squared());
    }
    ok.to_bitmask()
}

/// The smallest height of `cell`'s vertices (at `p`) over their rest heights (negative once
/// inverted).
fn height_ratio(er: &EdgeRepulsion, cell: usize, p: &[Vector; SIMPLEX_ARITY]) -> Real {
    let (d, g) = cell_geometry(er, cell, p);
    g.iter()
        .enumerate()
        .map(|(b, gb)| d / (gb.length() * er.h0[cell * SIMPLEX_ARITY + b]).max(Real::MIN_POSITIVE))
        .fold(Real::INFINITY, Real::min)
}

/// The inverse of a block, if it is well conditioned enough to have one.
fn invert(m: Matrix) -> Option<Matrix> {
    let det = m.determinant();
    (det.is_finite() && det.abs() > Real::MIN_POSITIVE).then(|| m.inverse())
}

#[cfg(test)]
mod tests {
    use super::super::super::body::DeformableBuilder;
    use super::super::super::math::FACET_ARITY;
    use super::super::edge_repulsion::{repulsion, OPPOSITE};
    use super::super::ElementModel;
    use super::*;

    fn max_diff(a: Matrix, b: Matrix) -> Real {
        (0..math::DIM)
            .flat_map(|c| (0..math::DIM).map(move |r| (c, r)))
            .map(|(c, r)| (a.col(c)[r] - b.col(c)[r]).abs())
            .fold(0.0, Real::max)
    }

    #[test]
    fn a_large_body_sweeps_by_slabs_that_no_term_spans_beyond_a_neighbour() {
        let (small, large) = if math::DIM == 3 { (9, 17) } else { (30, 60) };
        for (res, slabbed) in [(small, false), (large, true)] {
            let body = DeformableBuilder::cuboid(Vector::splat(0.5), [res; math::DIM])
                .model(ElementModel::EdgeRepulsion)
                .build()
                .unwrap();
            let er = super::super::fixtures::er_of(&body);
            let n = body.state.positions.len();
            let incidence = Incidence::of(&*body.state.elements.elements, None, n).unwrap();
            let slab = incidence.slab;
            assert_eq!(slab < n, slabbed, "res {res}: slab {slab} of {n} nodes");
            if !slabbed {
                continue;
            }
            assert!(n.div_ceil(slab) >= MIN_SLABS && slab >= MIN_SLAB_NODES);
            for ids in er.cells.chunks_exact(SIMPLEX_ARITY) {
                let slabs = ids.iter().map(|&i| i as usize / slab);
                let (low, high) = (slabs.clone().min().unwrap(), slabs.max().unwrap());
                assert!(high - low <= 1, "cell {ids:?} spans slabs {low}..={high}");
            }
        }
    }

    #[test]
    fn one_evaluation_per_cell_gives_each_repulsions_force_and_block() {
        // A lattice squashed to 60 % of its height and sheared, so the barriers are loaded and
        // the feet fall off-centre: the per-vertex terms from one evaluation of the cell must
        // equal the four repulsions (and their finite-difference-tested blocks) evaluated apart.
        let body = super::super::fixtures::er_lattice(Vector::splat(0.5), [4; math::DIM]);
        let er = super::super::fixtures::er_of(&body);
        let x = super::super::squashed(&body.state.positions, 0.6, 0.3);
        let mut loaded = 0;
        for cell in 0..er.cells.len() / SIMPLEX_ARITY {
            let ids = &er.cells[cell * SIMPLEX_ARITY..(cell + 1) * SIMPLEX_ARITY];
            for a in 0..SIMPLEX_ARITY {
                let (mut f, mut block) = (Vector::ZERO, Matrix::ZERO);
                for (b, facet_ids) in OPPOSITE.iter().enumerate() {
                    let slot = cell * SIMPLEX_ARITY + b;
                    let facet: [Vector; FACET_ARITY] =
                        std::array::from_fn(|m| x[ids[facet_ids[m]] as usize]);
                    let c = x[ids[b] as usize];
                    let r = repulsion(c, &facet, er.side[slot], er.h0[slot], er.k[slot]);
                    let blocks = hessian::repulsion_blocks(&r);
                    if b == a {
                        f += r.force;
                        block += blocks[0];
                    } else {
                        let m = facet_ids.iter().position(|&l| l == a).unwrap();
                        f -= r.force * r.weights[m];
                        block += blocks[m + 1];
                    }
                }
                let (d, g) = cell_geometry(er, cell, &cell_positions(er, cell, &x[..]));
                let (f2, block2) = repulsion_terms(er, cell, a, (d, &g));
                let scale = f.length().max(1e-3);
                assert!(
                    (f - f2).length() < 1e-3 * scale,
                    "cell {cell}/{a}: {f} {f2}"
                );
                let b_scale = max_diff(block, Matrix::ZERO).max(1e-3);
                assert!(max_diff(block, block2) < 1e-3 * b_scale, "cell {cell}/{a}");
                loaded += usize::from(f.length() > 1e-2);
            }
        }
        assert!(loaded > 10, "the squash loads the barriers");
    }

    /// Calls `check` with an edge-repulsion lattice squashed and sheared: its elements, its
    /// volumetric term, their incidence and the squashed positions.
    fn with_squashed_er(
        check: impl FnOnce(&EdgeRepulsion, Option<&Volume>, &Incidence, &[Vector]),
    ) {
        let body = super::super::fixtures::er_lattice(Vector::splat(0.05), [4; math::DIM]);
        let x = super::super::squashed(&body.state.positions, 0.5, 0.6);
        let elements = &body.state.elements;
        let er = super::super::fixtures::er_of(&body);
        let volume = elements.volume.as_ref();
        let incidence = Incidence::of(&*elements.elements, volume, x.len()).unwrap();
        check(er, volume, &incidence, &x);
    }

    #[test]
    fn the_cell_lanes_sum_each_cells_terms_at_the_vertex() {
        with_squashed_er(|er, volume, incidence, x| {
            let mut scale = 1e-3;
            let mut results = Vec::new();
            for i in 0..x.len() {
                let cells = incidence.cells_of(i);
                let (f, block, _) = cell_lanes_at(er, volume, cells, x);
                let (mut f1, mut block1) = (Vector::ZERO, Matrix::ZERO);
                for &(cell, a) in cells {
                    let (cell, a) = (cell as usize, a as usize);
                    let (d, g) = cell_geometry(er, cell, &cell_positions(er, cell, x));
                    let (df, db) = repulsion_terms(er, cell, a, (d, &g));
                    let (dv, dbv) = volume
                        .unwrap()
                        .vertex_terms_at(cell, a, d * er.sign[cell], &g);
                    (f1, block1) = (f1 + df + dv, block1 + db + dbv);
                }
                scale = f1.length().max(scale);
                results.push((f, f1, block, block1));
            }
            for (i, (f, f1, block, block1)) in results.into_iter().enumerate() {
                assert!((f - f1).length() < 1e-4 * scale, "node {i}: {f} {f1}");
                let b_scale = max_diff(block1, Matrix::ZERO).max(1e-3);
                assert!(max_diff(block, block1) < 1e-4 * b_scale, "node {i}");
            }
        });
    }

    #[test]
    fn a_node_moved_within_its_reach_leaves_its_cells_upright() {
        with_squashed_er(|er, volume, incidence, x| {
            let mut reaches = Vec::new();
            for i in 0..x.len() {
                let cells = incidence.cells_of(i);
                let (_, _, reach) = cell_lanes_at(er, volume, cells, x);
                reaches.push(reach);
                // Along each axis and diagonal, both ways, at the reach and at twice it (what
                // rounding and the half kept in hand allow).
                for k in 0..3usize.pow(math::DIM as u32) {
                    let mut dir = Vector::ZERO;
                    for d in 0..math::DIM {
                        dir[d] = (k / 3usize.pow(d as u32) % 3) as Real - 1.0;
                    }
                    if dir == Vector::ZERO {
                        continue;
                    }
                    let mut y = x.to_vec();
                    y[i] += dir.normalize() * (1.999 * reach);
                    for &(cell, _) in cells {
                        let cell = cell as usize;
                        assert!(
                            cell_upright(er, cell, &cell_positions(er, cell, &y[..])),
                            "node {i}, cell {cell}, moved {reach} along {dir}"
                        );
                    }
                }
            }
            // The reach is within the squashed cells' height, and mostly not zero.
            let height = 0.5 * 0.1 / 3.0;
            assert!(reaches.iter().all(|r| *r < height), "{reaches:?}");
            assert!(reaches.iter().filter(|r| **r > 0.0).count() > x.len() / 2);
        });
    }
}
