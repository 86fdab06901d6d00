//! The implicit integrator (issue 15, in progress): backward Euler by Vertex Block Descent.

use crate::dim::math::{Real, Vector, DIM, UP};
use crate::dim::rapier::dynamics::{IntegrationParameters, RigidBodySet};
use crate::dim::rapier::geometry::{BroadPhaseBvh, ColliderSet};
use crate::dim::{
    CellKind, DeformableBuilder, DeformablePipeline, DeformableSet, ElementModel, Integrator,
    Material,
};
use crate::scenes::{BallScene, CrushScene, FallScene, LimbScene, StackScene, Subject};

const IMPLICIT: Integrator = Integrator::Implicit { iterations: 10 };

fn step_free(
    set: &mut DeformableSet,
    pipeline: &mut DeformablePipeline,
    gravity: Vector,
    dt: Real,
) {
    let params = IntegrationParameters {
        dt,
        ..Default::default()
    };
    let (mut bodies, colliders, bp) = (
        RigidBodySet::new(),
        ColliderSet::new(),
        BroadPhaseBvh::new(),
    );
    pipeline.step(gravity, &params, set, &mut bodies, &colliders, &bp);
}

#[test]
fn an_unstressed_body_falls_ballistically() {
    // Free fall leaves every cell at rest shape: the minimiser is the inertial prediction.
    for model in [
        ElementModel::Springs,
        ElementModel::EdgeRepulsion,
        ElementModel::SHAPE_MATCHING,
    ] {
        let mut set = DeformableSet::new();
        let h = set.insert(
            DeformableBuilder::cuboid(Vector::splat(0.5), [3; DIM])
                .cells(CellKind::Simplex)
                .model(model)
                .build()
                .unwrap(),
        );
        let mut pipeline = DeformablePipeline::new();
        pipeline.settings.integrator = IMPLICIT;
        pipeline.settings.time_until_sleep = Real::INFINITY;
        let dt = 1.0 / 60.0;
        for _ in 0..30 {
            step_free(&mut set, &mut pipeline, -UP * 9.81, dt);
        }
        let v = set[h].center_of_mass_velocity().dot(UP);
        let r = pipeline.report().get(h).unwrap();
        assert!(
            r.min_volume_ratio > 0.99,
            "{}: {}",
            model.name(),
            r.min_volume_ratio
        );
        assert!(
            (v + 9.81 * 0.5).abs() < 1e-3 * 9.81 * 0.5,
            "{}: {v} m/s",
            model.name()
        );
        assert_eq!(pipeline.report().get(h).unwrap().substeps, 1);
    }
}

#[test]
fn edge_repulsion_and_shape_matching_land_and_rest_at_60_hz_without_inverted_cells() {
    // Two sweeps a step, the speed setting of the README's table.
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let run = |integrator, dt| {
            FallScene {
                subject: Subject::Sinew(model),
                integrator,
                dt,
                seconds: 8.0,
                ..Default::default()
            }
            .run()
            .unwrap()
        };
        let implicit = run(Integrator::Implicit { iterations: 2 }, 1.0 / 60.0);
        let explicit = run(Integrator::Explicit, 1e-3);
        let name = model.name();
        assert_eq!(implicit.max_inverted_elements, 0, "{name}");
        assert!(implicit.max_penetration.unwrap() < 1e-3, "{name}");
        let (a, b) = (implicit.rest_com.unwrap(), explicit.rest_com.unwrap());
        assert!(
            (a - b).abs() < 0.01 * b,
            "{name} rests at {a} m implicit, {b} m explicit"
        );
        // One substep a step at most against the explicit step's several (on average both
        // count the steps asleep as none).
        assert!(
            implicit.max_substeps <= 1 && explicit.max_substeps > 1,
            "{name}: {} implicit, {} explicit",
            implicit.max_substeps,
            explicit.max_substeps
        );
    }
}

#[test]
fn the_line_search_keeps_a_cell_driven_towards_inversion_upright() {
    // One node of a small edge-repulsion body thrown at 200 m/s into the body: a 60 Hz step
    // would carry it 3 m, through every cell; the line search stops it short of its facets.
    let mut set = DeformableSet::new();
    let h = set.insert(
        DeformableBuilder::cuboid(Vector::splat(0.5), [2; DIM])
            .cells(CellKind::Simplex)
            .model(ElementModel::EdgeRepulsion)
            .material(Material {
                density: 100.0,
                young_modulus: 1e4,
                ..Default::default()
            })
            .build()
            .unwrap(),
    );
    let corner = (0..set[h].positions().len())
        .max_by(|&a, &b| {
            let p = set[h].positions();
            p[a].element_sum().total_cmp(&p[b].element_sum())
        })
        .unwrap();
    let mut v = vec![Vector::ZERO; set[h].positions().len()];
    v[corner] = -Vector::splat(1.0).normalize() * 200.0;
    set[h].set_velocities(&v).unwrap();
    let mut pipeline = DeformablePipeline::new();
    pipeline.settings.integrator = IMPLICIT;
    for _ in 0..20 {
        step_free(&mut set, &mut pipeline, Vector::ZERO, 1.0 / 60.0);
        let r = pipeline.report().get(h).unwrap();
        assert_eq!(r.inverted_elements, 0);
        assert!(r.min_volume_ratio > 0.0);
        assert!(set[h].positions().iter().all(|p| p.is_finite()));
    }
}

#[test]
fn a_stiff_silicone_ball_lands_and_rests_at_60_hz_without_inverted_cells() {
    // The ball: 10 cm, 2 cm cells, E = 1 MPa, ρ = 1100, dropped from 0.5 m. Its
    // bottom nodes, thrown back by the contact, and its cells of four surface nodes pressed
    // onto the floor once inverted 96 cells at the impact. (Shape matching lands without an
    // inverted cell too, but at three sweeps rests 2 cm low on cells pressed nearly flat.)
    // From 0.55–0.7 m the last frame before the impact ends 3–5 cm above the floor, so the
    // contact stops three layers of nodes at once: lifting the contact nodes of the cells that
    // leaves flat off the floor flattened their neighbours, which kept 12–26 cells inside out
    // for good with two sweeps, until the lift-off went on until no cell was flat.
    let model = ElementModel::EdgeRepulsion;
    for (drop_height, iterations) in [(0.5, 3), (0.6, 2), (0.7, 2)] {
        let r = BallScene {
            subject: Subject::Sinew(model),
            integrator: Integrator::Implicit { iterations },
            drop_height,
            seconds: 2.5,
            ..Default::default()
        }
        .run()
        .unwrap();
        let name = format!("{} from {drop_height} m, {iterations} sweeps", model.name());
        assert_eq!(r.max_inverted_elements, 0, "{name}");
        assert!(r.max_penetration.unwrap() < 1e-3, "{name}");
        let rest = r.rest_com.unwrap();
        assert!((rest - 0.1).abs() < 0.01, "{name} ends at {rest} m");
        assert!(r.substeps <= 1.0, "{name}");
    }
}

#[test]
fn the_limb_bends_to_110_degrees_and_1000_kg_crushes_the_cube_at_60_hz_without_inverted_cells() {
    for implicit in [
        Integrator::Implicit { iterations: 2 },
        Integrator::Midpoint { iterations: 2 },
    ] {
        limb_and_crush(implicit);
    }
}

fn limb_and_crush(implicit: Integrator) {
    let limb = LimbScene {
        dt: 1.0 / 60.0,
        integrator: implicit,
        ..Default::default()
    }
    .run()
    .unwrap();
    assert_eq!(limb.max_inverted_elements, 0);
    assert!(
        limb.max_anchor_error.unwrap() < 1e-5,
        "{:?}",
        limb.max_anchor_error
    );
    assert!(limb.substeps <= 1.0, "{implicit:?}");
    // A 1000 kg box on a 1 kg cube: the held nodes pass the cube's elastic force on to the box
    // (without it the box sank through the cube, inverting 145 cells).
    let crush = CrushScene {
        cube: FallScene {
            dt: 1.0 / 60.0,
            integrator: implicit,
            ..Default::default()
        },
        mass: 1000.0,
        ..Default::default()
    }
    .run()
    .unwrap();
    assert!(!crush.failed, "{implicit:?}: {:?}", crush.failure);
    assert_eq!(crush.max_inverted_elements, 0, "{implicit:?}");
    assert!(crush.max_penetration.unwrap() < 1e-3, "{implicit:?}");
    assert!(
        crush.shape_error.unwrap() < 0.01,
        "{implicit:?}: {:?}",
        crush.shape_error
    );
}

#[test]
fn shape_matched_deformables_that_meet_are_solved_together_under_the_implicit_setting() {
    // A shape-matched cube dropped on another: the island takes the implicit step with its
    // contacts as terms, not the explicit substeps it fell back to (which the explicit run
    // counts); even asked for two sweeps it ends resting on the other, not inside it (51 mm in
    // 3D when the island took only two), with no energy from the contact. Eight seconds: with
    // four sweeps the soft stack still rocks at up to 9 cm/s after the default four, and with
    // two at 6 cm/s after six once its landing is taken again in shorter substeps
    // (`pipeline/guard.rs`).
    let run = |integrator, seconds| {
        StackScene {
            subject: Subject::Sinew(ElementModel::SHAPE_MATCHING),
            integrator,
            seconds,
            ..Default::default()
        }
        .run()
        .unwrap()
    };
    // The explicit step's substeps over the landing, before the stack sleeps.
    let explicit = run(Integrator::Explicit, 1.0);
    for iterations in [2, 10] {
        let implicit = run(Integrator::Implicit { iterations }, 8.0);
        assert!(!implicit.failed, "{iterations}: {:?}", implicit.failure);
        assert!(
            implicit.substeps * 5.0 < explicit.substeps,
            "{iterations}: {} substeps a step, explicitly {}",
            implicit.substeps,
            explicit.substeps
        );
        // With two sweeps the upper cube ends 1.04 mm (0.2 % of its size) inside the other:
        // resting bodies damp their settling against each other
        // (`PipelineSettings::damp_held`), and with it the last of the push out.
        let inside = implicit.rest_interpenetration.unwrap();
        assert!(inside < 1.5e-3, "{iterations}: {inside} m inside at rest");
        let speed = implicit.final_speed.unwrap();
        assert!(speed < 1e-3, "{iterations}: still moves at {speed} m/s");
        let gain = implicit.energy_gain.unwrap();
        assert!(gain <= 2e-3, "{iterations}: the landing created {gain}");
        let (a, b) = (implicit.rest_com.unwrap(), explicit.rest_com.unwrap());
        assert!(
            (a - b).abs() < 0.01,
            "{iterations}: rests at {a}, explicitly {b}"
        );
    }
}

#[test]
fn other_deformables_that_meet_step_explicitly_under_the_implicit_setting() {
    // Edge repulsion's energy is not convex: solved together, a pile of fifty such cubes
    // exploded. Its island steps explicitly, as it would without the setting.
    let run = |integrator| {
        StackScene {
            integrator,
            ..Default::default()
        }
        .run()
        .unwrap()
    };
    let (implicit, explicit) = (
        run(Integrator::Implicit { iterations: 2 }),
        run(Integrator::Explicit),
    );
    assert!(implicit.max_interpenetration.unwrap() < 1e-3);
    assert_eq!(implicit.substeps, explicit.substeps);
    assert_eq!(implicit.rest_com, explicit.rest_com);
}

#[test]
fn a_cube_landing_at_60_hz_with_two_sweeps_creates_no_energy() {
    // A stiff cube (E = 2 MPa, 0.4 m) dropped 10 cm lands at 1.3 m/s. Its free nodes started a
    // frame's fall into the bottom layer the contact held, and two sweeps left that layer
    // crushed: the landing raised the cube's energy twelvefold. The step starts them from
    // the part of their motion that costs least.
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let scene = crate::scenes::TowerScene {
            subject: Subject::Sinew(model),
            bodies: 1,
            gap: 0.1,
            seconds: 1.0,
            integrator: Integrator::Implicit { iterations: 2 },
            ..Default::default()
        };
        let r = scene.run().unwrap();
        let over = r.energy_over_start.unwrap();
        assert!(
            over <= 1e-3,
            "{}: energy rose {over} above its start",
            model.name()
        );
        assert_eq!(r.final_inverted_elements, 0, "{}", model.name());
    }
}

#[test]
fn a_box_dropped_with_a_soft_cube_does_not_press_its_cells_inside_out() {
    // A 0.5 m cube (E = 10⁶ Pa, 10 cm cells) and a 20 kg box 0.4 m wide just above it fall
    // 1 m onto the ground together, backward Euler at 60 Hz: the box lands on the cube at
    // ~4 m/s and its corners press the cube's top facets. Held where the corners took them,
    // the facets' nodes went 7 cm into 10 cm cells in one step and edge repulsion ended with
    // 4 cells inside out for good (3D).
    use crate::dim::rapier::dynamics::RigidBodyBuilder;
    use crate::dim::rapier::geometry::{ColliderBuilder, SharedShape};
    use crate::dim::rapier::parry::shape::Cuboid;
    use crate::dim::{DeformableWorld, Mesh};
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let dt = 1.0 / 60.0;
        let mut world = DeformableWorld::new();
        world.set_dt(dt);
        world.pipeline.settings.integrator = Integrator::Implicit { iterations: 2 };
        let mut ground = Vector::splat(5.0);
        ground[1] = 0.5;
        world.physics.insert(
            RigidBodyBuilder::fixed().translation(-UP * 0.5),
            ColliderBuilder::new(SharedShape::new(Cuboid::new(ground))),
        );
        world.physics.insert(
            RigidBodyBuilder::dynamic().translation(UP * 1.75),
            ColliderBuilder::new(SharedShape::new(Cuboid::new(Vector::splat(0.2)))).mass(20.0),
        );
        let mesh =
            Mesh::from_shape(&Cuboid::new(Vector::splat(0.25)), 0.1, CellKind::Simplex).unwrap();
        let body = DeformableBuilder::new(mesh)
            .model(model)
            .material(Material {
                density: 1000.0,
                young_modulus: 1e6,
                damping_ratio: 0.1,
                ..Default::default()
            })
            .translation(UP * 1.25)
            .build()
            .unwrap();
        let h = world.insert(body);
        let (mut inverted, mut pressed) = (0, 0);
        for _ in 0..(1.5 / dt) as usize {
            let report = world.step();
            let r = &report.deformables[0].1;
            pressed += r.facet_contacts;
            inverted = inverted.max(world.deformables[h].inverted_elements());
        }
        let name = model.name();
        assert!(
            pressed > 0,
            "{name}: the box's corners never pressed a facet"
        );
        if model == ElementModel::EdgeRepulsion {
            assert_eq!(inverted, 0, "{name}");
        }
        assert_eq!(world.deformables[h].inverted_elements(), 0, "{name}");
        assert!(!world.deformables[h].is_frozen(), "{name}");
    }
}
