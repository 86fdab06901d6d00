//! The stability suite's scenes with the outcomes issue 5 asks of them (the limb's are in
//! `bones.rs`).

use crate::dim::{ElementModel, Integrator};
use crate::scenes::{CrushScene, FallScene, ManipulatorScene};

#[test]
fn edge_repulsion_survives_a_1000_kg_crush_and_recovers() {
    let scene = CrushScene {
        cube: FallScene {
            subject: ElementModel::EdgeRepulsion.into(),
            ..FallScene::default()
        },
        mass: 1000.0,
        ..CrushScene::default()
    };
    let r = scene.run().expect("scene builds");
    assert_eq!(r.max_inverted_elements, 0, "an element inverted: {r:?}");
    assert!(!r.nan && !r.exploded, "blew up: {r:?}");
    assert!(!r.failed, "failed ({:?}): {r:?}", r.failure);
    let shape = r.shape_error.expect("crush measures the shape error");
    assert!(shape < 0.05, "did not recover: shape error {shape}");
    // It was crushed, not merely touched: some cell lost more than half its volume.
    assert!(r.min_vol_ratio < 0.5, "barely loaded: {r:?}");
}

#[test]
fn springs_are_crushed_flat_by_1000_kg() {
    let scene = CrushScene {
        cube: FallScene {
            subject: ElementModel::Springs.into(),
            ..FallScene::default()
        },
        mass: 1000.0,
        ..CrushScene::default()
    };
    let r = scene.run().expect("scene builds");
    assert!(
        r.failed && r.max_inverted_elements > 0,
        "springs held: {r:?}"
    );
}

#[test]
fn a_body_sinew_freezes_for_blowing_up_is_recorded_as_exploded() {
    // One substep of 1/60 s is far past the springs' stability bound: sinew's own check (a
    // cell past `max_stretch`) rolls the cube back and freezes it while every node is still
    // near and slow, so the record must take the flag from sinew's report.
    let scene = FallScene {
        subject: ElementModel::Springs.into(),
        dt: 1.0 / 60.0,
        fixed_substeps: Some(1),
        ..FallScene::default()
    };
    let r = scene.run().expect("scene builds");
    assert!(r.exploded && r.failed, "not recorded as a blow-up: {r:?}");
}

#[test]
fn a_cube_struck_deep_by_a_paddle_survives_with_calibrated_substeps() {
    // Six strikes 40 % deep into the 1 kg cube at E = 3·10⁴ Pa (1 ms steps, the explicit
    // default). While the paddle presses, the boundary nodes' accelerations are ~10⁵ m/s²: at
    // the calibrated substep their contacts could not hold them (shape matching inverted a cell
    // and threw a node at 150 m/s), so a pressed body takes the uncalibrated substep.
    for model in [ElementModel::EdgeRepulsion, ElementModel::SHAPE_MATCHING] {
        let scene = ManipulatorScene {
            cube: FallScene {
                subject: model.into(),
                young_modulus: 3.0e4,
                ..FallScene::default()
            },
            strikes: 6,
            ..ManipulatorScene::default()
        };
        let r = scene.run().expect("scene builds");
        assert!(!r.failed, "{model:?} failed ({:?}): {r:?}", r.failure);
        assert!(!r.nan && !r.exploded, "{model:?} blew up: {r:?}");
        // Struck, not grazed: some cell lost over a third of its volume.
        assert!(r.min_vol_ratio < 0.65, "{model:?} barely struck: {r:?}");
    }
}

#[test]
fn the_dent_scene_leaves_a_dent_where_the_steel_box_lay() {
    // The box rests on the plate, is taken away, and the plate keeps a dent: deeper than a
    // millimetre, shallower than the plate, with no cell inverted; rapier's peer runs too.
    use crate::scenes::{DentScene, RapierModel};
    let d = DentScene::default();
    let run = |subject| {
        DentScene {
            cube: FallScene { subject, ..d.cube },
            ..d
        }
        .run()
        .expect("scene builds")
    };
    let r = run(ElementModel::EdgeRepulsion.into());
    assert!(!r.failed, "failed ({:?}): {r:?}", r.failure);
    let dent = r.dent.unwrap();
    assert!(
        dent > 1e-3 && dent < 0.5 * d.thickness as f64,
        "dent {dent}"
    );
    let rapier = run(RapierModel::Corotational.into());
    assert!(!rapier.exploded && !rapier.nan, "{rapier:?}");
}

#[test]
fn the_bend_scene_keeps_the_bend_of_a_plastic_beam() {
    // sinew's bar keeps an elastic–perfectly-plastic beam's bend within 15 %; rapier's peer
    // (its own plastic yield) runs the same scene without blowing up.
    use crate::scenes::{BendScene, RapierModel};
    let d = BendScene::default();
    let run = |subject, integrator| {
        BendScene {
            cube: FallScene {
                subject,
                integrator,
                ..d.cube
            },
            ..d
        }
        .run()
        .expect("scene builds")
    };
    let r = run(
        ElementModel::EdgeRepulsion.into(),
        Integrator::Implicit { iterations: 2 },
    );
    assert!(!r.failed, "failed ({:?}): {r:?}", r.failure);
    let (kept, beam) = (r.kept_bend.unwrap(), r.kept_bend_theory.unwrap());
    assert!((kept / beam - 1.0).abs() < 0.15, "kept {kept}, beam {beam}");
    assert!(beam > 0.9 && beam < 1.1, "{beam}");
    let rapier = run(RapierModel::Corotational.into(), d.cube.integrator);
    assert!(!rapier.exploded && !rapier.nan, "{rapier:?}");
}

#[test]
fn the_tear_scene_pulls_a_slab_apart_at_its_tear_strain() {
    // sinew's slab and rapier's peer (its own `tear_strain`) in the same scene: each tears
    // within 10 % of the tear strain into two pieces that come to rest.
    use crate::scenes::{RapierModel, TearScene};
    let d = TearScene::default();
    for subject in [
        ElementModel::EdgeRepulsion.into(),
        ElementModel::SHAPE_MATCHING.into(),
        RapierModel::Corotational.into(),
    ] {
        let r = TearScene {
            cube: FallScene { subject, ..d.cube },
            ..d
        }
        .run()
        .expect("scene builds");
        assert!(!r.failed, "failed ({:?}): {r:?}", r.failure);
        let strain = r.torn_at_strain.unwrap();
        assert!((strain - 0.1).abs() <= 0.01, "{strain}: {r:?}");
        assert_eq!(r.pieces, Some(2), "{r:?}");
    }
}

#[test]
fn the_balloon_scene_squeezes_a_gas_filled_ball_that_springs_back() {
    // sinew's ball holds its gas; rapier's peer, a volume target on its material, runs the
    // same scene and measures its cavity the same way.
    use crate::scenes::{BalloonScene, RapierModel};
    let d = BalloonScene::default();
    let run = |subject| {
        BalloonScene {
            cube: FallScene { subject, ..d.cube },
            recover: 1.0,
            ..d
        }
        .run()
        .expect("scene builds")
    };
    let r = run(ElementModel::EdgeRepulsion.into());
    assert!(!r.failed, "failed ({:?}): {r:?}", r.failure);
    assert!(r.inflation.unwrap() > 1.05, "{r:?}");
    assert!(r.gas_volume_ratio.unwrap() <= 0.7, "{r:?}");
    assert!(r.recovery_error.unwrap() < 0.01, "{r:?}");
    assert!(r.boyle_error.unwrap() < 1e-3, "{r:?}");
    let rapier = run(RapierModel::Corotational.into());
    assert!(rapier.boyle_error.is_none(), "rapier has no gas");
    assert!(rapier.gas_volume_ratio.unwrap() < 0.72, "{rapier:?}");
    assert!(!rapier.exploded, "{rapier:?}");
}
