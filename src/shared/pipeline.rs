//! One step of every deformable, run before rapier's `PhysicsPipeline::step` over the same
//! `dt` (`DESIGN.md` §4).
//!
//! Each deformable advances on its own substeps. Every substep:
//! 1. element forces at the current state (each node's Gershgorin stiffness and damping
//!    bounds come out of the same loop);
//! 2. the substep size: the remaining time split evenly into pieces no longer than
//!    `safety · min_i 2/ω_i (√(1+ζ_i²) − ζ_i)`, with `ω_i² = Σ‖K_ij‖/m_i` and
//!    `ζ_i = Σ‖C_ij‖ / (2 √(Σ‖K_ij‖ m_i))` (symplectic Euler is stable for `h < 2/ω`), and no
//!    longer than the edge-repulsion crossing limiter allows — so a stiffening barrier gets
//!    more substeps and a resting body no more than it needs;
//! 3. `v += h (f/m + g)` (symplectic Euler, the papers' integrator);
//! 4. bound nodes follow their bones (see [`super::attach`]);
//! 5. contacts on velocities: nodes against colliders, then rigid features against surface
//!    facets (see [`super::contact`]);
//! 6. `x += h v`.
//!
//! After the step a state that turned non-finite is rolled back to the start of the step and
//! frozen, contact events are sent, and the report is filled in.

use std::time::Instant;

use super::body::{ContactPoint, Deformable};
use super::contact::{self, BodyMotion, Candidate, MotionKind};
use super::events::{DeformableContactEvent, DeformableEventHandler};
use super::math::{self, AngVector, Pose, Real, Vector, DIM, FACET_ARITY};
use super::rapier::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{Aabb, BoundingVolume, BroadPhaseBvh, ColliderHandle, ColliderSet};
use super::report::StepReport;
use super::set::DeformableSet;

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
    /// Surface position of each node (or `u32::MAX`).
    surface_slot: Vec<u32>,
    touched_nodes: Vec<bool>,
    touched_colliders: Vec<bool>,
    /// Dynamic bodies that took contact impulses this step.
    pushed: Vec<RigidBodyHandle>,
    last_contact: Vec<Option<ContactPoint>>,
    targets: Vec<Vector>,
    /// Per attachment: index into `motions` (or `usize::MAX`).
    attachment_motion: Vec<usize>,
    /// Colliders touched this step (for the events), and the contacts being assembled.
    now: Vec<ColliderHandle>,
    contacts: Vec<ContactPoint>,
    /// The dynamic bodies a deformable may push this step, as they were before it, for a
    /// rollback: handle, pose, linear and angular velocity.
    backup: Vec<(RigidBodyHandle, Pose, Vector, AngVector)>,
}

/// Most feature crossings resolved per surface facet and substep.
const FACET_PASSES: usize = 8;

/// Fraction of a dynamically bound node's position error corrected per substep.
const DYNAMIC_BINDING_CORRECTION: Real = 0.2;

/// Largest stable symplectic-Euler substep for the given per-node bounds.
pub(crate) fn stable_substep(masses: &[Real], stiffness: &[Real], damping: &[Real]) -> Real {
    let mut h = Real::INFINITY;
    for ((m, s), d) in masses.iter().zip(stiffness).zip(damping) {
        let hi = if *s > 0.0 {
            let omega = (s / m).sqrt();
            let zeta = d / (2.0 * (s * m).sqrt());
            2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)
        } else if *d > 0.0 {
            2.0 * m / d
        } else {
            continue;
        };
        h = h.min(hi);
    }
    h
}

/// Whether a rigid body moves this step: a dynamic body that is awake, a kinematic body with
/// a next pose or a velocity.
fn is_moving(body: &super::rapier::dynamics::RigidBody) -> bool {
    use super::rapier::dynamics::RigidBodyType;
    match body.body_type() {
        RigidBodyType::Fixed => false,
        RigidBodyType::KinematicPositionBased => {
            let (p0, p1) = (body.position(), body.next_position());
            p0.translation != p1.translation || p0.rotation != p1.rotation
        }
        RigidBodyType::KinematicVelocityBased => {
            body.linvel() != Vector::ZERO || math::ang_norm(body.angvel()) != 0.0
        }
        _ => !body.is_sleeping(),
    }
}

/// Whether something wakes a sleeping deformable: a bone it is bound to moves, a collider it
/// touched was removed, or a moving body's collider is near it.
fn disturbed(
    body: &Deformable,
    margin: Real,
    indexed: bool,
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    broad_phase: &BroadPhaseBvh,
    sc: &mut Scratch,
) -> bool {
    sc.attached_bodies.clear();
    for a in &body.attachments {
        if !sc.attached_bodies.contains(&a.body) {
            sc.attached_bodies.push(a.body);
        }
    }
    if sc
        .attached_bodies
        .iter()
        .any(|h| bodies.get(*h).is_none_or(is_moving))
    {
        return true;
    }
    if body.touching.iter().any(|c| !colliders.contains(*c)) {
        return true;
    }
    let mut region = Aabb::new_invalid();
    for &i in body.mesh.boundary_nodes() {
        region.take_point(body.positions[i as usize]);
    }
    let size = (region.maxs - region.mins).max_element().max(1e-3);
    contact::near_colliders(
        region.loosened(margin + 1e-2 * size),
        indexed,
        &body.contact,
        &sc.attached_bodies,
        bodies,
        colliders,
        broad_phase,
        &mut sc.near,
    );
    let woken = sc.near.iter().any(|h| {
        colliders
            .get(*h)
            .and_then(|c| c.parent())
            .and_then(|p| bodies.get(p))
            .is_some_and(is_moving)
    });
    sc.near.clear();
    woken
}

/// How far any collider attached to a moving body may travel in `dt` (a margin for broad-phase
/// boxes, which rapier stores at the bodies' current poses).
fn moving_margin(bodies: &RigidBodySet, colliders: &ColliderSet, dt: Real) -> Real {
    let mut margin: Real = 0.0;
    for (_, co) in colliders.iter() {
        let Some(body) = co.parent().and_then(|p| bodies.get(p)) else {
            continue;
        };
        if body.is_fixed() {
            continue;
        }
        let radius = co.compute_aabb().half_extents().length()
            + (co.position().translation - body.center_of_mass()).length();
        let travel = if body.is_kinematic()
            && body.body_type() == super::rapier::dynamics::RigidBodyType::KinematicPositionBased
        {
            let m = BodyMotion::new(RigidBodyHandle::invalid(), body, dt);
            m.travel(radius)
        } else {
            (body.linvel().length() + math::ang_norm(body.angvel()) * radius) * dt
        };
        margin = margin.max(travel);
    }
    margin
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
        self.step_with_events(
            gravity,
            params,
            deformables,
            bodies,
            colliders,
            broad_phase,
            &(),
        )
    }

    /// [`DeformablePipeline::step`], sending contact start/stop events to `events`.
    #[allow(clippy::too_many_arguments)]
    pub fn step_with_events(
        &mut self,
        gravity: Vector,
        params: &IntegrationParameters,
        deformables: &mut DeformableSet,
        bodies: &mut RigidBodySet,
        colliders: &ColliderSet,
        broad_phase: &BroadPhaseBvh,
        events: &dyn DeformableEventHandler,
    ) -> &StepReport {
        let start = Instant::now();
        let dt = params.dt;
        self.report.dt = dt;
        self.report.deformables.clear();
        let margin = moving_margin(bodies, colliders, dt);
        let indexed = contact::broad_phase_is_current(broad_phase, bodies, colliders);
        self.scratch.pushed.clear();
        for (handle, body) in deformables.iter_mut() {
            let detached = body.prune_attachments(bodies);
            if body.sleeping
                && (!body.can_sleep
                    || disturbed(
                        body,
                        margin,
                        indexed,
                        bodies,
                        colliders,
                        broad_phase,
                        &mut self.scratch,
                    ))
            {
                body.wake_up();
            }
            if body.sleeping {
                // Asleep: not simulated, contacts (and so events) unchanged.
                let r = &mut body.report;
                r.sleeping = true;
                r.substeps = 0;
                r.limiter_substeps = 0;
                r.time_forces = 0.0;
                r.time_contacts = 0.0;
                r.time_integrate = 0.0;
                r.detached = detached;
                r.attached_nodes = body.attachments.len();
                self.report.deformables.push((handle, body.report.clone()));
                continue;
            }
            body.report.sleeping = false;
            if !body.frozen && dt > 0.0 {
                self.step_one(
                    body,
                    gravity,
                    dt,
                    margin,
                    indexed,
                    bodies,
                    colliders,
                    broad_phase,
                );
            } else {
                body.report.substeps = 0;
                body.report.contacts = 0;
                body.report.frozen = body.frozen;
                self.scratch.near.clear();
                self.scratch.touched_colliders.clear();
            }
            body.report.detached = detached;
            body.report.attached_nodes = body.attachments.len();
            // Contact events: the colliders touched this step against those of the last one.
            let sc = &mut self.scratch;
            sc.now.clear();
            sc.now.extend(
                sc.near
                    .iter()
                    .zip(&sc.touched_colliders)
                    .filter(|(_, t)| **t)
                    .map(|(h, _)| *h),
            );
            sc.now.sort_unstable_by_key(|h| h.into_raw_parts());
            for c in body.touching.iter().filter(|c| !sc.now.contains(c)) {
                events.handle_contact_event(DeformableContactEvent::Stopped {
                    deformable: handle,
                    collider: *c,
                });
            }
            for c in sc.now.iter().filter(|c| !body.touching.contains(c)) {
                events.handle_contact_event(DeformableContactEvent::Started {
                    deformable: handle,
                    collider: *c,
                });
            }
            std::mem::swap(&mut body.touching, &mut sc.now);
            self.report.deformables.push((handle, body.report.clone()));
        }
        for h in &self.scratch.pushed {
            if let Some(rb) = bodies.get_mut(*h) {
                contact::match_rapier_integration(rb, gravity, dt, params.num_solver_iterations);
            }
        }
        self.report.wall_time = start.elapsed().as_secs_f64();
        &self.report
    }

    #[allow(clippy::too_many_arguments)]
    fn step_one(
        &mut self,
        body: &mut Deformable,
        gravity: Vector,
        dt: Real,
        margin: Real,
        indexed: bool,
        bodies: &mut RigidBodySet,
        colliders: &ColliderSet,
        broad_phase: &BroadPhaseBvh,
    ) {
        let settings = self.settings;
        let sc = &mut self.scratch;
        let g = gravity * body.gravity_scale;
        let n = body.positions.len();
        body.saved_positions.copy_from_slice(&body.positions);
        body.saved_velocities.copy_from_slice(&body.velocities);
        let mut time_forces = 0.0;

        // Bodies this deformable is bound to, and how every relevant body moves.
        let t0 = Instant::now();
        sc.motions.clear();
        sc.attached_bodies.clear();
        for a in &body.attachments {
            if !sc.attached_bodies.contains(&a.body) {
                sc.attached_bodies.push(a.body);
            }
        }
        let motion_of = |motions: &mut Vec<BodyMotion>,
                         handle: RigidBodyHandle,
                         bodies: &RigidBodySet|
         -> Option<usize> {
            if let Some(k) = motions.iter().position(|m| m.handle == handle) {
                return Some(k);
            }
            let b = bodies.get(handle)?;
            motions.push(BodyMotion::new(handle, b, dt));
            Some(motions.len() - 1)
        };
        sc.attachment_motion.clear();
        for a in &body.attachments {
            let m = motion_of(&mut sc.motions, a.body, bodies).unwrap_or(usize::MAX);
            sc.attachment_motion.push(m);
        }

        // Broad phase, once per deformable and then once per surface node.
        let surface = body.mesh.boundary_nodes();
        let facets = body.mesh.boundary_facets();
        let mut region = Aabb::new_invalid();
        let mut shortest = Real::INFINITY;
        for &i in surface {
            let p = body.positions[i as usize];
            region.take_point(p);
            region.take_point(p + body.velocities[i as usize] * dt + g * (0.5 * dt * dt));
        }
        for f in facets {
            for a in 0..FACET_ARITY {
                for b in a + 1..FACET_ARITY {
                    shortest = shortest
                        .min(body.positions[f[a] as usize].distance(body.positions[f[b] as usize]));
                }
            }
        }
        // Element forces can turn a node around within the step: widen every box by a quarter
        // of the shortest surface edge, on top of the motion predicted from the velocities.
        let size = (region.maxs - region.mins).max_element().max(1e-3);
        let node_margin = if shortest.is_finite() {
            0.25 * shortest
        } else {
            0.0
        } + 1e-3 * size
            + 1e-4;
        let region = region.loosened(node_margin + margin);
        contact::near_colliders(
            region,
            indexed,
            &body.contact,
            &sc.attached_bodies,
            bodies,
            colliders,
            broad_phase,
            &mut sc.near,
        );
        let mut candidates: Vec<Candidate<'_>> = Vec::with_capacity(sc.near.len());
        for &h in &sc.near {
            let Some(co) = colliders.get(h) else { continue };
            let m = co
                .parent()
                .and_then(|p| motion_of(&mut sc.motions, p, bodies));
            candidates.push(contact::candidate(
                h,
                co,
                m,
                &sc.motions,
                &body.contact,
                &region,
                0.5 * shortest.max(1e-4),
                bodies,
                gravity,
                dt,
            ));
        }
        sc.near.clear();
        sc.near.extend(candidates.iter().map(|c| c.handle));
        sc.touched_colliders.clear();
        sc.touched_colliders.resize(candidates.len(), false);
        sc.backup.clear();
        for m in sc.motions.iter().filter(|m| m.kind == MotionKind::Dynamic) {
            if let Some(rb) = bodies.get(m.handle) {
                sc.backup
                    .push((m.handle, *rb.position(), rb.linvel(), rb.angvel()));
            }
        }

        sc.surface_slot.clear();
        sc.surface_slot.resize(n, u32::MAX);
        sc.node_start.clear();
        sc.node_cands.clear();
        sc.node_start.push(0);
        for (k, &i) in surface.iter().enumerate() {
            sc.surface_slot[i as usize] = k as u32;
            if !candidates.is_empty() && !body.is_attached(i) {
                let p = body.positions[i as usize];
                let mut b = Aabb::new_invalid();
                b.take_point(p);
                b.take_point(p + body.velocities[i as usize] * dt + g * (0.5 * dt * dt));
                let b = b.loosened(node_margin + margin);
                contact::node_candidates(
                    b,
                    indexed,
                    &body.contact,
                    bodies,
                    colliders,
                    broad_phase,
                    &candidates,
                    &mut sc.node_cands,
                );
            }
            sc.node_start.push(sc.node_cands.len() as u32);
        }
        sc.facet_start.clear();
        sc.facet_cands.clear();
        sc.facet_start.push(0);
        let with_features = candidates.iter().any(|c| !c.features.is_empty());
        for f in facets {
            if with_features && !f.iter().all(|&i| body.is_attached(i)) {
                let mut b = Aabb::new_invalid();
                for &i in f {
                    let p = body.positions[i as usize];
                    b.take_point(p);
                    b.take_point(p + body.velocities[i as usize] * dt + g * (0.5 * dt * dt));
                }
                let begin = sc.facet_cands.len();
                contact::node_candidates(
                    b.loosened(node_margin + margin),
                    indexed,
                    &body.contact,
                    bodies,
                    colliders,
                    broad_phase,
                    &candidates,
                    &mut sc.facet_cands,
                );
                let mut k = begin;
                while k < sc.facet_cands.len() {
                    if candidates[sc.facet_cands[k] as usize].features.is_empty() {
                        sc.facet_cands.swap_remove(k);
                    } else {
                        k += 1;
                    }
                }
            }
            sc.facet_start.push(sc.facet_cands.len() as u32);
        }
        sc.touched_nodes.clear();
        sc.touched_nodes.resize(surface.len(), false);
        sc.last_contact.clear();
        sc.last_contact.resize(surface.len(), None);
        body.contacts.clear();
        let mut time_contacts = t0.elapsed().as_secs_f64();

        let mut t = 0.0;
        let mut substeps = 0;
        let mut limiter_substeps = 0;
        let mut cap_hit = false;
        let mut lost_time = 0.0;
        let mut facet_contacts = 0;
        loop {
            let remaining = dt - t;
            if let Some(k) = settings.fixed_substeps {
                if substeps >= k.max(1) {
                    break;
                }
            } else if remaining <= dt * 1e-6 {
                break;
            }
            let tf = Instant::now();
            if !body.forces_valid {
                body.acc.clear();
                body.limiter =
                    body.state
                        .accumulate(&body.positions, &body.velocities, &mut body.acc);
                body.forces_valid = true;
            }
            time_forces += tf.elapsed().as_secs_f64();

            let h = match settings.fixed_substeps {
                Some(k) => dt / k.max(1) as Real,
                None => {
                    let stable = settings.safety
                        * stable_substep(&body.masses, &body.acc.stiffness, &body.acc.damping);
                    let bound = stable.min(body.limiter);
                    if body.limiter < stable {
                        limiter_substeps += 1;
                    }
                    if substeps + 1 >= settings.max_substeps
                        || bound.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                    {
                        // Out of substeps: drop the rest of the step for this body rather than
                        // take it in one unstable leap (the report says how much time was lost).
                        cap_hit = true;
                        lost_time = remaining;
                        break;
                    } else if bound.is_finite() {
                        remaining / (remaining / bound).ceil().max(1.0)
                    } else {
                        remaining
                    }
                }
            };
            let s1 = ((t + h) / dt).min(1.0);

            // Symplectic Euler, velocities first.
            body.scratch_velocities.copy_from_slice(&body.velocities);
            for i in 0..n {
                body.velocities[i] += (body.acc.force[i] * body.inv_masses[i] + g) * h;
            }

            // Bound nodes follow their bones.
            sc.targets.clear();
            for (k, a) in body.attachments.iter().enumerate() {
                let m = sc.attachment_motion[k];
                if m == usize::MAX {
                    sc.targets.push(Vector::NAN);
                    continue;
                }
                let motion = sc.motions[m];
                let i = a.node as usize;
                let target = motion.pose_at(s1, dt, bodies).transform_point(a.anchor);
                let desired = (target - body.positions[i]) / h;
                if motion.kind == MotionKind::Dynamic {
                    let anchor_now = motion.pose_at(t / dt, dt, bodies).transform_point(a.anchor);
                    let Some(rb) = bodies.get_mut(a.body) else {
                        sc.targets.push(Vector::NAN);
                        continue;
                    };
                    // Velocity-level binding: the anchor's velocity plus a fraction of the
                    // position error per substep (a full correction on a body whose joints
                    // rapier solves later feeds energy into the pair).
                    let v_anchor = rb.velocity_at_point(anchor_now);
                    let wanted = v_anchor
                        + (anchor_now - body.positions[i]) * (DYNAMIC_BINDING_CORRECTION / h);
                    let delta = wanted - body.velocities[i];
                    let len = delta.length();
                    if len > 0.0 {
                        let dir = delta / len;
                        let props = rb.mass_properties();
                        let r = target - rb.center_of_mass();
                        let rn = math::cross(r, dir);
                        let w_body = (props.effective_inv_mass * dir).dot(dir)
                            + math::ang_dot(rn, props.effective_world_inv_inertia * rn);
                        let impulse = delta / (body.inv_masses[i] + w_body);
                        body.velocities[i] += impulse * body.inv_masses[i];
                        rb.apply_impulse_at_point(-impulse, target, true);
                    }
                    sc.targets.push(Vector::NAN);
                } else {
                    body.velocities[i] = desired;
                    sc.targets.push(target);
                }
            }

            // Contacts, on velocities, before positions move.
            if !candidates.is_empty() {
                let tc = Instant::now();
                for c in candidates.iter_mut() {
                    c.advance(s1, dt, &sc.motions, bodies);
                }
                // Sequential impulses in one fixed order are lopsided (a box landing flat on a
                // soft cube was kicked sideways and kept swaying): the sweeps alternate.
                let backward = substeps % 2 == 1;
                let order = |len: usize, j: usize| if backward { len - 1 - j } else { j };
                for j in 0..surface.len() {
                    let k = order(surface.len(), j);
                    let i = surface[k];
                    let (b0, b1) = (sc.node_start[k] as usize, sc.node_start[k + 1] as usize);
                    if b0 == b1 {
                        continue;
                    }
                    let n_i = i as usize;
                    let mut x = body.positions[n_i];
                    let Some(mut c) = contact::resolve_node(
                        i,
                        &mut x,
                        body.velocities[n_i],
                        body.scratch_velocities[n_i],
                        body.inv_masses[n_i],
                        h,
                        s1,
                        dt,
                        settings.restitution_threshold,
                        &sc.node_cands[b0..b1],
                        &candidates,
                        &sc.motions,
                        bodies,
                    ) else {
                        continue;
                    };
                    body.positions[n_i] = x;
                    c.solve(
                        &mut body.velocities,
                        s1,
                        dt,
                        &candidates,
                        &sc.motions,
                        bodies,
                    );
                    contact::refresh_poses(
                        &mut candidates,
                        c.candidate,
                        s1,
                        dt,
                        &sc.motions,
                        bodies,
                    );
                    c.note_pushed(&candidates, &sc.motions, &mut sc.pushed);
                    sc.touched_nodes[k] = true;
                    sc.last_contact[k] = Some(ContactPoint {
                        point: c.point,
                        normal: c.normal,
                        collider: candidates[c.candidate].handle,
                        node: i,
                    });
                    sc.touched_colliders[c.candidate] = true;
                }
                for j in 0..facets.len() {
                    let f = order(facets.len(), j);
                    let facet = &facets[f];
                    let (b0, b1) = (sc.facet_start[f] as usize, sc.facet_start[f + 1] as usize);
                    if b0 == b1 {
                        continue;
                    }
                    let im: [Real; FACET_ARITY] = std::array::from_fn(|a| {
                        let i = facet[a];
                        if body.is_attached(i) {
                            0.0
                        } else {
                            body.inv_masses[i as usize]
                        }
                    });
                    let x: [Vector; FACET_ARITY] =
                        std::array::from_fn(|a| body.positions[facet[a] as usize]);
                    // The deepest crossing first, then the next one, with the facet where the
                    // last push left it (each push only moves it further in): a flat face
                    // brings several features across one facet at once.
                    for _ in 0..FACET_PASSES {
                        let y: [Vector; FACET_ARITY] = std::array::from_fn(|a| {
                            let i = facet[a] as usize;
                            body.positions[i] + body.velocities[i] * h
                        });
                        let Some(mut c) = contact::resolve_facet(
                            facet,
                            &x,
                            &y,
                            &im,
                            h,
                            s1,
                            dt,
                            &sc.facet_cands[b0..b1],
                            &candidates,
                            &sc.motions,
                            bodies,
                        ) else {
                            break;
                        };
                        c.solve(
                            &mut body.velocities,
                            s1,
                            dt,
                            &candidates,
                            &sc.motions,
                            bodies,
                        );
                        contact::refresh_poses(
                            &mut candidates,
                            c.candidate,
                            s1,
                            dt,
                            &sc.motions,
                            bodies,
                        );
                        c.note_pushed(&candidates, &sc.motions, &mut sc.pushed);
                        facet_contacts += 1;
                        body.contacts.push(ContactPoint {
                            point: c.point,
                            normal: c.normal,
                            collider: candidates[c.candidate].handle,
                            node: u32::MAX,
                        });
                        sc.touched_colliders[c.candidate] = true;
                    }
                }
                time_contacts += tc.elapsed().as_secs_f64();
            }

            for i in 0..n {
                body.positions[i] += body.velocities[i] * h;
            }
            for (a, target) in body.attachments.iter().zip(&sc.targets) {
                if target.is_finite() {
                    body.positions[a.node as usize] = *target;
                }
            }
            body.forces_valid = false;
            t += h;
            substeps += 1;
        }

        let ti = Instant::now();
        // Node contacts first, then the facet contacts gathered during the substeps.
        sc.contacts.clear();
        sc.contacts
            .extend(sc.last_contact.iter().flatten().copied());
        sc.contacts.append(&mut body.contacts);
        std::mem::swap(&mut body.contacts, &mut sc.contacts);
        // Non-finite, or so far out that it can only be a blow-up (|x| or |v| above 1e8), or a
        // cell stretched past any material.
        let sane = |v: &Vector| v.is_finite() && v.abs().max_element() < 1e8;
        let finite = body.positions.iter().all(sane) && body.velocities.iter().all(sane);
        let most = settings.max_stretch.powi(DIM as i32);
        let exploded = finite
            && most.is_finite()
            && (0..body.mesh.num_cells())
                .any(|c| body.mesh.cell_quality(c, &body.positions) > most);
        body.report.non_finite = !finite;
        body.report.exploded = exploded;
        if !finite || exploded {
            body.positions.copy_from_slice(&body.saved_positions);
            body.velocities.copy_from_slice(&body.saved_velocities);
            body.frozen = true;
            body.forces_valid = false;
            // The bodies it pushed this step get their state back: a blow-up must not
            // launch them.
            for (h, pose, linvel, angvel) in &sc.backup {
                if let Some(rb) = bodies.get_mut(*h) {
                    rb.set_position(*pose, false);
                    rb.set_linvel(*linvel, false);
                    rb.set_angvel(*angvel, false);
                }
            }
        }
        let finite = finite && !exploded;
        let mut max_penetration: Real = 0.0;
        for (k, &i) in surface.iter().enumerate() {
            let (b0, b1) = (sc.node_start[k] as usize, sc.node_start[k + 1] as usize);
            if b0 < b1 {
                max_penetration = max_penetration.max(contact::penetration(
                    body.positions[i as usize],
                    &sc.node_cands[b0..b1],
                    &candidates,
                ));
            }
        }
        let mut inverted = 0;
        let mut min_ratio = Real::INFINITY;
        for c in 0..body.mesh.num_cells() {
            let q = body.mesh.cell_quality(c, &body.positions);
            if q <= 0.0 {
                inverted += 1;
            }
            min_ratio = min_ratio.min(q);
        }
        // Sleep: still long enough, with nothing around it moving.
        let quiet = sc
            .motions
            .iter()
            .all(|m| bodies.get(m.handle).is_some_and(|b| !is_moving(b)));
        let max_speed = (0..n)
            .filter(|&i| !body.is_attached(i as u32))
            .map(|i| body.velocities[i].length())
            .fold(0.0, Real::max);
        if body.can_sleep && finite && quiet && max_speed < settings.sleep_speed {
            body.still_time += dt;
        } else {
            body.still_time = 0.0;
        }
        if body.still_time >= settings.time_until_sleep {
            body.sleeping = true;
            body.velocities.fill(Vector::ZERO);
        }
        let kinetic = body.kinetic_energy();
        let gravity_energy = -body
            .positions
            .iter()
            .zip(&body.masses)
            .map(|(x, m)| m * g.dot(*x))
            .sum::<Real>();
        let elastic = body.state.elastic_energy(&body.positions);
        let r = &mut body.report;
        r.frozen = body.frozen;
        r.substeps = substeps;
        r.limiter_substeps = limiter_substeps;
        r.substep_cap_hit = cap_hit;
        r.lost_time = lost_time;
        r.contacts = sc.touched_nodes.iter().filter(|t| **t).count();
        r.facet_contacts = facet_contacts;
        r.max_penetration = max_penetration;
        r.inverted_elements = inverted;
        r.min_volume_ratio = min_ratio;
        r.kinetic_energy = kinetic;
        r.gravity_energy = gravity_energy;
        r.elastic_energy = elastic;
        r.time_forces = time_forces;
        r.time_contacts = time_contacts;
        r.time_integrate = ti.elapsed().as_secs_f64();
    }
}
