//! Phase 4 of a body's step: a body that blew up is rolled back and frozen.

use super::super::body::Deformable;
use super::super::math::{Real, Vector, DIM};
use super::super::model::volume::Ratios;
use super::super::rapier::dynamics::RigidBodySet;
use super::super::threads;
use super::{RigidHold, StepContext, Touch};

/// Checks the state after the substeps: non-finite, so far out that it can only be a blow-up
/// (|x| or |v| above 1e8), or a cell stretched past `max_stretch` in every direction. Such a
/// body is rolled back to the start of the step and frozen, and the dynamic bodies it pushed
/// get their state back; the report says which.
///
/// Returns the cell qualities of the state the body ends the step in, when it was sane (one
/// pass over the cells serves the stretch test and the report), or `None` after a rollback.
pub(super) fn contain(
    body: &mut Deformable,
    ctx: &StepContext<'_>,
    bodies: &mut RigidBodySet,
    (rigid, touch): (&RigidHold, &mut Touch),
) -> Option<Quality> {
    let sane = |v: &Vector| v.is_finite() && v.abs().max_element() < 1e8;
    let finite = body.state.positions.iter().all(sane) && body.state.velocities.iter().all(sane);
    let most = ctx.settings.max_stretch.powi(DIM as i32);
    let quality = finite.then(|| Quality::of(body, most));
    let exploded = quality.is_some_and(|q| q.stretched);
    body.last.report.non_finite = !finite;
    body.last.report.exploded = exploded;
    if !finite || exploded {
        body.step.restore(&mut body.state);
        body.activation.frozen = true;
        // A blow-up must not launch the bodies it pushed; restored, they took no impulse of
        // this body's and get no compensation for one.
        rigid.backup.restore(bodies);
        touch.pushed.clear();
    }
    quality.filter(|_| !exploded)
}

/// The cells' quality (signed volume over rest volume) over a body, and its elastic energy
/// (measured in the same pass over the cells when the model has a volumetric term).
#[derive(Copy, Clone, Debug)]
pub(super) struct Quality {
    /// Cells collapsed or inverted (quality ≤ 0).
    pub inverted: usize,
    /// The smallest quality.
    pub min_ratio: Real,
    /// Whether a cell's quality is above the stretch limit it was measured with.
    pub stretched: bool,
    /// The elastic energy.
    pub elastic: Real,
}

impl Quality {
    /// At the body's positions (`most`: the stretch limit, infinite for none).
    pub fn of(body: &mut Deformable, most: Real) -> Quality {
        let limited = most.is_finite();
        let (elastic, ratios) = body.measured_energy();
        let (mesh, x) = (&body.rest.mesh, &body.state.positions);
        let ratios = ratios.unwrap_or_else(|| {
            let part = |cells: std::ops::Range<usize>| {
                let mut r = Ratios::NONE;
                for c in cells {
                    let ratio = mesh.cell_quality(c, x);
                    if ratio <= 0.0 {
                        r.inverted += 1;
                    }
                    r.least = r.least.min(ratio);
                    r.most = r.most.max(ratio);
                }
                r
            };
            threads::chunked_fold(mesh.num_cells(), part, Ratios::and).unwrap_or(Ratios::NONE)
        });
        Quality {
            inverted: ratios.inverted,
            min_ratio: ratios.least,
            stretched: limited && ratios.most > most,
            elastic,
        }
    }
}
