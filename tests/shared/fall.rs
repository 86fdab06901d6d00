//! Fall and bounce, every model (issue 2, acceptance 4).

use crate::dim::ElementModel;
use crate::scenes::FallScene;

fn check(model: ElementModel) {
    // 8 s: a bounce can tip a body over (the 2D shape-matching square tumbles at its second
    // bounce and rocks on its corners until about 7.5 s); at the end it must lie still.
    let scene = FallScene {
        subject: model.into(),
        seconds: 8.0,
        ..FallScene::default()
    };
    let o = scene.run().expect("scene builds");
    let name = model.name();
    // Drop energy m g h, for a relative rest bound.
    let drop_energy = (scene.mass * 9.81 * scene.drop_height) as f64;
    assert!(!o.nan && !o.exploded, "{name}: state blew up: {o:?}");
    let apex = o
        .bounce_apex_com
        .unwrap_or_else(|| panic!("{name}: never rose after the first impact: {o:?}"));
    let size = scene.size as f64;
    assert!(
        apex > 0.5 * size + 0.05,
        "{name}: bounce apex {apex} barely above rest"
    );
    assert!(
        apex < (scene.drop_height + 0.5 * scene.size) as f64,
        "{name}: bounced higher than dropped ({apex})"
    );
    assert!(
        o.final_kinetic_energy < 1e-2 * drop_energy,
        "{name}: still moving at 8 s: {} J of {} J",
        o.final_kinetic_energy,
        drop_energy
    );
    let rest = o.rest_com.expect("the fall measures the rest height");
    assert!(
        (rest - 0.5 * size).abs() < 0.1 * size,
        "{name}: rests at {rest}"
    );
    let pen = o.max_penetration.expect("the fall measures penetration");
    assert!(
        pen <= 0.01 * size,
        "{name}: a node went {pen} m into the ground"
    );
    if matches!(
        model,
        ElementModel::EdgeRepulsion | ElementModel::ShapeMatching { .. }
    ) {
        assert_eq!(o.max_inverted_elements, 0, "{name}: inverted an element");
    }
}

#[test]
fn springs_fall_and_bounce() {
    check(ElementModel::Springs);
}

#[test]
fn centroid_springs_fall_and_bounce() {
    check(ElementModel::CentroidSprings);
}

#[test]
fn nonlinear_springs_fall_and_bounce() {
    check(ElementModel::NonlinearSprings);
}

#[test]
fn edge_repulsion_falls_and_bounces() {
    check(ElementModel::EdgeRepulsion);
}

#[test]
fn shape_matching_falls_and_bounces() {
    check(ElementModel::SHAPE_MATCHING);
}

/// The trajectory the fall's error is measured on is sampled at the same times whatever dt
/// is: a step longer than the sampling interval yields every sample it spans, each where the
/// free fall puts it.
#[test]
fn the_sampled_trajectory_is_on_time_at_any_dt() {
    for every in [0.0, -0.01, f64::NAN as crate::dim::math::Real] {
        assert!(
            FallScene::default().run_sampled(every).is_err(),
            "sampling every {every} s is refused"
        );
    }
    for dt in [1.0 / 600.0, 1.0 / 60.0, 1.0 / 30.0] {
        let scene = FallScene {
            subject: ElementModel::Springs.into(),
            resolution: 3,
            dt,
            // Contact comes at 0.64 s: the first 0.5 s are a free fall.
            seconds: 0.5,
            ..FallScene::default()
        };
        let (_, samples) = scene.run_sampled(0.01).expect("scene builds");
        assert_eq!(samples.len(), 50, "dt {dt}: {} samples", samples.len());
        let start = scene.drop_height + 0.5 * scene.size;
        for (k, c) in samples.iter().enumerate() {
            let t = 0.01 * (k + 1) as crate::dim::math::Real;
            let height = c.dot(crate::dim::math::UP);
            let theory = start - 0.5 * 9.81 * t * t;
            // Symplectic Euler is ahead of the parabola by g t dt / 2 (8 cm at 0.5 s, 1/30 s);
            // a sample one interval late would be g t · 0.01 off (5 cm at 0.5 s).
            let bound = 0.5 * 9.81 * t * dt + 0.01;
            assert!(
                (height - theory).abs() < bound,
                "dt {dt}: sample {k} at {height} m, free fall {theory} m"
            );
        }
    }
}
