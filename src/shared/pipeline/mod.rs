//! One step of every deformable, run before rapier's `PhysicsPipeline::step` over the same
//! `dt` (`docs/ARCHITECTURE.md` §4).
//!
//! [`DeformablePipeline::step`] is a list of phases, each a function of its own file:
//!
//! 1. **wake** ([`sleep`]): a sleeping body wakes if a bone it is bound to moves, a collider it
//!    touched was removed, or a moving body comes near; an asleep body skips the rest.
//! 2. **prepare** ([`prepare`]): the state is saved for a rollback; how every relevant rigid
//!    body moves over the step ([`BodyMotion`](super::coupling::BodyMotion)); the broad phase:
//!    one query per deformable, then per surface node and per surface facet, into tables of
//!    candidates; the dynamic bodies it may push are backed up.
//! 3. **substeps** ([`substep`]): each body advances on its own substeps. Every substep:
//!    element forces at the current state (with each node's Gershgorin stiffness and damping
//!    bounds); the substep size, the remaining time split evenly into pieces no longer than
//!    the integrator's stability bound (for symplectic Euler, the papers' integrator,
//!    `safety · min_i 2/ω_i (√(1+ζ_i²) − ζ_i)`, [`stable_substep`](super::model::stable_substep))
//!    and than the edge-repulsion crossing limiter allows; the integrator's velocity update
//!    (`v += h (f/m + g)`, [`super::integrator`]); the bone drive ([`super::attach`]); contacts on
//!    velocities, nodes against colliders then rigid features against surface facets
//!    ([`super::contact`]); `x += h v`.
//! 4. **containment** ([`containment`]): a state that turned non-finite, or a cell stretched
//!    past `max_stretch`, is rolled back to the start of the step with the rigid bodies it
//!    pushed, and the body frozen; the surface's hierarchy is refitted to the final positions.
//! 5. **report** ([`finish`]): penetration, inverted cells, energies, stage timings.
//! 6. **sleep** ([`sleep`]): still long enough with nothing moving near it (a dynamic body
//!    resting on it, slower than rapier lets a body sleep at, does not count), the body sleeps,
//!    and the dynamic bodies it touches or is bound to sleep with it; a woken body wakes them.
//! 7. **events** ([`finish`]): the colliders touched this step against those of the last.
//!
//! After every body: the dynamic bodies they pushed get rapier's integration compensated
//! ([`match_rapier_integration`](super::coupling::match_rapier_integration)).

mod containment;
mod finish;
mod prepare;
mod sleep;
mod substep;

use std::time::Instant;

use super::body::Deformable;
use super::contact::{Candidate, ContactMaterial, ContactPoint, Scan};
use super::coupling::{self, BodyMotion, RigidBackup};
use super::events::DeformableEventHandler;
use super::integrator::SymplecticEuler;
use super::math::{Real, Vector};
use super::rapier::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{BroadPhaseBvh, ColliderHandle, ColliderSet};
use super::report::StepReport;
use super::set::{DeformableHandle, DeformableSet};

/// Knobs of the pipeline.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PipelineSettings {
    /// Fraction of the stability bound used as the largest substep (default 0.5: the
    /// Gershgorin bound overestimates ω by 1.3–1.8×, and damping and nonlinearity eat the rest).
    pub safety: Real,
    /// Largest number of substeps per step (default 20 000). When reached, the rest of the
    /// step is skipped for that body and the report says so.
    pub max_substeps: usize,
    /// A fixed substep count instead of the automatic one (for experiments such as the
    /// dt sweep; `None`, the default, is automatic).
    pub fixed_substeps: Option<usize>,
    /// Approach speeds below this (m/s) give a resting contact, not a bounce (default 0.1).
    pub restitution_threshold: Real,
    /// A cell whose volume grows past `max_stretch^DIM` times its rest volume means the body
    /// blew up (default 10: a tenfold stretch in every direction, far past any elastic
    /// material): the step is rolled back and the body frozen, as for a non-finite state
    /// ([`DeformableReport::exploded`](super::DeformableReport::exploded)). Infinite turns the
    /// test off.
    pub max_stretch: Real,
    /// A body whose every free node is slower than this (m/s) is still (default 0.05 m/s,
    /// rapier 0.36's default `normalized_linear_threshold` at unit length).
    pub sleep_speed: Real,
    /// A body still this long (s), with no bone it is bound to moving and no moving or awake
    /// dynamic body near it, falls asleep (default 0.5 s, rapier 0.36's `time_until_sleep`).
    pub time_until_sleep: Real,
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            safety: 0.5,
            max_substeps: 20_000,
            fixed_substeps: None,
            restitution_threshold: 0.1,
            max_stretch: 10.0,
            sleep_speed: 0.05,
            time_until_sleep: 0.5,
        }
    }
}

/// Steps deformables beside a rapier world. Holds only settings and scratch buffers.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default)]
pub struct DeformablePipeline {
    /// The knobs.
    pub settings: PipelineSettings,
    /// Buffers rebuilt within every step: not part of a snapshot.
    #[cfg_attr(feature = "serde", serde(skip))]
    scratch: Scratch,
    report: StepReport,
}

/// The rapier sets a step reads and writes: it reads bodies and colliders, moves bound nodes
/// with their bones and applies impulses to dynamic bodies.
pub struct RigidSets<'a> {
    /// The rigid bodies (dynamic ones take impulses).
    pub bodies: &'a mut RigidBodySet,
    /// The colliders.
    pub colliders: &'a ColliderSet,
    /// Rapier's broad phase, for the candidate queries.
    pub broad_phase: &'a BroadPhaseBvh,
}

/// Buffers reused from step to step.
#[derive(Clone, Debug, Default)]
struct Scratch {
    near: Vec<ColliderHandle>,
    motions: Vec<BodyMotion>,
    attached_bodies: Vec<RigidBodyHandle>,
    /// Per surface node (CSR): candidate indices.
    node_start: Vec<u32>,
    node_cands: Vec<u32>,
    /// Per surface facet (CSR): candidate indices.
    facet_start: Vec<u32>,
    facet_cands: Vec<u32>,
    touched_nodes: Vec<bool>,
    touched_colliders: Vec<bool>,
    /// Dynamic bodies that took contact impulses this step.
    pushed: Vec<RigidBodyHandle>,
    last_contact: Vec<Option<ContactPoint>>,
    /// Per binding: where its node ends the substep (fixed and kinematic bones).
    targets: Vec<Option<Vector>>,
    /// Per binding: index into `motions` (`None`: its body is gone).
    attachment_motion: Vec<Option<usize>>,
    /// Colliders touched this step (for the events), and the contacts being assembled.
    now: Vec<ColliderHandle>,
    contacts: Vec<ContactPoint>,
    /// The dynamic bodies a deformable may push this step, as they were before it.
    backup: RigidBackup,
    /// The dynamic bodies a deformable holds (touches or is bound to).
    held: Vec<RigidBodyHandle>,
    /// How far off two-sided surfaces this body's nodes are kept.
    skin: Real,
    /// `pushed.len()` when this body's step began: the bodies after it are this body's.
    pushed_before: usize,
}

/// What every phase of one body's step reads.
#[derive(Copy, Clone)]
struct StepContext<'a> {
    settings: PipelineSettings,
    gravity: Vector,
    dt: Real,
    /// How far moving colliders travel this step (widens the broad phase).
    margin: Real,
    /// Whether rapier's broad phase indexes every collider.
    indexed: bool,
    colliders: &'a ColliderSet,
    broad_phase: &'a BroadPhaseBvh,
}

impl<'a> StepContext<'a> {
    /// The broad phase's view of the rigid world for one body's contacts.
    fn scan<'s>(&'s self, bodies: &'s RigidBodySet, material: &'s ContactMaterial) -> Scan<'s>
    where
        'a: 's,
    {
        Scan {
            bodies,
            colliders: self.colliders,
            broad_phase: self.broad_phase,
            indexed: self.indexed,
            material,
            gravity: self.gravity,
            dt: self.dt,
        }
    }
}

/// Wall-clock time per stage of one body's step, s.
#[derive(Copy, Clone, Debug, Default)]
struct StageTimes {
    forces: f64,
    contacts: f64,
    integrate: f64,
}

/// Runs `f`, adding its wall time to `slot`.
fn timed<R>(slot: &mut f64, f: impl FnOnce() -> R) -> R {
    let start = Instant::now();
    let r = f();
    *slot += start.elapsed().as_secs_f64();
    r
}

impl DeformablePipeline {
    /// A pipeline with default settings.
    pub fn new() -> Self {
        Self::default()
    }

    /// The report of the last step.
    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// Advances every deformable by `params.dt`. Call it before rapier's
    /// `PhysicsPipeline::step`, with the same sets: it reads bodies and colliders, moves bound
    /// nodes with their bones, and applies impulses to dynamic bodies.
    pub fn step(
        &mut self,
        gravity: Vector,
        params: &IntegrationParameters,
        deformables: &mut DeformableSet,
        bodies: &mut RigidBodySet,
        colliders: &ColliderSet,
        broad_phase: &BroadPhaseBvh,
    ) -> &StepReport {
        let rigid = RigidSets {
            bodies,
            colliders,
            broad_phase,
        };
        self.step_with_events(gravity, params, deformables, rigid, &())
    }

    /// [`DeformablePipeline::step`], sending contact start/stop events to `events`.
    pub fn step_with_events(
        &mut self,
        gravity: Vector,
        params: &IntegrationParameters,
        deformables: &mut DeformableSet,
        rigid: RigidSets<'_>,
        events: &dyn DeformableEventHandler,
    ) -> &StepReport {
        let start = Instant::now();
        let RigidSets {
            bodies,
            colliders,
            broad_phase,
        } = rigid;
        let dt = params.dt;
        self.report.dt = dt;
        self.report.deformables.clear();
        let ctx = StepContext {
            settings: self.settings,
            gravity,
            dt,
            margin: coupling::moving_margin(bodies, colliders, dt),
            indexed: super::contact::broad_phase_is_current(broad_phase, bodies, colliders),
            colliders,
            broad_phase,
        };
        self.scratch.pushed.clear();
        for (handle, body) in deformables.iter_mut() {
            self.step_body(handle, body, &ctx, bodies, events);
        }
        for h in &self.scratch.pushed {
            if let Some(rb) = bodies.get_mut(*h) {
                coupling::match_rapier_integration(rb, gravity, dt, params.num_solver_iterations);
            }
        }
        self.report.wall_time = start.elapsed().as_secs_f64();
        &self.report
    }

    /// One body's step: the phases of the module docs, in order.
    fn step_body(
        &mut self,
        handle: DeformableHandle,
        body: &mut Deformable,
        ctx: &StepContext<'_>,
        bodies: &mut RigidBodySet,
        events: &dyn DeformableEventHandler,
    ) {
        let sc = &mut self.scratch;
        let detached = body.prune_attachments(bodies);
        // 1. wake
        let asleep = sleep::stays_asleep(body, ctx, bodies, sc);
        sleep::wake_held_bodies(body, ctx, bodies, sc);
        if asleep {
            sleep::report_asleep(body, detached);
            self.report
                .deformables
                .push((handle, body.last.report.clone()));
            return;
        }
        body.last.report.sleeping = false;
        if !body.activation.frozen && ctx.dt > 0.0 {
            let mut times = StageTimes::default();
            // 2. prepare
            let mut candidates = timed(&mut times.contacts, || {
                prepare::prepare(body, ctx, bodies, sc)
            });
            // 3. substeps
            let stats = substep::run(
                &SymplecticEuler,
                body,
                ctx,
                bodies,
                sc,
                &mut candidates,
                &mut times,
            );
            let integrate_start = Instant::now();
            // 4. containment
            let quality = containment::contain(body, ctx, bodies, sc);
            body.refit_surface();
            // 5. report
            finish::diagnose(body, sc, &candidates, stats, quality);
            // 6. sleep
            sleep::update(body, ctx, bodies, sc, quality.is_some());
            finish::energies(body, ctx);
            times.integrate = integrate_start.elapsed().as_secs_f64();
            finish::timings(body, &times);
        } else {
            body.last.report.substeps = 0;
            body.last.report.contacts = 0;
            body.last.report.frozen = body.activation.frozen;
            sc.near.clear();
            sc.touched_colliders.clear();
        }
        body.last.report.detached = detached;
        body.last.report.attached_nodes = body.bindings.len();
        // 7. events
        finish::send_events(handle, body, sc, events);
        self.report
            .deformables
            .push((handle, body.last.report.clone()));
    }
}

/// The candidates of one body's step (they borrow the collider set).
type Candidates<'a> = Vec<Candidate<'a>>;
