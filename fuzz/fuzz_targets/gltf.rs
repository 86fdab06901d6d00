//! Arbitrary bytes into the GLTF surface reader: it must return, never panic, and a surface it
//! accepts must enclose a positive volume and pass its own check again unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sinew::dim3::surface::{gltf, Surface};

fuzz_target!(|data: &[u8]| {
    if let Ok(surface) = gltf::read_bytes(data) {
        assert!(surface.volume() > 0.0);
        let again = Surface::new(surface.vertices().to_vec(), surface.triangles().to_vec())
            .expect("an accepted surface passes its check again");
        assert_eq!(again, surface);
    }
});
