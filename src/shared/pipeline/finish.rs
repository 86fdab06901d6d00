//! Phases 5 and 7 of a body's step: the report (contacts, penetration, cell quality, energies,
//! timings) and the contact events.

use super::super::body::Deformable;
use super::super::contact;
use super::super::events::{DeformableContactEvent, DeformableEventHandler, DeformableTearEvent};
use super::super::math::Real;
use super::super::set::DeformableHandle;
use super::containment::Quality;
use super::substep::SubstepStats;
use super::{Candidates, Scratch, StageTimes, StepContext};

/// The step's contacts (node contacts first, then the facet contacts gathered during the
/// substeps), the deepest penetration, the cells' quality and the substep counts, into the
/// body's report. `quality` is that of the final state when containment measured it.
pub(super) fn diagnose(
    body: &mut Deformable,
    sc: &mut Scratch,
    candidates: &Candidates<'_>,
    stats: SubstepStats,
    quality: Option<Quality>,
) {
    sc.touch.contacts.clear();
    sc.touch
        .contacts
        .extend(sc.touch.last_contact.iter().flatten().copied());
    sc.touch.contacts.append(&mut body.last.contacts);
    std::mem::swap(&mut body.last.contacts, &mut sc.touch.contacts);
    let mut max_penetration: Real = 0.0;
    for (k, &i) in body.rest.mesh.boundary_nodes().iter().enumerate() {
        let (b0, b1) = (
            sc.broad.node_start[k] as usize,
            sc.broad.node_start[k + 1] as usize,
        );
        if b0 < b1 {
            max_penetration = max_penetration.max(contact::penetration(
                body.state.positions[i as usize],
                &sc.broad.node_cands[b0..b1],
                candidates,
            ));
        }
    }
    let quality = quality.unwrap_or_else(|| Quality::of(body, Real::INFINITY));
    let r = &mut body.last.report;
    r.frozen = body.activation.frozen;
    r.teleported = sc.bones.teleported;
    r.substeps = stats.substeps;
    r.implicit = stats.implicit;
    r.limiter_substeps = stats.limiter_substeps;
    r.substep_cap_hit = stats.cap_hit;
    r.lost_time = stats.lost_time;
    r.contacts = sc.touch.touched_nodes.iter().filter(|t| **t).count();
    r.facet_contacts = stats.facet_contacts;
    r.soft_contacts = stats.soft_contacts;
    r.self_contacts = stats.self_contacts;
    r.max_penetration = max_penetration;
    r.inverted_elements = quality.inverted;
    r.min_volume_ratio = quality.min_ratio;
    r.elastic_energy = quality.elastic;
}

/// Kinetic and gravitational energy at the end of the step, into the report (the elastic
/// energy came with the cells' quality, [`diagnose`]).
pub(super) fn energies(body: &mut Deformable, ctx: &StepContext<'_>) {
    let g = ctx.gravity * body.gravity_scale;
    let (kinetic, gravity_energy) = body.kinetic_and_gravity_energy(g);
    let r = &mut body.last.report;
    r.kinetic_energy = kinetic;
    r.gravity_energy = gravity_energy;
}

/// The stage timings, into the report.
pub(super) fn timings(body: &mut Deformable, times: &StageTimes) {
    let r = &mut body.last.report;
    r.time_forces = times.forces;
    r.time_contacts = times.contacts;
    r.time_integrate = times.integrate;
}

/// Contact events: the colliders touched this step against those of the last one.
pub(super) fn send_events(
    handle: DeformableHandle,
    body: &mut Deformable,
    sc: &mut Scratch,
    events: &dyn DeformableEventHandler,
) {
    sc.touch.now.clear();
    sc.touch.now.extend(
        sc.broad
            .near
            .iter()
            .zip(&sc.touch.touched_colliders)
            .filter(|(_, t)| **t)
            .map(|(h, _)| *h),
    );
    sc.touch.now.sort_unstable_by_key(|h| h.into_raw_parts());
    for c in body
        .last
        .touching
        .iter()
        .filter(|c| !sc.touch.now.contains(c))
    {
        events.handle_contact_event(DeformableContactEvent::Stopped {
            deformable: handle,
            collider: *c,
        });
    }
    for c in sc
        .touch
        .now
        .iter()
        .filter(|c| !body.last.touching.contains(c))
    {
        events.handle_contact_event(DeformableContactEvent::Started {
            deformable: handle,
            collider: *c,
        });
    }
    std::mem::swap(&mut body.last.touching, &mut sc.touch.now);
    if !body.last.tears.is_empty() {
        events.handle_tear_event(DeformableTearEvent {
            deformable: handle,
            faces: body.last.tears.clone(),
        });
    }
}
