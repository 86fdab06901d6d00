//! Soft pads on two kinematic fingers pinch a dynamic box at 60 Hz, lift it 0.2 m and hold it:
//! the pads, stepped as one island with the box they both push, grip it without slipping, and
//! neither throw it nor press it through the floor.

use crate::dim::ElementModel;
use crate::scenes::{PinchScene, Subject};

#[test]
fn two_soft_pads_lift_a_box_at_60_hz_without_slip() {
    // The previous step stepped each pad on its own: a 1 kg box slipped 54–199 mm, was thrown,
    // or exploded the pads.
    let mut runs = vec![
        (ElementModel::EdgeRepulsion, 1.0),
        (ElementModel::SHAPE_MATCHING, 1.0),
    ];
    if crate::dim::math::DIM == 3 {
        runs.push((ElementModel::SHAPE_MATCHING, 0.1));
    }
    for (model, mass) in runs {
        let scene = PinchScene {
            subject: Subject::Sinew(model),
            mass,
            ..Default::default()
        };
        let r = scene.run().unwrap();
        let name = format!("{} with {mass} kg", model.name());
        assert!(!r.failed, "{name}: {:?}", r.failure);
        let slip = r.slip.unwrap();
        assert!(slip < 0.005, "{name}: slipped {slip} m");
        let over = r.overspeed.unwrap();
        assert!(over < 0.1, "{name}: {over} m/s faster than the fingers");
        let floor = r.max_penetration.unwrap();
        assert!(floor < 0.002, "{name}: {floor} m into the floor");
        // Lifted: the box's centre ends 0.2 m above where it rested.
        let height = r.rest_com.unwrap();
        assert!(
            (height - 0.25).abs() < 0.01,
            "{name}: the box ended at {height} m"
        );
    }
}
