//! Arbitrary bytes into the Gmsh reader, 2D and 3D: it must return, never panic, and a mesh
//! it accepts must survive a write and a read unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sinew::{dim2, dim3};

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = dim2::mesh::io::gmsh::read_from(data) {
        for v in [
            dim2::mesh::io::gmsh::GmshVersion::V4_1,
            dim2::mesh::io::gmsh::GmshVersion::V2_2,
        ] {
            let back = dim2::mesh::io::gmsh::read_str(&dim2::mesh::io::gmsh::to_string(&mesh, v))
                .expect("a written mesh reads back");
            assert_eq!(back.nodes(), mesh.nodes());
            assert_eq!(back.cell_indices(), mesh.cell_indices());
        }
    }
    if let Ok(mesh) = dim3::mesh::io::gmsh::read_from(data) {
        for v in [
            dim3::mesh::io::gmsh::GmshVersion::V4_1,
            dim3::mesh::io::gmsh::GmshVersion::V2_2,
        ] {
            let back = dim3::mesh::io::gmsh::read_str(&dim3::mesh::io::gmsh::to_string(&mesh, v))
                .expect("a written mesh reads back");
            assert_eq!(back.nodes(), mesh.nodes());
            assert_eq!(back.cell_indices(), mesh.cell_indices());
        }
    }
});
