//! Tissue hanging from a dynamic rigid bar on a revolute joint: the bar, level without the
//! tissue, swings down on the side where the tissue hangs and oscillates while the tissue
//! pulls on it (two-way binding). One line every half second, 2D and 3D.
//!
//! ```text
//! cargo run --release --example hanging
//! cargo run --release --features rerun --example hanging [-- --rrd DIR | --connect [ADDR]]
//! ```
//!
//! With the `rerun` feature each run is logged to `out/hanging/<dim>.rrd` (attachments shown).

#[path = "common/sink.rs"]
mod sink;

macro_rules! run_dimension {
    ($dim:ident, $label:expr, $joint:expr, $sink:expr, $files:expr) => {{
        use sinew::$dim::math::{Real, Vector, DIM, UP};
        use sinew::$dim::rapier::geometry::{Cuboid, SharedShape};
        use sinew::$dim::rapier::prelude::{ColliderBuilder, RigidBodyBuilder};
        use sinew::$dim::{DeformableBuilder, DeformableWorld, ElementModel, Material};

        let mut world = DeformableWorld::new();
        world.set_dt(1.0 / 120.0);
        let pivot = world.physics.insert_body(RigidBodyBuilder::fixed());
        let mut half = Vector::splat(0.05);
        half[0] = 1.0;
        let (bar, _) = world
            .physics
            .insert(RigidBodyBuilder::dynamic(), ColliderBuilder::new(SharedShape::new(Cuboid::new(half))).density(500.0));
        world.physics.insert_impulse_joint(pivot, bar, $joint);
        let mut at = -UP * 0.45;
        at[0] = 0.7;
        let tissue = DeformableBuilder::cuboid(Vector::splat(0.2), [5; DIM])
            .model(ElementModel::EdgeRepulsion)
            .material(Material { density: 200.0, young_modulus: 5e3, damping_ratio: 0.1, ..Default::default() })
            .translation(at)
            .build()
            .expect("valid tissue");
        let h = world.insert(tissue);
        let top: Vec<u32> = (0..world.deformables[h].num_nodes() as u32)
            .filter(|&i| world.deformables[h].positions()[i as usize].dot(UP) > at.dot(UP) + 0.19)
            .collect();
        world.attach_nodes(h, bar, &top).expect("bar exists");
        println!("{} bar 2 m, {:.1} kg; tissue {:.1} kg bound by {} nodes at x = 0.7 m", $label,
            world.physics.bodies[bar].mass(), world.deformables[h].total_mass(), top.len());
        #[cfg(feature = "rerun")]
        let mut recorder = {
            use sinew::$dim::{RecorderOptions, RerunRecorder};
            let options = RecorderOptions { every_n_steps: 2, ..Default::default() };
            let made = match $sink {
                sink::Sink::Folder(dir) => {
                    let file = dir.join(format!("{}.rrd", $label.to_lowercase()));
                    $files.push(file.clone());
                    RerunRecorder::save("sinew-hanging", &file, options).map(Some)
                }
                sink::Sink::Connect(addr) => RerunRecorder::connect("sinew-hanging", addr.as_deref(), options).map(Some),
                sink::Sink::Off => Ok(None),
            };
            made.unwrap_or_else(|e| {
                eprintln!("not logging: {e}");
                None
            })
        };
        #[cfg(feature = "rerun")]
        if let Some(r) = recorder.as_mut() {
            r.set_name(h, "tissue");
        }
        for k in 1..=480 {
            world.step();
            #[cfg(feature = "rerun")]
            if let Some(r) = recorder.as_mut() {
                if let Err(e) = r.log_world(&world) {
                    eprintln!("logging failed: {e}");
                }
            }
            if k % 60 == 0 {
                let b = &world.physics.bodies[bar];
                let tip = b.position().transform_point(Vector::X);
                let angle = tip.dot(UP).atan2(tip[0]).to_degrees();
                let d = &world.deformables[h];
                let r = world.report().get(h).unwrap();
                println!(
                    "{}  t {:.1} s  bar angle {:+6.1}°  tissue centre height {:+.3} m  inverted {}  substeps {}",
                    $label,
                    world.time(),
                    angle,
                    d.center_of_mass().dot(UP),
                    r.inverted_elements,
                    r.substeps,
                );
            }
        }
        #[cfg(feature = "rerun")]
        if let Some(r) = recorder.as_mut() {
            if let Err(e) = r.flush() {
                eprintln!("logging failed: {e}");
            }
        }
        let _: Real = 0.0;
    }};
}

fn main() {
    let sink = sink::from_args("hanging");
    #[allow(unused_mut)]
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    run_dimension!(
        dim2,
        "2D",
        sinew::dim2::rapier::dynamics::RevoluteJointBuilder::new(),
        &sink,
        files
    );
    run_dimension!(
        dim3,
        "3D",
        sinew::dim3::rapier::dynamics::RevoluteJointBuilder::new(sinew::dim3::math::Vector::Z),
        &sink,
        files
    );
    if cfg!(feature = "rerun") {
        sink::print_how_to_view(&sink, &files);
    } else {
        sink::print_no_feature("hanging", "3d.rrd");
    }
}
