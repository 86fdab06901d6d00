//! Arbitrary bytes into the legacy VTK reader, 2D and 3D: it must return, never panic, and a
//! mesh it accepts must survive a write and a read unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sinew::{dim2, dim3};

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = dim2::mesh::io::vtk::read_from(data) {
        let back = dim2::mesh::io::vtk::read_str(&dim2::mesh::io::vtk::to_string(&mesh))
            .expect("a written mesh reads back");
        assert_eq!(back.nodes(), mesh.nodes());
        assert_eq!(back.cell_indices(), mesh.cell_indices());
    }
    if let Ok(mesh) = dim3::mesh::io::vtk::read_from(data) {
        let back = dim3::mesh::io::vtk::read_str(&dim3::mesh::io::vtk::to_string(&mesh))
            .expect("a written mesh reads back");
        assert_eq!(back.nodes(), mesh.nodes());
        assert_eq!(back.cell_indices(), mesh.cell_indices());
    }
});
