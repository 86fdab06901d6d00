//! `Integrator::Auto`: the explicit step for a body it takes in a few substeps, the midpoint
//! step for one that would need many.

use crate::dim::math::{Vector, DIM, UP};
use crate::dim::{DeformableBuilder, DeformableWorld, ElementModel, Integrator, Material};
use crate::scenes::{BallScene, FallScene, Subject};

const AUTO: Integrator = Integrator::Auto { iterations: 2 };

#[test]
fn auto_steps_a_soft_cube_at_1_ms_exactly_as_the_explicit_step_does() {
    // The `fall` cube (E = 10⁴ Pa) at 1 ms takes 1–3 substeps a step: Auto keeps it explicit.
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let run = |integrator| {
            FallScene {
                subject: Subject::Sinew(model),
                seconds: 1.5,
                integrator,
                ..Default::default()
            }
            .run()
            .unwrap()
        };
        let (explicit, auto) = (run(Integrator::Explicit), run(AUTO));
        let name = model.name();
        assert!(
            auto.substeps > 1.0,
            "{name}: {} substeps a step",
            auto.substeps
        );
        assert_eq!(auto.substeps, explicit.substeps, "{name}");
        assert_eq!(auto.bounce_apex_com, explicit.bounce_apex_com, "{name}");
        assert_eq!(auto.rest_com, explicit.rest_com, "{name}");
    }
}

#[test]
fn auto_steps_a_stiff_ball_at_60_hz_implicitly_and_it_bounces_as_the_explicit_step_does() {
    // The 10 cm silicone ball (E = 10⁶ Pa, 2 cm cells) dropped from 0.5 m at 60 Hz: the
    // explicit step takes ~95 substeps a step. Auto takes the midpoint step, its impacts in
    // explicit substeps: the ball bounces as high as under the explicit step (the flight
    // after an impact carries on what its substeps left, without storing their ringing), and
    // comes to rest upright (under the explicit step too it still bounces after 4 s).
    let explicit = BallScene {
        integrator: Integrator::Explicit,
        seconds: 1.0,
        ..Default::default()
    }
    .run()
    .unwrap();
    let scene = BallScene {
        integrator: AUTO,
        seconds: 8.0,
        ..Default::default()
    };
    let r = scene.run().unwrap();
    assert!(!r.failed, "{:?}", r.failure);
    assert_eq!(r.max_inverted_elements, 0);
    assert!(r.substeps < 40.0, "{} substeps a step", r.substeps);
    let radius = scene.radius as f64;
    let (apex, reference) = (
        r.bounce_apex_com.unwrap(),
        explicit.bounce_apex_com.unwrap(),
    );
    assert!(
        (apex - reference).abs() < 0.02 * (reference - radius),
        "bounced to {apex} m (explicit: {reference} m)"
    );
    let rest = r.rest_com.unwrap();
    assert!(
        (rest - radius).abs() < 0.01 * radius.max(1.0),
        "rests at {rest} m"
    );
}
#[test]
fn the_report_says_which_step_auto_took() {
    // A stiff 20 cm cube (E = 10⁷ Pa) at 60 Hz would take dozens of substeps: implicit. A
    // soft one (E = 10³ Pa) at 1 ms takes one or two: explicit. Both in free fall.
    let run = |young: f32, dt: f32| {
        let mut world = DeformableWorld::new();
        world.set_dt(dt);
        world.pipeline.settings.integrator = AUTO;
        let body = DeformableBuilder::cuboid(Vector::splat(0.1), [5; DIM])
            .material(Material {
                young_modulus: young,
                ..Default::default()
            })
            .translation(UP * 10.0)
            .build()
            .unwrap();
        let h = world.insert(body);
        world.step();
        let r = world.report().get(h).unwrap().clone();
        (r.implicit, r.substeps)
    };
    let (stiff, stiff_substeps) = run(1e7, 1.0 / 60.0);
    assert!(
        stiff,
        "the stiff cube at 60 Hz stepped explicitly ({stiff_substeps} substeps)"
    );
    assert_eq!(stiff_substeps, 1);
    let (soft, soft_substeps) = run(1e3, 1e-3);
    assert!(!soft, "the soft cube at 1 ms stepped implicitly");
    assert!(soft_substeps >= 1);
}

#[test]
fn the_default_integrator_is_auto_and_a_new_world_runs_it() {
    // A new user's world and the ball scene take it: the stiff ball at 60 Hz then takes few
    // substeps a step (the explicit step: ~95) and turns no cell inside out.
    assert_eq!(Integrator::default(), AUTO);
    assert_eq!(DeformableWorld::new().pipeline.settings.integrator, AUTO);
    let ball = BallScene::default();
    assert_eq!(ball.integrator, AUTO);
    let r = BallScene {
        seconds: 1.0,
        ..ball
    }
    .run()
    .unwrap();
    assert!(r.substeps < 40.0, "{} substeps a step", r.substeps);
    assert_eq!(r.max_inverted_elements, 0);
}
