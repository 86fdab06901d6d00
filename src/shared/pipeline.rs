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
//! 4. contacts, on velocities (and pushing out nodes found inside);
//! 5. `x += h v`.
//!
//! After the step: impulses go to dynamic rigid bodies, a state that turned non-finite is
//! rolled back to the start of the step and frozen, and the report is filled in.

use std::time::Instant;

use super::body::Deformable;
use super::contact::{self, Candidate};
use super::math::{Real, Vector};
use super::rapier::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};
use super::rapier::geometry::{Aabb, BoundingVolume, BroadPhaseBvh, ColliderSet};
use super::report::StepReport;
use super::set::DeformableSet;

/// Knobs of the pipeline.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PipelineSettings {
    /// Fraction of the stability bound used as the largest substep (default 0.5: the
    /// Gershgorin bound overestimates ω by 1.3–1.8×, and damping and nonlinearity eat the rest).
    pub safety: Real,
    /// Largest number of substeps per step (default 20 000). When reached, the rest of the
    /// step is taken in one substep and the report says so.
    pub max_substeps: usize,
    /// A fixed substep count instead of the automatic one (for experiments such as the
    /// dt sweep; `None`, the default, is automatic).
    pub fixed_substeps: Option<usize>,
    /// Approach speeds below this (m/s) give a resting contact, not a bounce (default 0.1).
    pub restitution_threshold: Real,
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            safety: 0.5,
            max_substeps: 20_000,
            fixed_substeps: None,
            restitution_threshold: 0.1,
        }
    }
}

/// Steps deformables beside a rapier world. Holds only settings and scratch buffers.
#[derive(Clone, Debug, Default)]
pub struct DeformablePipeline {
    /// The knobs.
    pub settings: PipelineSettings,
    impulses: Vec<(RigidBodyHandle, Vector, Vector)>,
    touched: Vec<bool>,
    report: StepReport,
}

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
    /// `PhysicsPipeline::step`, with the same sets: it reads collider poses through the broad
    /// phase and applies contact impulses to dynamic bodies.
    pub fn step(
        &mut self,
        gravity: Vector,
        params: &IntegrationParameters,
        deformables: &mut DeformableSet,
        bodies: &mut RigidBodySet,
        colliders: &ColliderSet,
        broad_phase: &BroadPhaseBvh,
    ) -> &StepReport {
        let start = Instant::now();
        let dt = params.dt;
        self.report.dt = dt;
        self.report.deformables.clear();
        let mut candidates: Vec<Candidate<'_>> = Vec::new();
        for (handle, body) in deformables.iter_mut() {
            self.impulses.clear();
            if !body.frozen && dt > 0.0 {
                self.step_one(
                    body,
                    gravity,
                    dt,
                    bodies,
                    colliders,
                    broad_phase,
                    &mut candidates,
                );
                for (b, impulse, point) in self.impulses.drain(..) {
                    if let Some(rb) = bodies.get_mut(b) {
                        rb.apply_impulse_at_point(impulse, point, true);
                    }
                }
            } else {
                body.report.substeps = 0;
                body.report.contacts = 0;
                body.report.frozen = body.frozen;
            }
            self.report.deformables.push((handle, body.report.clone()));
        }
        self.report.wall_time = start.elapsed().as_secs_f64();
        &self.report
    }

    #[allow(clippy::too_many_arguments)]
    fn step_one<'c>(
        &mut self,
        body: &mut Deformable,
        gravity: Vector,
        dt: Real,
        bodies: &RigidBodySet,
        colliders: &'c ColliderSet,
        broad_phase: &BroadPhaseBvh,
        candidates: &mut Vec<Candidate<'c>>,
    ) {
        let settings = self.settings;
        let g = gravity * body.gravity_scale;
        let n = body.positions.len();
        body.saved_positions.copy_from_slice(&body.positions);
        body.saved_velocities.copy_from_slice(&body.velocities);
        let mut time_forces = 0.0;
        let mut time_contacts = 0.0;

        // Broad phase: colliders near the box the surface sweeps this step.
        let t0 = Instant::now();
        let surface = body.mesh.boundary_nodes();
        let mut region = Aabb::new_invalid();
        for &i in surface {
            let p = body.positions[i as usize];
            region.take_point(p);
            region.take_point(p + body.velocities[i as usize] * dt + g * (0.5 * dt * dt));
        }
        let margin = 0.01 * (region.maxs - region.mins).max_element().max(1e-3);
        contact::gather(
            region.loosened(margin),
            dt,
            &body.contact,
            bodies,
            colliders,
            broad_phase,
            candidates,
        );
        self.touched.clear();
        self.touched.resize(surface.len(), false);
        time_contacts += t0.elapsed().as_secs_f64();

        let mut t = 0.0;
        let mut substeps = 0;
        let mut limiter_substeps = 0;
        let mut cap_hit = false;
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
                    if substeps + 1 >= settings.max_substeps {
                        cap_hit = true;
                        remaining
                    } else if bound.is_finite() && bound > 0.0 {
                        let pieces = (remaining / bound).ceil().max(1.0);
                        remaining / pieces
                    } else if bound > 0.0 {
                        remaining
                    } else {
                        cap_hit = true;
                        remaining
                    }
                }
            };

            // Symplectic Euler, velocities first.
            body.scratch_velocities.copy_from_slice(&body.velocities);
            for i in 0..n {
                body.velocities[i] += (body.acc.force[i] * body.inv_masses[i] + g) * h;
            }

            // Contacts on velocities, before positions move.
            if !candidates.is_empty() {
                let tc = Instant::now();
                for (k, &i) in surface.iter().enumerate() {
                    let i = i as usize;
                    let (mut x, mut v) = (body.positions[i], body.velocities[i]);
                    if let Some(c) = contact::resolve_node(
                        &mut x,
                        &mut v,
                        body.scratch_velocities[i],
                        body.masses[i],
                        h,
                        settings.restitution_threshold,
                        candidates,
                        bodies,
                    ) {
                        body.positions[i] = x;
                        body.velocities[i] = v;
                        self.touched[k] = true;
                        if let (Some(b), true) = (c.body, c.dynamic) {
                            self.impulses.push((b, c.impulse, c.point));
                        }
                    }
                }
                time_contacts += tc.elapsed().as_secs_f64();
            }

            for i in 0..n {
                body.positions[i] += body.velocities[i] * h;
            }
            body.forces_valid = false;
            t += h;
            substeps += 1;
        }

        let ti = Instant::now();
        let finite = body.positions.iter().all(|p| p.is_finite())
            && body.velocities.iter().all(|v| v.is_finite());
        let r = &mut body.report;
        r.non_finite = !finite;
        if !finite {
            body.positions.copy_from_slice(&body.saved_positions);
            body.velocities.copy_from_slice(&body.saved_velocities);
            body.frozen = true;
            body.forces_valid = false;
            self.impulses.clear();
        }
        r.frozen = body.frozen;
        r.substeps = substeps;
        r.limiter_substeps = limiter_substeps;
        r.substep_cap_hit = cap_hit;
        r.contacts = self.touched.iter().filter(|t| **t).count();
        r.max_penetration = surface
            .iter()
            .map(|&i| contact::penetration(body.positions[i as usize], candidates))
            .fold(0.0, Real::max);
        let mut inverted = 0;
        let mut min_ratio = Real::INFINITY;
        for c in 0..body.mesh.num_cells() {
            let q = body.mesh.cell_quality(c, &body.positions);
            if q <= 0.0 {
                inverted += 1;
            }
            min_ratio = min_ratio.min(q);
        }
        let r = &mut body.report;
        r.inverted_elements = inverted;
        r.min_volume_ratio = min_ratio;
        r.kinetic_energy = body
            .velocities
            .iter()
            .zip(&body.masses)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum();
        r.gravity_energy = -body
            .positions
            .iter()
            .zip(&body.masses)
            .map(|(x, m)| m * g.dot(*x))
            .sum::<Real>();
        r.elastic_energy = body.state.elastic_energy(&body.positions);
        r.time_forces = time_forces;
        r.time_contacts = time_contacts;
        r.time_integrate = ti.elapsed().as_secs_f64();
    }
}
