//! Plastic flow (issue 31, acceptance 1 and 4).

use super::support::weightless_with_bone;
use crate::dim::math::{Pose, Real, Vector, DIM};
use crate::dim::rapier::prelude::RigidBodyBuilder;
use crate::dim::{
    BuildError, DeformableBuilder, DeformableHandle, DeformableWorld, ElementModel, FlowIn,
    Integrator, Material, Plasticity,
};

const YIELD: Real = 0.02;

fn plasticity() -> Plasticity {
    Plasticity {
        yield_strain: YIELD,
        flow_rate: Real::INFINITY,
        max_strain: 1.0,
        flow: FlowIn::Both,
    }
}

/// A 1 m bar along the first axis, 10 cm across: its nodes along and across, its material and
/// deformation damping, and where its left end is.
struct Bar {
    along: usize,
    across: usize,
    material: Material,
    deformation_damping: Real,
    left: Real,
}

/// The bar pulled in the stretch tests: centred on the origin, 10 cm cells.
fn pulled() -> Bar {
    Bar {
        along: 11,
        across: 3,
        material: Material {
            density: 1000.0,
            young_modulus: 1e5,
            damping_ratio: 0.3,
            ..Default::default()
        },
        deformation_damping: 0.0,
        left: -0.5,
    }
}

/// A bar's world, the bar, and its two bones (left, right).
type BarWorld = (
    DeformableWorld,
    DeformableHandle,
    [crate::dim::rapier::prelude::RigidBodyHandle; 2],
);

/// `bar` under `model` and `integrator`, its end faces bound to two kinematic bones (left,
/// right) that start where the ends are.
fn bar_of(bar: Bar, model: ElementModel, integrator: Integrator) -> BarWorld {
    let (mut world, left) = weightless_with_bone();
    world.pipeline.settings.integrator = integrator;
    let right = world
        .physics
        .insert_body(RigidBodyBuilder::kinematic_position_based());
    let mut half = Vector::splat(0.05);
    half[0] = 0.5;
    let mut res = [bar.across; DIM];
    res[0] = bar.along;
    let mut shift = Vector::ZERO;
    shift[0] = bar.left + 0.5;
    let body = DeformableBuilder::cuboid(half, res)
        .model(model)
        .material(bar.material)
        .plasticity(plasticity())
        .deformation_damping(bar.deformation_damping)
        .translation(shift)
        .build()
        .unwrap();
    let h = world.insert(body);
    let ends = |x: Real| -> Vec<u32> {
        let d = &world.deformables[h];
        (0..d.num_nodes() as u32)
            .filter(|&i| (d.positions()[i as usize][0] - x).abs() < 1e-4)
            .collect()
    };
    let (l, r) = (ends(bar.left), ends(bar.left + 1.0));
    world.attach_nodes(h, left, &l).unwrap();
    world.attach_nodes(h, right, &r).unwrap();
    (world, h, [left, right])
}

/// [`pulled`] under `model` and `integrator`.
fn bar(model: ElementModel, integrator: Integrator) -> BarWorld {
    bar_of(pulled(), model, integrator)
}

/// The bar's length: the mean first coordinate of its right end's nodes less its left end's
/// (the nodes that were at ±0.5 when built).
fn length(world: &DeformableWorld, h: DeformableHandle) -> Real {
    let d = &world.deformables[h];
    let rest = d.mesh().nodes();
    let end = |x: Real| {
        let ids: Vec<usize> = (0..rest.len())
            .filter(|&i| (rest[i][0] - x).abs() < 1e-4)
            .collect();
        ids.iter().map(|&i| d.positions()[i][0]).sum::<Real>() / ids.len() as Real
    };
    end(0.5) - end(-0.5)
}

#[test]
fn a_bar_stretched_past_yield_and_released_keeps_the_strain_beyond_yield() {
    // Stretched to 1.1 of its length over a second, held half a second, let go for three: it
    // keeps ln 1.1 − yield, within 5 %, in every model that flows under both integrators.
    let total = Real::ln(1.1);
    let expected = total - YIELD;
    for model in [
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
        ElementModel::Springs,
        ElementModel::NonlinearSprings,
        ElementModel::CentroidSprings,
    ] {
        for integrator in [Integrator::Explicit, Integrator::Implicit { iterations: 2 }] {
            let (mut world, h, [_, right]) = bar(model, integrator);
            let mut dissipated = 0.0;
            for k in 1..=90 {
                let t = (k as Real / 60.0).min(1.0);
                let mut at = Vector::ZERO;
                at[0] = 0.1 * t;
                world.physics.bodies[right].set_next_kinematic_position(Pose::from_translation(at));
                world.step();
                dissipated += world.deformables[h].report().plastic_dissipation;
            }
            world.deformables[h].detach_all();
            for _ in 0..180 {
                world.step();
                dissipated += world.deformables[h].report().plastic_dissipation;
            }
            let d = &world.deformables[h];
            let kept = length(&world, h).ln();
            let name = format!("{} {integrator:?}", model.name());
            assert!(
                (kept - expected).abs() < 0.05 * expected,
                "{name}: kept {kept}, expected {expected} (stretched {total})"
            );
            assert_eq!(d.inverted_elements(), 0, "{name}");
            assert!(dissipated > 0.0, "{name}: the flow released {dissipated} J");
            assert!(d.min_volume_ratio() > 0.5, "{name}");
            // Each cell's set (what Rerun's plastic field draws): on average the bar's (cells
            // near the bones flow less, and a cell's largest strain may lie off the axis).
            let set = d.plastic_strains();
            assert_eq!(set.len(), d.mesh().num_cells(), "{name}");
            let mean = set.iter().sum::<Real>() / set.len() as Real;
            assert!(
                (mean / kept - 1.0).abs() < 0.05,
                "{name}: cells set by {mean} on average, the bar by {kept}"
            );
        }
    }
}

#[test]
fn a_bar_stretched_within_yield_springs_back() {
    let total = 0.5 * YIELD;
    for model in [
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
        ElementModel::CentroidSprings,
    ] {
        let (mut world, h, [_, right]) = bar(model, Integrator::Implicit { iterations: 2 });
        for k in 1..=60 {
            let mut at = Vector::ZERO;
            at[0] = (Real::exp(total) - 1.0) * k as Real / 60.0;
            world.physics.bodies[right].set_next_kinematic_position(Pose::from_translation(at));
            world.step();
            assert_eq!(world.deformables[h].report().plastic_dissipation, 0.0);
        }
        world.deformables[h].detach_all();
        for _ in 0..180 {
            world.step();
        }
        let kept = length(&world, h).ln();
        assert!(kept.abs() < 1e-3, "{}: kept {kept}", model.name());
        let set = world.deformables[h].plastic_strains();
        assert!(
            set.iter().all(|s| *s < 1e-4),
            "{}: a cell flowed",
            model.name()
        );
    }
}

#[test]
fn plasticity_is_refused_for_bad_parameters_and_cells_without_flow() {
    let build = |model, p: Plasticity| {
        DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
            .model(model)
            .plasticity(p)
            .build()
            .map(|_| ())
    };
    let er = ElementModel::EdgeRepulsion;
    for (bad, name) in [
        (
            Plasticity {
                yield_strain: -0.1,
                ..plasticity()
            },
            "yield_strain",
        ),
        (
            Plasticity {
                flow_rate: 0.0,
                ..plasticity()
            },
            "flow_rate",
        ),
        (
            Plasticity {
                max_strain: Real::INFINITY,
                ..plasticity()
            },
            "max_strain",
        ),
        (
            Plasticity {
                yield_strain: Real::NAN,
                ..plasticity()
            },
            "yield_strain",
        ),
    ] {
        match build(er, bad) {
            Err(BuildError::InvalidParameter { name: got, .. }) => assert_eq!(got, name),
            other => panic!("{bad:?}: {other:?}"),
        }
    }
    let cubes = DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
        .cells(crate::dim::mesh::CellKind::Cube)
        .model(ElementModel::SHAPE_MATCHING)
        .plasticity(plasticity())
        .build();
    assert!(matches!(cubes, Err(BuildError::NoPlasticity { .. })));
}

/// A snapshot taken after the flow restores the flowed rest shapes: the restored world goes on
/// as the original, bit for bit: edge repulsion, shape matching, and centroid springs (edges
/// and centroid distances).
#[cfg(feature = "serde")]
#[test]
fn a_snapshot_after_flow_continues_bit_for_bit() {
    for model in [
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
        ElementModel::CentroidSprings,
    ] {
        let (mut world, h, [_, right]) = bar(model, Integrator::Implicit { iterations: 2 });
        for k in 1..=60 {
            let mut at = Vector::ZERO;
            at[0] = 0.1 * k as Real / 60.0;
            world.physics.bodies[right].set_next_kinematic_position(Pose::from_translation(at));
            world.step();
        }
        let bytes = bincode::serialize(&world).expect("a snapshot serializes");
        let mut restored: DeformableWorld = bincode::deserialize(&bytes).expect("it restores");
        assert_eq!(restored.deformables[h].plasticity(), Some(plasticity()));
        for w in [&mut world, &mut restored] {
            w.deformables[h].detach_all();
            for _ in 0..60 {
                w.step();
            }
        }
        let (a, b) = (&world.deformables[h], &restored.deformables[h]);
        assert_eq!(a.positions(), b.positions(), "{}", model.name());
        // Both kept their set (a restore that lost the flow would spring back).
        assert!(length(&restored, h).ln() > 0.05, "{}", model.name());
    }
}

/// The residual curvature of an elastic–perfectly-plastic beam of thickness `t` bent to
/// curvature `k` and released: `k − M(k)/EI` with `M = 1.5 M_y (1 − (k_y/k)²/3)` past the
/// yield curvature `k_y = 2 ε_y / t` (a rectangular section in pure bending).
fn kept_curvature(k: Real, t: Real) -> Real {
    let ky = 2.0 * YIELD / t;
    k - 1.5 * ky * (1.0 - (ky / k).powi(2) / 3.0)
}

#[test]
fn a_bar_bent_a_quarter_turn_and_released_keeps_the_bend_of_a_plastic_beam() {
    // A 1 m bar, 10 cm thick, clamped at one end to a fixed bone and bent a quarter turn in 2 s
    // by a bone at the other that follows the arc of a uniform bend, then let go. It keeps the
    // bend of an elastic–perfectly-plastic beam (0.98 rad for yield 0.02) within 15 % in both
    // models under both integrators. Cells about square: 2.5 cm along and across the bend (a
    // lattice of 5 cm by 2.5 cm cells kept up to 1.35 times the bend, and 1.2 in 3D with 5 cm across
    // the bend axis).
    use crate::dim::math::{planar_angle, rotation_from_angle};
    let quarter = std::f32::consts::FRAC_PI_2;
    let expected = kept_curvature(quarter, 0.1);
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        for integrator in [Integrator::Explicit, Integrator::Implicit { iterations: 2 }] {
            let bent = Bar {
                along: 41,
                across: 5,
                material: Material {
                    density: 100.0,
                    young_modulus: 1e6,
                    damping_ratio: 0.3,
                    ..Default::default()
                },
                deformation_damping: 5.0,
                left: 0.0,
            };
            let (mut world, h, [_, right]) = bar_of(bent, model, integrator);
            let steps = 120;
            for k in 1..=steps + 30 {
                // The end where a uniform bend by `theta` takes it, turned by `theta`.
                let theta = quarter * (k.min(steps) as Real / steps as Real);
                let mut end = Vector::ZERO;
                end[0] = theta.sin() / theta;
                end[1] = (1.0 - theta.cos()) / theta;
                let turn = rotation_from_angle(planar_angle(theta));
                let mut tip = Vector::ZERO;
                tip[0] = 1.0;
                let pose = Pose::from_parts(end - turn * tip, turn);
                world.physics.bodies[right].set_next_kinematic_position(pose);
                world.step();
            }
            world.deformables[h].detach_body(right);
            // The direction of the last cell layer (the bend kept over the whole length),
            // averaged over the last of two seconds: the bar rings about its set.
            let direction = |world: &DeformableWorld| -> Real {
                let d = &world.deformables[h];
                let rest = d.mesh().nodes();
                let layer = |x: Real| -> Vector {
                    let ids: Vec<usize> = (0..rest.len())
                        .filter(|&i| (rest[i][0] - x).abs() < 1e-3)
                        .collect();
                    ids.iter().map(|&i| d.positions()[i]).sum::<Vector>() / ids.len() as Real
                };
                let last = layer(0.5) - layer(0.475);
                last[1].atan2(last[0])
            };
            let mut sum = 0.0;
            for k in 0..120 {
                world.step();
                if k >= 60 {
                    sum += direction(&world);
                }
            }
            let kept = sum / 60.0;
            let d = &world.deformables[h];
            let name = format!("{} {integrator:?}", model.name());
            assert!(
                (kept / expected - 1.0).abs() < 0.15,
                "{name}: kept {kept} rad, an elastic–perfectly-plastic beam {expected}"
            );
            assert_eq!(d.inverted_elements(), 0, "{name}");
        }
    }
}
