//! Render meshes (issue 30): a render surface ten times finer than the body's is bound to its
//! cells, and after the body falls, bounces and turns each render vertex is the barycentric
//! map of its cell's current nodes, within 1e-5 m.

use crate::dim::math::{Real, Vector, DIM, FACET_ARITY};
use crate::dim::rapier::geometry::{ColliderBuilder, SharedShape};
use crate::dim::{BuildError, CellKind, DeformableBuilder, DeformableWorld, Embedding, Mesh};

/// The boundary of a ball of `radius` cut from a lattice of `res` nodes across, its vertices
/// pushed out onto the sphere: a smooth render surface (vertices, facets).
fn sphere(radius: Real, res: usize) -> (Vec<Vector>, Vec<[u32; FACET_ARITY]>) {
    let mesh = Mesh::ball(radius, res, CellKind::Simplex).unwrap();
    let used = mesh.boundary_nodes();
    let mut index = vec![u32::MAX; mesh.nodes().len()];
    let mut vertices = Vec::new();
    for &i in used {
        index[i as usize] = vertices.len() as u32;
        vertices.push(mesh.nodes()[i as usize].normalize() * radius);
    }
    let facets = mesh
        .boundary_facets()
        .iter()
        .map(|f| f.map(|i| index[i as usize]))
        .collect();
    (vertices, facets)
}

/// `Σ w x` over a vertex's cell, from its binding.
fn mapped(mesh: &Mesh, positions: &[Vector], cell: u32, w: &[Real]) -> Vector {
    mesh.cell(cell as usize)
        .iter()
        .zip(w)
        .map(|(&i, &w)| positions[i as usize] * w)
        .sum()
}

#[test]
fn a_fine_render_mesh_follows_the_cells() {
    let coarse = Mesh::ball(0.25, 7, CellKind::Simplex).unwrap();
    let (render, facets) = sphere(0.25, if DIM == 3 { 25 } else { 70 });
    let surface_nodes = coarse.boundary_nodes().len();
    assert!(
        render.len() >= 10 * surface_nodes,
        "{} against {surface_nodes}",
        render.len()
    );

    let mut world = DeformableWorld::new();
    world
        .physics
        .colliders
        .insert(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)).friction(0.8));
    let body = DeformableBuilder::new(coarse.clone())
        .translation(Vector::Y * 0.6)
        .linvel(Vector::X * 1.0)
        .build()
        .unwrap();
    let h = world.insert(body);
    world.deformables[h]
        .set_render_mesh(&render, facets)
        .unwrap();

    // Bound at rest: every vertex is its cell's map of the rest nodes; the ones inside a cell
    // are inside their own, the others as little outside it as any cell.
    let e = world.deformables[h].render_mesh().unwrap().clone();
    let (mut inside, mut outside) = (0, 0);
    for ((cell, w), p) in e.binding().zip(&render) {
        assert!(mapped(&coarse, coarse.nodes(), cell, &w).distance(*p) < 1e-5);
        let worst = w.iter().copied().fold(Real::INFINITY, Real::min);
        if worst >= -1e-5 {
            inside += 1;
        } else {
            outside += 1;
            let best = (0..coarse.num_cells())
                .map(|c| {
                    let q: Vec<Vector> = coarse
                        .cell(c)
                        .iter()
                        .map(|&i| coarse.nodes()[i as usize])
                        .collect();
                    barycentric_min(&q, *p)
                })
                .fold(Real::NEG_INFINITY, Real::max);
            assert!(worst >= best - 1e-4, "{worst} against {best}");
        }
    }
    println!("{inside} render vertices inside a cell, {outside} outside the body");

    for _ in 0..90 {
        world.step();
        let b = &world.deformables[h];
        let e = b.render_mesh().unwrap();
        for ((cell, w), v) in e.binding().zip(e.vertices()) {
            let want = mapped(&coarse, b.positions(), cell, &w);
            assert!(want.distance(*v) < 1e-5, "{want} against {v}");
        }
    }
    // The normals are unit and face out of the (round, barely squashed) body.
    let b = &world.deformables[h];
    let centre = b.positions().iter().copied().sum::<Vector>() / b.positions().len() as Real;
    let e = b.render_mesh().unwrap();
    for (v, n) in e.vertices().iter().zip(e.normals()) {
        assert!((n.length() - 1.0).abs() < 1e-4);
        assert!(n.dot((*v - centre).normalize()) > 0.5, "{n} at {v}");
    }
    // It fell, moved and turned with the body.
    assert!(centre.y < 0.4 && centre.x > 0.2, "{centre}");
}

/// The smallest barycentric weight of `p` in the simplex `q`.
fn barycentric_min(q: &[Vector], p: Vector) -> Real {
    // Solve with the volumes of the simplices that replace each vertex by p.
    let total = crate::dim::math::simplex_volume(q);
    (0..q.len())
        .map(|k| {
            let mut r = q.to_vec();
            r[k] = p;
            crate::dim::math::simplex_volume(&r) / total
        })
        .fold(Real::INFINITY, Real::min)
}

#[test]
fn bad_render_meshes_are_refused() {
    let mesh = Mesh::ball(0.25, 5, CellKind::Simplex).unwrap();
    let (v, f) = sphere(0.25, 9);
    let mut bad = v.clone();
    bad[3].x = Real::NAN;
    assert!(matches!(
        Embedding::bind(&mesh, &bad, f.clone()),
        Err(BuildError::InvalidParameter {
            name: "render vertex",
            ..
        })
    ));
    let mut far = f.clone();
    far[0][0] = v.len() as u32;
    assert!(matches!(
        Embedding::bind(&mesh, &v, far),
        Err(BuildError::InvalidParameter {
            name: "render facet index",
            ..
        })
    ));
    let cubes = Mesh::ball(0.25, 5, CellKind::Cube).unwrap();
    assert!(matches!(
        Embedding::bind(&cubes, &v, f.clone()),
        Err(BuildError::InvalidParameter { name: "mesh", .. })
    ));
    // A body keeps no render mesh after a refused one, and clears one on request.
    let mut body = DeformableBuilder::new(mesh).build().unwrap();
    assert!(body.set_render_mesh(&bad, f.clone()).is_err());
    assert!(body.render_mesh().is_none());
    body.set_render_mesh(&v, f).unwrap();
    assert_eq!(body.render_mesh().unwrap().vertices().len(), v.len());
    body.clear_render_mesh();
    assert!(body.render_mesh().is_none());
}
