//! Deformables held against each other by their contacts damp their motion against each
//! other (run every `HELD_PERIOD` of a step and at its end, before the sleep test).
//!
//! A material's damping acts on each term's stretching rate, so a slow mode of bodies resting
//! on each other, such as a tower of cubes swaying in its first bending mode (each cube
//! rocking nearly whole on the one below), is damped by about `ζ · ω / ω_element`: nearly
//! nothing. Rubber loses about the same share of its energy per cycle at any frequency; a
//! viscous law cannot. So deformables that hold each other form a *composite* for this pass,
//! and the composite's slow modes are damped as a body's own: each member's rigid motion (its
//! best-fit translation and rotation) is pulled toward the composite's target motion by
//! `1 − exp(−α dt)`, `α = 2ζω`, `ω = π c / L` the composite's reference frequency (`ζc` the
//! members' mass-weighted product of damping ratio and wave speed `c = √(E/ρ)`, `L` the composite's
//! diagonal: a free bar's first axial mode). The share of a slow mode that is the members'
//! rigid motion against each other is damped at `α / 2ω`, at least `ζ` below `ω`; the members'
//! deformation is left to the material.
//!
//! - Two members *hold* each other when their contacts of the last substep press them together
//!   over a patch (its spread across the contact at least [`PATCH_SHARE`] of the smaller
//!   body's least extent: a face holds, an edge or a corner, about which a body tips, does not)
//!   and they do not slide: their rigid motions slip across the patch's centre, and twist
//!   about its normal, slower than the sleep speed or than their relative rocking moves the
//!   patch's edge. Composites are the connected sets of such pairs. Friction's own verdict is
//!   no guide: a single pass of the explicit step's contacts leaves the lightly pressed rows of
//!   a resting pair slipping within each substep, and the implicit step's regularised friction
//!   sticks a little while it slides.
//! - A composite one of whose members rests the same way on a still, non-dynamic collider (the
//!   ground) is *anchored*: its target is rest, so the members' settling
//!   along the ground's normal is damped too. Otherwise its target is its own rigid motion
//!   (the one carrying its momentum and angular momentum), so a stack thrown or falling
//!   together keeps its flight. A composite on the ground is not pulled toward its own motion:
//!   that would push the members near the ground into it and into each other (a pile in a
//!   bowl gains energy so).
//!
//! What it leaves alone: a body alone (its damping is the material's), bodies sliding on each
//! other, touching along an edge or at a corner, or rolling on each other over a small patch,
//! bodies bound to bones, and undamped materials (ζ = 0, or stiffness given raw or per mass).
//! What it guarantees: kinetic energy never rises (each member's rigid motion moves toward the
//! target, its deformation stays), and an unanchored composite's momentum and angular momentum
//! are unchanged.

use super::super::material::Stiffness;
use super::super::math::{self, AngVector, Real, Vector, DIM};
use super::super::model::Motion;
use super::box_sides;
use super::substep::Member;

/// The narrowest contact patch that holds two bodies (the spread of its points across the
/// contact, a standard deviation), as a share of the smaller body's least rest extent.
const PATCH_SHARE: Real = 0.15;

/// Damps the rigid motion of each composite's members toward its target over `dt` (module
/// docs); `still`: the speed under which bodies count as not slipping (the sleep speed).
/// Returns the kinetic energy it took.
pub(super) fn damp(members: &mut [Member<'_, '_>], dt: Real, still: Real) -> Real {
    let n = members.len();
    if n < 2 || dt <= 0.0 {
        return 0.0;
    }
    // The pairs that touched in the last substep, each once.
    let mut pairs: Vec<(usize, usize)> = members
        .iter()
        .enumerate()
        .flat_map(|(i, m)| m.held.iter().map(move |h| (i.min(h.other), i.max(h.other))))
        .collect();
    if pairs.is_empty() {
        return 0.0;
    }
    pairs.sort_unstable();
    pairs.dedup();
    let touching: Vec<bool> = (0..n)
        .map(|i| pairs.iter().any(|&(a, b)| a == i || b == i))
        .collect();
    let fits: Vec<Option<Fit>> = members
        .iter()
        .zip(&touching)
        .map(|(m, &t)| if t && eligible(m) { Fit::of(m) } else { None })
        .collect();
    let mut parent: Vec<usize> = (0..n).collect();
    let mut any = false;
    for (a, b) in pairs {
        let (Some(fa), Some(fb)) = (&fits[a], &fits[b]) else {
            continue;
        };
        if holds(members, (a, fa), (b, fb), still) {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
            any = true;
        }
    }
    if !any {
        return 0.0;
    }
    let mut taken = 0.0;
    for r in 0..n {
        let composite: Vec<usize> = (0..n).filter(|&i| root(&mut parent, i) == r).collect();
        if composite.len() > 1 {
            let kinetic = |members: &[Member<'_, '_>]| -> Real {
                composite
                    .iter()
                    .map(|&i| members[i].body.kinetic_energy())
                    .sum()
            };
            let before = kinetic(members);
            damp_composite(members, &composite, &fits, (dt, still));
            taken += (before - kinetic(members)).max(0.0);
        }
    }
    taken
}

fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// The `(ζ, c)` of a member's material, `None` where it names no wave speed (the papers' raw
/// and per-mass stiffness forms).
fn damping_and_wave_speed(m: &Member<'_, '_>) -> Option<(Real, Real)> {
    let params = &m.body.rest.params;
    match params.stiffness {
        Stiffness::FromMaterial => {
            let material = params.material;
            let c = (material.young_modulus / material.density).sqrt();
            Some((material.damping_ratio, c))
        }
        _ => None,
    }
}

/// A member this pass may move: simulated this step, damped, with no node bound to a bone.
fn eligible(m: &Member<'_, '_>) -> bool {
    m.live
        && m.body.bindings.len() == 0
        && damping_and_wave_speed(m).is_some_and(|(zeta, c)| zeta > 0.0 && c > 0.0)
}

/// A member's rigid motion: its centre of mass, the velocity of that centre and the angular
/// velocity that carries its angular momentum.
struct Fit {
    centre: Vector,
    velocity: Vector,
    spin: AngVector,
}

impl Fit {
    fn of(m: &Member<'_, '_>) -> Option<Fit> {
        let (x, masses) = (&m.body.state.positions, &m.body.rest.masses);
        let motion = Motion::of(x, &m.body.state.velocities, masses)?;
        Some(Fit {
            centre: x[0] - motion.r[0],
            velocity: motion.velocity,
            spin: math::angular_velocity_for(&motion.r, masses, motion.momentum),
        })
    }

    /// The velocity of the point at `x` moving with the body's rigid motion.
    fn at(&self, x: Vector) -> Vector {
        self.velocity + math::ang_cross(self.spin, x - self.centre)
    }
}

/// The least side of a member's rest bounding box.
fn least_extent(m: &Member<'_, '_>) -> Real {
    box_sides(m.body.rest.mesh.nodes()).min_element()
}

/// A contact patch: its points' centre, the mean normal, and the spread of the points across
/// it; `None` with fewer than `DIM` points or no normal.
fn patch(points: &[Vector], normal: Vector) -> Option<(Vector, Vector, Real)> {
    if points.len() < DIM {
        return None;
    }
    let normal = normal.try_normalize()?;
    let centre = points.iter().copied().sum::<Vector>() / points.len() as Real;
    Some((centre, normal, spread(points, centre, normal)))
}

/// The spread of `points` about `centre` across the plane (2D: the line) of `normal`: in 2D
/// their standard deviation along the line, in 3D the smaller of the two principal standard
/// deviations in the plane (points along a line have none).
fn spread(points: &[Vector], centre: Vector, normal: Vector) -> Real {
    let [t1, t2] = math::tangents(normal);
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for p in points {
        let (u, v) = ((*p - centre).dot(t1), (*p - centre).dot(t2));
        a += u * u;
        b += u * v;
        c += v * v;
    }
    let count = points.len() as Real;
    let (a, b, c) = (a / count, b / count, c / count);
    if DIM == 2 {
        return a.sqrt();
    }
    // The smaller eigenvalue of [[a, b], [b, c]].
    let mean = 0.5 * (a + c);
    let radius = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    (mean - radius).max(0.0).sqrt()
}

/// Whether two sides touching over a patch (centre, normal, spread) at least `narrowest` wide
/// do not slide: the relative velocity `velocity` of their rigid motions at the patch's centre
/// slips across it slower than the sleep speed `still` or than their relative rocking `spin`
/// moves the patch's edge, and their twist about the normal moves that edge slower than
/// `still`.
fn together(
    (centre, normal, spread): (Vector, Vector, Real),
    narrowest: Real,
    velocity: impl Fn(Vector) -> Vector,
    spin: AngVector,
    still: Real,
) -> bool {
    if spread < narrowest {
        return false;
    }
    let turn = math::ang_norm(spin);
    let twist = math::twist_about(spin, normal);
    let rocking = (turn * turn - twist * twist).max(0.0).sqrt();
    let v = velocity(centre);
    let slip = (v - normal * normal.dot(v)).length();
    slip <= (rocking * spread).max(still) && twist.abs() * spread <= still
}

/// Whether members `a` and `b` hold each other (module docs).
fn holds(
    members: &[Member<'_, '_>],
    (a, fa): (usize, &Fit),
    (b, fb): (usize, &Fit),
    still: Real,
) -> bool {
    let ab = members[a].held.iter().filter(|h| h.other == b);
    let ba = members[b].held.iter().filter(|h| h.other == a);
    let mut normal = Vector::ZERO;
    let mut points = Vec::new();
    // Normals from `b`'s facets point toward `a`'s node, and the other way round.
    for (h, side) in ab.map(|h| (h, 1.0)).chain(ba.map(|h| (h, -1.0))) {
        normal += h.grip.normal * (h.grip.push * side);
        points.push(h.point);
    }
    let Some(patch) = patch(&points, normal) else {
        return false;
    };
    let narrowest = PATCH_SHARE * least_extent(&members[a]).min(least_extent(&members[b]));
    together(
        patch,
        narrowest,
        |x| fb.at(x) - fa.at(x),
        fb.spin - fa.spin,
        still,
    )
}

/// Whether member `m` rests on a still, non-dynamic collider: its nodes that touched such
/// colliders this step span a patch, and it does not slide on it.
fn anchored(m: &Member<'_, '_>, fit: &Fit, still: Real) -> bool {
    let touch = &m.sc.touch;
    let boundary = m.body.rest.mesh.boundary_nodes();
    let resting_on = |handle| {
        m.candidates
            .iter()
            .any(|c| c.handle == handle && !c.dynamic && c.pose == c.prev_pose)
    };
    let (mut points, mut normal) = (Vec::new(), Vector::ZERO);
    for (k, contact) in touch.last_contact.iter().enumerate() {
        let Some(contact) = contact else { continue };
        if resting_on(contact.collider) {
            points.push(m.body.state.positions[boundary[k] as usize]);
            normal += contact.normal;
        }
    }
    let Some(patch) = patch(&points, normal) else {
        return false;
    };
    let narrowest = PATCH_SHARE * least_extent(m);
    together(patch, narrowest, |x| fit.at(x), fit.spin, still)
}

/// Pulls the rigid motion of each member of `composite` toward the composite's target.
fn damp_composite(
    members: &mut [Member<'_, '_>],
    composite: &[usize],
    fits: &[Option<Fit>],
    (dt, still): (Real, Real),
) {
    let (mut x, mut v, mut m) = (Vec::new(), Vec::new(), Vec::new());
    let (mut mass, mut zeta_c, mut anchor) = (0.0, 0.0, false);
    for &i in composite {
        let body = &*members[i].body;
        let (zeta, c) = damping_and_wave_speed(&members[i]).unwrap_or((0.0, 0.0));
        x.extend_from_slice(&body.state.positions);
        v.extend_from_slice(&body.state.velocities);
        m.extend_from_slice(&body.rest.masses);
        let own: Real = body.rest.masses.iter().sum();
        mass += own;
        zeta_c += own * zeta * c;
        anchor = anchor
            || fits[i]
                .as_ref()
                .is_some_and(|f| anchored(&members[i], f, still));
    }
    let length = box_sides(&x).length();
    if !(mass > 0.0 && length > 0.0) {
        return;
    }
    let rate = 2.0 * (zeta_c / mass) * std::f64::consts::PI as Real / length;
    let pull = 1.0 - (-rate * dt).exp();
    if !(pull > 0.0 && pull.is_finite()) {
        return;
    }
    let Some(whole) = Motion::of(&x, &v, &m) else {
        return;
    };
    let target = if anchor {
        Target::Rest
    } else {
        Target::Moving(Fit {
            centre: x[0] - whole.r[0],
            velocity: whole.velocity,
            spin: math::angular_velocity_for(&whole.r, &m, whole.momentum),
        })
    };
    for &i in composite {
        let Some(own) = &fits[i] else { continue };
        let body = &mut *members[i].body;
        for (u, p) in body.state.velocities.iter_mut().zip(&body.state.positions) {
            let towards = match &target {
                Target::Rest => -own.at(*p),
                Target::Moving(fit) => fit.at(*p) - own.at(*p),
            };
            *u += towards * pull;
        }
        body.step.invalidate_forces();
    }
}

/// What a composite's members' rigid motions are pulled toward.
enum Target {
    /// Rest on the ground.
    Rest,
    /// The composite's own rigid motion.
    Moving(Fit),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_face_spreads_and_an_edge_does_not() {
        let up = math::UP;
        let [t1, t2] = math::tangents(up);
        let mut face = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (u, w) = (i as Real * 0.1, j as Real * 0.1);
                face.push(t1 * u + t2 * w);
                if DIM == 2 && j > 0 {
                    face.pop();
                }
            }
        }
        let (_, normal, wide) = patch(&face, up).unwrap();
        assert!((normal - up).length() < 1e-6);
        // Four points 0.1 apart along each direction: a standard deviation of 0.112.
        assert!((wide - 0.1118).abs() < 1e-3, "{wide}");
        let edge: Vec<Vector> = (0..4).map(|i| t1 * (i as Real * 0.1)).collect();
        let (_, _, narrow) = patch(&edge, up).unwrap();
        if DIM == 3 {
            assert!(narrow < 1e-6, "{narrow}");
        } else {
            assert!((narrow - wide).abs() < 1e-6);
        }
        assert!(patch(&edge[..DIM - 1], up).is_none());
    }
}
