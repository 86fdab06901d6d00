//! Islands: the deformables that step together, as one group.
//!
//! Two deformables are in one island when they may touch each other this step (the pairs of
//! [`soft::pairs`](super::super::contact::soft::pairs)), or when both may touch, or are bound
//! to, the same dynamic rigid body. The second rule matters as much as the first: two soft
//! pads squeezing a box push it from both sides, and stepped one after the other, the first
//! pad's whole step shoves the box away before the second pad has pushed back (a 1 kg box
//! pinched at 60 Hz left at 1 m/s sideways). In one island their substeps interleave.

use super::super::body::{Deformable, SurfaceTree};
use super::super::contact;
use super::super::math::Real;
use super::super::rapier::dynamics::{RigidBodyHandle, RigidBodySet};
use super::super::rapier::geometry::{Aabb, BoundingVolume, ColliderHandle};
use super::super::set::{DeformableHandle, DeformableSet};
use super::StepContext;

/// The pairs of deformables that may touch this step, from their boxes swept over the step (a
/// BVH over the bodies' boxes in `tree`, refitted from step to step, one query each), by their
/// collision groups; both asleep, or either frozen, a pair is left out. Also wakes a sleeping
/// body that a moving one comes near.
pub(super) fn pairs(
    set: &mut DeformableSet,
    (dt, sleep_speed): (Real, Real),
    tree: &mut SurfaceTree,
    out: &mut Vec<(DeformableHandle, DeformableHandle)>,
) {
    out.clear();
    if set.len() < 2 {
        return;
    }
    let bodies: Vec<(DeformableHandle, Aabb, bool)> = set
        .iter()
        .map(|(h, b)| {
            let fastest = b
                .rest
                .mesh
                .boundary_nodes()
                .iter()
                .map(|&i| b.state.velocities[i as usize].length())
                .fold(0.0, Real::max);
            let moving = !b.activation.sleeping && fastest > sleep_speed;
            (h, swept_region(b, dt), moving)
        })
        .collect();
    let boxes: Vec<Aabb> = bodies.iter().map(|b| b.1).collect();
    tree.set(&boxes);
    let mut wake = Vec::new();
    for (a, (ha, box_a, moving_a)) in bodies.iter().enumerate() {
        for b in tree.bvh().intersect_aabb(box_a) {
            let b = b as usize;
            if b <= a {
                continue;
            }
            let (hb, _, moving_b) = bodies[b];
            let (da, db) = (&set[*ha], &set[hb]);
            // A frozen body blew up: its last finite state is no shape to meet.
            let frozen = da.activation.frozen || db.activation.frozen;
            if frozen || !da.contact.groups.test(db.contact.groups) {
                continue;
            }
            let (sleep_a, sleep_b) = (da.activation.sleeping, db.activation.sleeping);
            if sleep_a && sleep_b {
                continue;
            }
            if sleep_a && moving_b {
                wake.push(*ha);
            }
            if sleep_b && *moving_a {
                wake.push(hb);
            }
            out.push((*ha, hb));
        }
    }
    out.sort_unstable_by_key(|(a, b)| (a.into_raw_parts(), b.into_raw_parts()));
    // An island wakes as one: a woken body wakes the sleeping bodies it touched, and those the
    // bodies they touched; then the pairs are found again with them awake.
    let mut woke_more = false;
    while let Some(h) = wake.pop() {
        if !set[h].activation.sleeping {
            continue;
        }
        set[h].wake_up();
        for &o in &set[h].last.touching_bodies {
            if set.get(o).is_some_and(|b| b.activation.sleeping) {
                wake.push(o);
                woke_more = true;
            }
        }
    }
    if woke_more {
        pairs(set, (dt, sleep_speed), tree, out);
    }
}

/// Pairs of deformables (asleep or awake) that may push, or are bound to, the same dynamic
/// rigid body this step (smaller handle first, sorted, each once).
pub(super) fn rigid_links(
    set: &DeformableSet,
    ctx: &StepContext<'_>,
    bodies: &RigidBodySet,
    out: &mut Vec<(DeformableHandle, DeformableHandle)>,
) {
    out.clear();
    if set.len() < 2 {
        return;
    }
    let mut shared: Vec<(RigidBodyHandle, DeformableHandle)> = Vec::new();
    let (mut near, mut attached) = (Vec::<ColliderHandle>::new(), Vec::new());
    for (h, body) in set.iter() {
        if body.activation.frozen {
            continue;
        }
        body.bindings.bodies(&mut attached);
        let region = swept_region(body, ctx.dt).loosened(ctx.margin);
        let scan = ctx.scan(bodies, &body.contact);
        contact::near_colliders(&scan, region, &attached, &mut near);
        let touched = near
            .iter()
            .filter_map(|&c| ctx.colliders.get(c)?.parent())
            .chain(attached.iter().copied());
        for rb in touched {
            if bodies.get(rb).is_some_and(|b| b.is_dynamic()) {
                shared.push((rb, h));
            }
        }
    }
    shared.sort_unstable_by_key(|(rb, h)| (rb.into_raw_parts(), h.into_raw_parts()));
    shared.dedup();
    for run in shared.chunk_by(|a, b| a.0 == b.0) {
        for w in run.windows(2) {
            out.push((w[0].1, w[1].1));
        }
    }
    out.sort_unstable_by_key(|(a, b)| (a.into_raw_parts(), b.into_raw_parts()));
    out.dedup();
}

/// The box a body's surface sweeps over the step at its present velocities, widened by 5 % of
/// its size (forces turn nodes within the step).
fn swept_region(body: &Deformable, dt: Real) -> Aabb {
    let mut region = Aabb::new_invalid();
    for &i in body.rest.mesh.boundary_nodes() {
        let (x, v) = (
            body.state.positions[i as usize],
            body.state.velocities[i as usize],
        );
        region.take_point(x);
        region.take_point(x + v * dt);
    }
    let size = (region.maxs - region.mins).max_element().max(1e-3);
    region.loosened(0.05 * size + 1e-4)
}

/// The islands: groups of indices into `handles` (sorted, as the set iterates them) joined by
/// `links`, each group in index order, the groups in the order of their first member.
pub(super) fn groups(
    handles: &[DeformableHandle],
    links: &[(DeformableHandle, DeformableHandle)],
) -> Vec<Vec<usize>> {
    // The set iterates in arena order: the handles are sorted by index.
    let index = |h: DeformableHandle| {
        handles
            .binary_search_by_key(&h.into_raw_parts().0, |x| x.into_raw_parts().0)
            .ok()
            .filter(|&k| handles[k] == h)
    };
    let mut parent: Vec<usize> = (0..handles.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for &(a, b) in links {
        if let (Some(a), Some(b)) = (index(a), index(b)) {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut group_of: Vec<Option<usize>> = vec![None; handles.len()];
    for i in 0..handles.len() {
        let r = root(&mut parent, i);
        match group_of[r] {
            Some(g) => out[g].push(i),
            None => {
                group_of[r] = Some(out.len());
                out.push(vec![i]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_are_the_connected_sets_of_pairs() {
        let h: Vec<DeformableHandle> = (0..5)
            .map(|i| DeformableHandle::from_raw_parts(i, 0))
            .collect();
        // 0–3 and 3–4 touch, 1 and 2 are alone; a pair naming a stale handle is ignored.
        let stale = DeformableHandle::from_raw_parts(2, 7);
        let pairs = [(h[3], h[4]), (h[0], h[3]), (h[1], stale)];
        assert_eq!(groups(&h, &pairs), vec![vec![0, 3, 4], vec![1], vec![2]]);
        assert_eq!(groups(&h, &[]).len(), 5);
    }
}
