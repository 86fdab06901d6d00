//! Arbitrary bytes into the TetGen / Triangle reader, 2D and 3D. The input is the `.node`
//! text, a NUL byte, then the `.ele` text (no NUL: all `.node`, empty `.ele`). The reader
//! must return, never panic, and a mesh it accepts must survive a write and a read unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sinew::{dim2, dim3};

fuzz_target!(|data: &[u8]| {
    let (node, ele) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    if let Ok(mesh) = dim2::mesh::io::tetgen::read_from(node, ele) {
        let (n, e) = dim2::mesh::io::tetgen::to_strings(&mesh).expect("simplices");
        let back = dim2::mesh::io::tetgen::read_str(&n, &e).expect("a written mesh reads back");
        assert_eq!(back.nodes(), mesh.nodes());
        assert_eq!(back.cell_indices(), mesh.cell_indices());
    }
    if let Ok(mesh) = dim3::mesh::io::tetgen::read_from(node, ele) {
        let (n, e) = dim3::mesh::io::tetgen::to_strings(&mesh).expect("simplices");
        let back = dim3::mesh::io::tetgen::read_str(&n, &e).expect("a written mesh reads back");
        assert_eq!(back.nodes(), mesh.nodes());
        assert_eq!(back.cell_indices(), mesh.cell_indices());
    }
});
