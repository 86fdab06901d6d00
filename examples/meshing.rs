//! Three ways to fill a shape with tetrahedra, side by side at one cell size: sinew's
//! isosurface stuffing (`Mesh::stuffed`), parry's lattice cover (`transformation::volume_mesh`,
//! raw and shrink-wrapped, what rapier 0.36's soft bodies are built from) and sinew's voxels
//! (`Mesh::from_shape`). For a ball, a capsule, a torus and the trefoil-knot asset, each at a
//! tenth of its thickness: cells, the smallest and largest dihedral angle, the Hausdorff
//! distance between the mesh's boundary and the surface (both ways, sampled at the vertices),
//! the volume error, and the cost of a 1 s fall of the mesh as an edge-repulsion body at 60 Hz
//! (`Integrator::Auto`; not run past 20 000 cells). One markdown table.
//!
//! ```text
//! cargo run --release --example meshing
//! ```

use std::time::Instant;

use sinew::dim3::math::{Real, Vector};
use sinew::dim3::rapier::geometry::{ColliderBuilder, SharedShape};
use sinew::dim3::rapier::parry::query::PointQuery;
use sinew::dim3::rapier::parry::shape::{Ball, Capsule, Shape, TriMesh};
use sinew::dim3::rapier::parry::transformation::{
    volume_mesh, MeshEnclosure, VolumeMeshParameters,
};
use sinew::dim3::surface::obj;
use sinew::dim3::{
    CellKind, DeformableBuilder, DeformableWorld, ElementModel, Integrator, Mesh, Surface,
};
use sinew_scenes::dim3::meshing::{dihedral_range, torus};

struct Row {
    cells: usize,
    dihedral: (Real, Real),
    hausdorff: Real,
    volume_error: Real,
    fall: Option<f64>,
}

/// Both ways: the boundary's vertices to the shape's surface, and `samples` (points on the
/// shape's surface) to the boundary.
fn hausdorff(mesh: &Mesh, shape: &dyn Shape, samples: &[Vector]) -> Real {
    let faces = mesh.boundary_facets().to_vec();
    let mut out: Real = 0.0;
    for v in faces.iter().flatten() {
        let p = mesh.nodes()[*v as usize];
        out = out.max(p.distance(shape.project_local_point(p, false).point));
    }
    let skin = TriMesh::new(mesh.nodes().to_vec(), faces).expect("a boundary");
    for p in samples {
        out = out.max(p.distance(skin.project_local_point(*p, false).point));
    }
    out
}

/// Wall seconds per simulated second of a 1 s fall of `mesh` from 0.3 m onto the ground
/// (not run past 20 000 cells).
fn fall(mesh: &Mesh) -> Option<f64> {
    if mesh.num_cells() > 20_000 {
        return None;
    }
    let mut world = DeformableWorld::new();
    world.set_dt(1.0 / 60.0);
    world.pipeline.settings.integrator = Integrator::Auto { iterations: 2 };
    world.physics.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y)),
        None,
    );
    let low = mesh
        .nodes()
        .iter()
        .map(|p| p.y)
        .fold(Real::INFINITY, Real::min);
    let body = DeformableBuilder::new(mesh.clone())
        .model(ElementModel::EdgeRepulsion)
        .translation(Vector::Y * (0.3 - low))
        .build()
        .ok()?;
    world.insert(body);
    let started = Instant::now();
    for _ in 0..60 {
        world.step();
    }
    Some(started.elapsed().as_secs_f64())
}

fn measure(mesh: &Mesh, shape: &dyn Shape, samples: &[Vector], volume: Real) -> Row {
    Row {
        cells: mesh.num_cells(),
        dihedral: dihedral_range(mesh),
        hausdorff: hausdorff(mesh, shape, samples),
        volume_error: mesh.total_volume() / volume - 1.0,
        fall: fall(mesh),
    }
}

fn main() {
    let knot =
        obj::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/torus-knot.obj"))
            .unwrap_or_else(|e| panic!("{e}"));
    let pi = std::f64::consts::PI as Real;
    let ball = Ball::new(0.5);
    let capsule = Capsule::new_y(0.4, 0.25);
    let ring = torus(0.4, 0.15, 96, 48);
    // (name, shape as a surface for parry's mesher and the samples, the exact shape, volume, cell)
    type Case = (&'static str, Surface, Box<dyn Shape>, Real, Real);
    let (bv, bi) = ball.to_trimesh(40, 40);
    let ball_surface = Surface::welded(bv, bi, 1e-6).expect("parry's ball trimesh is closed");
    let (cv, ci) = capsule.to_trimesh(40, 20);
    let capsule_surface = Surface::welded(cv, ci, 1e-6).expect("parry's capsule trimesh is closed");
    let cases: Vec<Case> = vec![
        (
            "ball r 0.5",
            ball_surface,
            Box::new(ball),
            4.0 / 3.0 * pi * 0.125,
            0.1,
        ),
        (
            "capsule 0.8 + 2 × 0.25",
            capsule_surface,
            Box::new(capsule),
            pi * 0.0625 * 0.8 + 4.0 / 3.0 * pi * 0.015625,
            0.05,
        ),
        (
            "torus 0.4 / 0.15",
            ring.clone(),
            Box::new(ring.to_trimesh()),
            ring.volume(),
            0.03,
        ),
        // A fifth of its 8 cm tube: a tenth makes 150 000 cells.
        (
            "trefoil knot (asset)",
            knot.clone(),
            Box::new(knot.to_trimesh()),
            knot.volume(),
            0.016,
        ),
    ];
    println!("| shape | cell m | mesher | cells | dihedral ° | Hausdorff / cell | volume | fall 1 s, wall s |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, surface, shape, volume, cell) in &cases {
        let samples = surface.vertices();
        let mut rows: Vec<(&str, Option<Row>)> = Vec::new();
        rows.push((
            "sinew stuffing",
            Mesh::stuffed(&**shape, *cell)
                .ok()
                .map(|m| measure(&m, &**shape, samples, *volume)),
        ));
        for (label, smoothing) in [("parry cover", 0), ("parry cover, 10 smoothing", 10)] {
            let mut params = VolumeMeshParameters::new(*cell);
            params.enclosure = MeshEnclosure::Cover;
            params.cover_smoothing = smoothing;
            let row = volume_mesh(surface.vertices(), surface.triangles(), &params).and_then(|v| {
                let cells = v.cells.iter().flatten().copied().collect();
                Mesh::new(v.vertices, cells, CellKind::Simplex).ok()
            });
            rows.push((label, row.map(|m| measure(&m, &**shape, samples, *volume))));
        }
        rows.push((
            "sinew voxels",
            Mesh::from_shape(&**shape, *cell, CellKind::Simplex)
                .ok()
                .map(|m| measure(&m, &**shape, samples, *volume)),
        ));
        for (mesher, row) in rows {
            match row {
                Some(r) => println!(
                    "| {name} | {cell} | {mesher} | {} | {:.1} – {:.1} | {:.2} | {:+.1} % | {} |",
                    r.cells,
                    r.dihedral.0,
                    r.dihedral.1,
                    r.hausdorff / cell,
                    100.0 * r.volume_error,
                    r.fall.map_or("—".into(), |s| format!("{s:.2}")),
                ),
                None => println!("| {name} | {cell} | {mesher} | failed | | | | |"),
            }
        }
    }
}
