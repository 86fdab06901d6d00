//! The `vibration` scene: a free bar rings in its first axial mode; its frequency against
//! beam theory and its decay against the damping ratio asked for (issue 17).

use super::super::lib::math::{Real, Vector, DIM};
use super::super::lib::mesh::{CellKind, Mesh};
use super::super::lib::model::ElementModel;
use super::super::lib::BuildError;
use super::super::lib::DeformableWorld;
use super::super::lib::Integrator;
use super::super::lib::Material;
use super::sim::{BodySpec, Sim};
use super::subject::Subject;
use super::Record;
use crate::reference;

/// A free bar `length` long and `length / 10` across, no gravity, nothing to touch, set
/// ringing by an axial velocity field `v_x = rate · x` (x from the bar's middle: a uniform
/// stretching, which is mostly the first axial mode).
///
/// **Measures** the bar's length `L(t)` (the mean x of its end faces' nodes, one end minus the
/// other) after every step:
/// - `measured_frequency`: from the zero crossings of `L − L₀` (half a period apart), against
///   `theory_frequency` = [`reference::free_bar_axial_frequency`]`(1, L, E, ρ)/2π = √(E/ρ) / 2L`
///   (a slender bar, so the lateral inertia's correction is below 0.1 %);
/// - `measured_damping_ratio`: from the logarithmic decrement of the successive extremes of
///   `L − L₀` ([`reference::damping_ratio`]), against the material's damping ratio.
///
/// A run fails when it explodes or inverts a cell, or rings for fewer than two periods.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct VibrationScene {
    /// What is simulated.
    pub subject: Subject,
    /// Nodes across the bar (the cells are cubes: `10·(n − 1) + 1` nodes along it).
    pub resolution: usize,
    /// Length, m.
    pub length: Real,
    /// Young's modulus, Pa.
    pub young_modulus: Real,
    /// Poisson's ratio.
    pub poisson_ratio: Real,
    /// Density, kg/m³ (kg/m² in 2D).
    pub density: Real,
    /// Damping ratio asked for.
    pub damping_ratio: Real,
    /// Initial stretching rate, 1/s (the ends move apart at `rate · L`).
    pub rate: Real,
    /// Periods of the first mode simulated.
    pub periods: Real,
    /// Step length, s.
    pub dt: Real,
    /// sinew's integrator.
    pub integrator: Integrator,
}

impl Default for VibrationScene {
    /// 1 m × 0.1 m, E = 10⁴ Pa, ν = 0.3, 1000 kg/m³ (first axial mode at 1.58 Hz), damping
    /// ratio 0.05, 2 % of the length per second (an amplitude of about 0.2 %), 6 periods, 3
    /// nodes across, dt 1 ms, edge repulsion.
    fn default() -> Self {
        VibrationScene {
            subject: Subject::Sinew(ElementModel::EdgeRepulsion),
            resolution: 3,
            length: 1.0,
            young_modulus: 1.0e4,
            poisson_ratio: 0.3,
            density: 1000.0,
            damping_ratio: 0.05,
            rate: 0.02,
            periods: 6.0,
            dt: 1.0e-3,
            integrator: Integrator::Explicit,
        }
    }
}

impl VibrationScene {
    /// The first axial frequency of beam theory, Hz.
    pub fn theory_frequency(&self) -> f64 {
        reference::free_bar_axial_frequency(
            1,
            self.length as f64,
            self.young_modulus as f64,
            self.density as f64,
        ) / (2.0 * std::f64::consts::PI)
    }

    /// Runs the scene.
    pub fn run(&self) -> Result<Record, BuildError> {
        let mut world = DeformableWorld::new();
        world.set_dt(self.dt);
        world.pipeline.settings.integrator = self.integrator;
        world.physics.gravity = Vector::ZERO;
        world.pipeline.settings.time_until_sleep = Real::INFINITY;
        let across = self.resolution.max(2);
        let mut half = Vector::splat(0.05 * self.length);
        half[0] = 0.5 * self.length;
        let mut res = [across; DIM];
        res[0] = 10 * (across - 1) + 1;
        let mesh = Mesh::cuboid(half, res, CellKind::Simplex)?;
        let material = Material {
            density: self.density,
            young_modulus: self.young_modulus,
            damping_ratio: self.damping_ratio,
            poisson_ratio: self.poisson_ratio,
        };
        let ends: [Vec<usize>; 2] = [-1.0, 1.0].map(|side: Real| {
            (0..mesh.nodes().len())
                .filter(|&i| (mesh.nodes()[i][0] - side * half[0]).abs() < 1e-4 * self.length)
                .collect()
        });
        let spec = BodySpec::new(mesh, Vector::ZERO, material);
        let mut sim = Sim::new(world, self.subject, spec, self.length, None)?;
        let velocities: Vec<Vector> = sim
            .positions()
            .iter()
            .map(|p| Vector::X * (self.rate * p[0]))
            .collect();
        sim.set_velocities(&velocities)?;
        let length = |sim: &Sim| {
            let mean = |nodes: &[usize]| {
                nodes.iter().map(|&i| sim.positions()[i][0]).sum::<Real>() / nodes.len() as Real
            };
            (mean(&ends[1]) - mean(&ends[0])) as f64
        };
        let rest = length(&sim);
        let seconds = self.periods as f64 / self.theory_frequency();
        let steps = (seconds / self.dt as f64).round().max(1.0) as usize;
        let mut trace = Vec::with_capacity(steps);
        for k in 0..steps {
            sim.step();
            if sim.exploded() {
                break;
            }
            trace.push(((k + 1) as f64 * self.dt as f64, length(&sim) - rest));
        }
        let mut r = sim.record("vibration", self.resolution);
        let ring = Ring::of(&trace);
        r.theory_frequency = Some(self.theory_frequency());
        r.measured_frequency = ring.frequency;
        r.measured_damping_ratio = ring.damping_ratio;
        r.failure = crate::record::failure(&[
            (r.nan, "non-finite state"),
            (r.exploded, "exploded"),
            (r.max_inverted_elements > 0, "inverted cells"),
            (ring.frequency.is_none(), "rang for under two periods"),
        ]);
        r.failed = r.failure.is_some();
        Ok(r)
    }
}

/// The frequency and decay of a ringing signal.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Ring {
    /// From the zero crossings over a whole number of periods, Hz (`None` under four
    /// crossings).
    pub frequency: Option<f64>,
    /// From the logarithmic decrement of the extremes between crossings (`None` under three
    /// extremes, or when they do not decay monotonically in magnitude and grow instead).
    pub damping_ratio: Option<f64>,
}

impl Ring {
    /// Of `trace`, `(t, signal)` pairs about zero, in time order.
    pub fn of(trace: &[(f64, f64)]) -> Ring {
        // Zero crossings, interpolated linearly, and the largest |signal| between two.
        let mut crossings = Vec::new();
        let mut extremes = Vec::new();
        let mut peak: f64 = 0.0;
        for w in trace.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            peak = peak.max(a.abs());
            if a != 0.0 && (a < 0.0) != (b < 0.0) {
                crossings.push(t0 + (t1 - t0) * a / (a - b));
                if crossings.len() > 1 {
                    extremes.push(peak);
                }
                peak = 0.0;
            }
        }
        // An even number of half-periods: about an offset, the half-periods alternate long
        // and short, and an odd count would keep one more of one kind.
        let frequency = (crossings.len() >= 4).then(|| {
            let n = 2 * ((crossings.len() - 1) / 2);
            n as f64 / (2.0 * (crossings[n] - crossings[0]))
        });
        // Successive extremes are half a period apart: the decrement per period is twice
        // the mean log ratio between neighbours.
        let damping_ratio = (extremes.len() >= 3).then(|| {
            let n = extremes.len() - 1;
            let per_half = (extremes[0] / extremes[n]).ln() / n as f64;
            reference::damping_ratio(2.0 * per_half)
        });
        Ring {
            frequency,
            damping_ratio: damping_ratio.filter(|z| z.is_finite()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damped_cosine_gives_back_its_frequency_and_damping_ratio() {
        let (f, zeta) = (2.0_f64, 0.05_f64);
        let w = 2.0 * std::f64::consts::PI * f;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let trace: Vec<(f64, f64)> = (1..=4000)
            .map(|k| {
                let t = k as f64 * 1e-3;
                (t, (-zeta * w * t).exp() * (wd * t).sin())
            })
            .collect();
        let ring = Ring::of(&trace);
        let measured = ring.frequency.unwrap();
        assert!((measured / (wd / (2.0 * std::f64::consts::PI)) - 1.0).abs() < 1e-3);
        let z = ring.damping_ratio.unwrap();
        assert!((z / zeta - 1.0).abs() < 0.02, "{z}");
    }

    #[test]
    fn an_offset_ring_over_an_odd_count_of_half_periods_keeps_its_frequency() {
        // 5 % off centre, 3.75 periods: 8 crossings, 7 half-periods alternating long and
        // short. Counting all seven would be 0.6 % off; a whole number of periods is exact.
        let f = 2.0_f64;
        let w = 2.0 * std::f64::consts::PI * f;
        let trace: Vec<(f64, f64)> = (1..=1875)
            .map(|k| {
                let t = k as f64 * 1e-3;
                (t, (w * t).cos() + 0.05)
            })
            .collect();
        let measured = Ring::of(&trace).frequency.unwrap();
        assert!((measured / f - 1.0).abs() < 1e-3, "{measured}");
    }

    #[test]
    fn a_signal_that_never_turns_has_no_frequency() {
        let trace: Vec<(f64, f64)> = (0..100).map(|k| (k as f64, 1.0 + k as f64)).collect();
        assert_eq!(
            Ring::of(&trace),
            Ring {
                frequency: None,
                damping_ratio: None
            }
        );
    }
}
