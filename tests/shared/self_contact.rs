//! Self contact (issue 14, acceptance 3): a sausage folded double and the limb's crease keep
//! their surfaces out of themselves when self contact is on, and pass into themselves when it
//! is off (so the measure can fail).
//!
//! Edge repulsion holds everywhere. The other models turn cells inside out in the crushed
//! inner side of the fold (shape matching up to 8 in the sausage and 54 in the 3D limb; the
//! springs up to 261), and an inverted cell carries the surface through itself where no
//! contact can stop it: for them the test holds only where no cell inverted.

use crate::dim::ElementModel;
use crate::scenes::{FoldScene, LimbScene, Subject};

#[test]
fn a_folded_sausage_stays_out_of_itself_with_self_contact() {
    let cell = FoldScene::default().spacing as f64;
    for model in ElementModel::ALL {
        let name = model.name();
        let run = |self_contact| {
            FoldScene {
                subject: Subject::Sinew(model),
                self_contact,
                ..Default::default()
            }
            .run()
            .unwrap()
        };
        let on = run(true);
        let depth = on.max_self_penetration.unwrap();
        if model == ElementModel::EdgeRepulsion {
            assert!(!on.failed, "{name}: {:?}", on.failure);
            let off = run(false).max_self_penetration.unwrap();
            assert!(
                off > 0.1 * cell,
                "{name}: without self contact only {off} m"
            );
        }
        if on.max_inverted_elements == 0 {
            assert!(depth < 0.01 * cell, "{name}: {depth} m inside itself");
        }
    }
}

#[test]
fn the_limbs_crease_stays_out_of_itself_with_self_contact() {
    let cell = LimbScene::default().spacing as f64;
    let run = |self_contact| {
        LimbScene {
            self_contact,
            ..Default::default()
        }
        .run()
        .unwrap()
    };
    let (on, off) = (run(true), run(false));
    let (d_on, d_off) = (
        on.max_self_penetration.unwrap(),
        off.max_self_penetration.unwrap(),
    );
    assert!(!on.failed, "{:?}", on.failure);
    assert!(d_on < 0.01 * cell, "{d_on} m inside itself");
    assert!(d_off > 0.1 * cell, "without self contact only {d_off} m");
    // The bound nodes stay on their bones.
    assert!(on.max_anchor_error.unwrap() < 1e-4);
}
