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
    assert!(
        one_fine < 0.1 * one,
        "dt/10 barely helped: {one_fine} vs {one}"
    );
    // From 2 iterations on, the fit is at the float-noise floor that the exact polar fit
    // shares: what is left is f32 rounding of k (R X + c − x). Rows at the floor are ordered
    // by noise, so they are compared as a band.
    let floor = [two, three, polar];
    let (lo, hi) = floor.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    assert!(
        hi < 2.0 * lo,
        "2, 3 iterations and polar not one floor: {floor:?}"
    );
    assert!(
        polar < 0.01 * one,
        "polar not at the noise floor: {polar} vs {one}"
    );
}
