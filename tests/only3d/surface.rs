//! Closed triangle surfaces (issue 30): what `Surface` accepts, one test per kind of bad input
//! (each checking the error names the element), and the readers on the fixtures of
//! `tests/fixtures/surface` (written by its `make.py`), on broken files and on random bytes.

use sinew::dim3::math::{Real, Vector};
use sinew::dim3::{CellKind, Mesh, Surface, SurfaceError};

/// A cube of side `side` at the origin's corner: 8 vertices, 12 triangles facing outwards.
fn cube(side: Real) -> (Vec<Vector>, Vec<[u32; 3]>) {
    let vertices = (0..8)
        .map(|i| Vector::new((i >> 2) as Real, ((i >> 1) & 1) as Real, (i & 1) as Real) * side)
        .collect();
    // Quads counter-clockwise seen from outside, vertex (x, y, z) at 4x + 2y + z.
    let quads = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    (vertices, triangles)
}

#[test]
fn a_closed_cube_is_a_surface_with_its_volume_and_area() {
    let (v, t) = cube(2.0);
    let s = Surface::new(v, t).unwrap();
    assert_eq!((s.vertices().len(), s.triangles().len()), (8, 12));
    assert!((s.volume() - 8.0).abs() < 1e-5, "{}", s.volume());
    assert!((s.area() - 24.0).abs() < 1e-4, "{}", s.area());
    assert_eq!(s.bounds(), (Vector::ZERO, Vector::splat(2.0)));
}

#[test]
fn an_inward_surface_is_turned_outwards_whole() {
    let (v, t) = cube(1.0);
    let inward: Vec<[u32; 3]> = t.iter().map(|t| [t[0], t[2], t[1]]).collect();
    let s = Surface::new(v, inward.clone()).unwrap();
    assert!((s.volume() - 1.0).abs() < 1e-6);
    for (a, b) in s.triangles().iter().zip(&inward) {
        assert_eq!(*a, [b[0], b[2], b[1]]);
    }
}

#[test]
fn unused_vertices_are_dropped_and_the_rest_renumbered() {
    let (mut v, t) = cube(1.0);
    v.insert(0, Vector::splat(9.0));
    let t: Vec<[u32; 3]> = t.iter().map(|t| t.map(|i| i + 1)).collect();
    let s = Surface::new(v, t).unwrap();
    assert_eq!(s.vertices().len(), 8);
    assert_eq!(s.vertices()[0], Vector::ZERO);
    assert!((s.volume() - 1.0).abs() < 1e-6);
}

#[test]
fn an_open_surface_names_its_open_edge() {
    let (v, mut t) = cube(1.0);
    let gone = t.remove(5);
    let e = Surface::new(v, t).unwrap_err();
    let SurfaceError::OpenEdge { a, b, .. } = e else {
        panic!("{e:?}");
    };
    // The open edge is one of the removed triangle's.
    assert!(gone.contains(&a) && gone.contains(&b), "{e}");
    assert!(e.to_string().contains(&format!("edge {a}–{b}")), "{e}");
}

#[test]
fn a_flipped_triangle_is_named() {
    let (v, mut t) = cube(1.0);
    t[7].swap(1, 2);
    let e = Surface::new(v, t).unwrap_err();
    let SurfaceError::InconsistentWinding {
        triangle,
        neighbour,
        ..
    } = e
    else {
        panic!("{e:?}");
    };
    assert!(triangle == 7 || neighbour == 7, "{e}");
    assert!(e.to_string().contains("triangle 7"), "{e}");
}

#[test]
fn an_edge_of_three_triangles_is_non_manifold() {
    let (mut v, mut t) = cube(1.0);
    // A fin on the cube's edge 0–1, closed into a thin tetrahedron of its own.
    v.push(Vector::new(-1.0, -1.0, 0.5));
    t.push([0, 1, 8]);
    let e = Surface::new(v, t).unwrap_err();
    assert!(
        matches!(
            e,
            SurfaceError::NonManifoldEdge { .. } | SurfaceError::OpenEdge { .. }
        ),
        "{e:?}"
    );
    let (mut v, mut t) = cube(1.0);
    // Two fins on edge 0–1, wound so that each is closed: three triangles on 0–1 besides
    // the cube's two.
    v.push(Vector::new(-1.0, -1.0, 0.5));
    t.extend([[0, 1, 8], [1, 0, 8]]);
    let e = Surface::new(v, t).unwrap_err();
    let SurfaceError::NonManifoldEdge { a, b, count, .. } = e else {
        panic!("{e:?}");
    };
    assert_eq!((a, b, count), (0, 1, 4), "{e}");
}

#[test]
fn two_cubes_touching_at_a_corner_are_non_manifold_there() {
    let (mut v, mut t) = cube(1.0);
    let (v2, t2) = cube(1.0);
    // The second cube's vertex 0 is the first's vertex 7, (1, 1, 1).
    let base = v.len() as u32 - 1;
    v.extend(v2.iter().skip(1).map(|p| *p + Vector::ONE));
    t.extend(
        t2.iter()
            .map(|t| t.map(|i| if i == 0 { 7 } else { i + base })),
    );
    let e = Surface::new(v, t).unwrap_err();
    assert_eq!(e, SurfaceError::NonManifoldVertex { vertex: 7, fans: 2 });
    assert!(e.to_string().contains("vertex 7"), "{e}");
}

#[test]
fn bad_numbers_and_indices_are_named() {
    let (mut v, t) = cube(1.0);
    v[3].y = Real::NAN;
    let e = Surface::new(v, t.clone()).unwrap_err();
    assert!(
        matches!(e, SurfaceError::NonFinite { vertex: 3, .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("vertex 3"), "{e}");

    let (v, mut t) = cube(1.0);
    t[4][2] = 8;
    let e = Surface::new(v, t).unwrap_err();
    assert_eq!(
        e,
        SurfaceError::IndexOutOfRange {
            triangle: 4,
            index: 8,
            vertices: 8
        }
    );

    let (mut v, t) = cube(1.0);
    // Vertex 3 moved onto the line of 0 and 1: triangle 0 (0, 1, 3) has no area.
    v[3] = Vector::new(0.0, 0.0, 2.0);
    let e = Surface::new(v, t).unwrap_err();
    assert_eq!(
        e,
        SurfaceError::DegenerateTriangle {
            triangle: 0,
            vertices: [0, 1, 3]
        }
    );

    let (v, t) = cube(1.0);
    let e = Surface::new(v, t[..3].to_vec()).unwrap_err();
    assert_eq!(e, SurfaceError::TooFewTriangles { count: 3 });
}

#[test]
fn welding_joins_a_triangle_soup() {
    let (v, t) = cube(1.0);
    // Every triangle with its own corners, as STL stores them, jittered below the tolerance.
    let mut soup = Vec::new();
    let mut tris = Vec::new();
    for (k, tri) in t.iter().enumerate() {
        let base = soup.len() as u32;
        for (j, &i) in tri.iter().enumerate() {
            soup.push(v[i as usize] + Vector::splat(1e-7 * ((k + j) % 3) as Real));
        }
        tris.push([base, base + 1, base + 2]);
    }
    assert!(matches!(
        Surface::new(soup.clone(), tris.clone()),
        Err(SurfaceError::OpenEdge { .. })
    ));
    let s = Surface::welded(soup.clone(), tris.clone(), 1e-5).unwrap();
    assert_eq!((s.vertices().len(), s.triangles().len()), (8, 12));
    // A zero-area triangle with a repeated corner, as CAD exports hold, first in the list: the
    // weld drops it, and an error after names the triangles as given.
    let mut with_sliver = vec![[0, 0, 1]];
    with_sliver.extend(&tris);
    let s = Surface::welded(soup.clone(), with_sliver.clone(), 1e-5).unwrap();
    assert_eq!(s.triangles().len(), 12);
    with_sliver[8].swap(1, 2);
    let e = Surface::welded(soup.clone(), with_sliver, 1e-5).unwrap_err();
    let SurfaceError::InconsistentWinding {
        triangle,
        neighbour,
        ..
    } = e
    else {
        panic!("{e:?}");
    };
    assert!(triangle == 8 || neighbour == 8, "{e}");
    assert!(matches!(
        Surface::welded(soup, tris, -1.0),
        Err(SurfaceError::InvalidTolerance { .. })
    ));
}

#[test]
fn a_surface_meshes_into_cells_of_its_volume() {
    let (v, t) = cube(1.0);
    let s = Surface::new(v, t).unwrap();
    let mesh = Mesh::from_shape(&s.to_trimesh(), 0.1, CellKind::Simplex).unwrap();
    assert!(
        (mesh.total_volume() - 1.0).abs() < 0.05,
        "{}",
        mesh.total_volume()
    );
}

#[cfg(any(feature = "stl", feature = "obj", feature = "gltf"))]
mod files {
    use super::*;
    use sinew::dim3::surface::SurfaceReadError;

    pub fn fixture(name: &str) -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/surface")
            .join(name)
    }

    /// The fixture read back: its counts, and its volume against `volume` within 1 %.
    pub fn check(s: &Surface, vertices: usize, triangles: usize, volume: Real) {
        assert_eq!(
            (s.vertices().len(), s.triangles().len()),
            (vertices, triangles)
        );
        assert!(
            (s.volume() - volume).abs() < 0.01 * volume,
            "{} against {volume}",
            s.volume()
        );
    }

    /// The error names `<memory>` and, for a surface error, the element.
    pub fn surface_error(e: SurfaceReadError) -> SurfaceError {
        assert!(e.to_string().starts_with("<memory>: "), "{e}");
        match e {
            SurfaceReadError::Surface { error, .. } => error,
            e => panic!("{e:?}"),
        }
    }

    /// The icosphere's volume: 80 flat faces inside the 0.5 m sphere (its 0.5236), the sum
    /// over its facets in double precision.
    pub const ICOSPHERE: Real = 0.45734;

    /// Every file of `fuzz/corpus/<target>` (the fuzz target's seeds and finds), read:
    /// how many the reader accepted. None may panic.
    pub fn corpus(target: &str, read: impl Fn(&[u8]) -> bool) -> usize {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/corpus")
            .join(target);
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        files
            .iter()
            .filter(|f| read(&std::fs::read(f).unwrap()))
            .count()
    }

    #[test]
    fn a_missing_file_is_an_io_error_naming_it() {
        #[cfg(feature = "stl")]
        let e = sinew::dim3::surface::stl::read(fixture("nothing.stl")).unwrap_err();
        #[cfg(all(not(feature = "stl"), feature = "obj"))]
        let e = sinew::dim3::surface::obj::read(fixture("nothing.obj")).unwrap_err();
        #[cfg(all(not(feature = "stl"), not(feature = "obj")))]
        let e = sinew::dim3::surface::gltf::read(fixture("nothing.glb")).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Io { .. }), "{e:?}");
        assert!(e.to_string().contains("nothing."), "{e}");
    }
}

#[cfg(feature = "stl")]
mod stl {
    use super::files::*;
    use super::*;
    use proptest::prelude::*;
    use sinew::dim3::surface::{stl, SurfaceReadError};

    #[test]
    fn ascii_and_binary_stl_read_back_welded() {
        let ascii = stl::read(fixture("icosphere.stl")).unwrap();
        check(&ascii, 42, 80, ICOSPHERE);
        let binary = stl::read(fixture("icosphere-binary.stl")).unwrap();
        check(&binary, 42, 80, ICOSPHERE);
        assert_eq!(ascii.triangles(), binary.triangles());
    }

    #[test]
    fn broken_stl_is_named() {
        let text = std::fs::read_to_string(fixture("icosphere.stl")).unwrap();
        // A facet dropped: its three edges are open.
        let start = text.find("  facet").unwrap();
        let end = text[start..].find("endfacet").unwrap() + start + "endfacet\n".len();
        let open = format!("{}{}", &text[..start], &text[end..]);
        let e = surface_error(stl::read_bytes(open.as_bytes()).unwrap_err());
        assert!(matches!(e, SurfaceError::OpenEdge { .. }), "{e:?}");
        // A facet's winding flipped: its first two vertex lines swapped.
        let lines: Vec<&str> = text.lines().collect();
        let mut flipped = lines.clone();
        flipped.swap(3, 4);
        let e = surface_error(stl::read_bytes(flipped.join("\n").as_bytes()).unwrap_err());
        assert!(
            matches!(
                e,
                SurfaceError::InconsistentWinding { triangle: 0, .. }
                    | SurfaceError::InconsistentWinding { neighbour: 0, .. }
            ),
            "{e:?}"
        );
        // A NaN coordinate.
        let mut nan = lines.clone();
        let line = nan[3].replace(|c: char| c != ' ', "");
        let replaced = format!("{line}vertex nan 0 0");
        nan[3] = &replaced;
        let e = stl::read_bytes(nan.join("\n").as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                SurfaceReadError::Surface {
                    error: SurfaceError::NonFinite { vertex: 0, .. },
                    ..
                } | SurfaceReadError::Parse { .. }
            ),
            "{e:?}"
        );
        // A truncated binary file.
        let bytes = std::fs::read(fixture("icosphere-binary.stl")).unwrap();
        let e = stl::read_bytes(&bytes[..bytes.len() - 30]).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Parse { .. }), "{e:?}");
        assert!(matches!(
            stl::read_bytes(b"solid empty\nendsolid empty\n"),
            Err(SurfaceReadError::Empty { .. })
        ));
    }

    #[test]
    fn the_stl_fuzz_corpus_reads() {
        assert!(corpus("stl", |b| stl::read_bytes(b).is_ok()) >= 2);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn stl_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400),
                            cut in 0usize..4100, flip in 84usize..4084) {
            let _ = stl::read_bytes(&bytes);
            let mut binary = std::fs::read(fixture("icosphere-binary.stl")).unwrap();
            binary[flip] ^= 0x5a;
            let _ = stl::read_bytes(&binary);
            binary.truncate(cut);
            let _ = stl::read_bytes(&binary);
        }
    }
}

#[cfg(feature = "obj")]
mod obj {
    use super::files::*;
    use super::*;
    use proptest::prelude::*;
    use sinew::dim3::surface::{obj, SurfaceReadError};

    #[test]
    fn an_obj_of_quads_reads_back_welded() {
        let s = obj::read(fixture("cube.obj")).unwrap();
        check(&s, 8, 12, 1.0);
    }

    #[test]
    fn broken_obj_is_named() {
        let text = std::fs::read_to_string(fixture("cube.obj")).unwrap();
        let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
        // A face dropped.
        let open = text.replace(&format!("{}\n", faces[2]), "");
        let e = surface_error(obj::read_bytes(open.as_bytes()).unwrap_err());
        assert!(matches!(e, SurfaceError::OpenEdge { .. }), "{e:?}");
        // A face wound the other way.
        let mut reversed: Vec<&str> = faces[0].split(' ').skip(1).collect();
        reversed.reverse();
        let flipped = text.replace(faces[0], &format!("f {}", reversed.join(" ")));
        let e = surface_error(obj::read_bytes(flipped.as_bytes()).unwrap_err());
        assert!(
            matches!(e, SurfaceError::InconsistentWinding { .. }),
            "{e:?}"
        );
        // A vertex index past the vertices.
        let far = text.replace(faces[1], "f 1/1/1 2/2/1 99/3/1");
        let e = obj::read_bytes(far.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                SurfaceReadError::Parse { .. }
                    | SurfaceReadError::Surface {
                        error: SurfaceError::IndexOutOfRange { .. },
                        ..
                    }
            ),
            "{e:?}"
        );
        // A NaN.
        let nan = text.replacen("v 0 0 0", "v nan 0 0", 1);
        let e = obj::read_bytes(nan.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                SurfaceReadError::Parse { .. }
                    | SurfaceReadError::Surface {
                        error: SurfaceError::NonFinite { .. },
                        ..
                    }
            ),
            "{e:?}"
        );
    }

    #[test]
    fn the_obj_fuzz_corpus_reads() {
        assert!(corpus("obj", |b| obj::read_bytes(b).is_ok()) >= 1);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn obj_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400),
                            at in 0usize..390, with in any::<u8>()) {
            let _ = obj::read_bytes(&bytes);
            let mut text = std::fs::read(fixture("cube.obj")).unwrap();
            text[at] = with;
            let _ = obj::read_bytes(&text);
        }
    }
}

#[cfg(feature = "gltf")]
mod gltf {
    use super::files::*;
    use super::*;
    use proptest::prelude::*;
    use sinew::dim3::surface::{gltf, SurfaceReadError};

    /// The torus (R = 0.4, r = 0.15, 24 × 12 flat quads) scaled by 0.5: its volume.
    fn torus_volume() -> Real {
        let (n, m): (Real, Real) = (24.0, 12.0);
        let pi = std::f64::consts::PI as Real;
        // A prism of the 12-gon cross-section swept along the 24-gon of radius R (the
        // polygonal torus's volume by Pappus, close enough for 1 %).
        let section = 0.5 * m * 0.15 * 0.15 * (2.0 * pi / m).sin();
        let path = n * 2.0 * 0.4 * (pi / n).sin();
        section * path * 0.125
    }

    #[test]
    fn glb_and_embedded_gltf_read_back_placed_by_their_node() {
        for name in ["torus.glb", "torus.gltf"] {
            let s = gltf::read(fixture(name)).unwrap();
            check(&s, 288, 576, torus_volume());
            let (lo, hi) = s.bounds();
            // Scaled by 0.5 and moved up 1 m: its centre plane at y = 1.
            assert!(
                (0.5 * (lo.y + hi.y) - 1.0).abs() < 1e-5,
                "{name}: {lo} {hi}"
            );
            assert!((hi.x - 0.275).abs() < 1e-4, "{name}: {hi}");
        }
        let bytes = std::fs::read(fixture("torus.glb")).unwrap();
        check(&gltf::read_bytes(&bytes).unwrap(), 288, 576, torus_volume());
    }

    #[test]
    fn broken_gltf_is_named() {
        let text = std::fs::read_to_string(fixture("torus.gltf")).unwrap();
        let refused = |e: &SurfaceReadError| {
            matches!(
                e,
                SurfaceReadError::Unsupported { .. } | SurfaceReadError::Parse { .. }
            )
        };
        // Fewer indices: the last triangles gone, their edges open.
        let open = text.replace("\"count\": 1728", "\"count\": 1722");
        let e = surface_error(gltf::read_bytes(open.as_bytes()).unwrap_err());
        assert!(matches!(e, SurfaceError::OpenEdge { .. }), "{e:?}");
        // More indices than the buffer holds.
        let past = text.replace("\"count\": 1728", "\"count\": 9999");
        let e = gltf::read_bytes(past.as_bytes()).unwrap_err();
        assert!(refused(&e), "{e:?}");
        // Lines, not triangles.
        let lines = text.replace("\"indices\": 1", "\"indices\": 1, \"mode\": 1");
        let e = gltf::read_bytes(lines.as_bytes()).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Unsupported { .. }), "{e:?}");
        assert!(e.to_string().contains("mesh 0 primitive 0"), "{e}");
        // A node that is its own child: refused, not followed forever.
        let cycle = text.replace("\"mesh\": 0,", "\"mesh\": 0, \"children\": [0],");
        assert_ne!(cycle, text);
        let e = gltf::read_bytes(cycle.as_bytes()).unwrap_err();
        assert!(refused(&e), "{e:?}");
        // A position accessor past the accessors (panicked inside `gltf`'s validation; found
        // by the fuzz target).
        let missing = text.replace("\"POSITION\": 0", "\"POSITION\": 7");
        assert_ne!(missing, text);
        let e = gltf::read_bytes(missing.as_bytes()).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Parse { .. }), "{e:?}");
        assert!(
            e.to_string().contains("mesh 0 primitive 0: accessor 7"),
            "{e}"
        );
        // Positions as two floats (the reader would read them as three).
        let flat = text.replacen("\"type\": \"VEC3\"", "\"type\": \"VEC2\"", 1);
        assert_ne!(flat, text);
        let e = gltf::read_bytes(flat.as_bytes()).unwrap_err();
        assert!(refused(&e), "{e:?}");
        // A GLB declaring itself shorter than its header (an overflow inside `gltf`).
        let mut glb = std::fs::read(fixture("torus.glb")).unwrap();
        glb[8..12].copy_from_slice(&4u32.to_le_bytes());
        let e = gltf::read_bytes(&glb).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Parse { .. }), "{e:?}");
        // Not JSON.
        let e = gltf::read_bytes(b"{ not json").unwrap_err();
        assert!(matches!(e, SurfaceReadError::Parse { .. }), "{e:?}");
        // An external buffer read from bytes.
        let external = text.replace("data:application/octet-stream;base64,", "torus.bin#");
        let e = gltf::read_bytes(external.as_bytes()).unwrap_err();
        assert!(matches!(e, SurfaceReadError::Unsupported { .. }), "{e:?}");
    }

    #[test]
    fn the_gltf_fuzz_corpus_reads() {
        assert!(corpus("gltf", |b| gltf::read_bytes(b).is_ok()) >= 2);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn gltf_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400),
                             at in 0usize..11000, with in any::<u8>(), cut in 0usize..11012) {
            let _ = gltf::read_bytes(&bytes);
            let mut glb = std::fs::read(fixture("torus.glb")).unwrap();
            glb[at] = with;
            let _ = gltf::read_bytes(&glb);
            glb.truncate(cut);
            let _ = gltf::read_bytes(&glb);
        }
    }
}
