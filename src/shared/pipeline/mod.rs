//! One step of every deformable, run before rapier's `PhysicsPipeline::step` over the same
//! `dt` (`docs/ARCHITECTURE.md` §4).
//!
//! [`DeformablePipeline::step`] is a list of phases, each a function of its own file. The
//! deformables that may touch each other, or push the same dynamic rigid body, form islands
//! ([`islands`]) that step together: phases 1–2 for each member, the substeps of phase 3 in
//! lockstep (with contacts between the members, and passes over the contacts with a rigid body
//! two members push), phases 4–7 for each member; a body alone is an island of one.
//!
//! 1. **wake** ([`sleep`]): a sleeping body wakes if a bone it is bound to moves, a collider it
//!    touched was removed, or a moving body comes near, and with it the members that push the
//!    same dynamic body; an asleep body skips the rest.
//! 2. **prepare** ([`prepare`]): the state is saved for a rollback; how every relevant rigid
//!    body moves over the step ([`BodyMotion`](super::coupling::BodyMotion)); the broad phase:
//!    one query per deformable, then per surface node and per surface facet, into tables of
//!    candidates; the dynamic bodies it may push are backed up.
//! 3. **substeps** ([`substep`]): each body advances on its own substeps. Every substep:
//!    element forces at the current state (with each node's Gershgorin stiffness and damping
//!    bounds); the substep size, the remaining time split evenly into pieces no longer than
//!    the integrator's stability bound (for symplectic Euler, the papers' integrator,
//!    `safety · min_i 2/ω_i (√(1+ζ_i²) − ζ_i)`, with each node's bounds divided by the body's
//!    measured slack when the explicit integrator steps it alone, and never beyond the bounds
//!    themselves,
//!    [`stable_substeps`](super::model::stable_substeps)) and than the edge-repulsion crossing
//!    limiter allows; the integrator's velocity update
//!    (`v += h (f/m + g)`, [`super::integrator`]); the bone drive ([`super::attach`]); contacts on
//!    velocities, nodes against colliders then rigid features against surface facets
//!    ([`super::contact`]); `x += h v`.
//!    Under [`Integrator::Midpoint`] a body in an impact on a collider takes the explicit
//!    step ([`impact`]).
//!    An island the implicit step solved with its contacts between members that ended with
//!    more energy, or a body deeper inside another, is rolled back and stepped again in
//!    shorter substeps, then explicitly ([`guard`]).
//! 4. **containment** ([`containment`]): a state that turned non-finite, or a cell stretched
//!    past `max_stretch`, is rolled back to the start of the step with the rigid bodies it
//!    pushed, and the body frozen; the surface's hierarchy is refitted to the final positions.
//! 5. **report** ([`finish`]): penetration, inverted cells, energies, stage timings.
//! 6. **sleep** ([`sleep`]): a group is one island: once every live member has been still long
//!    enough with nothing moving near it (a dynamic body resting on it, slower than rapier lets
//!    a body sleep at, does not count), all of them sleep, and the dynamic bodies they touch or
//!    are bound to sleep with them at the start of the next step (rapier wakes a body moved in
//!    the step it is put to sleep); a woken body wakes them, and the deformables it touched.
//! 7. **events** ([`finish`]): the colliders touched this step against those of the last.
//!
//! After every body: the dynamic bodies they pushed get rapier's integration compensated
//! ([`match_rapier_integration`](super::coupling::match_rapier_integration)).

mod containment;
mod finish;
mod guard;
mod held;
mod impact;
mod islands;
mod prepare;
mod sleep;
mod substep;
mod teleport;

use guard::Guard;
use substep::{Member, SubstepStats};

use std::time::Instant;

use super::body::{Deformable, SurfaceTree};
use super::contact::soft::{self, SoftSurface};
use super::contact::{Candidate, ContactMaterial, ContactPoint, Scan};
use super::coupling::{self, BodyMotion, RigidBackup};
use super::events::{DeformableContactEvent, DeformableEventHandler};
use super::integrator::{Integrator, AUTO_GLOBAL_ITERATIONS, AUTO_SUBSTEPS, GLOBAL_SUBSTEPS};
use super::math::{Real, Vector};
use super::rapier::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{Aabb, BroadPhaseBvh, ColliderHandle, ColliderSet};
use super::report::StepReport;
use super::set::{DeformableHandle, DeformableSet};
use super::threads;

/// Knobs of the pipeline.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PipelineSettings {
    /// Fraction of the estimated stability limit used as the largest substep (default 0.5,
    /// for damping, nonlinearity and the estimate's error). The estimate is the per-node
    /// Gershgorin bound calibrated by the body's measured slack for a body the explicit
    /// integrator steps alone, the bound itself otherwise; the substep never exceeds the
    /// uncalibrated bound (`docs/ARCHITECTURE.md` §4.1).
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
    /// A body whose every free node moved slower than this (m/s) over the step, from where it
    /// started the step to where it ends it, is still (default 0.05 m/s, rapier 0.36's default
    /// `normalized_linear_threshold` at unit length; like rapier's dynamic bodies, the drift
    /// counts, not the velocity the last substep left).
    pub sleep_speed: Real,
    /// A body still this long (s), with no bone it is bound to moving and no moving or awake
    /// dynamic body near it, falls asleep (default 0.5 s, rapier 0.36's `time_until_sleep`).
    pub time_until_sleep: Real,
    /// How the bodies' velocities advance (default [`Integrator::Auto`] with 2 sweeps).
    #[cfg_attr(feature = "serde", serde(default))]
    pub integrator: Integrator,
    /// A fixed or kinematic bone that would drag a bound node faster than this (m/s) jumped (a
    /// teleport, a respawn, a kinematic target set far away): its body is carried along
    /// rigidly instead of stretched after it ([`DeformableReport::teleported`](super::DeformableReport::teleported);
    /// default 50 m/s, 0.8 m in a 60 Hz step; infinite turns it off).
    #[cfg_attr(feature = "serde", serde(default = "default_teleport_speed"))]
    pub teleport_speed: Real,
    /// Under the implicit and midpoint steps: conjugate-gradient iterations of one Newton step
    /// over each whole body before its Gauss–Seidel sweeps (`docs/ARCHITECTURE.md` §4.2), for
    /// bodies whose soft modes the sweeps cannot reach, such as a stiff slender beam at 60 Hz
    /// (it hangs straight under the sweeps alone). `None`, the default: automatic,
    /// [`AUTO_GLOBAL_ITERATIONS`](super::AUTO_GLOBAL_ITERATIONS) for a body whose explicit
    /// step would take more than [`GLOBAL_SUBSTEPS`](super::GLOBAL_SUBSTEPS) substeps a step at
    /// rest (the beam: 746 at 60 Hz) and for a plastic body (which flows where its solve
    /// ends), none otherwise (the `fall` cube at res 9: 90; the 10 cm silicone ball of
    /// `scenes ball`: 95; the limb: 3); `Some(0)`: the sweeps alone. Each
    /// step assembles and factors a coarse system of at most 384 unknowns (32 clusters of
    /// nodes, each moving affinely) and each iteration costs about a sweep: with 10, the
    /// 1 075-node beam of `scenes bending --res 5` costs 4–7× what its 2 sweeps cost alone;
    /// 5–10 iterations converge the beam.
    /// Every model with an implicit step. A body bound to bones takes the midpoint step only
    /// with it ([`Integrator::Midpoint`]). Not yet for bodies under heavy contact loads: with
    /// it, `scenes advise --trial crush` (1000 kg on a soft cube) inverts edge-repulsion cells
    /// under backward Euler, which hold without it (the midpoint step holds either way).
    #[cfg_attr(feature = "serde", serde(default))]
    pub global_iterations: Option<usize>,
    /// Whether deformables that rest on each other (pressed together over a face, not sliding)
    /// damp their rigid motions against each other, at a rate set by their materials' damping
    /// ratio, and such a stack resting on the ground its motion against the ground (default
    /// true): a stack's slow sway, which the materials' own damping barely reaches, dies out and
    /// the stack sleeps (`docs/ARCHITECTURE.md` §6.10). A body alone and bodies sliding on
    /// each other are left alone.
    #[cfg_attr(feature = "serde", serde(default = "default_true"))]
    pub damp_held: bool,
    /// With the `parallel` feature: whether, while a step with a body of more than 1 024 cells
    /// runs, rayon's other threads poll for its work instead of sleeping between its parallel
    /// loops (default true). Waking a sleeping thread costs tens of microseconds a loop (70 µs
    /// on the 2-core machine of `docs/PERFORMANCE.md`, a tenth of a res-17 cube's explicit
    /// step); polling keeps those cores busy for the length of the step. Turn it off when
    /// other threads need the cores during the step. The results are the same either way.
    #[cfg_attr(feature = "serde", serde(default = "default_true"))]
    pub poll_threads: bool,
}

#[cfg(feature = "serde")]
fn default_true() -> bool {
    true
}

#[cfg(feature = "serde")]
fn default_teleport_speed() -> Real {
    PipelineSettings::default().teleport_speed
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
            integrator: Integrator::default(),
            teleport_speed: 50.0,
            global_iterations: None,
            damp_held: true,
            poll_threads: true,
        }
    }
}

impl PipelineSettings {
    /// Whether the explicit step sizes `body`'s substeps by its calibrated stability bound
    /// when it steps alone (its slack measured once, `model/slack.rs`): not under fixed
    /// substeps, with self contact (whose contacts want the certain bound), or when the body
    /// steps implicitly.
    pub(crate) fn calibrates(&self, body: &Deformable) -> bool {
        self.fixed_substeps.is_none()
            && !body.self_contact()
            && !self.integrator.steps_implicitly(body)
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
    work: Work,
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
struct Work {
    /// One per member of the group being stepped.
    scratches: Vec<Scratch>,
    /// Dynamic bodies this body's contacts pushed this step.
    pushed: Vec<RigidBodyHandle>,
    /// Pairs of deformables that may touch this step.
    pairs: Vec<(DeformableHandle, DeformableHandle)>,
    /// The hierarchy of the bodies' boxes that finds them.
    boxes: SurfaceTree,
    /// Pairs that push, or are bound to, the same dynamic body this step.
    shared: Vec<(DeformableHandle, DeformableHandle)>,
    /// Pairs that step together this step: `pairs` and `shared`.
    links: Vec<(DeformableHandle, DeformableHandle)>,
    /// Dynamic bodies held by deformables that fell asleep last step, to sleep now.
    to_sleep: Vec<RigidBodyHandle>,
    /// Pairs of deformables touching before and after this step (smaller handle first).
    touching_before: Vec<(DeformableHandle, DeformableHandle)>,
    touching_now: Vec<(DeformableHandle, DeformableHandle)>,
}

/// One body's buffers, reused from step to step, by the phase that fills them.
#[derive(Clone, Debug, Default)]
struct Scratch {
    /// Phase 2's broad phase: what the body may touch this step.
    broad: Broad,
    /// What the substeps' contacts touched (for the events, the report and sleep).
    touch: Touch,
    /// The bone drive's view of the bindings.
    bones: BoneDrive,
    /// The dynamic rigid bodies the body may push or holds.
    rigid: RigidHold,
    /// Its surface as the other members of its group meet it, and theirs near it.
    soft: SoftScratch,
}

/// What the body may touch this step (phase 2).
#[derive(Clone, Debug, Default)]
struct Broad {
    near: Vec<ColliderHandle>,
    motions: Vec<BodyMotion>,
    attached_bodies: Vec<RigidBodyHandle>,
    /// Per surface node: the box it sweeps over the step as its velocity predicts (made for
    /// the broad phase, and stale once the substeps move the nodes).
    swept: Vec<Aabb>,
    /// Per surface node (CSR): candidate indices.
    node_start: Vec<u32>,
    node_cands: Vec<u32>,
    /// Per surface facet (CSR): candidate indices.
    facet_start: Vec<u32>,
    facet_cands: Vec<u32>,
    /// How far off two-sided surfaces this body's nodes are kept.
    skin: Real,
}

/// What the body's contacts touched this step.
#[derive(Clone, Debug, Default)]
struct Touch {
    touched_nodes: Vec<bool>,
    touched_colliders: Vec<bool>,
    /// Dynamic bodies that took contact impulses this step.
    pushed: Vec<RigidBodyHandle>,
    last_contact: Vec<Option<ContactPoint>>,
    /// Colliders touched this step (for the events), and the contacts being assembled.
    now: Vec<ColliderHandle>,
    contacts: Vec<ContactPoint>,
}

/// The bindings as the bone drive moves them.
#[derive(Clone, Debug, Default)]
struct BoneDrive {
    /// Per binding: where its node ends the substep (fixed and kinematic bones).
    targets: Vec<Option<Vector>>,
    /// Per binding: index into `motions` (`None`: its body is gone).
    attachment_motion: Vec<Option<usize>>,
    /// Whether the body was carried along with bones that jumped this step.
    teleported: bool,
}

/// The dynamic rigid bodies the body may push or holds.
#[derive(Clone, Debug, Default)]
struct RigidHold {
    /// The dynamic bodies a deformable may push this step, as they were before it.
    backup: RigidBackup,
    /// The dynamic bodies a deformable holds (touches or is bound to).
    held: Vec<RigidBodyHandle>,
    /// The dynamic bodies it held as it fell asleep this step.
    to_sleep: Vec<RigidBodyHandle>,
}

/// Soft contact's tables for the body.
#[derive(Clone, Debug, Default)]
struct SoftScratch {
    /// Its surface as the other members of its group meet it this step.
    soft_surface: SoftSurface,
    /// Per surface node (CSR): the other members' facets near it, `(member, facet)`.
    soft_start: Vec<u32>,
    soft_cands: Vec<(u32, u32)>,
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
        self.work.pushed.clear();
        sleep::sleep_held(&mut self.work.to_sleep, bodies);
        // A body large enough for the threads' loops keeps the threads polling through the
        // step ([`threads::with_team`]).
        let busy = self.settings.poll_threads
            && deformables
                .iter()
                .any(|(_, b)| b.rest.mesh.num_cells() > threads::CHUNK);
        threads::with_team(busy, || self.step_bodies(deformables, &ctx, bodies, events));
        for h in &self.work.pushed {
            if let Some(rb) = bodies.get_mut(*h) {
                coupling::match_rapier_integration(rb, gravity, dt, params.num_solver_iterations);
            }
        }
        self.report.wall_time = start.elapsed().as_secs_f64();
        &self.report
    }

    /// Every body's step: the bodies that may touch each other step together, as a group
    /// ([`islands`]), each after the other.
    fn step_bodies(
        &mut self,
        deformables: &mut DeformableSet,
        ctx: &StepContext<'_>,
        bodies: &mut RigidBodySet,
        events: &dyn DeformableEventHandler,
    ) {
        let work = &mut self.work;
        let pairs_start = Instant::now();
        islands::pairs(
            deformables,
            (ctx.dt, ctx.settings.sleep_speed),
            &mut work.boxes,
            &mut work.pairs,
        );
        touching_pairs(deformables, &mut work.touching_before);
        islands::rigid_links(deformables, ctx, bodies, &mut work.shared);
        let handles: Vec<DeformableHandle> = deformables.iter().map(|(h, _)| h).collect();
        work.links.clear();
        work.links.extend_from_slice(&work.shared);
        work.links.extend_from_slice(&work.pairs);
        let groups = islands::groups(&handles, &work.links);
        self.report.pairs_time = pairs_start.elapsed().as_secs_f64();
        // Every body, once, to be handed to its group.
        let mut slots: Vec<Option<&mut Deformable>> =
            deformables.iter_mut().map(|(_, b)| Some(b)).collect();
        for group in groups {
            if work.scratches.len() < group.len() {
                work.scratches.resize_with(group.len(), Scratch::default);
            }
            let chosen = group
                .iter()
                .filter_map(|&k| Some((handles[k], slots[k].take()?)));
            let mut members: Vec<Member<'_, '_>> = chosen
                .zip(work.scratches.iter_mut())
                .map(|((handle, body), sc)| Member {
                    handle,
                    body,
                    sc,
                    candidates: Vec::new(),
                    times: StageTimes::default(),
                    stats: SubstepStats::default(),
                    live: false,
                    asleep: false,
                    touched: Vec::new(),
                    rigid_rows: Vec::new(),
                    fixed_rows: Vec::new(),
                    held: Vec::new(),
                    shares_bodies: work.shared.iter().any(|p| p.0 == handle || p.1 == handle),
                    pressed: None,
                })
                .collect();
            let touch = |(a, b): &(DeformableHandle, DeformableHandle)| {
                members.iter().any(|m| m.handle == *a) && members.iter().any(|m| m.handle == *b)
            };
            let soft = work.pairs.iter().any(touch);
            let shared = (soft, &work.shared[..]);
            step_group(&mut members, shared, ctx, bodies, events, &mut self.report);
            for m in members.iter_mut() {
                for h in &m.sc.touch.pushed {
                    if !work.pushed.contains(h) {
                        work.pushed.push(*h);
                    }
                }
                work.to_sleep.append(&mut m.sc.rigid.to_sleep);
            }
        }
        drop(slots);
        touching_pairs(deformables, &mut work.touching_now);
        pair_events(&work.touching_before, &work.touching_now, events);
    }
}

/// The sides of the box around `x` (zero when empty).
fn box_sides(x: &[Vector]) -> Vector {
    if x.is_empty() {
        return Vector::ZERO;
    }
    let lo = x
        .iter()
        .fold(Vector::splat(Real::INFINITY), |a, p| a.min(*p));
    let hi = x
        .iter()
        .fold(Vector::splat(Real::NEG_INFINITY), |a, p| a.max(*p));
    hi - lo
}

/// `PairStopped` for each pair of `before` not in `now`, then `PairStarted` for each new one
/// (a removed body's pairs stop; a sleeping body keeps its pairs).
fn pair_events(
    before: &[(DeformableHandle, DeformableHandle)],
    now: &[(DeformableHandle, DeformableHandle)],
    events: &dyn DeformableEventHandler,
) {
    for &(deformable, other) in before.iter().filter(|p| !now.contains(p)) {
        events.handle_contact_event(DeformableContactEvent::PairStopped { deformable, other });
    }
    for &(deformable, other) in now.iter().filter(|p| !before.contains(p)) {
        events.handle_contact_event(DeformableContactEvent::PairStarted { deformable, other });
    }
}

/// A group's step: the phases of the module docs, for every member, the substeps together
/// (`may_touch`: some of its members may touch each other; `shared`: the pairs that push or are
/// bound to the same dynamic body).
fn step_group<'a>(
    members: &mut [Member<'_, 'a>],
    (may_touch, shared): (bool, &[(DeformableHandle, DeformableHandle)]),
    ctx: &StepContext<'a>,
    bodies: &mut RigidBodySet,
    events: &dyn DeformableEventHandler,
    report: &mut StepReport,
) {
    let mut detached = Vec::with_capacity(members.len());
    for m in members.iter_mut() {
        let (body, sc) = (&mut *m.body, &mut *m.sc);
        sc.touch.pushed.clear();
        detached.push(body.prune_attachments(bodies));
        // 1. wake
        sleep::stays_asleep(body, ctx, bodies, &mut sc.broad);
    }
    sleep::wake_linked(members, shared);
    for m in members.iter_mut() {
        let (body, sc) = (&mut *m.body, &mut *m.sc);
        let asleep = body.activation.sleeping;
        sleep::wake_held_bodies(body, ctx, bodies, &mut sc.rigid);
        m.asleep = asleep;
        m.live = !asleep && !body.activation.frozen && ctx.dt > 0.0;
        if !asleep {
            body.last.report.sleeping = false;
        }
        if m.live {
            // 2. prepare
            m.candidates = timed(&mut m.times.contacts, || {
                prepare::prepare(body, ctx, bodies, sc)
            });
        }
    }
    // Contacts between deformables: the members' against each other's surfaces, and a body
    // with self contact against its own.
    let soft = may_touch
        || members
            .iter()
            .any(|m| m.live && m.body.contact.self_contact);
    if soft {
        for m in members.iter_mut() {
            let still = !m.live;
            m.sc.soft
                .soft_surface
                .build(m.body, ctx.gravity, ctx.dt, still);
        }
        // A still member's nodes too: a live member's facets must not creep into them.
        for i in 0..members.len() {
            if !members[i].body.activation.frozen {
                soft_tables(members, i, ctx);
            }
        }
    }
    // 3. substeps. The implicit step solves the contacts between its members inside its
    // sweeps when every live member takes it with a convex energy (shape matching; a step that
    // gains energy or sinks a body into another is taken again, [`guard`]); it does
    // not answer a dynamic body that two of them push (a box pinched between two pads at 60 Hz
    // was launched): such an island, or one with another member, steps explicitly.
    let shares = members.len() > 1 && !shared.is_empty();
    let integrator = ctx.settings.integrator;
    if let Integrator::Auto { .. } = integrator {
        // Implicit when the explicit step would take more than AUTO_SUBSTEPS substeps at rest.
        let most = AUTO_SUBSTEPS as Real * ctx.settings.safety;
        for m in members.iter_mut() {
            let at_rest = m.body.rest.slack(&m.body.state.elements).at_rest;
            m.body.step.auto_implicit = ctx.dt > most * at_rest;
        }
    }
    let together = soft
        && !shares
        && members
            .iter()
            .all(|m| !m.live || integrator.steps_together(m.body));
    let in_impact = if soft || shares {
        impact::end(members);
        false
    } else {
        impact::any(members, ctx, bodies)
    };
    let integrator = if (soft || shares) && !together || in_impact {
        Integrator::Explicit
    } else {
        integrator
    };
    for m in members.iter_mut() {
        m.body.step.global_iterations = global_iterations(m.body, ctx);
    }
    let guard = together.then(|| Guard::start(members, ctx)).flatten();
    let (mut undamped, mut taken) = substep::run(
        &integrator,
        members,
        (soft, together.then_some(1)),
        ctx,
        bodies,
    );
    if let Some(guard) = guard {
        // Again in shorter substeps, then explicitly.
        let retries = [
            (integrator, Some(guard::SPLIT)),
            (Integrator::Explicit, None),
        ];
        for (integrator, together) in retries {
            if !guard.failed(members, ctx, taken) {
                break;
            }
            guard.roll_back(members, bodies);
            (undamped, taken) = substep::run(&integrator, members, (soft, together), ctx, bodies);
        }
    }
    damp_held(members, ctx, undamped);
    record_touching(members);
    let mut ready = Vec::with_capacity(members.len());
    for m in members.iter_mut() {
        ready.push(check_member(m, ctx, bodies));
    }
    // The group is one island: its live members fall asleep together, once every one of them
    // has been still long enough (one by one, a sleeping cube was woken by its neighbour's
    // last settling and a tower never slept).
    let island_sleeps = members
        .iter()
        .zip(&ready)
        .all(|(m, ready)| !m.live || *ready == Some(true));
    for ((m, detached), ready) in members.iter_mut().zip(detached).zip(ready) {
        let sleeps = island_sleeps && ready == Some(true);
        finish_member(m, ctx, events, (detached, sleeps), report);
    }
}

/// The damping of deformables held against each other ([`held`]) over the last `dt` of the
/// step, on the last substep's contacts; returns the kinetic energy it took.
fn damp_held(members: &mut [Member<'_, '_>], ctx: &StepContext<'_>, dt: Real) -> Real {
    if !ctx.settings.damp_held {
        return 0.0;
    }
    held::damp(members, dt, ctx.settings.sleep_speed)
}

/// Phases 4–5 of a live member's step and its still time (phase 6); whether it has been still
/// long enough to sleep (`None` for a member not simulated this step).
fn check_member(
    m: &mut Member<'_, '_>,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
) -> Option<bool> {
    if !m.live {
        return None;
    }
    let (body, sc) = (&mut *m.body, &mut *m.sc);
    let integrate_start = Instant::now();
    // 4. containment
    let mut quality = containment::contain(body, ctx, bodies, (&sc.rigid, &mut sc.touch));
    // 4b. plastic flow, of a sane state
    let released = quality.and_then(|_| body.flow(ctx.dt));
    if released.is_some() {
        quality = Some(containment::Quality::of(body, Real::INFINITY));
    }
    body.last.report.plastic_dissipation = released.unwrap_or(0.0);
    body.refit_surface();
    // 5. report
    finish::diagnose(body, sc, &m.candidates, m.stats, quality);
    // A body that ran out of substeps did not cover the step: its drift says nothing.
    let sane = quality.is_some() && !m.stats.cap_hit;
    let mut ready = sleep::update(body, ctx, bodies, &sc.broad, sane);
    // 5b. tearing, of a sane state: the body is rebuilt on its torn mesh (its node count
    // changes, so nothing of this step's node tables is read after it).
    if sane {
        body.tear(ctx.dt);
    } else {
        body.last.tears.clear();
    }
    body.last.report.torn_faces = body.last.tears.len();
    if !body.last.tears.is_empty() {
        ready = false;
        body.activation.still_time = 0.0;
    }
    m.times.integrate = integrate_start.elapsed().as_secs_f64();
    Some(ready)
}

/// The Newton iterations over `body`'s whole before its sweeps this step
/// ([`PipelineSettings::global_iterations`]).
fn global_iterations(body: &Deformable, ctx: &StepContext<'_>) -> usize {
    let settings = &ctx.settings;
    if let Some(n) = settings.global_iterations {
        return n;
    }
    if !settings.integrator.steps_implicitly(body) {
        return 0;
    }
    // A plastic body flows where its solve ends: the sweeps' unconverged strain would flow (a
    // bar bent 90° under 2 sweeps kept 2.7 times the bend it should).
    if body.plasticity().is_some() {
        return AUTO_GLOBAL_ITERATIONS;
    }
    let at_rest = body.rest.slack(&body.state.elements).at_rest;
    if ctx.dt > GLOBAL_SUBSTEPS as Real * settings.safety * at_rest {
        AUTO_GLOBAL_ITERATIONS
    } else {
        0
    }
}

/// The deformables each live member touched this step (either's node on the other's facet).
fn record_touching(members: &mut [Member<'_, '_>]) {
    let n = members.len();
    for i in 0..n {
        if !members[i].live {
            continue;
        }
        let mut now: Vec<DeformableHandle> = (0..n)
            .filter(|&j| members[i].touched.contains(&j) || members[j].touched.contains(&i))
            .map(|j| members[j].handle)
            .collect();
        now.sort_unstable_by_key(|h| h.into_raw_parts());
        members[i].body.last.touching_bodies = now;
    }
}

/// The touching pairs of deformables, each once as (smaller handle, larger), sorted.
fn touching_pairs(set: &DeformableSet, out: &mut Vec<(DeformableHandle, DeformableHandle)>) {
    out.clear();
    for (h, body) in set.iter() {
        for &o in &body.last.touching_bodies {
            let pair = if h.into_raw_parts() < o.into_raw_parts() {
                (h, o)
            } else {
                (o, h)
            };
            out.push(pair);
        }
    }
    out.sort_unstable_by_key(|(a, b)| (a.into_raw_parts(), b.into_raw_parts()));
    out.dedup();
}

/// The soft-contact tables of member `i` against the other members' surfaces (and its own,
/// with self contact).
fn soft_tables(members: &mut [Member<'_, '_>], i: usize, ctx: &StepContext<'_>) {
    let mut start = std::mem::take(&mut members[i].sc.soft.soft_start);
    let mut cands = std::mem::take(&mut members[i].sc.soft.soft_cands);
    let m = &members[i];
    let others = members
        .iter()
        .enumerate()
        .filter(move |(j, _)| *j != i)
        .map(|(j, o)| (j, &o.sc.soft.soft_surface));
    let own = m
        .body
        .contact
        .self_contact
        .then_some((i, &m.sc.soft.soft_surface));
    let widen = m.sc.soft.soft_surface.margin() + ctx.margin;
    soft::node_tables(m.body, others, own, ctx.dt, widen, &mut start, &mut cands);
    members[i].sc.soft.soft_start = start;
    members[i].sc.soft.soft_cands = cands;
}

/// Phases 6–7 of a member's step after [`check_member`] (or the report of one that slept or is
/// frozen); `sleeps`: its island falls asleep.
fn finish_member(
    m: &mut Member<'_, '_>,
    ctx: &StepContext<'_>,
    events: &dyn DeformableEventHandler,
    (detached, sleeps): (usize, bool),
    report: &mut StepReport,
) {
    let (handle, body, sc) = (m.handle, &mut *m.body, &mut *m.sc);
    if m.asleep {
        sleep::report_asleep(body, detached);
        report.deformables.push((handle, body.last.report.clone()));
        return;
    }
    if m.live {
        let times = &mut m.times;
        let integrate_start = Instant::now();
        // 6. sleep
        if sleeps {
            sleep::fall_asleep(body, ctx, &mut sc.rigid.to_sleep);
        }
        finish::energies(body, ctx);
        times.integrate += integrate_start.elapsed().as_secs_f64();
        finish::timings(body, times);
    } else {
        body.last.report.substeps = 0;
        body.last.report.contacts = 0;
        body.last.tears.clear();
        body.last.report.torn_faces = 0;
        body.last.report.frozen = body.activation.frozen;
        sc.broad.near.clear();
        sc.touch.touched_colliders.clear();
    }
    body.last.report.detached = detached;
    body.last.report.attached_nodes = body.bindings.len();
    // 7. events
    finish::send_events(handle, body, sc, events);
    report.deformables.push((handle, body.last.report.clone()));
}

/// The candidates of one body's step (they borrow the collider set).
type Candidates<'a> = Vec<Candidate<'a>>;
