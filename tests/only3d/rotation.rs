//! The shape-based element's rotation error (shape paper §4, Table 1; issue 5, acceptance 4):
//! the spurious angular acceleration falls with more iterations and with a smaller dt, and
//! the polar fit's is at the float-noise floor every fit shares.

use sinew::dim3::scenes::RotationErrorScene;
use sinew::dim3::RotationFit;

#[test]
fn rotation_error_falls_with_iterations_and_smaller_dt() {
    let rows = RotationErrorScene::table_rows(1.0e4);
    let mean = |fit: RotationFit, divisions: f32| {
        let row = rows
            .iter()
            .find(|r| r.fit == fit && r.divisions == divisions)
            .expect("row in the table");
        let r = row.run().expect("scene builds");
        assert!(!r.exploded, "{fit:?}: blew up");
        r.spurious.expect("measured").mean
    };
    let one = mean(RotationFit::Iterative(1), 10.0);
    let two = mean(RotationFit::Iterative(2), 10.0);
    let three = mean(RotationFit::Iterative(3), 10.0);
    let polar = mean(RotationFit::Polar, 10.0);
    let one_fine = mean(RotationFit::Iterative(1), 100.0);
    assert!(
        one > 10.0 * two,
        "2 iterations barely beat 1: {one} vs {two}"
    );
    assert!(three <= two, "3 iterations worse than 2: {three} vs {two}");
    assert!(
        one_fine < 0.1 * one,
        "dt/10 barely helped: {one_fine} vs {one}"
    );
    // The polar fit is exact: what is left is f32 rounding of k (R X + c − x), the floor
    // under every row.
    assert!(
        polar <= three * 1.05,
        "polar above 3 iterations: {polar} vs {three}"
    );
    assert!(
        polar < 0.01 * one,
        "polar not at the noise floor: {polar} vs {one}"
    );
}
