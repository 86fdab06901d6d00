//! The robot example's scene: a gripper read from its URDF file, soft pads stuffed from its pad
//! links, lifting a box.

use sinew_scenes::dim3::gripper::GripperScene;

/// A shorter timeline and coarser pads than the example's, for a test's budget.
fn quick() -> GripperScene {
    GripperScene {
        cell: 0.025,
        timeline: [0.1, 0.4, 0.6, 0.4],
        ..GripperScene::default()
    }
}

#[test]
fn a_gripper_from_its_urdf_lifts_a_box_on_soft_pads() {
    let scene = quick();
    let r = scene.run_with(|_, _| {}).unwrap();
    assert_eq!(r.pads.len(), 2);
    for pad in &r.pads {
        assert!(
            pad.nodes > 20 && pad.bound > 0 && pad.bound < pad.nodes,
            "{pad:?}"
        );
    }
    assert!(
        (r.lifted - scene.lift).abs() < 5e-3,
        "the box ends {} m up, lifted {}",
        r.lifted,
        scene.lift
    );
    assert!(r.slip < 5e-3, "slip {} m", r.slip);
    assert!(
        r.lowest > -2e-3,
        "the box went {} m into the table",
        -r.lowest
    );
}

#[test]
fn without_squeezing_the_pads_do_not_hold_the_box() {
    // The fingers stop at the box's faces: nothing presses the pads on it, so the lift must not
    // carry it (the grip above comes from the pads' squeeze, not from a binding or a stray
    // contact).
    let scene = GripperScene {
        close: 0.005,
        ..quick()
    };
    let r = scene.run_with(|_, _| {}).unwrap();
    assert!(r.lifted < 0.01, "the box rose {} m", r.lifted);
}

#[test]
fn a_robot_the_scene_cannot_drive_is_an_error_naming_what() {
    let dir = std::env::temp_dir().join(format!("sinew-gripper-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let original = std::fs::read_to_string(GripperScene::default().urdf).unwrap();
    // The left pad link without its collision shape (and its inertia).
    let bare_pad = {
        let start = original.find("<link name=\"left_pad\">").unwrap();
        let end = start + original[start..].find("</link>").unwrap();
        format!(
            "{}<link name=\"left_pad\">{}",
            &original[..start],
            &original[end..]
        )
    };
    let cases: [(&str, String, &str); 5] = [
        (
            "no-pad.urdf",
            original.replace("right_pad", "right_tip"),
            "right_pad",
        ),
        ("bare-pad.urdf", bare_pad, "left_pad"),
        (
            "turned.urdf",
            original.replacen("rpy=\"0 0 0\"", "rpy=\"0 0 0.3\"", 1),
            "lift",
        ),
        (
            "revolute.urdf",
            original.replacen("type=\"prismatic\"", "type=\"revolute\"", 1),
            "lift",
        ),
        (
            "broken.urdf",
            original[..original.len() / 2].to_string(),
            "broken.urdf",
        ),
    ];
    for (file, text, named) in cases {
        let path = dir.join(file);
        std::fs::write(&path, text).unwrap();
        let scene = GripperScene {
            urdf: path,
            ..quick()
        };
        let err = scene
            .build()
            .err()
            .unwrap_or_else(|| panic!("{file} built"));
        assert!(err.contains(named), "{file}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
