//! A game asset from its own file: the trefoil knot of `assets/torus-knot.obj` (a closed
//! triangle mesh, 3840 vertices, written by `assets/make_torus_knot.py`) is read, stuffed with tetrahedra, drawn by its own smooth
//! surface bound to the cells as a render mesh, carried by a kinematic bone swinging it, then
//! let go onto the ground. 60 Hz, `Integrator::Auto`.
//!
//! ```text
//! cargo run --release --example asset [-- --cell 0.035 --seconds 4]
//! cargo run --release --features rerun --example asset [-- --rrd DIR | --connect [ADDR]]
//! ```
//!
//! It prints the mesh, the cost of a step and the cost of moving the render mesh (its share
//! of the step).

#[path = "common/sink.rs"]
mod sink;

use std::time::Instant;

use sinew::dim3::math::{Real, Vector};
use sinew::dim3::rapier::dynamics::RigidBodyBuilder;
use sinew::dim3::rapier::geometry::{ColliderBuilder, SharedShape};
use sinew::dim3::surface::obj;
use sinew::dim3::{DeformableBuilder, DeformableWorld, Integrator, Material, Mesh};

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/torus-knot.obj");
    let cell: Real = sink::arg("--cell", 0.035);
    let seconds: Real = sink::arg("--seconds", 4.0);
    let surface = obj::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let started = Instant::now();
    let mesh = Mesh::stuffed(&surface.to_trimesh(), cell).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "{}: {} vertices, {} triangles, {:.3} l; stuffed at {cell} m in {:.0} ms: {} nodes, {} cells ({} on the surface), {:.3} l",
        path.display(),
        surface.vertices().len(),
        surface.triangles().len(),
        surface.volume() * 1e3,
        started.elapsed().as_secs_f64() * 1e3,
        mesh.nodes().len(),
        mesh.num_cells(),
        mesh.boundary_nodes().len(),
        mesh.total_volume() * 1e3,
    );

    let dt: Real = 1.0 / 60.0;
    let mut world = DeformableWorld::new();
    world.set_dt(dt);
    world.pipeline.settings.integrator = Integrator::Auto { iterations: 2 };
    world.physics.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y)).friction(0.7),
        None,
    );
    let lift = Vector::Y * 0.9;
    let body = DeformableBuilder::new(mesh)
        .material(Material {
            density: 1100.0,
            young_modulus: 3e5,
            damping_ratio: 0.1,
            ..Default::default()
        })
        .translation(lift)
        .friction(0.7)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    let h = world.insert(body);
    world.deformables[h]
        .set_render_mesh(surface.vertices(), surface.triangles().to_vec())
        .unwrap_or_else(|e| panic!("{e}"));

    // The bone: a kinematic ball at the knot's highest strand, the nodes inside it bound.
    let top = world.deformables[h]
        .positions()
        .iter()
        .copied()
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    let bone = world
        .physics
        .insert_body(RigidBodyBuilder::kinematic_position_based().translation(top));
    let grip = world
        .physics
        .insert_collider(ColliderBuilder::ball(0.06).sensor(true), Some(bone));
    let bound = {
        let physics = &world.physics;
        world.deformables[h]
            .attach_nodes_inside(&physics.bodies, &physics.colliders, grip, 0.0)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    println!("bone: {bound} nodes bound; swings 1.5 s, then lets go");

    let sink = sink::from_args("asset");
    #[cfg(feature = "rerun")]
    let mut recorder = {
        let options = sinew::dim3::RecorderOptions {
            every_n_steps: 1,
            attachments: true,
            ..Default::default()
        };
        sink::recorder_3d(&sink, "sinew-asset", "torus-knot.rrd", options)
    };

    let steps = (seconds / dt).round() as usize;
    let mut step_seconds = Vec::with_capacity(steps);
    for k in 0..steps {
        let t = k as Real * dt;
        if t < 1.5 {
            let to = top + Vector::X * (0.15 * (2.0 * t).sin());
            world.physics.bodies[bone].set_next_kinematic_translation(to);
        } else if !world.deformables[h].attachments().is_empty() {
            world.deformables[h].detach_all();
        }
        let started = Instant::now();
        world.step();
        step_seconds.push(started.elapsed().as_secs_f64());
        #[cfg(feature = "rerun")]
        if let Some(r) = recorder.as_mut() {
            r.set_name(h, "torus_knot");
            if let Err(e) = r.log_world(&world) {
                eprintln!("logging failed: {e}");
            }
        }
    }
    #[cfg(feature = "rerun")]
    if let Some(r) = recorder.as_mut() {
        if let Err(e) = r.flush() {
            eprintln!("logging failed: {e}");
        }
    }

    // The render mesh's update alone, on the final positions, against a step.
    let b = &world.deformables[h];
    let mut render = b.render_mesh().unwrap().clone();
    let repeats = 200;
    let started = Instant::now();
    for _ in 0..repeats {
        render.update(b.positions());
    }
    let update = started.elapsed().as_secs_f64() / repeats as f64;
    let mean = step_seconds.iter().sum::<f64>() / steps as f64;
    let centre = b.positions().iter().copied().sum::<Vector>() / b.positions().len() as Real;
    println!(
        "{steps} steps: {:.2} ms a step on average ({:.2} s per simulated s); moving the render mesh ({} vertices) {:.3} ms, {:.1} % of a step",
        mean * 1e3,
        mean / dt as f64,
        render.vertices().len(),
        update * 1e3,
        100.0 * update / mean
    );
    println!(
        "end: centre at ({:.3}, {:.3}, {:.3}) m, lowest node {:.3} m, asleep {}, smallest volume ratio {:+.3}",
        centre.x,
        centre.y,
        centre.z,
        b.positions().iter().map(|p| p.y).fold(Real::INFINITY, Real::min),
        b.is_sleeping(),
        b.report().min_volume_ratio
    );
    if cfg!(feature = "rerun") {
        let files: Vec<_> = match &sink {
            sink::Sink::Folder(dir) => vec![dir.join("torus-knot.rrd")],
            _ => Vec::new(),
        };
        sink::print_how_to_view(&sink, &files);
    } else {
        sink::print_no_feature("asset", "torus-knot.rrd");
    }
}
