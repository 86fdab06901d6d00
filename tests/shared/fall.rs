//! Fall and bounce, every model (issue 2, acceptance 4).

use crate::dim::math::Real;
use crate::dim::scenes::FallScene;
use crate::dim::ElementModel;

fn check(model: ElementModel) {
    let scene = FallScene {
        model,
        seconds: 5.0,
        ..FallScene::default()
    };
    let o = scene.run().expect("scene builds");
    let name = model.name();
    // Drop energy m g h, for a relative rest bound.
    let drop_energy = scene.mass * 9.81 * scene.drop_height;
    assert!(!o.non_finite, "{name}: state turned non-finite");
    assert!(o.first_impact.is_some(), "{name}: never hit the ground");
    assert!(
        o.bounced,
        "{name}: did not leave the ground after the first impact: {o:?}"
    );
    let apex = o.bounce_apex_com.unwrap_or(0.0);
    assert!(
        apex > 0.5 * scene.size + 0.05,
        "{name}: bounce apex {apex} barely above rest"
    );
    assert!(
        apex < scene.drop_height + 0.5 * scene.size,
        "{name}: bounced higher than dropped ({apex})"
    );
    assert!(
        o.final_kinetic_energy < 1e-2 * drop_energy,
        "{name}: still moving at 5 s: {} J of {} J",
        o.final_kinetic_energy,
        drop_energy
    );
    assert!(
        (o.rest_com - 0.5 * scene.size).abs() < 0.1 * scene.size,
        "{name}: rests at {}",
        o.rest_com
    );
    assert!(
        o.max_penetration <= 0.01 * scene.size,
        "{name}: a node went {} m into the ground",
        o.max_penetration
    );
    if matches!(
        model,
        ElementModel::EdgeRepulsion | ElementModel::ShapeMatching { .. }
    ) {
        assert_eq!(o.max_inverted_elements, 0, "{name}: inverted an element");
    }
    let _: Real = o.min_volume_ratio;
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
