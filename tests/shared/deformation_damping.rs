//! `DeformableBuilder::deformation_damping`: a body's deformation is damped toward its rigid
//! motion, which it keeps.

use super::support::weightless_with_bone;
use crate::dim::math::{ang_cross, ang_norm, cross, AngVector, Pose, Real, Vector, DIM};
use crate::dim::{
    BuildError, DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel, Integrator,
    Material,
};
use crate::scenes::{Subject, TowerScene};

/// A 1 × 0.4 (× 0.6) m box in free space, no gravity, its nodes moving with a drift, a spin
/// about an axis off its principal ones and a stretch along x.
fn ringing_box(
    model: ElementModel,
    integrator: Integrator,
    rate: Real,
) -> (DeformableWorld, DeformableHandle) {
    let mut world = DeformableWorld::new();
    world.physics.gravity = Vector::ZERO;
    world.set_dt(1.0 / 60.0);
    world.pipeline.settings.integrator = integrator;
    let mut half = Vector::splat(0.2);
    half[0] = 0.5;
    if DIM == 3 {
        half[1] = 0.3;
    }
    let body = DeformableBuilder::cuboid(half, [4; DIM])
        .model(model)
        .material(Material {
            density: 500.0,
            young_modulus: 1e5,
            damping_ratio: 0.05,
            ..Default::default()
        })
        .deformation_damping(rate)
        .build()
        .unwrap();
    let h = world.insert(body);
    let mut spin = AngVector::default();
    if DIM == 3 {
        spin = ang_from([0.3, 1.0, 0.5]);
    } else {
        spin += 1.0;
    }
    let drift = Vector::splat(0.4);
    let v: Vec<Vector> = world.deformables[h]
        .positions()
        .iter()
        .map(|p| drift + ang_cross(spin, *p) + Vector::X * (2.0 * p.x))
        .collect();
    world.deformables[h].set_velocities(&v).unwrap();
    (world, h)
}

/// An angular vector from its three components (3D only).
fn ang_from(c: [Real; 3]) -> AngVector {
    crate::dim::math::ang_from_components(c)
}

/// Kinetic energy of the motion that is not the rigid one carrying the same momenta.
fn deformation_energy(world: &DeformableWorld, h: DeformableHandle) -> Real {
    let b = &world.deformables[h];
    let (m, c) = (b.total_mass(), b.center_of_mass());
    let p = b.linear_momentum();
    let l = b.angular_momentum() - cross(c, p);
    let r: Vec<Vector> = b.positions().iter().map(|x| *x - c).collect();
    let w = crate::dim::math::angular_velocity_for(&r, b.masses(), l);
    let rigid_ke = 0.5 * p.length_squared() / m + 0.5 * crate::dim::math::ang_dot(w, l);
    b.kinetic_energy() - rigid_ke
}

/// Damped at 20 per second, the stretch's ringing dies within a second (under 10⁻³ of its
/// kinetic energy left) while the drift and the spin go on: momentum and angular momentum
/// (about the centre of mass) within 10⁻³ of their start. Undamped but for the material's
/// ζ = 0.05, the same body still rings with ten times as much.
#[test]
fn deformation_damping_stills_the_stretch_and_keeps_the_momenta() {
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        for integrator in [
            Integrator::Explicit,
            Integrator::Midpoint { iterations: 10 },
        ] {
            let name = format!("{} {integrator:?}", model.name());
            let mut left = [0.0; 2];
            for (k, rate) in [0.0, 20.0].into_iter().enumerate() {
                let (mut world, h) = ringing_box(model, integrator, rate);
                let start = deformation_energy(&world, h);
                let b = &world.deformables[h];
                let (p0, l0) = (
                    b.linear_momentum(),
                    b.angular_momentum() - cross(b.center_of_mass(), b.linear_momentum()),
                );
                // The ringing over the last tenth of a second (its kinetic energy passes through
                // zero twice a period).
                let mut ringing: Real = 0.0;
                for k in 0..60 {
                    world.step();
                    if k >= 54 {
                        ringing = ringing.max(deformation_energy(&world, h));
                    }
                }
                let b = &world.deformables[h];
                assert!(!b.is_frozen(), "{name}: frozen");
                let p = b.linear_momentum();
                let l = b.angular_momentum() - cross(b.center_of_mass(), p);
                assert!(
                    (p - p0).length() <= 1e-3 * p0.length(),
                    "{name} rate {rate}: momentum {p0:?} -> {p:?}"
                );
                assert!(
                    ang_norm(l - l0) <= 1e-3 * ang_norm(l0),
                    "{name} rate {rate}: angular momentum {l0:?} -> {l:?}"
                );
                left[k] = ringing / start;
            }
            assert!(
                left[1] < 1e-3 && left[0] > 1e-2,
                "{name}: deformation's kinetic energy left after 1 s, undamped {} damped {}",
                left[0],
                left[1]
            );
        }
    }
}

/// A negative or non-finite rate is a typed error, from the builder and the setter (which then
/// changes nothing).
#[test]
fn a_negative_or_nan_deformation_damping_is_an_error() {
    for rate in [-1.0, Real::NAN, Real::INFINITY] {
        let built = DeformableBuilder::cuboid(Vector::splat(0.5), [2; DIM])
            .deformation_damping(rate)
            .build();
        assert!(
            matches!(
                built,
                Err(BuildError::InvalidParameter {
                    name: "deformation_damping",
                    ..
                })
            ),
            "{rate}: {built:?}"
        );
        let mut body = DeformableBuilder::cuboid(Vector::splat(0.5), [2; DIM])
            .deformation_damping(3.0)
            .build()
            .unwrap();
        assert!(body.set_deformation_damping(rate).is_err());
        assert_eq!(body.deformation_damping(), 3.0);
    }
}

/// Dropped from 10 cm gaps at 1 ms, shape-matched squares that keep rocking on each other walk
/// off the axis (10 cm in 2D, `scenes tower --dim 2 --gap 0.1 --dt 0.001`); damped toward their
/// rigid motion they land within 5 cm of it.
#[test]
fn a_dropped_tower_damped_toward_rigid_motion_lands_on_its_axis() {
    if DIM == 3 {
        // The same in 3D costs a minute; the scene runner measures it
        // (`scenes tower --gap 0.1 --dt 0.001 --deformation-damping 100`).
        return;
    }
    let scene = |rate| TowerScene {
        subject: Subject::Sinew(ElementModel::SHAPE_MATCHING),
        gap: 0.1,
        dt: 0.001,
        deformation_damping: rate,
        ..Default::default()
    };
    let damped = scene(100.0).run().unwrap();
    let scatter = damped.scatter.unwrap();
    assert!(scatter <= 0.05, "damped: a square ended {scatter} m off");
    assert!(damped.energy_over_start.unwrap() <= 1e-3);
}

/// The bound nodes are left out of the fit: free nodes at rest, with no force on them (no
/// stiffness, no gravity), stay at rest while the bone they hang from moves off; counted in,
/// the bone's speed would drag them along.
#[test]
fn deformation_damping_does_not_drag_the_free_nodes_after_a_bone() {
    let (mut world, bone) = weightless_with_bone();
    let body = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
        .model(ElementModel::SHAPE_MATCHING)
        .material(Material {
            young_modulus: 0.0,
            damping_ratio: 0.0,
            ..Default::default()
        })
        .deformation_damping(50.0)
        .build()
        .unwrap();
    let h = world.insert(body);
    let low: Vec<u32> = (0..world.deformables[h].num_nodes() as u32)
        .filter(|&i| world.deformables[h].positions()[i as usize].x < -0.4)
        .collect();
    world.attach_nodes(h, bone, &low).unwrap();
    for k in 1..=10 {
        let at = Vector::X * (0.05 * k as Real);
        world.physics.bodies[bone].set_next_kinematic_position(Pose::from_translation(at));
        world.step();
    }
    let b = &world.deformables[h];
    let fastest = (0..b.num_nodes())
        .filter(|&i| !b.is_attached(i as u32))
        .map(|i| b.velocities()[i].length())
        .fold(0.0, Real::max);
    assert!(fastest < 1e-6, "a free node moves at {fastest} m/s");
    assert!(low.iter().all(|&i| b.is_attached(i)));
}
